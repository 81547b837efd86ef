"""Where a tracker's estimate is on the absent frames of the PETS views on which its lost flag is down.

    python scripts/views_flag_trace.py reports/views_report [MORE_VIEWS ...] --pets ../shared/data/pets09_s2l1_dev \
        --trackers fusion-pf,color-pf --seeds 0,1

The views (``scripts/make_pets_views.py``) are single-person sequences cut from PETS 2009 S2.L1 through four
fixed windows. On a frame where the person is out of the window (absent), the flag should be up. Each absent
frame with the flag down is put in the first class that applies:

* ``walker, never up`` / ``walker, taken again``: the estimate overlaps (IoU >= 0.3) the box of another annotated
  person, clipped to the window; the flag has not been up since the person's last present frame (the estimate
  was on the other walker before the exit, or moved to them without a loss) / it was up, and the search has since
  taken that walker;
* ``sliver``: less than 60 % of the estimate's box lies inside the window;
* ``never up``: the flag has not been up since the person's last present frame;
* ``taken again``: the flag was up after the exit, and the search has since acquired something unannotated.

It also counts the acquisitions made while the person is absent (the flag going down), by whether the search was
confined to an exit strip (``reenter_border``: the loss taken for an exit) on the frame before, and how many of
them took another annotated walker: one who entered the window within the ``ENTERED`` frames before (less than half
inside it then, or not yet annotated) or one who stayed in it. Last, it sums per person the absent frames and those
with the flag up.

Diagnosis only: it chooses nothing. Each view folder's ``img/`` links to its window's frames, named by the PETS
frame number, which maps the view's frames onto the PETS annotation.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

import cv2
import numpy as np

from pftrack.eval.runner import parse_tracker_list
from pftrack.geometry import in_frame_fraction, iou
from pftrack.io.datasets import read_sequence
from pftrack.trackers import create_tracker

sys.path.insert(0, str(Path(__file__).parent))
from make_pets_views import windows  # noqa: E402

CLASSES = ("walker, never up", "walker, taken again", "sliver", "never up", "taken again")
ENTERED = 20  # an acquired walker less than half inside the window this many frames before had just entered it


def view_window(folder: Path, width: int, height: int) -> tuple[int, int, int, int]:
    """The window ``x0, y0, w, h`` of a view, from its folder name (``..._right_f..``, ``..._right40_f..``: the
    share of :func:`make_pets_views.windows`, 55 % when not named)."""
    side, share = re.search(r"_(left|right|top|bottom)(\d*)_f", folder.name).groups()
    return windows(width, height, int(share) / 100 if share else 0.55)[side]


def pets_frame(path: Path) -> int:
    """The PETS frame number a view's image links to (its file name)."""
    return int(re.findall(r"(\d+)", Path(os.readlink(path)).stem)[-1])


def view_walkers(folder: Path, seq, gt: np.ndarray, width: int, height: int) -> tuple[int, tuple, dict]:
    """A view's person id, its window ``x0, y0, w, h`` and, per view frame, the other annotated walkers (rows
    ``id, x, y, w, h`` in frame coordinates) from the PETS annotation ``gt``."""
    pid = int(folder.name.rsplit("_id", 1)[1])
    numbers = [pets_frame(p) for p in seq.frames]
    others = {t: gt[(gt[:, 0] == n) & (gt[:, 1] != pid), 1:6] for t, n in enumerate(numbers)}
    return pid, view_window(folder, width, height), others


def walker_on(box, others_t, window) -> int | None:
    """The id of the walker whose box, clipped to the window, ``box`` (window coordinates) overlaps most, with IoU
    >= 0.3; None if none does. ``others_t`` holds rows ``id, x, y, w, h`` in frame coordinates."""
    x0, y0, ww, wh = window
    best, who = 0.3, None
    for pid, *g in others_t:
        gx, gy = max(g[0], x0), max(g[1], y0)
        gw, gh = min(g[0] + g[2], x0 + ww) - gx, min(g[1] + g[3], y0 + wh) - gy
        if gw > 0 and gh > 0 and (v := iou(box, (gx - x0, gy - y0, gw, gh))) >= best:
            best, who = v, int(pid)
    return who


def on_walker(box, others_t, window) -> bool:
    """Does ``box`` (window coordinates) overlap (IoU >= 0.3) one of the walkers ``others_t`` (rows ``id, x, y, w,
    h``, frame coordinates), clipped to the window?"""
    return walker_on(box, others_t, window) is not None


def share_inside(others_t, pid: int, window) -> float:
    """The share of walker ``pid``'s box inside the window on one frame (0 when the walker has no box there)."""
    x0, y0, ww, wh = window
    for row in others_t:
        if int(row[0]) == pid:
            return in_frame_fraction((row[1] - x0, row[2] - y0, row[3], row[4]), ww, wh)
    return 0.0


def classify(seq, boxes, lost, others, window) -> dict[str, int]:
    """Counts of the absent frames with the flag down by class (see the module's docstring)."""
    ww, wh = window[2:]
    out = dict.fromkeys(CLASSES, 0)
    up_since_exit = False
    for t in range(1, len(boxes)):
        if not seq.absent[t]:
            up_since_exit = False
            continue
        up_since_exit |= bool(lost[t])
        if lost[t]:
            continue
        b = boxes[t]
        if on_walker(b, others.get(t, ()), window):
            out["walker, taken again" if up_since_exit else "walker, never up"] += 1
        elif in_frame_fraction(b, ww, wh) < 0.6:
            out["sliver"] += 1
        elif not up_since_exit:
            out["never up"] += 1
        else:
            out["taken again"] += 1
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("views", type=Path, nargs="+", help="folders of views (scripts/make_pets_views.py)")
    ap.add_argument("--pets", type=Path, default=Path("../shared/data/pets09_s2l1_dev"))
    ap.add_argument("--trackers", default="fusion-pf,color-pf")
    ap.add_argument("--seeds", default="0,1")
    args = ap.parse_args()
    pets = read_sequence(args.pets)
    gt = pets.mot_gt
    height, width = cv2.imread(str(pets.frames[0])).shape[:2]
    seeds = [int(s) for s in args.seeds.split(",")]
    for cfg in parse_tracker_list(args.trackers):  # variants as pftrack eval takes them: fusion-pf[key=value]
        name = cfg.label
        total = dict.fromkeys(CLASSES, 0)
        absent = up = 0
        # exit strip on the frame before -> [acquisitions, on a walker who had just entered, on one who stayed]
        acquired = {True: [0, 0, 0], False: [0, 0, 0]}
        per_person: dict[int, list[int]] = {}  # person -> [absent frames, flag up]
        # every view has its ground truth; only some have a meta.json (the frames left unscored)
        for folder in sorted(p for v in args.views for p in v.iterdir() if (p / "groundtruth_rect.txt").exists()):
            seq = read_sequence(folder)
            if seq.absent is None or not seq.absent[1:].any():
                continue
            pid, window, others = view_walkers(folder, seq, gt, width, height)
            frames = [cv2.imread(str(p)) for p in seq.frames]
            for seed in seeds:
                tr = create_tracker(cfg.name, seed=seed, params=cfg.param_dict)
                boxes, lost = [seq.init_box], [False]
                tr.init(frames[0], seq.init_box)
                for t, f in enumerate(frames[1:], start=1):
                    strip = getattr(tr, "_exit_strip", lambda: None)() is not None  # the colour PFs only
                    st = tr.update(f)
                    est = st.info.get("box_full", st.box)  # the whole estimate (st.box is its part in the frame)
                    boxes.append(est)
                    lost.append(bool(st.lost))
                    if lost[-2] and not st.lost and seq.absent[t]:
                        acquired[strip][0] += 1
                        if (who := walker_on(est, others.get(t, ()), window)) is not None:
                            before = share_inside(others.get(max(t - ENTERED, 0), ()), who, window)
                            acquired[strip][1 if before < 0.5 else 2] += 1
                counts = classify(seq, np.asarray(boxes, float), lost, others, window)
                n_abs = int(seq.absent[1:].sum())
                absent += n_abs
                up += n_abs - sum(counts.values())
                pp = per_person.setdefault(pid, [0, 0])
                pp[0] += n_abs
                pp[1] += n_abs - sum(counts.values())
                for k in CLASSES:
                    total[k] += counts[k]
                print(f"{name} {folder.name} seed {seed}: absent {n_abs}, flag up {n_abs - sum(counts.values())}, "
                      + ", ".join(f"{k} {v}" for k, v in counts.items()), flush=True)
        print(f"== {name}: {absent} absent frames, flag up on {up} ({up / max(absent, 1):.3f}); down: "
              + ", ".join(f"{k} {v}" for k, v in total.items()), flush=True)
        for strip, label in ((True, "with an exit strip"), (False, "without")):
            n, entered, stayed = acquired[strip]
            print(f"== {name}: acquisitions while absent, {label}: {n} ({entered} on a walker who entered the window "
                  f"within {ENTERED} frames before, {stayed} on one who stayed in it)", flush=True)
        print(f"== {name}: flag up per person: " + ", ".join(
            f"{pid} {u} of {a}" for pid, (a, u) in sorted(per_person.items())), flush=True)


if __name__ == "__main__":
    main()
