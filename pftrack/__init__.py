"""pftrack: fast, training-free, probabilistic visual object tracking.

>>> import pftrack
>>> tracker = pftrack.create_tracker("color-pf", seed=0)        # doctest: +SKIP
>>> state = tracker.init(frame, (x, y, w, h))                   # doctest: +SKIP
>>> for frame in pftrack.open_source("clip.mp4"):               # doctest: +SKIP
...     state = tracker.update(frame)
"""

from .errors import (BoxError, FormatError, FrameError, InputError, OutputError, ParameterError, PftrackError,
                     SourceError)
from .io.sources import open_source
from .trackers.base import Tracker, TrackState
from .trackers.registry import create_tracker, list_trackers, tracker_names

__version__ = "0.1.0"

__all__ = [
    "create_tracker", "list_trackers", "tracker_names", "open_source", "Tracker", "TrackState", "PftrackError",
    "InputError", "SourceError", "FrameError", "BoxError", "ParameterError", "FormatError", "OutputError",
    "__version__",
]
