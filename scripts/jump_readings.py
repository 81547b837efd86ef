"""Frame-to-frame colour jumps: what ``pftrack.cues.still_gain.frame_jump`` reads on sequences.

For every sequence (an OTB-layout folder, a video, or a synthetic scene's folder) and every frame after the first,
the per-channel median log-ratio of the frame's levels against the previous frame's on a lattice of pixels, and the
chromatic part of that jump (the largest difference between two channels' medians). A white balance that switches
shows as a chromatic jump on one frame; camera motion, walkers and a gradual drift show as small ones.

    python scripts/jump_readings.py reports/split/tune_real reports/split/tune_pets

Prints one line per sequence: its largest chromatic jump, the frame where it is, the channels' medians there, and
the number of frames whose chromatic jump exceeds 0.05 / 0.1 / 0.15, and the largest common jump of the light (the
absolute mean of the three medians, on frames whose MADs are at most 0.4). Grey sequences are read too (their
chromatic jumps are 0); a frame where the camera switches between colour and grey reads no jump.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pftrack.cues.still_gain import JUMP_MAX_MAD, frame_jump, reference_lattice
from pftrack.frames import as_bgr_uint8
from pftrack.io import discover_sequences
from pftrack.io.sources import read_image


def readings(seq) -> tuple[np.ndarray, np.ndarray]:
    """Per frame (from the second): the channels' median log-ratios ``(n - 1, 3)`` and their MADs."""
    prev, meds, mads = None, [], []
    for f in seq.frames:
        frame = read_image(f)
        if frame is None:
            return np.zeros((0, 3)), np.zeros((0, 3))
        frame = as_bgr_uint8(frame)  # a grey image file: three equal channels, as the trackers see it
        lat = reference_lattice(frame)
        if prev is not None:
            m, d = frame_jump(prev, lat, grey=True)  # a grey camera's lamps read too (light_jump_grey)
            meds.append(m)
            mads.append(d)
        prev = lat
    return np.array(meds).reshape(-1, 3), np.array(mads).reshape(-1, 3)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path)
    args = ap.parse_args(argv)
    allc, alll = [], []
    for p in (s for folder in args.folders for s in discover_sequences(folder)):
        meds, mads = readings(p)
        if not len(meds):
            print(f"{p.name}: unreadable or too short")
            continue
        chroma = meds.max(1) - meds.min(1)
        light = np.where(mads.max(1) <= JUMP_MAX_MAD, np.abs(meds.mean(1)), 0.0)  # the common part, where still
        allc.append(chroma)
        alll.append(light)
        k, j = int(np.argmax(chroma)), int(np.argmax(light))
        counts = [int(np.sum(chroma > t)) for t in (0.05, 0.1, 0.15)]
        print(f"{p.name}: max chroma {chroma[k]:.3f} at frame {k + 1} (medians {np.round(meds[k], 3).tolist()}, "
              f"MAD {np.round(mads[k], 3).tolist()}); frames > 0.05/0.1/0.15: {counts} of {len(chroma)}; "
              f"max light {light[j]:.3f} at frame {j + 1}")
    if allc:
        c, li = np.concatenate(allc), np.concatenate(alll)
        print(f"all: {len(c)} frames, chroma 99th pct {np.percentile(c, 99):.3f}, max {c.max():.3f}; light (the "
              f"channels' mean median, MADs <= {JUMP_MAX_MAD}) 99th pct {np.percentile(li, 99):.3f}, "
              f"max {li.max():.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
