"""Single-object sequences from a multi-object (MOTChallenge) one: one per identity, absences included.

A MOT annotation tells where every person is on every frame, and that a person has left (their track
ends). Cut into one single-object sequence per identity, running from the person's first annotated frame
to the end of a frame range, it measures a single-object tracker on small people among similar ones, and
its lost flag on real absences: the frames after the person has left have no box (``NaN``), as in TLD
files. ``scripts/make_mot_sot.py`` writes them in the OTB layout for ``pftrack eval``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .datasets import Sequence

__all__ = ["PersonSequence", "person_sequences", "write_otb"]


@dataclass(frozen=True)
class PersonSequence:
    """One identity: ``frames`` are 1-based frame numbers of the source, ``boxes`` ``(len(frames), 4)`` with
    ``NaN`` rows where the identity is not annotated."""

    identity: int
    frames: np.ndarray
    boxes: np.ndarray

    @property
    def absent(self) -> int:
        return int(np.count_nonzero(~np.isfinite(self.boxes).all(axis=1)))


def person_sequences(mot_gt: np.ndarray, first: int, last: int, *, min_frames: int = 30) -> list[PersonSequence]:
    """Every identity with at least ``min_frames`` annotated frames in ``first..last`` (1-based, inclusive),
    from its first annotated frame there to ``last``, in identity order."""
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
        out.append(PersonSequence(int(pid), frames, boxes))
    return out


def write_otb(seq: Sequence, person: PersonSequence, dest: str | Path, *, credit: str = "") -> Path:
    """Write ``person`` of ``seq`` as an OTB folder: ``img/0001...`` as relative symbolic links to the source
    frames, ``groundtruth_rect.txt`` (``NaN,NaN,NaN,NaN`` for absent frames), and ``ATTRIBUTION.md``."""
    dest = Path(dest)
    (dest / "img").mkdir(parents=True, exist_ok=True)
    for k, number in enumerate(person.frames):
        src = Path(seq.frames[int(number) - 1]).resolve()
        link = dest / "img" / f"{k + 1:04d}{src.suffix}"
        if link.is_symlink() or link.exists():
            link.unlink()
        os.symlink(os.path.relpath(src, link.parent), link)
    lines = ["NaN,NaN,NaN,NaN" if not np.isfinite(b).all() else ",".join(f"{v:.2f}" for v in b) for b in person.boxes]
    (dest / "groundtruth_rect.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
    (dest / "ATTRIBUTION.md").write_text(
        f"Identity {person.identity} of {seq.name}, source frames {int(person.frames[0])}-{int(person.frames[-1])} "
        f"(frame k of this folder is source frame {int(person.frames[0])} + k - 1). {credit}\n".rstrip() + "\n",
        encoding="utf-8")
    return dest
