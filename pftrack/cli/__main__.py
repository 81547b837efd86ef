"""``python -m pftrack.cli``."""

import sys

from . import main

sys.exit(main())
