"""Per-sequence timelines of the HTML report: each tracker's overlap with the ground truth frame by frame, with the
frames where its lost flag is up and the frames where the target is absent, so that the flag can be read as the
detector it is meant to be (up on the shaded frames, down where the overlap is high)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .jobs import ONE_PASS
from .metrics import per_frame_iou

__all__ = ["timelines"]


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of True in a bool array (stop exclusive)."""
    f = np.concatenate([[False], np.asarray(flags, dtype=bool), [False]])
    edges = np.flatnonzero(np.diff(f.astype(np.int8)))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def timelines(records: list[dict], sequences: dict, out: Path) -> dict[str, str]:
    """One figure per one-pass sequence with ground truth (``timelines/NAME.png`` under ``out``): for each tracker's
    run of the lowest seed, its IoU per frame, and beneath it a strip marking the frames with ``lost`` raised;
    the frames where the target is absent (no ground-truth box, or hidden) are shaded.  Returns name -> file."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    from ..io.datasets import Sequence, read_sequence

    runs = [r for r in records if r.get("protocol") in ONE_PASS and r.get("boxes") and r.get("lost")]
    trackers = list(dict.fromkeys(r["tracker"] for r in runs))
    made: dict[str, str] = {}
    if not runs:
        return made
    (out / "timelines").mkdir(exist_ok=True)
    for name, path in sequences.items():
        mine = {}
        for t in trackers:
            recs = [r for r in runs if r["tracker"] == t and r["sequence"] == name]
            if recs:
                mine[t] = min(recs, key=lambda r: r["seed"])
        if not mine:
            continue
        seq = path if isinstance(path, Sequence) else read_sequence(path)
        if seq.groundtruth is None:
            continue
        gt = seq.groundtruth
        n = len(gt)
        absent = seq.absent if seq.absent is not None else ~np.all(np.isfinite(gt), axis=1)
        fig, (ax, strip) = plt.subplots(2, 1, figsize=(9, 2.2 + 0.25 * len(mine)), dpi=90, sharex=True,
                                        gridspec_kw={"height_ratios": [3, max(1, len(mine)) * 0.45]})
        for a, b in _runs(absent[:n]):
            for axis in (ax, strip):
                axis.axvspan(a + 0.5, b + 0.5, color="0.85", lw=0)
        for k, (t, rec) in enumerate(mine.items()):
            boxes = np.array([np.nan if v is None else v for v in rec["boxes"]], dtype=np.float64).reshape(-1, 4)[:n]
            overlap = per_frame_iou(boxes, gt)
            colour = f"C{k}"
            ax.plot(np.arange(1, len(overlap) + 1), overlap, lw=1, color=colour, label=t)
            lost = np.asarray(rec["lost"], dtype=bool)[:n]
            for a, b in _runs(lost):
                strip.broken_barh([(a + 0.5, b - a)], (k + 0.1, 0.8), color=colour)
        ax.set_ylim(0, 1)
        ax.set_ylabel("IoU")
        ax.set_title(f"{name}: overlap, lost flag (bars), target absent (shaded)", fontsize=9)
        ax.legend(fontsize=7, loc="lower left", ncol=min(4, len(mine)))
        ax.grid(alpha=0.3)
        strip.set_yticks([k + 0.5 for k in range(len(mine))])
        strip.set_yticklabels(list(mine), fontsize=7)
        strip.set_ylim(0, len(mine))
        strip.set_xlim(0.5, n + 0.5)
        strip.set_xlabel("frame")
        fig.tight_layout()
        safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).lstrip(".") or "sequence"
        fn = f"timelines/{safe}.png"
        fig.savefig(out / fn)
        plt.close(fig)
        made[name] = fn
    return made
