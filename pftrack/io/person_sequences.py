"""Single-object sequences from a multi-object (MOTChallenge) one: one per identity, absences included.

A MOT annotation tells where every person is on every frame, and that a person has left (their track
ends). Cut into one single-object sequence per identity, running from the person's first annotated frame
to the end of a frame range, it measures a single-object tracker on small people among similar ones, and
its lost flag on real absences: the frames after the person has left have no box (``NaN``), as in TLD
files. ``scripts/make_mot_sot.py`` writes them in the OTB layout for ``pftrack eval``.

A MOT track may end before the person has left the image: PETS 2009 S2.L1's annotation stops as a
walker reaches the border, with the whole box still inside. The frames in between show the person but have
no box. Given the frame size, :func:`person_sequences` marks them ``in_view``: the frames without a box on
which the last annotated box, moved on at the mean velocity of the last annotated frames (or the next run's
first box, moved back), would still have at least ``HIDDEN_BELOW`` (10 %) of its area inside the image, as
the synthetic scenes count a target as present. :func:`write_otb` lists them as ``unannotated`` in
``meta.json``: they count neither as absent nor as present for the lost flag.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..geometry import in_frame_fraction
from .datasets import Sequence, write_groundtruth

IN_VIEW_FRACTION = 0.1  # the synthetic scenes' HIDDEN_BELOW: a target with less of its area in view is absent
VELOCITY_FRAMES = 5  # the velocity of an extrapolated box: mean displacement over this many annotated frames

__all__ = ["PersonSequence", "people_of", "person_sequences", "write_otb"]


@dataclass(frozen=True)
class PersonSequence:
    """One identity: ``frames`` are 1-based frame numbers of the source, ``boxes`` ``(len(frames), 4)`` with
    ``NaN`` rows where the identity is not annotated."""

    identity: int
    frames: np.ndarray
    boxes: np.ndarray
    in_view: np.ndarray | None = None  # (len(frames),) bool: no box, but the person is still (partly) in the image

    @property
    def absent(self) -> int:
        """Frames without a box on which the person is out of view (all frames without a box when ``in_view`` is
        unknown)."""
        gone = ~np.isfinite(self.boxes).all(axis=1)
        if self.in_view is not None:
            gone &= ~self.in_view
        return int(np.count_nonzero(gone))


def in_view_frames(boxes: np.ndarray, width: float, height: float, *, fraction: float = IN_VIEW_FRACTION,
                   velocity_frames: int = VELOCITY_FRAMES) -> np.ndarray:
    """Bool per row of ``boxes`` (``NaN`` rows: no annotation): a row without a box on which the box of the
    annotated run before it, moved on at that run's mean velocity over its last ``velocity_frames`` frames, or
    the box of the run after it, moved back at that run's first velocity, keeps ``fraction`` of its area or more
    inside the ``width`` x ``height`` image."""
    boxes = np.asarray(boxes, dtype=np.float64)
    ok = np.isfinite(boxes).all(axis=1)
    out = np.zeros(len(boxes), dtype=bool)
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return out
    for t in np.flatnonzero(~ok):
        for annotated, step in ((idx[idx < t], -1), (idx[idx > t], 1)):  # the run before t, the run after it
            if annotated.size == 0:
                continue
            k = int(annotated[-1] if step < 0 else annotated[0])  # that run's box nearest to t
            near = idx[(idx <= k) & (idx >= k - velocity_frames)] if step < 0 else \
                idx[(idx >= k) & (idx <= k + velocity_frames)]
            v = (boxes[near[-1], :2] - boxes[near[0], :2]) / max(near[-1] - near[0], 1) if near.size > 1 else 0.0
            box = boxes[k].copy()
            box[:2] += v * (t - k)
            if in_frame_fraction(box, width, height) >= fraction:
                out[t] = True
                break
    return out


def person_sequences(mot_gt: np.ndarray, first: int, last: int, *, min_frames: int = 30,
                     frame_size: tuple[int, int] | None = None) -> list[PersonSequence]:
    """Every identity with at least ``min_frames`` annotated frames in ``first..last`` (1-based, inclusive),
    from its first annotated frame there to ``last``, in identity order.  With ``frame_size`` ``(width,
    height)``, the frames without a box on which the person is still in view are marked (:func:`in_view_frames`)."""
    gt = np.asarray(mot_gt, dtype=np.float64)
    if last < first:
        raise ValueError(f"empty frame range {first}-{last}")
    out = []
    for pid in np.unique(gt[:, 1]).astype(int) if len(gt) else []:
        rows = gt[(gt[:, 1] == pid) & (gt[:, 0] >= first) & (gt[:, 0] <= last)]
        if len(rows) < min_frames:
            continue
        start = int(rows[:, 0].min())
        frames = np.arange(start, last + 1)
        boxes = np.full((frames.size, 4), np.nan)
        boxes[rows[:, 0].astype(int) - start] = rows[:, 2:6]
        in_view = None if frame_size is None else in_view_frames(boxes, *frame_size)
        out.append(PersonSequence(int(pid), frames, boxes, in_view))
    return out


def people_of(seq: Sequence, *, min_frames: int = 30, identity: int | None = None) -> list[Sequence]:
    """The single-object sequences of a MOTChallenge sequence with ground truth, in memory: one per identity with at
    least ``min_frames`` annotated frames (only ``identity``'s when given), from its first annotated frame to the
    sequence's end, named ``NAME.ID`` (``Sequence.target`` = ID). The frames without a box are absent, but for those
    on which the person is still in view (:func:`in_view_frames`, from the sequence's frame size), listed as
    ``unannotated`` in ``meta`` and neither absent nor scored, as :func:`write_otb` writes them."""
    from ..errors import SourceError
    from .sequence import _absent_rows

    if seq.mot_gt is None or not len(seq.mot_gt):
        raise SourceError(f"{seq.path}: no ground truth (gt/gt.txt) to cut into people")
    size = seq.size
    if size is None:
        from .sources import read_image

        img = read_image(seq.frames[0])
        if img is None:
            raise SourceError(f"{seq.frames[0]}: cannot be decoded")
        size = (int(img.shape[1]), int(img.shape[0]))
    gt = seq.mot_gt if identity is None else seq.mot_gt[seq.mot_gt[:, 1] == identity]
    out = []
    for person in person_sequences(gt, 1, len(seq.frames), min_frames=min_frames, frame_size=size):
        first, last = int(person.frames[0]), int(person.frames[-1])
        meta: dict = {"kind": "mot-person"}
        if person.in_view is not None and person.in_view.any():
            meta["unannotated"] = [int(k) + 1 for k in np.flatnonzero(person.in_view)]
        frames = seq.frames[first - 1:last]
        out.append(Sequence(f"{seq.name}.{person.identity}", "mot", seq.path, frames, groundtruth=person.boxes,
                            fps=seq.fps, size=seq.size, absent=_absent_rows(person.boxes, len(frames), meta, seq.path),
                            meta=meta, target=person.identity))
    return out


def write_otb(seq: Sequence, person: PersonSequence, dest: str | Path, *, credit: str = "") -> Path:
    """Write ``person`` of ``seq`` as an OTB folder: ``img/0001...`` as relative symbolic links to the source
    frames, ``groundtruth_rect.txt`` (``NaN,NaN,NaN,NaN`` for frames without a box), ``meta.json`` listing the
    ``unannotated`` frames (numbers from 1: no box, but the person is in view) when there are any, and
    ``ATTRIBUTION.md``."""
    dest = Path(dest)
    (dest / "img").mkdir(parents=True, exist_ok=True)
    for k, number in enumerate(person.frames):
        src = Path(seq.frames[int(number) - 1]).resolve()
        link = dest / "img" / f"{k + 1:04d}{src.suffix}"
        if link.is_symlink() or link.exists():
            link.unlink()
        os.symlink(os.path.relpath(src, link.parent), link)
    write_groundtruth(dest / "groundtruth_rect.txt", person.boxes)
    meta = dest / "meta.json"
    if person.in_view is not None and person.in_view.any():
        unannotated = [int(k) + 1 for k in np.flatnonzero(person.in_view)]
        meta.write_text(json.dumps({"kind": "mot-person", "unannotated": unannotated}) + "\n", encoding="utf-8")
    elif meta.exists():
        meta.unlink()
    (dest / "ATTRIBUTION.md").write_text(
        f"Identity {person.identity} of {seq.name}, source frames {int(person.frames[0])}-{int(person.frames[-1])} "
        f"(frame k of this folder is source frame {int(person.frames[0])} + k - 1). {credit}\n".rstrip() + "\n",
        encoding="utf-8")
    return dest
