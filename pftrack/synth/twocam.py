"""Two cameras with disjoint views cut from one real sequence, for hand-over experiments (book ch. 11).

Camera A sees the left part of each frame, camera B the right part; the strip between
them is seen by neither (people vanish there).  Camera B's pixels go through a seeded,
nonlinear, per-channel colour response ``v' = 255·clip(g·(v/255)^γ + o)`` that the
hand-over method does not know (γ ∈ [0.55, 1.8], gain g ∈ [0.7, 1.25], offset o ∈
[−0.1, 0.1] per channel; ``response="strong"``: γ log-uniform in [0.4, 2.5], g ∈ [0.55, 1.45],
o ∈ [−0.15, 0.15], a stress test).  Each camera's tracks are the annotated boxes lying fully inside
its view, split where a person leaves it; ``identity`` maps ``(camera, track)`` to the
person.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from ..io.datasets import write_mot_groundtruth, write_seqinfo

__all__ = ["TwoCamScene", "check_frames", "default_split", "export_twocam", "twocam_scene"]


@dataclass
class TwoCamScene:
    frames: list[Path]            # source frames (1-based numbers index frames[n - 1])
    split: tuple[int, int]        # camera A: x < split[0]; camera B: x >= split[1]
    response: np.ndarray          # (3, 256) RGB tables of camera B
    tracks_a: np.ndarray          # MOT rows in camera A's coordinates
    tracks_b: np.ndarray
    identity: dict                # ("a"|"b", track) -> person
    numbers: tuple[int, int]      # frame range used
    meta: dict

    def frame_a(self, n: int) -> np.ndarray | None:
        img = cv2.imread(str(self.frames[n - 1]))
        return None if img is None else np.ascontiguousarray(img[:, :self.split[0]])

    def frame_b(self, n: int) -> np.ndarray | None:
        img = cv2.imread(str(self.frames[n - 1]))
        if img is None:
            return None
        from ..multicam.btf import apply_btf_image

        return apply_btf_image(np.ascontiguousarray(img[:, self.split[1]:]), self.response)

    def handovers(self) -> list[tuple[int, int]]:
        """Consecutive (track_a, track_b) of one person in the other camera, in either order of time."""
        out = []
        for person in sorted(set(self.identity.values())):
            ta = [t for (c, t), p in self.identity.items() if c == "a" and p == person]
            tb = [t for (c, t), p in self.identity.items() if c == "b" and p == person]
            span = {("a", t): _span(self.tracks_a, t) for t in ta} | {("b", t): _span(self.tracks_b, t) for t in tb}
            order = sorted(span, key=lambda k: span[k][0])
            for k0, k1 in zip(order[:-1], order[1:]):
                if k0[0] != k1[0]:
                    out.append((k0[1], k1[1]) if k0[0] == "a" else (k1[1], k0[1]))
        return out


def _span(rows: np.ndarray, tid: int) -> tuple[int, int]:
    f = rows[rows[:, 1] == tid, 0]
    return int(f.min()), int(f.max())


#: per-channel response ranges: gain, gamma, offset, and whether gamma is drawn log-uniformly
RESPONSES = {"mild": ((0.7, 1.25), (0.55, 1.8), (-0.1, 0.1), False),
             "strong": ((0.55, 1.45), (0.4, 2.5), (-0.15, 0.15), True)}


def colour_response(rng: np.random.Generator, strength: str = "mild") -> np.ndarray:
    """Camera B's (3, 256) tables: ``255·clip(g·(v/255)^γ + o)`` per channel, made non-decreasing."""
    (g0, g1), (c0, c1), (o0, o1), log_gamma = RESPONSES[strength]
    v = np.arange(256) / 255.0
    out = []
    for _ in range(3):
        g = rng.uniform(g0, g1)
        gamma = float(np.exp(rng.uniform(np.log(c0), np.log(c1)))) if log_gamma else rng.uniform(c0, c1)
        o = rng.uniform(o0, o1)
        out.append(255.0 * np.clip(g * v ** gamma + o, 0.0, 1.0))
    return np.maximum.accumulate(np.stack(out), axis=1)


def _tracks(gt: np.ndarray, inside, shift: float, cam: str, min_len: int, identity: dict) -> np.ndarray:
    rows = []
    next_id = 1
    for pid in np.unique(gt[:, 1]).astype(int):
        r = gt[gt[:, 1] == pid]
        r = r[np.argsort(r[:, 0])]
        ok = np.array([inside(b) for b in r[:, 2:6]])
        idx = np.flatnonzero(ok)
        if len(idx) == 0:
            continue
        runs = np.split(idx, np.flatnonzero(np.diff(r[idx, 0]) > 1) + 1)
        for run in runs:
            if len(run) < min_len:
                continue
            for row in r[run]:
                rows.append([row[0], next_id, row[2] - shift, row[3], row[4], row[5], 1, -1, -1, -1])
            identity[(cam, next_id)] = int(pid)
            next_id += 1
    return np.asarray(rows, dtype=np.float64).reshape(-1, 10)


#: The blind strip's edges as fractions of the frame's width when none is given: 340 and 430 of PETS 2009's 768
#: pixels, the scenes of docs/handover.md.
STRIP = (340 / 768, 430 / 768)


def default_split(width: int, left: float | None = None, strip: float | None = None) -> tuple[int, int]:
    """Camera A's right edge and camera B's left edge in a frame ``width`` pixels wide: the blind strip starts at
    ``left`` pixels and is ``strip`` pixels wide (by default at the fractions :data:`STRIP` of the width)."""
    x0 = round(STRIP[0] * width) if left is None else int(round(left))
    x1 = x0 + (round((STRIP[1] - STRIP[0]) * width) if strip is None else int(round(strip)))
    if not 0 < x0 < x1 < width:
        raise ValueError(f"the blind strip {x0}..{x1} must lie inside the frame's width {width}")
    return x0, x1


def check_frames(numbers: tuple[int, int], n_frames: int) -> None:
    """``numbers`` (first and last frame, 1-based) must be an ordered range within a sequence of ``n_frames``."""
    if not 1 <= numbers[0] < numbers[1] <= n_frames:
        raise ValueError(f"frames {numbers[0]}-{numbers[1]} outside the sequence's frames 1-{n_frames}")


def twocam_scene(sequence_dir, seed: int = 0, *, numbers: tuple[int, int] | None = None,
                 split: tuple[int, int] | None = None, min_len: int = 5, response: str = "mild") -> TwoCamScene:
    """Cut a MOTChallenge sequence (frames and ground truth) into two disjoint cameras.  ``numbers``: the first and
    last frame used (default: all); ``split``: camera A's right edge and camera B's left edge (default
    :func:`default_split`)."""
    from ..io.datasets import read_sequence

    seq = read_sequence(sequence_dir)
    if seq.mot_gt is None:
        raise ValueError(f"{sequence_dir}: needs MOTChallenge ground truth")
    if numbers is None:
        numbers = (1, len(seq.frames))
    check_frames(numbers, len(seq.frames))
    gt = seq.mot_gt[(seq.mot_gt[:, 0] >= numbers[0]) & (seq.mot_gt[:, 0] <= numbers[1])]
    w = seq.size[0] if seq.size else cv2.imread(str(seq.frames[0])).shape[1]
    if split is None:
        split = default_split(w)
    rng = np.random.default_rng(seed)
    identity: dict = {}
    ta = _tracks(gt, lambda b: b[0] >= 2 and b[0] + b[2] <= split[0] - 2, 0.0, "a", min_len, identity)
    tb = _tracks(gt, lambda b: b[0] >= split[1] + 2 and b[0] + b[2] <= w - 2, float(split[1]), "b", min_len,
                 identity)
    resp = colour_response(rng, response)
    meta = {"seed": seed, "frames": list(numbers), "split": list(split), "source": str(sequence_dir),
            "response": response, "fps": seq.fps or 7.0}
    return TwoCamScene(list(seq.frames), tuple(split), resp, ta, tb, identity, tuple(numbers), meta)


def export_twocam(scene: TwoCamScene, folder) -> None:
    """``cam_a/`` and ``cam_b/`` MOTChallenge folders (img1, gt/gt.txt, seqinfo.ini) and ``identity.csv``
    (``camera,track,person``); frames are renumbered from 1."""
    folder = Path(folder)
    off = scene.numbers[0] - 1
    for cam, rows, get in (("a", scene.tracks_a, scene.frame_a), ("b", scene.tracks_b, scene.frame_b)):
        d = folder / f"cam_{cam}"
        (d / "img1").mkdir(parents=True, exist_ok=True)
        (d / "gt").mkdir(parents=True, exist_ok=True)
        size = None
        for n in range(scene.numbers[0], scene.numbers[1] + 1):
            img = get(n)
            size = img.shape[:2]
            cv2.imwrite(str(d / "img1" / f"{n - off:06d}.jpg"), img, [cv2.IMWRITE_JPEG_QUALITY, 95])
        shifted = rows.copy()
        shifted[:, 0] -= off
        write_mot_groundtruth(d / "gt" / "gt.txt", shifted)
        write_seqinfo(d, name=f"cam_{cam}", fps=scene.meta.get("fps", 7.0), length=scene.numbers[1] - off,
                      width=size[1], height=size[0])
    rows = ["camera,track,person"] + [f"{c},{t},{p}" for (c, t), p in sorted(scene.identity.items())]
    (folder / "identity.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
