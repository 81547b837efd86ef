"""A sequence on disk (:class:`Sequence`) and the helpers every layout reader shares: image listing, rows of
numbers, ``meta.json``, absent frames.  Files are read as data, never executed; malformed files raise
:class:`~pftrack.errors.FormatError` with a one-line message naming the file and line."""

from __future__ import annotations

import json
import math
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FormatError, SourceError
from ..geometry import polygon_to_box

IMAGE_EXTENSIONS = {".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".ppm", ".pgm", ".pbm", ".jp2"}


@dataclass
class Sequence:
    """One sequence on disk with its ground truth."""

    name: str
    kind: str  # "otb" | "vot" | "mot" | "video" | "frames"
    path: Path
    frames: list  # image files (Path), or the frames of a folder's video (pftrack.io.video_frames.VideoFrame)
    groundtruth: np.ndarray | None = None  # (n_frames, 4) boxes, NaN = not visible (single object)
    polygons: np.ndarray | None = None  # VOT: (n_frames, k) raw rows when they were polygons
    mot_gt: np.ndarray | None = None  # MOT: (rows, >=6) frame,id,x,y,w,h,conf,...
    fps: float | None = None
    size: tuple[int, int] | None = None  # (width, height) when the layout states it
    attributes: list[str] = field(default_factory=list)
    #: (n_frames,) bool: frames where the target is out of view or fully hidden (ground truth rows of NaN
    #: in the file, or the ``hidden`` frames of a ``meta.json`` beside it); None when unknown
    absent: np.ndarray | None = None
    meta: dict = field(default_factory=dict)  # the parsed meta.json, when present
    #: OTB folders with several annotated targets (``groundtruth_rect.1.txt``, ``.2.txt``: Jogging, Skating2): which
    #: one this sequence is (its name is then ``FOLDER.N``); None for a folder's only or first target
    target: int | None = None

    def __len__(self) -> int:
        return len(self.frames)

    @property
    def init_box(self) -> tuple[float, float, float, float] | None:
        """The first valid ground-truth box (the standard initialisation)."""
        if self.groundtruth is None:
            return None
        gt = self.groundtruth
        ok = np.all(np.isfinite(gt), axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)
        if not ok.any():
            return None
        return tuple(float(v) for v in gt[int(np.argmax(ok))])

    @property
    def init_index(self) -> int:
        """Index of the frame whose ground truth gives :attr:`init_box` (0 normally)."""
        if self.groundtruth is None:
            return 0
        gt = self.groundtruth
        ok = np.all(np.isfinite(gt), axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)
        return int(np.argmax(ok)) if ok.any() else 0


def _natural_key(p: Path):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]


def list_images(folder: Path) -> list[Path]:
    """Image files of a folder, sorted by name (numbers in natural order)."""
    try:
        entries = list(folder.iterdir())
    except OSError as exc:
        raise SourceError(f"{folder}: cannot list folder ({exc.strerror or exc})") from None
    files = [p for p in entries if p.is_file() and p.suffix.lower() in IMAGE_EXTENSIONS]
    files.sort(key=_natural_key)
    return files


_SPLIT = re.compile(r"[,\t; ]+")


def read_number_rows(path: Path, *, widths: tuple[int, ...], allow_nan: bool = True) -> list[list[float]]:
    """Read rows of numbers separated by commas, tabs, semicolons or spaces.

    Each non-empty row must have one of ``widths`` values.  Raises FormatError
    with the file and line number otherwise.
    """
    try:
        text = path.read_text(encoding="utf-8", errors="strict")
    except UnicodeDecodeError:
        raise FormatError(f"{path}: not a text file") from None
    except OSError as exc:
        raise FormatError(f"{path}: cannot read ({exc.strerror or exc})") from None
    rows = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if not line:
            continue
        parts = [p for p in _SPLIT.split(line) if p]
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            raise FormatError(f"{path}:{lineno}: expected numbers, got {line[:60]!r}") from None
        if len(vals) not in widths:
            want = " or ".join(str(w) for w in widths)
            raise FormatError(f"{path}:{lineno}: expected {want} values, got {len(vals)}")
        if not allow_nan and not all(math.isfinite(v) for v in vals):
            raise FormatError(f"{path}:{lineno}: non-finite value")
        if any(math.isinf(v) for v in vals):
            raise FormatError(f"{path}:{lineno}: infinite value")
        rows.append(vals)
    return rows


def _pad_gt(boxes: np.ndarray, n: int) -> np.ndarray:
    out = np.full((n, 4), np.nan)
    m = min(n, boxes.shape[0])
    out[:m] = boxes[:m]
    return out


def _frame_numbers(meta: dict, key: str, path: Path) -> list[int]:
    """``meta[key]``, a list of frame numbers from 1 (empty when missing)."""
    numbers = meta.get(key, [])
    if not isinstance(numbers, list) or not all(isinstance(v, int) and not isinstance(v, bool) for v in numbers):
        raise FormatError(f"{path / 'meta.json'}: '{key}' must be a list of frame numbers (from 1)")
    return numbers


def read_json_object(path: Path) -> dict:
    """A JSON file holding one object; FormatError with the file's name otherwise."""
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise FormatError(f"{path}: invalid JSON ({exc})") from None
    if not isinstance(obj, dict):
        raise FormatError(f"{path}: expected a JSON object")
    return obj


def read_meta(path: Path) -> dict:
    """The optional ``meta.json`` of a sequence folder (synthetic scenes write one), or ``{}``."""
    meta_path = Path(path) / "meta.json"
    return read_json_object(meta_path) if meta_path.is_file() else {}


def _absent_rows(boxes: np.ndarray, n: int, meta: dict, path: Path) -> np.ndarray:
    """Absent frames of ``n``: the NaN rows of the ground truth (out of view, the TLD convention), its rows of no
    extent (a width or height of 0 or less, as ``0,0,0,0``, another way datasets write a frame without the target),
    and ``meta.json``'s ``hidden`` frames (fully occluded); its ``unannotated`` frames have no box but show the target
    (a MOT track cut short at the border), so they are neither absent nor scored."""
    absent = np.zeros(n, dtype=bool)
    m = min(n, boxes.shape[0])
    rows = boxes[:m]
    absent[:m] = ~(np.all(np.isfinite(rows), axis=1) & (rows[:, 2] > 0) & (rows[:, 3] > 0))  # eval's valid_gt, negated
    for key, value in (("hidden", True), ("unannotated", False)):
        for number in _frame_numbers(meta, key, path):
            if 1 <= number <= n:
                absent[number - 1] = value
    return absent


def _warn_rows(name: str, rows: int, frames: int, what: str) -> None:
    if rows != frames:  # a misaligned folder scores near zero; say so
        rest = f"the {what} past the rows are not scored" if rows < frames else "the extra rows are ignored"
        warnings.warn(f"{name}: {rows} ground-truth rows for {frames} {what}; row i is taken for "
                      f"{what[:-1]} i ({rest})", stacklevel=3)


def _vot_rows(gt_path: Path) -> tuple[np.ndarray, np.ndarray | None]:
    """A VOT ``groundtruth.txt``: the boxes (the axis-aligned boxes of polygons; NaN where a row is a single 0/NaN,
    VOT's missing annotation) and the raw polygon rows (None when every row is a box)."""
    rows = read_number_rows(gt_path, widths=(1, 4, 6, 8, 10, 12, 14, 16))
    width = max((len(r) for r in rows), default=4)
    boxes = np.full((len(rows), 4), np.nan)
    polys = None
    if width > 4:
        polys = np.full((len(rows), width), np.nan)
    for i, r in enumerate(rows):
        if len(r) == 1:
            continue
        if polys is not None:
            polys[i, : len(r)] = r
        boxes[i] = polygon_to_box(np.asarray(r, dtype=np.float64))
    return boxes, polys
