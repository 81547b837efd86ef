"""Book ch. 2 experiments: the cue comparison (Table 5), the 20-particle hybrid test (Fig. 6), batch SSIM speed.

    python scripts/ssim_experiments.py [--data ../shared/data] [--seeds 10] [--out docs/ssim-experiments.md]
                                       [--first 300] [--real NAMES]

* **Table 5 analogue.** The same particle filter (``ssim-pf``: random walk, N = 100, likelihood (29))
  with the chapter's four cues: colour, edges, colour & edges, SSIM (the chapter's local MSSIM), over
  ``--seeds`` seeds, on freshly seeded camouflage scenes (seeds 100+: the target is a flipped patch of
  the background under a falling light) and on real sequences. Metric (43): RMSE of the box's upper-left
  corner over the runs, per frame; mean and std over frames.
* **Fig. 6 analogue.** A fast mover (5 px/frame, turning every 10 frames) with position noise 3 px, too
  small for the motion: ssim-pf with 20 particles against hybrid-ssim-pf with 20 (both proposals), over
  ``--seeds`` seeds. A run is lost when its centre error exceeds 20 px in some frame.
* ``--first S`` draws the synthetic scenes from seed S instead of 100 (the camouflage scenes S..S+2 and the fast
  movers S..S+seeds-1): a fresh draw of neither split. ``--real ''`` leaves out the real sequences.
* **Speed of the batched cue.** 100 patches of 64x64: ``ssim_batch`` against a per-particle loop of the
  reference formula (and of scikit-image's ``structural_similarity`` when it is installed).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

import pftrack
from pftrack.cues import ssim as S
from pftrack.geometry import center_error
from pftrack.io.datasets import read_sequence
from pftrack.io.sources import read_image
from pftrack.synth import Scene, SceneSpec, Target, camouflage_scene
from pftrack.trackers.warmup import warm_up

CUES = ["color", "edges", "color+edges", "ssim"]


def run(name: str, frames, gt, seed: int, **params) -> np.ndarray:
    t = pftrack.create_tracker(name, seed=seed, **params)
    start = int(np.argmax(np.all(np.isfinite(gt), axis=1)))
    t.init(frames[start], tuple(gt[start]))
    boxes = np.full((len(frames), 4), np.nan)
    boxes[start] = gt[start]
    for k in range(start + 1, len(frames)):
        boxes[k] = t.update(frames[k]).box
    return boxes


def rmse43(runs: list[np.ndarray], gt: np.ndarray) -> tuple[float, float]:
    """Eq. (43): per frame sqrt(mean over runs of the squared upper-left-corner error); mean and std over frames."""
    ok = np.all(np.isfinite(gt), axis=1)
    err2 = np.stack([np.sum((b[:, :2] - gt[:, :2]) ** 2, axis=1) for b in runs])[:, ok]
    per_frame = np.sqrt(np.nanmean(err2, axis=0))
    return float(per_frame.mean()), float(per_frame.std())


def table5(sequences: dict[str, tuple[list, np.ndarray]], seeds: int) -> list[str]:
    lines = ["| sequence | " + " | ".join(f"{c} mean" for c in CUES) + " | "
             + " | ".join(f"{c} std" for c in CUES) + " |",
             "|" + "---|" * (2 * len(CUES) + 1)]
    for name, (frames, gt) in sequences.items():
        means, stds = [], []
        for cue in CUES:
            runs = [run("ssim-pf", frames, gt, s, cue=cue, statistics="local", n_particles=100) for s in range(seeds)]
            m, sd = rmse43(runs, gt)
            means.append(m)
            stds.append(sd)
        best = int(np.argmin(means))
        cells = [f"**{v:.1f}**" if i == best else f"{v:.1f}" for i, v in enumerate(means)]
        lines.append(f"| {name} | " + " | ".join(cells) + " | " + " | ".join(f"{v:.1f}" for v in stds) + " |")
        print(lines[-1], flush=True)
    return lines


def fast_mover(seed: int, n_frames: int = 80, step: float = 50.0) -> SceneSpec:
    rng = np.random.default_rng([seed, 76])
    pts, x, y = [], 160.0, 120.0
    ang = rng.uniform(0, 2 * np.pi)
    for t in range(0, n_frames + 10, 10):
        pts.append((t, x, y))
        for _ in range(20):  # a turn that keeps the target inside
            a = ang + rng.uniform(-2.0, 2.0)
            nx, ny = x + step * np.cos(a), y + step * np.sin(a)
            if 30 < nx < 290 and 40 < ny < 200:
                break
        ang, x, y = a, nx, ny
    tgt = Target(path=tuple(pts), size=(30.0, 44.0), colors=((60, 90, 200), (200, 150, 60)), texture=30.0,
                 shape="rect")
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt,), kind="fast-mover")


def fig6(seeds: int, first: int = 100) -> list[str]:
    configs = {"ssim-pf, N = 20": ("ssim-pf", {"n_particles": 20}),
               "ssim-pf, N = 100": ("ssim-pf", {"n_particles": 100}),
               "hybrid-ssim-pf, N = 20, literal weights": ("hybrid-ssim-pf", {"n_particles": 20}),
               "hybrid-ssim-pf, N = 20, mixture sampling": ("hybrid-ssim-pf", {"n_particles": 20,
                                                                                "proposal": "mixture_sample"}),
               "dssim": ("dssim", {})}
    for name, p in configs.values():
        warm_up(name, p)
    res = {k: [[], [], 0.0, 0] for k in configs}
    for seed in range(seeds):
        scene = Scene(fast_mover(first + seed))
        frames, gt = scene.frames(), scene.groundtruth(0)
        for label, (name, p) in configs.items():
            t0 = time.perf_counter()
            boxes = run(name, frames, gt, seed, position_noise=3.0, **p) if name != "dssim" else run(name, frames, gt,
                                                                                                      seed)
            res[label][2] += time.perf_counter() - t0
            res[label][3] += len(frames) - 1
            err = center_error(boxes, gt)
            res[label][0].append(bool(np.max(err) > 20))
            res[label][1].append(float(np.mean(err)))
    lines = ["| tracker | runs lost (centre error > 20 px in some frame) | mean centre error (px) | ms per frame |",
             "|---|---|---|---|"]
    for label, (lost, errs, sec, n) in res.items():
        lines.append(f"| {label} | {sum(lost)} / {len(lost)} | {np.mean(errs):.1f} | {1e3 * sec / n:.2f} |")
        print(lines[-1], flush=True)
    return lines


def batch_speed() -> list[str]:
    rng = np.random.default_rng(0)
    patches = rng.uniform(0, 255, (100, 64, 64)).astype(np.float32)
    tmpl = rng.uniform(0, 255, (64, 64))
    S.ssim_batch(patches, tmpl)

    def timeit(f, n):
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        return (time.perf_counter() - t0) / n * 1e3

    tb = timeit(lambda: S.ssim_batch(patches, tmpl), 20)
    tr = timeit(lambda: [S.ssim_reference(p, tmpl) for p in patches], 3)
    lines = ["| 100 patches of 64x64 | ms per frame | ratio |", "|---|---|---|",
             f"| `ssim_batch` (one call) | {tb:.2f} | 1 |",
             f"| loop of the reference formula (`ssim_reference`, OpenCV filters) | {tr:.2f} | {tr / tb:.1f}x |"]
    if hasattr(cv2, "quality"):  # OpenCV-contrib's SSIM (reflect-101 borders, no crop), one pair per call
        p64 = patches.astype(np.float64)
        tq = timeit(lambda: [cv2.quality.QualitySSIM_compute(p, tmpl)[0][0] for p in p64], 3)
        lines.append(f"| loop of OpenCV-contrib's `quality.QualitySSIM_compute` | {tq:.2f} | {tq / tb:.1f}x |")
    try:
        from skimage.metrics import structural_similarity as sk

        ts = timeit(lambda: [sk(p, tmpl, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                data_range=255) for p in patches.astype(np.float64)], 3)
        lines.append(f"| loop of scikit-image's `structural_similarity` | {ts:.2f} | {ts / tb:.1f}x |")
    except ImportError:
        lines.append("| scikit-image not installed | – | – |")
    for ln in lines:
        print(ln, flush=True)
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--out", default=None, help="write the tables (Markdown) here")
    ap.add_argument("--first", type=int, default=100, help="first seed of the synthetic scenes (100: the report's; "
                                                         "e.g. 300 for a fresh draw of neither split)")
    ap.add_argument("--real", default="otb_crossing,otb_couple,tld_pedestrian2,davis16_car-shadow",
                    help="real sequences for the cue comparison")
    args = ap.parse_args()
    for cue in CUES:
        warm_up("ssim-pf", {"cue": cue, "statistics": "local"})
    seqs = {}
    for k in range(3):
        scene = Scene(camouflage_scene(args.first + k, n_frames=120))
        seqs[f"camouflage-{args.first + k}"] = (scene.frames(), scene.groundtruth(0))
    data = Path(args.data)
    for name in [s for s in args.real.split(",") if s]:
        if (data / name).is_dir():
            seq = read_sequence(data / name)
            seqs[name] = ([read_image(p) for p in seq.frames], seq.groundtruth)
    out = ["## Table 5 analogue: cues in the same particle filter", "",
           f"RMSE (eq. 43, upper-left corner, px) over {args.seeds} seeds; mean and std over frames. "
           "Best mean in bold.",
           ""]
    out += table5(seqs, args.seeds)
    out += ["", "## Fig. 6 analogue: 20 particles, fast mover", ""] + fig6(args.seeds, args.first)
    out += ["", "## Batched SSIM cue", ""] + batch_speed()
    if args.out:
        Path(args.out).write_text("\n".join(out) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
