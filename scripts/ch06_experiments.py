"""Book ch. 6 claims that are not accuracy tables (docs/covariance.md).

C6.3: the Log-Euclidean mean of T = 10 covariances (d = 9) against the affine-invariant (Karcher)
mean: time of each (ours, and pyriemann's when installed), their ratio, and how far apart the two
means are (affine-invariant distance) compared with the typical distance between consecutive
covariances of a real track.  C6.2: the time of one local step (fs-meanshift update) and of one
global covariance search at 640x480.

    python scripts/ch06_experiments.py [--data ../shared/data] [--repeat 200]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

import pftrack
from pftrack.cues import covariance as cv
from pftrack.cues import covariance_search as cs
from pftrack.io.datasets import read_sequence


def _timeit(fn, repeat: int) -> float:
    fn()
    t = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t) / repeat


def track_covariances(seq_path: Path, n: int = 40) -> np.ndarray:
    """Standardised covariances of the ground-truth boxes of the first ``n`` frames."""
    seq = read_sequence(seq_path)
    out = []
    for i in range(min(n, len(seq.frames))):
        frame = cv2.imread(str(seq.frames[i]))
        lv = cs.Level.build(frame, 1, kind="porikli9", gray=False)
        C = cs.window_covariance(lv, tuple(seq.groundtruth[i]), kind="porikli9", gray=False)
        if C is not None:
            out.append(C)
    return np.stack(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--repeat", type=int, default=200)
    args = ap.parse_args()
    seq = Path(args.data) / "davis16_blackswan"
    Cs = track_covariances(seq)
    T = 10
    win = Cs[:T]
    t_le = _timeit(lambda: cv.le_mean(win), args.repeat)
    t_ai = _timeit(lambda: cv.airm_mean(win), max(10, args.repeat // 10))
    print(f"C6.3 on {seq.name} (T={T}, d={win.shape[1]}):")
    print(f"  Log-Euclidean mean      {t_le * 1e3:8.3f} ms")
    print(f"  affine-invariant mean   {t_ai * 1e3:8.3f} ms   (ours; ratio {t_ai / t_le:5.1f}x)")
    try:
        try:
            from pyriemann.geometry.mean import mean_logeuclid, mean_riemann
        except ImportError:
            from pyriemann.utils.mean import mean_logeuclid, mean_riemann

        t_ple = _timeit(lambda: mean_logeuclid(win), args.repeat)
        t_pai = _timeit(lambda: mean_riemann(win), max(10, args.repeat // 10))
        print(f"  pyriemann mean_logeuclid {t_ple * 1e3:7.3f} ms, mean_riemann {t_pai * 1e3:7.3f} ms "
              f"(ratio {t_pai / t_ple:5.1f}x; mean_riemann / our LE mean {t_pai / t_le:5.1f}x)")
    except ImportError:
        print("  (pyriemann not installed: pip install pyriemann for its reference timings)")
    m_le, m_ai = cv.le_mean(win), cv.airm_mean(win)
    steps = [cv.airm_distance(Cs[k], Cs[k + 1]) for k in range(len(Cs) - 1)]
    print(f"  AIRM distance between the two means {cv.airm_distance(m_le, m_ai):.4f}; "
          f"consecutive frames: median {np.median(steps):.4f}")
    # C6.2: local step and global search at 640x480
    rng = np.random.default_rng(0)
    frame = cv2.GaussianBlur(cv2.resize(rng.integers(0, 256, (60, 80, 3), dtype=np.uint8), (640, 480)), (0, 0), 2)
    frame[200:320, 300:360] = (40, 60, 200)
    t = pftrack.create_tracker("fs-meanshift")
    t.init(frame, (300, 200, 60, 120))
    t_local = _timeit(lambda: t.update(frame), args.repeat)
    lv = cs.Level.build(frame, 1, kind="porikli9", gray=False)
    model = cv.SPDModel(cs.window_covariance(lv, (300, 200, 60, 120), kind="porikli9", gray=False))
    t_glob = _timeit(lambda: cs.search(frame, model, (60, 120), kind="porikli9", gray=False, refine_pitch=1),
                     max(5, args.repeat // 20))
    print(f"C6.2 at 640x480, 60x120 target: fs-meanshift update {t_local * 1e3:.2f} ms; "
          f"global covariance search {t_glob * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
