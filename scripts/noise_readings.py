"""The readings of the colour trackers' input gates for every sequence under the given folders, sorted, with the
count above a limit: ``denoise``'s noise between the first two frames (pftrack.cues.noise.temporal_noise), or with
``--span`` ``haze_stretch``'s gain of the first frame's level span (pftrack.cues.quantize.level_range; grey frames,
whose features are not RGB bins, are listed apart).

    python scripts/noise_readings.py reports/split/tune_real reports/split/tune_synth --limit 5
    python scripts/noise_readings.py reports/split/tune_real --span --limit 1.8
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2

from pftrack.cues.intensity import is_gray
from pftrack.cues.noise import temporal_noise
from pftrack.cues.quantize import level_range
from pftrack.io import discover_sequences
from pftrack.io.sources import read_image


def first_two(seq) -> tuple:
    """The frame a tracker starts on (the first annotated one) and the next."""
    i = seq.init_index
    return tuple(read_image(f) for f in seq.frames[i:i + 2])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--limit", type=float, default=5.0)
    ap.add_argument("--span", action="store_true", help="the level span's gain (haze_stretch) instead of the noise")
    a = ap.parse_args(argv)
    rows, grey = [], 0
    for folder in a.folders:
        for seq in discover_sequences(Path(folder)):
            pair = first_two(seq)
            if len(pair) < 2 or any(f is None for f in pair):
                continue
            if not a.span:
                rows.append((temporal_noise(*pair), seq.name, folder))
            elif is_gray(pair[0]):
                grey += 1
            else:
                rows.append((level_range(pair[0])[0], seq.name, folder))
    rows.sort()
    for level, name, folder in rows:
        print(f"{level:6.2f}  {folder}/{name}")
    above = sum(level > a.limit for level, _, _ in rows)
    print(f"{len(rows)} sequences, {above} above {a.limit:g}; range {rows[0][0]:.2f}-{rows[-1][0]:.2f}"
          if rows else "no sequences")
    if grey:
        print(f"{grey} grey sequences (no RGB bins)")
    return 0


if __name__ == "__main__":
    cv2.setNumThreads(1)
    sys.exit(main())
