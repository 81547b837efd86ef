"""Would snapping a hand-drawn first box to the object help? GrabCut on a grown box, measured on OTB's SRE starts
(docs/results.md, "A first box drawn off the target").

A box is snapped by GrabCut (OpenCV, ``--iterations`` rounds) in a rectangle ``--grow`` times the box about its
centre: the snapped box bounds the foreground component that covers most of the given box, and the given box is kept
where GrabCut finds no foreground there or the snapped box overlaps it by less than ``--accept`` (IoU). For every
``--step``-th annotated frame of each sequence the script starts from the ground-truth box and from each of the 12
SRE perturbations (:data:`pftrack.eval.jobs.SRE_PERTURBATIONS`: 8 shifts of 10 %, scales 0.8, 0.9, 1.1, 1.2) and
prints, per kind of start, the mean IoU with the ground truth before and after the snap, and the shares of starts
it moved closer or further by more than 0.02.

    python scripts/first_box_grabcut.py reports/split/tune_real/* reports/split/tune_pets/* --step 25
"""

from __future__ import annotations

import argparse

import numpy as np

#: the kinds of start, as (name, indices into (truth,) + SRE_PERTURBATIONS)
KINDS = (("truth", (0,)), ("shift", tuple(range(1, 9))), ("scale 0.8", (9,)), ("scale 0.9", (10,)),
         ("scale 1.1", (11,)), ("scale 1.2", (12,)))


def box_iou(a, b) -> float:
    """IoU of two ``(x, y, w, h)`` boxes (:func:`pftrack.geometry.iou`)."""
    from pftrack.geometry import iou

    return float(iou(a, b))


def snap_box(image: np.ndarray, box, *, grow: float = 1.4, iterations: int = 3, accept: float = 0.5,
             seed: int = 0) -> tuple[float, float, float, float]:
    """``box`` (x, y, w, h) snapped to the object GrabCut finds in the rectangle ``grow`` times it (see the module
    docstring); the box itself where it finds none or the snap overlaps it by less than ``accept``."""
    import cv2

    box = tuple(float(v) for v in box)
    h, w = image.shape[:2]
    x, y, bw, bh = box
    cx, cy = x + bw / 2, y + bh / 2
    x0, y0 = int(max(cx - grow * bw / 2, 0)), int(max(cy - grow * bh / 2, 0))
    x1, y1 = int(min(cx + grow * bw / 2, w)), int(min(cy + grow * bh / 2, h))
    margin = int(max(bw, bh))  # GrabCut learns the background around the rectangle: a crop with that much of it
    X0, Y0, X1, Y1 = max(x0 - margin, 0), max(y0 - margin, 0), min(x1 + margin, w), min(y1 + margin, h)
    if x1 - x0 < 2 or y1 - y0 < 2 or (X0, Y0, X1, Y1) == (x0, y0, x1, y1):
        return box
    crop = np.ascontiguousarray(image[Y0:Y1, X0:X1])
    if crop.ndim == 2:
        crop = cv2.cvtColor(crop, cv2.COLOR_GRAY2BGR)
    mask = np.zeros(crop.shape[:2], np.uint8)
    bgd, fgd = np.zeros((1, 65)), np.zeros((1, 65))
    cv2.setRNGSeed(seed)
    cv2.grabCut(crop, mask, (x0 - X0, y0 - Y0, x1 - x0, y1 - y0), bgd, fgd, iterations, cv2.GC_INIT_WITH_RECT)
    fg = ((mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD)).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(fg)
    inner = labels[max(int(y) - Y0, 0):max(int(y + bh) - Y0, 0), max(int(x) - X0, 0):max(int(x + bw) - X0, 0)]
    counts = np.bincount(inner.ravel(), minlength=n)
    counts[0] = 0
    if n <= 1 or counts.max() == 0:
        return box
    sx, sy, sw, sh = (float(v) for v in stats[int(np.argmax(counts)), :4])
    snapped = (sx + X0, sy + Y0, sw, sh)
    return snapped if box_iou(snapped, box) >= accept else box


def probe(images_and_truths, **snap) -> dict[str, np.ndarray]:
    """Per kind of start (:data:`KINDS`): an array of (IoU before, IoU after) rows over the frames given as
    ``(image, ground-truth box)`` pairs."""
    from pftrack.eval.jobs import SRE_PERTURBATIONS, perturb

    rows = {name: [] for name, _ in KINDS}
    starts = ((0.0, 0.0, 1.0),) + SRE_PERTURBATIONS
    for image, truth in images_and_truths:
        h, w = image.shape[:2]
        for name, ks in KINDS:
            for k in ks:
                b = perturb(truth, starts[k], (w, h))
                rows[name].append((box_iou(b, truth), box_iou(snap_box(image, b, **snap), truth)))
    return {name: np.asarray(r, np.float64).reshape(-1, 2) for name, r in rows.items()}


def frames_of(paths, step: int):
    """``(image, ground-truth box)`` of every ``step``-th frame of each sequence whose box is at least 4 px a side."""
    import cv2

    from pftrack.io.datasets import read_sequence

    for path in paths:
        seq = read_sequence(path)
        for i in range(0, len(seq.frames), step):
            g = seq.groundtruth[i]
            if np.all(np.isfinite(g)) and g[2] >= 4 and g[3] >= 4:
                yield cv2.imread(str(seq.frames[i])), tuple(float(v) for v in g)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sequences", nargs="+")
    ap.add_argument("--step", type=int, default=25)
    ap.add_argument("--grow", type=float, default=1.4)
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--accept", type=float, default=0.5)
    a = ap.parse_args(argv)
    res = probe(frames_of(a.sequences, a.step), grow=a.grow, iterations=a.iterations, accept=a.accept)
    print(f"grow {a.grow}, {a.iterations} iterations, accept {a.accept}; {len(res['truth'])} frames")
    print(f"{'start':10s} {'IoU before':>10s} {'after':>6s} {'closer':>7s} {'further':>8s}")
    for name, r in res.items():
        print(f"{name:10s} {r[:, 0].mean():10.3f} {r[:, 1].mean():6.3f} {np.mean(r[:, 1] > r[:, 0] + 0.02):7.2f} "
              f"{np.mean(r[:, 1] < r[:, 0] - 0.02):8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
