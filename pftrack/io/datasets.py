"""Readers for the standard sequence layouts: OTB, VOT, MOTChallenge and plain frame folders.

Every reader returns a :class:`Sequence`: the ordered frame files plus whatever
ground truth the layout provides.  Files are read as data (numbers, INI, JSON),
never executed.  Malformed files raise :class:`~pftrack.errors.FormatError`
with a one-line message naming the file and line.

Layouts
-------
* **OTB**: ``img/`` + ``groundtruth_rect.txt`` (``x,y,w,h`` per row; commas, tabs or
  spaces; ``NaN`` rows = target not visible; may have fewer rows than images),
  optional ``cfg.json`` (``startFrame``/``endFrame``/``imgFormat``) and ``attrs.txt``.  Temple Color 128's
  folders are read the same way: ``img/`` + ``FOLDER_gt.txt``, the stretch in ``FOLDER_frames.txt``.  Without
  ``cfg.json``, the five OTB-100 sequences whose annotated stretch is not their whole image folder (David from
  frame 300; Football1, Freeman3, Freeman4 and Diving up to a frame) are cut to that stretch, as the benchmark's
  own configuration and its common loaders do (:data:`OTB_FRAME_RANGES`), when the ground truth has exactly
  that stretch's rows.
* **VOT**: frames (in the folder itself or in ``color/``) + ``groundtruth.txt`` with
  4-value boxes or 8-value polygons (converted to their axis-aligned boxes).  The same reader takes LaSOT
  (frames in ``img/``; ``full_occlusion.txt`` and ``out_of_view.txt`` mark absent frames) and GOT-10k
  (``absence.label``).
* **MOTChallenge**: ``img1/``, ``seqinfo.ini`` and, when present, ``gt/gt.txt``
  (``frame,id,x,y,w,h,conf,class,visibility``).
* **video**: a folder holding one video file and no images, with ``groundtruth_rect.txt`` (OTB rows) or
  ``groundtruth.txt`` (VOT rows) beside it, like the bundled clip; its frames are :class:`VideoFrame` s.
* **frames**: any folder of images, sorted by name.
"""

from __future__ import annotations

import configparser
import re
from pathlib import Path

import numpy as np

from ..errors import FormatError, SourceError
from .layout_writers import write_groundtruth, write_mot_groundtruth, write_seqinfo  # noqa: F401 - re-exported
from .sequence import (IMAGE_EXTENSIONS, Sequence, _absent_rows, _natural_key, _pad_gt,  # noqa: F401 - re-exported
                       _vot_rows, _warn_rows, list_images, read_json_object, read_meta, read_number_rows)
from .video_frames import VIDEO_EXTENSIONS, _video_groundtruth, read_video_folder, single_video  # noqa: F401

# ------------------------------------------------------------------------------ detection

def detect_layout(path: Path) -> str | None:
    """``"otb"``, ``"vot"``, ``"mot"``, ``"video"``, ``"frames"`` or None for a folder."""
    if not path.is_dir():
        return None
    if (path / "img1").is_dir() and ((path / "seqinfo.ini").is_file() or (path / "gt").is_dir()):
        return "mot"
    if (path / "img").is_dir() and (any(path.glob("groundtruth_rect*.txt")) or _tc128_gt(path) is not None):
        return "otb"
    if single_video(path) is not None:
        return "video"
    if (path / "groundtruth.txt").is_file():
        return "vot"
    if (path / "img").is_dir() and list_images(path / "img"):
        return "frames"
    if list_images(path):
        return "frames"
    return None


def read_sequence(path: str | Path) -> Sequence:
    """Read one sequence folder of any supported layout."""
    path = Path(path)
    if not path.exists():
        raise SourceError(f"{path}: no such file or folder")
    layout = detect_layout(path)
    if layout == "otb":
        return read_otb(path)
    if layout == "vot":
        return read_vot(path)
    if layout == "mot":
        return read_mot(path)
    if layout == "video":
        return read_video_folder(path)
    if layout == "frames":
        folder = path / "img" if (path / "img").is_dir() and list_images(path / "img") else path
        return Sequence(path.name, "frames", path, list_images(folder))
    raise SourceError(f"{path}: not a sequence folder (no images, no single video, no OTB, VOT or MOTChallenge layout)")


def discover_sequences(path: str | Path) -> list[Sequence]:
    """A sequence folder gives itself; a dataset folder gives its sequence subfolders (sorted), or, when none of
    them is one, the sequence folders one level further (a dataset grouped in folders: LaSOT's categories,
    ``pftrack synth``'s kinds)."""
    path = Path(path)
    if not path.exists():
        raise SourceError(f"{path}: no such file or folder")
    if not path.is_dir():
        raise SourceError(f"{path}: not a folder")
    if _annotated(path):
        return _targets_of(path)
    subs = sorted((p for p in path.iterdir() if p.is_dir()), key=_natural_key)
    seqs = [s for p in subs if _annotated(p) for s in _targets_of(p)]
    if not seqs:  # grouped: the subfolders' own subfolders
        seqs = [s for p in subs for q in sorted((q for q in p.iterdir() if q.is_dir()), key=_natural_key)
                if _annotated(q) for s in _targets_of(q)]
    if not seqs:
        raise SourceError(f"{path}: no OTB, VOT or MOTChallenge sequences or annotated videos found")
    return seqs


def _annotated(path: Path) -> bool:
    """Is ``path`` a sequence folder with ground truth (an OTB, VOT or MOTChallenge folder, or a video with its
    ground-truth file)?"""
    layout = detect_layout(path)
    return layout in ("otb", "vot", "mot") or (layout == "video" and _video_groundtruth(path) is not None)


def _targets_of(path: Path) -> list[Sequence]:
    """The sequences of one folder: one per annotated target of an OTB folder with several, else the one."""
    targets = otb_targets(path) if detect_layout(path) == "otb" else []
    if len(targets) > 1:
        return [read_otb(path, target=t) for t in targets]
    return [read_sequence(path)]


# ------------------------------------------------------------------------------ OTB

#: The OTB-100 sequences whose ground truth covers only part of ``img/``: first and last frame numbers (from 1) of
#: the annotated stretch, from the benchmark's sequence configuration (the tracker benchmark's ``configSeqs``; the
#: same cuts as got10k's OTB loader).  Keys are lower-case folder names (an ``otb_`` or ``otb-`` prefix is ignored).
OTB_FRAME_RANGES: dict[str, tuple[int, int]] = {
    "david": (300, 770), "football1": (1, 74), "freeman3": (1, 460), "freeman4": (1, 283), "diving": (1, 215)}


def _otb_range(name: str, n_files: int, n_rows: int) -> tuple[int, int] | None:
    """The annotated stretch of a known OTB sequence folder, when its images extend past it and its ground truth
    has exactly the stretch's rows (a folder already cut to the stretch, or another sequence of that name, is left
    as it is)."""
    key = re.sub(r"^otb[_-]", "", name.lower())
    rng = OTB_FRAME_RANGES.get(key)
    if rng is None:
        return None
    start, end = rng
    if n_rows == end - start + 1 and n_files >= end and n_files != n_rows:
        return rng
    return None


def _tc128_gt(path: Path) -> Path | None:
    """Temple Color 128's ground truth, ``FOLDER_gt.txt`` beside ``img/`` (None when absent)."""
    gt = path / f"{path.name}_gt.txt"
    return gt if gt.is_file() else None


def _tc128_frames(path: Path, files: list[Path]) -> list[Path]:
    """The images of the stretch ``FOLDER_frames.txt`` names (``start,end``, frame numbers of the images' names),
    as Temple Color 128 gives it; all the images without that file, or when it names images that are not there."""
    spec = path / f"{path.name}_frames.txt"
    if not spec.is_file():
        return files
    nums = [int(t) for t in re.findall(r"\d+", spec.read_text(encoding="utf-8", errors="replace"))[:2]]
    if len(nums) < 2 or nums[1] < nums[0]:
        raise FormatError(f"{spec}: expected the first and last frame numbers, 'start,end'")
    by_number = {int(m.group()): f for f in files if (m := re.search(r"\d+", f.stem))}
    chosen = [by_number.get(i) for i in range(nums[0], nums[1] + 1)]
    return files if any(c is None for c in chosen) else chosen


_TARGET_FILE = re.compile(r"groundtruth_rect\.(\d+)\.txt$")


def otb_targets(path: str | Path) -> list[int]:
    """The numbers ``N`` of an OTB folder's ``groundtruth_rect.N.txt`` files, ascending (OTB-100's Jogging and
    Skating2 annotate two people; empty for a folder with one ``groundtruth_rect.txt``)."""
    found = (_TARGET_FILE.match(p.name) for p in Path(path).glob("groundtruth_rect.*.txt"))
    return sorted(int(m.group(1)) for m in found if m)


def read_otb(path: str | Path, *, target: int | None = None) -> Sequence:
    """An OTB folder; ``target``: the ``N`` of its ``groundtruth_rect.N.txt`` (the sequence is then named
    ``FOLDER.N``, as the benchmark names Jogging's two people); without it, its first ground-truth file."""
    path = Path(path)
    img_dir = path / "img"
    files = list_images(img_dir) if img_dir.is_dir() else []
    if not files:
        raise SourceError(f"{img_dir}: no images")
    if target is not None:
        gt_files = [path / f"groundtruth_rect.{int(target)}.txt"]
        if not gt_files[0].is_file():
            raise FormatError(f"{path}: missing {gt_files[0].name}")
    else:
        gt_files = sorted(path.glob("groundtruth_rect*.txt"))
        if not gt_files and (tc := _tc128_gt(path)) is not None:  # Temple Color 128: FOLDER_gt.txt, FOLDER_frames.txt
            gt_files = [tc]
            files = _tc128_frames(path, files)
    if not gt_files:
        raise FormatError(f"{path}: missing groundtruth_rect.txt")
    rows = read_number_rows(gt_files[0], widths=(4,))
    boxes = np.array(rows, dtype=np.float64).reshape(-1, 4)
    attributes: list[str] = []
    cfg_path = path / "cfg.json"
    if cfg_path.is_file():
        cfg = read_json_object(cfg_path)
        start, end, fmt = cfg.get("startFrame"), cfg.get("endFrame"), cfg.get("imgFormat")
        if isinstance(start, int) and isinstance(end, int) and isinstance(fmt, str) and end >= start:
            try:
                chosen = [img_dir / fmt.format(i) for i in range(start, end + 1)]
            except (IndexError, KeyError, ValueError):
                chosen = []
            if chosen and all(p.is_file() for p in chosen):
                files = chosen
        attrs = cfg.get("attributes")
        if isinstance(attrs, list):
            attributes = [str(a) for a in attrs]
    elif (rng := _otb_range(path.name, len(files), boxes.shape[0])) is not None:
        files = files[rng[0] - 1:rng[1]]
    _warn_rows(path.name, boxes.shape[0], len(files), "images")
    attrs_txt = path / "attrs.txt"
    if not attributes and attrs_txt.is_file():
        text = attrs_txt.read_text(encoding="utf-8", errors="replace")
        attributes = [a.strip() for a in text.split(",") if a.strip()]
    meta = read_meta(path)
    absent = _absent_rows(boxes, len(files), meta, path)
    name = path.name if target is None else f"{path.name}.{int(target)}"
    return Sequence(name, "otb", path, files, groundtruth=_pad_gt(boxes, len(files)), attributes=attributes,
                    absent=absent, meta=meta, target=None if target is None else int(target))


# ------------------------------------------------------------------------------ VOT

def _flag_file(path: Path) -> np.ndarray:
    """0/1 flags per frame, separated by commas or white space (LaSOT writes one line, GOT-10k one per line)."""
    text = path.read_text(encoding="utf-8", errors="replace")
    tokens = [t for t in re.split(r"[,\s]+", text) if t]
    if not all(t in ("0", "1") for t in tokens):
        raise FormatError(f"{path}: expected 0/1 flags, one per frame")
    return np.array([t == "1" for t in tokens], dtype=bool)


def _absent_flags(path: Path, n: int) -> np.ndarray | None:
    """Frames where the target is absent, from LaSOT's ``full_occlusion.txt`` and ``out_of_view.txt`` or GOT-10k's
    ``absence.label`` beside the ground truth (None without them)."""
    names = [f for f in ("full_occlusion.txt", "out_of_view.txt", "absence.label") if (path / f).is_file()]
    if not names:
        return None
    absent = np.zeros(n, dtype=bool)
    for f in names:
        flags = _flag_file(path / f)[:n]
        absent[: flags.size] |= flags
    return absent


def read_vot(path: str | Path) -> Sequence:
    """A VOT folder (frames in it or in ``color/``), and the same layout with frames in ``img/`` (LaSOT) or beside
    GOT-10k's ``absence.label``."""
    path = Path(path)
    folder = path
    for sub in ("color", "img"):
        if (path / sub).is_dir() and list_images(path / sub):
            folder = path / sub
            break
    files = list_images(folder)
    if not files:
        raise SourceError(f"{folder}: no images")
    boxes, polys = _vot_rows(path / "groundtruth.txt")
    return Sequence(path.name, "vot", path, files, groundtruth=_pad_gt(boxes, len(files)), polygons=polys,
                    absent=_absent_flags(path, len(files)))


# ------------------------------------------------------------------------------ MOTChallenge

def read_seqinfo(path: Path) -> dict[str, str]:
    cp = configparser.ConfigParser(interpolation=None)
    try:
        with open(path, encoding="utf-8") as fh:
            cp.read_file(fh)
    except (configparser.Error, UnicodeDecodeError) as exc:
        raise FormatError(f"{path}: malformed seqinfo.ini ({str(exc).splitlines()[0]})") from None
    if not cp.has_section("Sequence"):
        raise FormatError(f"{path}: missing [Sequence] section")
    return {k: v for k, v in cp.items("Sequence")}


def read_mot_txt(path: str | Path) -> np.ndarray:
    """MOTChallenge rows ``frame,id,x,y,w,h,conf[,class,visibility[,z]]`` as a float array."""
    path = Path(path)
    rows = read_number_rows(path, widths=(6, 7, 8, 9, 10))
    if not rows:
        return np.zeros((0, 10))
    out = np.full((len(rows), 10), -1.0)
    for i, r in enumerate(rows):
        out[i, : len(r)] = r
        if len(r) == 6:
            out[i, 6] = 1.0
    bad = (out[:, 0] < 1) | (out[:, 4] <= 0) | (out[:, 5] <= 0) | ~np.isfinite(out[:, :6]).all(axis=1)
    if bad.any():
        line = int(np.argmax(bad)) + 1
        raise FormatError(f"{path}: row {line}: frame must be >= 1 and the box size positive")
    return out


def read_mot(path: str | Path) -> Sequence:
    path = Path(path)
    info: dict[str, str] = {}
    ini = path / "seqinfo.ini"
    if ini.is_file():
        info = read_seqinfo(ini)
    img_dir = path / info.get("imdir", "img1")
    files = list_images(img_dir) if img_dir.is_dir() else []
    if not files:
        raise SourceError(f"{img_dir}: no images")
    seq_len = info.get("seqlength")
    if seq_len is not None:
        try:
            n = int(seq_len)
        except ValueError:
            raise FormatError(f"{ini}: seqLength must be an integer, got {seq_len!r}") from None
        files = files[:n]
    fps = size = None
    try:
        if "framerate" in info:
            fps = float(info["framerate"])
        if "imwidth" in info and "imheight" in info:
            size = (int(info["imwidth"]), int(info["imheight"]))
    except ValueError:
        raise FormatError(f"{ini}: frameRate, imWidth and imHeight must be numbers") from None
    gt = None
    gt_path = path / "gt" / "gt.txt"
    if gt_path.is_file():
        gt = read_mot_txt(gt_path)
    return Sequence(info.get("name", path.name), "mot", path, files, mot_gt=gt, fps=fps, size=size)


def mot_target(seq: Sequence, identity: int) -> Sequence:
    """One ground-truth track of a MOTChallenge sequence as a single-object sequence over all its frames: the
    track's boxes, ``NaN`` on the frames without one (before it starts, after it ends, where it is broken), named
    ``NAME.ID``.  Its :attr:`~Sequence.init_box` is the track's first box, on frame :attr:`~Sequence.init_index`.
    Raises :class:`~pftrack.errors.SourceError` (one line) without ``gt/gt.txt`` or without that track."""
    gt = seq.mot_gt
    if gt is None or not len(gt):
        raise SourceError(f"{seq.path}: no ground truth (gt/gt.txt) to take track {identity} from")
    n = len(seq.frames)
    rows = gt[(gt[:, 1] == identity) & (gt[:, 0] >= 1) & (gt[:, 0] <= n)]
    if not len(rows):
        raise SourceError(f"{seq.path}: no ground-truth track {identity} on its {n} frames "
                          f"({track_ids_text(gt)})")
    boxes = np.full((n, 4), np.nan)
    boxes[rows[:, 0].astype(int) - 1] = rows[:, 2:6]
    return Sequence(f"{seq.name}.{int(identity)}", "mot", seq.path, seq.frames, groundtruth=boxes, fps=seq.fps,
                    size=seq.size, target=int(identity))


def track_ids_text(mot_gt: np.ndarray) -> str:
    """The track ids of MOTChallenge ground-truth rows, for a message: ``3 tracks: ids 1, 2, 7`` (a range when
    there are more than 12)."""
    ids = np.unique(np.asarray(mot_gt)[:, 1]).astype(int)
    listed = ", ".join(str(i) for i in ids) if ids.size <= 12 else f"{ids.min()} to {ids.max()}"
    return f"{ids.size} track{'s' if ids.size != 1 else ''}: id{'s' if ids.size != 1 else ''} {listed}"
