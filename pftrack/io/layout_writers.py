"""Writers of the standard ground-truth files (OTB ``groundtruth_rect.txt``, MOTChallenge ``gt.txt`` and
``seqinfo.ini``), read back by :mod:`pftrack.io.datasets`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_groundtruth", "write_mot_groundtruth", "write_seqinfo"]


def write_groundtruth(path: str | Path, boxes, *, decimals: int = 2) -> Path:
    """An OTB ``groundtruth_rect.txt``: one ``x,y,w,h`` row per frame, ``NaN,NaN,NaN,NaN`` where a box is missing
    (read back by :func:`read_otb`)."""
    lines = ["NaN,NaN,NaN,NaN" if not np.all(np.isfinite(b)) else ",".join(f"{v:.{decimals}f}" for v in b)
             for b in np.asarray(boxes, dtype=np.float64).reshape(-1, 4)]
    path = Path(path)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def write_mot_groundtruth(path: str | Path, rows) -> Path:
    """A MOTChallenge ``gt.txt``: rows ``frame,id,x,y,w,h,...``, the box with 2 decimals and every other column an
    integer (read back by :func:`read_mot_txt`)."""
    lines = [",".join(f"{v:.2f}" if i in (2, 3, 4, 5) else f"{int(v)}" for i, v in enumerate(r))
             for r in np.asarray(rows, dtype=np.float64)]
    path = Path(path)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def write_seqinfo(folder: str | Path, *, name: str, fps: float, length: int, width: int, height: int,
                  ext: str = ".jpg") -> Path:
    """A MOTChallenge ``seqinfo.ini`` for the frames in ``folder/img1``."""
    path = Path(folder) / "seqinfo.ini"
    path.write_text(f"[Sequence]\nname={name}\nimDir=img1\nframeRate={fps:g}\nseqLength={length}\n"
                    f"imWidth={width}\nimHeight={height}\nimExt={ext}\n", encoding="utf-8")
    return path
