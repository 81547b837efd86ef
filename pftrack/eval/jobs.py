"""One evaluation run: a tracker on one sequence with one seed, scored (``run_job``).

A run opens its sequence, decodes the frames, times only ``update`` (decode excluded), scores the trajectory and
returns a plain JSON-serialisable record.  A tracker that raises does not stop an evaluation: the run is recorded
as failed (``error``, ``error_frame``, ``traceback``), its one-pass scores count the frames before the failure and
no box after it, and :class:`pftrack.eval.runner.Runner` goes on with the other runs.  Bad input (an unreadable
frame, a sequence without ground truth, an unknown parameter) still stops the evaluation with its one-line error.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import time
import traceback
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FormatError, ParameterError
from .metrics import lost_detection, ope_scores, valid_gt, within_frame

#: 2: lost-flag detection metrics; 3: identification rate (MOT); 4: IoU within the frame; 5: normalised precision
RESULT_VERSION = 5

#: OTB's spatial robustness evaluation (Wu, Lim & Yang, CVPR 2013, §4.2): the first box shifted by 10 % of its
#: size in 8 directions (4 centre shifts, 4 corner shifts) and scaled by 0.8, 0.9, 1.1 and 1.2 about its centre;
#: each entry is ``(dx, dy, scale)``, shifts as fractions of the width and height.  Run ``k`` of a tracker on a
#: sequence starts from perturbation ``k`` (its seed).
SRE_PERTURBATIONS = ((-0.1, 0.0, 1.0), (0.1, 0.0, 1.0), (0.0, -0.1, 1.0), (0.0, 0.1, 1.0),
                     (-0.1, -0.1, 1.0), (0.1, -0.1, 1.0), (-0.1, 0.1, 1.0), (0.1, 0.1, 1.0),
                     (0.0, 0.0, 0.8), (0.0, 0.0, 0.9), (0.0, 0.0, 1.1), (0.0, 0.0, 1.2))
#: OTB's temporal robustness evaluation (Wu, Lim & Yang, CVPR 2013, §4.2): every tracker starts once from each
#: of this many frames spread over the sequence, with that frame's ground-truth box, and runs to the end
TRE_SEGMENTS = 20
#: TRE: the last start leaves at least this many frames (OTB's ``minNum``)
TRE_MIN_FRAMES = 20
#: TRE: a start frame's box lies at least this much inside the frame (OTB starts on boxes whose corner is inside)
TRE_MIN_IN_FRAME = 0.9
#: protocols that run one pass from a first box and are scored by the OTB curves
ONE_PASS = ("ope", "sre", "tre")


def perturbed_box(box, k: int, frame_size: tuple[int, int] | None = None) -> tuple[float, float, float, float]:
    """The first box under SRE perturbation ``k`` (:data:`SRE_PERTURBATIONS`); see :func:`perturb`."""
    return perturb(box, SRE_PERTURBATIONS[int(k) % len(SRE_PERTURBATIONS)], frame_size)


def perturb(box, shift_scale: tuple[float, float, float], frame_size: tuple[int, int] | None = None
            ) -> tuple[float, float, float, float]:
    """``box`` shifted by ``(dx, dy)`` times its width and height and scaled by ``s`` about its centre, clipped
    to the frame ``(width, height)`` when given (the part of the box inside it)."""
    x, y, w, h = (float(v) for v in box)
    dx, dy, s = shift_scale
    nw, nh = w * s, h * s
    x0, y0 = x + dx * w + (w - nw) / 2, y + dy * h + (h - nh) / 2
    x1, y1 = x0 + nw, y0 + nh
    if frame_size is not None:
        x0, y0 = max(x0, 0.0), max(y0, 0.0)
        x1, y1 = min(x1, float(frame_size[0])), min(y1, float(frame_size[1]))
        if x1 - x0 < 1 or y1 - y0 < 1:  # shifted out of the frame: the unperturbed box
            return x, y, w, h
    return x0, y0, x1 - x0, y1 - y0


def tre_starts(gt, absent=None, frame_size: tuple[int, int] | None = None, *, segments: int = TRE_SEGMENTS,
               min_frames: int = TRE_MIN_FRAMES) -> np.ndarray:
    """The ``segments`` start frames (0-based, ascending, repeated on short sequences) of OTB's TRE on a sequence
    with ground truth ``gt`` ``(n, 4)``, as OTB's ``splitSeqTRE`` chooses them: the frames a tracker may start on
    are those with a valid box, the target present (not ``absent``) and the box at least
    :data:`TRE_MIN_IN_FRAME` inside the frame (any present frame when none is); the last of them that leaves at
    least ``min_frames`` frames (or the first, on a shorter sequence) ends the range, and the starts are spread
    evenly over the candidates up to it, the first candidate first. Start ``0`` is OPE's first frame whenever that
    frame is a candidate."""
    gt = np.asarray(gt, dtype=np.float64).reshape(-1, 4)
    n = len(gt)
    ok = valid_gt(gt)
    if absent is not None:
        a = np.asarray(absent, dtype=bool).ravel()[:n]
        ok[: a.size] &= ~a
    cand = np.flatnonzero(ok)
    if frame_size is not None and cand.size:
        boxes, cut = gt[cand], within_frame(gt[cand], frame_size)
        inside = cut[:, 2] * cut[:, 3] >= TRE_MIN_IN_FRAME * boxes[:, 2] * boxes[:, 3]
        if inside.any():
            cand = cand[inside]
    if cand.size == 0:
        raise FormatError("no frame with a ground-truth box to start a TRE run from")
    room = np.flatnonzero(n - cand >= min_frames)
    last = int(room[-1]) if room.size else 0
    idx = np.floor(np.arange(segments) * (last / max(segments - 1, 1))).astype(int)
    idx[-1] = last
    return cand[np.minimum(idx, last)]


# ---------------------------------------------------------------------------------------------- a run

@dataclass(frozen=True)
class TrackerConfig:
    label: str
    name: str
    params: tuple[tuple[str, str], ...] = ()

    @property
    def param_dict(self) -> dict[str, str]:
        return dict(self.params)


@dataclass(frozen=True)
class Job:
    tracker: TrackerConfig
    sequence: str  # path
    sequence_name: str
    seed: int
    protocol: str  # "ope" | "sre" | "tre" | "vot" | "mot"
    threads: int = 1
    extra: tuple[tuple[str, Any], ...] = ()
    #: which annotated target of an OTB folder with several, or which person of a MOTChallenge folder cut into
    #: people (``Sequence.target``)
    target: int | None = None

    @property
    def key(self) -> str:
        slug = re.sub(r"[^A-Za-z0-9_.=-]+", "_", self.tracker.label)[:80]
        h = hashlib.sha1(json.dumps([self.tracker.label, list(self.tracker.params), self.sequence_name,
                                     self.seed, self.protocol, _effective_params(self.tracker, self.protocol)],
                                    default=str).encode()).hexdigest()[:8]
        return f"{self.protocol}__{self.sequence_name}__{slug}__s{self.seed}__{h}"


def _effective_params(cfg: TrackerConfig, protocol: str) -> dict | None:
    """Every parameter of the run with the defaults filled in, so that a cached result is not reused after a
    default changed (resume is for interrupted runs of the same code)."""
    try:
        if protocol == "mot":
            from ..multi.tracker import MULTI_TRACKERS

            cls = MULTI_TRACKERS[cfg.name].Params
        else:
            from ..trackers.monitor import grey_restart_for, split_wrapper_options, wrapper_options
            from ..trackers.registry import get_spec

            spec = get_spec(cfg.name)
            out = spec.cls.Params.from_mapping(split_wrapper_options(dict(cfg.params))[1]).as_dict()
            wrap = wrapper_options(dict(cfg.params))
            if wrap.monitor:  # the loss monitor's settings too (the keys of unmonitored runs are unchanged)
                out["monitor"] = wrap.monitor_params().as_dict()
            grey_restart = grey_restart_for(spec.cls, dict(cfg.params))
            if grey_restart:
                out["grey_restart"] = grey_restart
            return out
        return cls.from_mapping(dict(cfg.params)).as_dict()
    except Exception:  # noqa: BLE001 - invalid parameters are reported when the run starts
        return None


# ---------------------------------------------------------------------------------------------- one run

def _pin_threads(n: int) -> None:
    """OpenCV's and Numba's parallel kernels get ``n`` threads: one run measures one core by default."""
    import cv2

    cv2.setNumThreads(int(n))
    try:
        import numba

        numba.set_num_threads(max(1, min(int(n), numba.config.NUMBA_NUM_THREADS)))
    except Exception:  # numba absent or its threading layer unavailable: the NumPy paths are single-threaded
        pass


def _finite_list(a) -> list:
    return [None if (isinstance(v, float) and not math.isfinite(v)) else v
            for v in np.asarray(a, dtype=np.float64).ravel().tolist()]


def _job_sequence(job: Job):
    """The sequence a job runs on: the folder, one annotated target of an OTB folder, or one person of a
    MOTChallenge folder (:func:`~pftrack.io.person_sequences.people_of`)."""
    from ..io.datasets import detect_layout, read_otb, read_sequence
    from ..io.person_sequences import people_of

    if job.target is None:
        return read_sequence(job.sequence)
    if detect_layout(Path(job.sequence)) == "mot":
        people = people_of(read_sequence(job.sequence), min_frames=1, identity=job.target)
        if not people:
            raise FormatError(f"{job.sequence}: no ground-truth track {job.target}")
        return people[0]
    return read_otb(job.sequence, target=job.target)


def run_job(job: Job) -> dict:
    """Run one job and return its result record (no side effects on disk)."""
    from ..io.sources import read_image
    from ..trackers.registry import create_tracker
    from .vot import run_vot

    _pin_threads(job.threads)
    with warnings.catch_warnings():  # the folder's own warnings were given once, when the sequences were found
        warnings.simplefilter("ignore")
        seq = _job_sequence(job)
    if job.protocol == "mot":
        return _run_mot_job(job, seq)
    if seq.groundtruth is None:
        raise FormatError(f"{job.sequence}: no single-object ground truth for protocol {job.protocol}")
    from ..trackers.warmup import warm_up

    try:
        warm_up(job.tracker.name, job.tracker.param_dict)  # no compilation inside the timed updates
    except ParameterError:
        raise
    except Exception:  # noqa: BLE001 - a tracker that fails on the warm-up clips is judged on the sequence itself
        pass
    tracker = create_tracker(job.tracker.name, seed=job.seed, params=job.tracker.param_dict)

    def frames(first: int = 0):
        """The frames from ``first`` on. Image files before it are not read; a video's are decoded in order and
        dropped (seeking a video to a frame number is not exact with every codec)."""
        from ..frames import as_bgr_uint8
        from ..io.video_frames import VideoFrame

        video = bool(seq.frames) and isinstance(seq.frames[0], VideoFrame)
        for i in range(0 if video else first, len(seq.frames)):
            path = seq.frames[i]
            img = read_image(path)
            if img is None:
                raise FormatError(f"{path}: frame {i + 1} cannot be decoded")
            if i >= first:
                yield as_bgr_uint8(img, where=str(path))

    gt = seq.groundtruth
    rec: dict[str, Any] = {"version": RESULT_VERSION, "tracker": job.tracker.label, "name": job.tracker.name,
                           "params": dict(job.tracker.params), "sequence": job.sequence_name, "seed": job.seed,
                           "protocol": job.protocol, "frames": len(seq.frames)}
    if job.protocol in ONE_PASS:
        start = seq.init_index
        first = seq.init_box
        if job.protocol == "tre":  # the seed is the segment: its start frame, with that frame's box
            start = int(tre_starts(gt, seq.absent, _frame_size(seq, read_image))[job.seed % TRE_SEGMENTS])
            first = tuple(float(v) for v in gt[start])
            rec["start_frame"] = start + 1
        boxes = np.full((len(seq.frames), 4), np.nan)
        lost_flags = np.zeros(len(seq.frames), dtype=bool)
        upd_s = 0.0
        times = []
        end = len(seq.frames)  # the frames the tracker answered (all but after a failure)
        bounds = None  # the frame's (width, height): boxes are scored within it (metrics.ope_scores)
        for t, frame in enumerate(frames(start), start=start):  # the frames before the start are not decoded
            bounds = bounds or (frame.shape[1], frame.shape[0])
            try:
                if t == start:
                    if job.protocol == "sre":
                        first = perturbed_box(seq.init_box, job.seed, (frame.shape[1], frame.shape[0]))
                        rec["init_box"] = list(first)
                    st = tracker.init(frame, first)
                else:
                    t0 = time.perf_counter()
                    st = tracker.update(frame)
                    dt = time.perf_counter() - t0
                    upd_s += dt
                    times.append(dt)
                box, lost = st.box, bool(st.lost)
            except Exception as exc:  # noqa: BLE001 - the run fails, the evaluation goes on
                rec.update(_failure_fields(TrackerFailure(exc, t + 1)))
                end = t
                break
            boxes[t] = box
            lost_flags[t] = lost
        # a failed run keeps no box from its failure on: those frames score IoU 0
        scores = ope_scores(boxes[start:], gt[start:], bounds=bounds)
        # the init frame is given, not detected: the flag is scored from the first update on, up to a failure
        absent = seq.absent if seq.absent is not None else ~valid_gt(gt)
        absent = absent | (valid_gt(gt) & ~valid_gt(within_frame(gt, bounds)))  # a box wholly outside the frame
        ld = lost_detection(lost_flags[start + 1:end], boxes[start + 1:end], gt[start + 1:end],
                            absent[start + 1:end], bounds=bounds)
        rec.update(auc=scores.auc, precision=scores.precision, norm_precision=scores.norm_precision,
                   mean_iou=scores.mean_iou, failures=None,
                   accuracy=None, lost_frames=int(lost_flags.sum()), lost_recall=ld.recall,
                   false_lost=ld.false_rate, absent_frames=ld.absent_frames, covered_frames=ld.covered_frames,
                   reappearances=ld.reappearances, reacquired=ld.reacquired,
                   lost=[int(v) for v in lost_flags], success=_finite_list(scores.success),
                   precision_curve=_finite_list(scores.precision_curve), boxes=_finite_list(boxes),
                   update_seconds=upd_s, updates=len(times),
                   fps=(len(times) / upd_s) if upd_s > 0 else None,
                   median_frame_ms=float(np.median(times) * 1e3) if times else None)
    elif job.protocol == "vot":
        try:
            res = run_vot(_Guarded(tracker), frames(), gt)
        except TrackerFailure as fail:  # no partial scores: the reset protocol's counts need the whole run
            rec.update(auc=None, precision=None, mean_iou=None, failures=None, accuracy=None, lost_frames=None,
                       fps=None, **_failure_fields(fail))
            return rec
        ok = np.isfinite(res.ious)
        rec.update(auc=None, precision=None, mean_iou=float(res.ious[ok].mean()) if ok.any() else None,
                   failures=res.failures, accuracy=res.accuracy, lost_frames=None,
                   failure_frames=res.failure_frames, inits=res.inits, boxes=_finite_list(res.boxes),
                   update_seconds=res.update_seconds, updates=res.updates,
                   fps=(res.updates / res.update_seconds) if res.update_seconds > 0 else None)
    else:
        raise ParameterError(f"unknown protocol {job.protocol!r}")
    for k, v in list(rec.items()):
        if isinstance(v, float) and not math.isfinite(v):
            rec[k] = None
    return rec


def _frame_size(seq, read_image) -> tuple[int, int]:
    """A sequence's frame ``(width, height)``: as its layout states it, or read from its first frame."""
    if seq.size is not None:
        return int(seq.size[0]), int(seq.size[1])
    img = read_image(seq.frames[0])
    if img is None:
        raise FormatError(f"{seq.frames[0]}: frame 1 cannot be decoded")
    return int(img.shape[1]), int(img.shape[0])


def _run_mot_job(job: Job, seq) -> dict:
    from ..frames import as_bgr_uint8
    from ..io.sources import read_image
    from ..multi.tracker import create_multi_tracker
    from .mot import mot_scores

    if seq.mot_gt is None:
        raise FormatError(f"{job.sequence}: no MOTChallenge ground truth (gt/gt.txt) for protocol mot")
    tracker = create_multi_tracker(job.tracker.name, seed=job.seed, **dict(job.tracker.params))
    rows = []
    failure: dict = {}
    answered = 0  # frames the tracker answered
    t_all = time.perf_counter()

    def decoded(t: int, path) -> np.ndarray:
        img = read_image(path)
        if img is None:
            raise FormatError(f"{path}: frame {t} cannot be decoded")
        return as_bgr_uint8(img, where=str(path))

    # bootstrap_frames: the first frames read ahead for the detector's background (counted as updates), then
    # tracked without a second decoding
    frames, upd = tracker.read_ahead(decoded(t, path) for t, path in enumerate(seq.frames, start=1))
    for t, frame in enumerate(frames, start=1):
        t0 = time.perf_counter()
        try:
            outs = tracker.update(frame)
            row = [[t, o.track_id, *o.box, o.score] for o in outs]
        except Exception as exc:  # noqa: BLE001 - scored on the frames before the failure, no track after it
            failure = _failure_fields(TrackerFailure(exc, t))
            break
        upd += time.perf_counter() - t0
        rows.extend(row)
        answered = t
    total = time.perf_counter() - t_all
    hyp = np.array(rows, dtype=np.float64).reshape(-1, 7)
    gt = seq.mot_gt[seq.mot_gt[:, 0] <= len(seq.frames)]
    s = mot_scores(gt, hyp, frames=np.arange(1, len(seq.frames) + 1))
    rec = {"version": RESULT_VERSION, "tracker": job.tracker.label, "name": job.tracker.name,
           "params": dict(job.tracker.params), "sequence": job.sequence_name, "seed": job.seed, "protocol": "mot",
           "frames": len(seq.frames), **{k: v for k, v in s.as_dict().items()},
           "fps": answered / upd if upd > 0 else None, "e2e_fps": answered / total if total > 0 else None,
           "update_seconds": upd, "identities": int(len(np.unique(hyp[:, 1]))) if len(hyp) else 0,
           "auc": None, "precision": None, "mean_iou": None, "failures": None, "accuracy": None, **failure}
    for k, v in list(rec.items()):
        if isinstance(v, float) and not math.isfinite(v):
            rec[k] = None
    return rec


# ---------------------------------------------------------------------------------------------- a tracker's failure

class TrackerFailure(Exception):
    """A tracker raised during a run; ``frame`` is the 1-based frame it was given when it did (None: unknown)."""

    def __init__(self, exc: BaseException, frame: int | None = None):
        super().__init__(f"{type(exc).__name__}: {exc}")
        self.exc = exc
        self.frame = frame


class _Guarded:
    """A tracker whose exceptions become :class:`TrackerFailure` (the protocols that drive it themselves)."""

    def __init__(self, tracker):
        self._tracker = tracker

    def init(self, frame, box):
        try:
            return self._tracker.init(frame, box)
        except Exception as exc:  # noqa: BLE001 - any failure of the tracker is the run's result
            raise TrackerFailure(exc) from exc

    def update(self, frame):
        try:
            return self._tracker.update(frame)
        except Exception as exc:  # noqa: BLE001
            raise TrackerFailure(exc) from exc


def _failure_fields(fail: TrackerFailure) -> dict:
    """The record's fields of a failed run: the one-line message, the frame, the tail of the traceback."""
    msg = " ".join(str(fail).split())
    tb = "".join(traceback.format_exception(type(fail.exc), fail.exc, fail.exc.__traceback__))
    return {"error": msg[:300], "error_frame": fail.frame, "traceback": tb[-4000:]}


def failure_record(job: Job, message: str, *, trace: str = "") -> dict:
    """The record of a run that gave no result (killed after its time limit, or its process died): no scores."""
    return {"version": RESULT_VERSION, "tracker": job.tracker.label, "name": job.tracker.name,
            "params": dict(job.tracker.params), "sequence": job.sequence_name, "seed": job.seed,
            "protocol": job.protocol, "frames": None, "auc": None, "precision": None, "mean_iou": None,
            "failures": None, "accuracy": None, "lost_frames": None, "fps": None,
            "error": " ".join(message.split())[:300], "error_frame": None, "traceback": trace[-4000:]}


def failed(rec: dict) -> bool:
    """Whether a run's record is that of a failed run (its tracker raised)."""
    return bool(rec.get("error"))
