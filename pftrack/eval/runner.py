"""The evaluation runner: trackers × sequences × seeds, in parallel, resumable.

Each (tracker, sequence, seed, protocol) run is a :class:`Job`.  A job opens its
sequence, decodes frames, times only ``update`` (decode excluded), scores the
trajectory and returns a plain dict (JSON-serialisable).  With a report folder
every finished run is written atomically to ``DIR/runs/<key>.json``; a later
call finds it and skips the run, so an interrupted evaluation resumes where it
stopped.

Executors: in-process (``workers=1``), local processes (``workers>1``,
``concurrent.futures``) or a Dask distributed cluster (``scheduler=ADDRESS`` or
a ``dask.distributed.Client``).  Every worker pins OpenCV to ``threads`` threads
(1 by default) so speeds are per core.  Results other than timings are identical
whatever the executor (tested).

Tracker specs: ``NAME`` or ``NAME[key=value;key=value]`` (also ``,`` inside the
brackets), e.g. ``local-motion-pf[motion=false]``; the whole spec is the label.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np

from ..errors import FormatError, ParameterError
from .metrics import lost_detection, ope_scores, valid_gt

RESULT_VERSION = 3  # 2: lost-flag detection metrics; 3: identification rate (MOT)

#: OTB's spatial robustness evaluation (Wu, Lim & Yang, CVPR 2013, §4.2): the first box shifted by 10 % of its
#: size in 8 directions (4 centre shifts, 4 corner shifts) and scaled by 0.8, 0.9, 1.1 and 1.2 about its centre;
#: each entry is ``(dx, dy, scale)``, shifts as fractions of the width and height.  Run ``k`` of a tracker on a
#: sequence starts from perturbation ``k`` (its seed).
SRE_PERTURBATIONS = ((-0.1, 0.0, 1.0), (0.1, 0.0, 1.0), (0.0, -0.1, 1.0), (0.0, 0.1, 1.0),
                     (-0.1, -0.1, 1.0), (0.1, -0.1, 1.0), (-0.1, 0.1, 1.0), (0.1, 0.1, 1.0),
                     (0.0, 0.0, 0.8), (0.0, 0.0, 0.9), (0.0, 0.0, 1.1), (0.0, 0.0, 1.2))
#: protocols that run one pass from a first box and are scored by the OTB curves
ONE_PASS = ("ope", "sre")


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


# ---------------------------------------------------------------------------------------------- specs

@dataclass(frozen=True)
class TrackerConfig:
    label: str
    name: str
    params: tuple[tuple[str, str], ...] = ()

    @property
    def param_dict(self) -> dict[str, str]:
        return dict(self.params)


def _split_top(text: str) -> list[str]:
    out, depth, cur = [], 0, []
    for ch in text:
        if ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
        if ch == "," and depth == 0:
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur))
    return [s.strip() for s in out if s.strip()]


_SPEC = re.compile(r"^([A-Za-z0-9_.\-]+)(?:\[(.*)\])?$")


def parse_tracker_list(text: str, *, protocol: str = "ope") -> list[TrackerConfig]:
    """Parse ``"color-pf,opencv-csrt,local-motion-pf[motion=false]"``.

    The keywords ``all``, ``ours``, ``baselines`` and ``opencv`` expand to the
    available registered trackers of those families.  With ``protocol="mot"`` the
    names are multi-target trackers (``multi-pf[detector=motion;occlusion=false]``).
    """
    from ..trackers.registry import get_spec, list_trackers

    if protocol == "mot":
        from ..multi.tracker import MULTI_TRACKERS

        out = []
        for item in _split_top(text):
            m = _SPEC.match(item)
            if not m or m.group(1) not in MULTI_TRACKERS:
                raise ParameterError(f"unknown multi-target tracker spec {item!r}; choose from "
                                     f"{', '.join(MULTI_TRACKERS)}")
            params = tuple(tuple(kv.split("=", 1)) for kv in re.split(r"[;,]", m.group(2) or "") if kv.strip())
            if any(len(kv) != 2 for kv in params):
                raise ParameterError(f"tracker spec {item!r}: expected key=value")
            params = tuple((k.strip(), v.strip()) for k, v in params)
            MULTI_TRACKERS[m.group(1)].Params.from_mapping(dict(params))
            out.append(TrackerConfig(item, m.group(1), params))
        if not out:
            raise ParameterError("no trackers given")
        return out

    configs: list[TrackerConfig] = []
    for item in _split_top(text):
        families = {"all": None, "ours": "pftrack", "baselines": "baseline", "opencv": "opencv"}
        if item in families:
            for spec in list_trackers(families[item]):
                if spec.available():
                    configs.append(TrackerConfig(spec.name, spec.name))
            continue
        m = _SPEC.match(item)
        if not m:
            raise ParameterError(f"malformed tracker spec {item!r} (expected NAME or NAME[key=value;...])")
        name, inner = m.group(1), m.group(2)
        spec = get_spec(name)
        params: list[tuple[str, str]] = []
        if inner:
            for kv in re.split(r"[;,]", inner):
                if not kv.strip():
                    continue
                if "=" not in kv:
                    raise ParameterError(f"tracker spec {item!r}: expected key=value, got {kv!r}")
                k, v = kv.split("=", 1)
                params.append((k.strip(), v.strip()))
        spec.params_cls.from_mapping(dict(params))  # validate now, not in a worker
        if not spec.available():
            raise ParameterError(f"tracker '{name}' is not available in this installation")
        configs.append(TrackerConfig(item, name, tuple(params)))
    if not configs:
        raise ParameterError("no trackers given")
    labels = [c.label for c in configs]
    if len(set(labels)) != len(labels):
        raise ParameterError("a tracker is listed twice")
    return configs


@dataclass(frozen=True)
class Job:
    tracker: TrackerConfig
    sequence: str  # path
    sequence_name: str
    seed: int
    protocol: str  # "ope" | "sre" | "vot" | "mot"
    threads: int = 1
    extra: tuple[tuple[str, Any], ...] = ()
    target: int | None = None  # which annotated target of an OTB folder with several (``Sequence.target``)

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
            from ..trackers.registry import get_spec

            cls = get_spec(cfg.name).cls.Params
        return cls.from_mapping(dict(cfg.params)).as_dict()
    except Exception:  # noqa: BLE001 - invalid parameters are reported when the run starts
        return None


def build_jobs(sequences: Iterable, trackers: list[TrackerConfig], *, seeds: int, protocol: str,
               threads: int = 1) -> list[Job]:
    from ..trackers.registry import get_spec

    jobs = []
    for seq in sequences:
        for cfg in trackers:
            if protocol == "sre":  # every tracker once from each perturbed first box
                runs = len(SRE_PERTURBATIONS)
            else:
                stochastic = True if protocol == "mot" else get_spec(cfg.name).cls.stochastic
                runs = seeds if stochastic else 1
            for seed in range(runs):
                jobs.append(Job(cfg, str(seq.path), seq.name, seed, protocol, threads, target=seq.target))
    return jobs


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
    return [None if (isinstance(v, float) and not math.isfinite(v)) else v for v in np.asarray(a, dtype=np.float64).ravel().tolist()]


def run_job(job: Job) -> dict:
    """Run one job and return its result record (no side effects on disk)."""
    from ..io.datasets import read_otb, read_sequence
    from ..io.sources import read_image
    from ..trackers.registry import create_tracker
    from .vot import run_vot

    _pin_threads(job.threads)
    with warnings.catch_warnings():  # the folder's own warnings were given once, when the sequences were found
        warnings.simplefilter("ignore")
        seq = read_sequence(job.sequence) if job.target is None else read_otb(job.sequence, target=job.target)
    if job.protocol == "mot":
        return _run_mot_job(job, seq)
    if seq.groundtruth is None:
        raise FormatError(f"{job.sequence}: no single-object ground truth for protocol {job.protocol}")
    from ..trackers.warmup import warm_up

    warm_up(job.tracker.name, job.tracker.param_dict)  # no compilation inside the timed updates
    tracker = create_tracker(job.tracker.name, seed=job.seed, params=job.tracker.param_dict)

    def frames():
        from ..frames import as_bgr_uint8

        for i, path in enumerate(seq.frames):
            img = read_image(path)
            if img is None:
                raise FormatError(f"{path}: frame {i + 1} cannot be decoded")
            yield as_bgr_uint8(img, where=str(path))

    gt = seq.groundtruth
    rec: dict[str, Any] = {"version": RESULT_VERSION, "tracker": job.tracker.label, "name": job.tracker.name,
                           "params": dict(job.tracker.params), "sequence": job.sequence_name, "seed": job.seed,
                           "protocol": job.protocol, "frames": len(seq.frames)}
    if job.protocol in ONE_PASS:
        start = seq.init_index
        first = seq.init_box
        boxes = np.full((len(seq.frames), 4), np.nan)
        lost_flags = np.zeros(len(seq.frames), dtype=bool)
        upd_s = 0.0
        times = []
        for t, frame in enumerate(frames()):
            if t < start:
                continue
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
            boxes[t] = st.box
            lost_flags[t] = bool(st.lost)
        scores = ope_scores(boxes[start:], gt[start:])
        # the init frame is given, not detected: the flag is scored from the first update on
        absent = seq.absent if seq.absent is not None else ~valid_gt(gt)
        ld = lost_detection(lost_flags[start + 1:], boxes[start + 1:], gt[start + 1:], absent[start + 1:])
        rec.update(auc=scores.auc, precision=scores.precision, mean_iou=scores.mean_iou, failures=None,
                   accuracy=None, lost_frames=int(lost_flags.sum()), lost_recall=ld.recall,
                   false_lost=ld.false_rate, absent_frames=ld.absent_frames, covered_frames=ld.covered_frames,
                   reappearances=ld.reappearances, reacquired=ld.reacquired,
                   lost=[int(v) for v in lost_flags], success=_finite_list(scores.success),
                   precision_curve=_finite_list(scores.precision_curve), boxes=_finite_list(boxes),
                   update_seconds=upd_s, updates=len(times),
                   fps=(len(times) / upd_s) if upd_s > 0 else None,
                   median_frame_ms=float(np.median(times) * 1e3) if times else None)
    elif job.protocol == "vot":
        res = run_vot(tracker, frames(), gt)
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


def _run_mot_job(job: Job, seq) -> dict:
    from ..frames import as_bgr_uint8
    from ..io.sources import read_image
    from ..multi.tracker import create_multi_tracker
    from .mot import mot_scores

    if seq.mot_gt is None:
        raise FormatError(f"{job.sequence}: no MOTChallenge ground truth (gt/gt.txt) for protocol mot")
    tracker = create_multi_tracker(job.tracker.name, seed=job.seed, **dict(job.tracker.params))
    rows = []
    upd = 0.0
    t_all = time.perf_counter()
    for t, path in enumerate(seq.frames, start=1):
        img = read_image(path)
        if img is None:
            raise FormatError(f"{path}: frame {t} cannot be decoded")
        frame = as_bgr_uint8(img, where=str(path))
        t0 = time.perf_counter()
        outs = tracker.update(frame)
        upd += time.perf_counter() - t0
        rows.extend([t, o.track_id, *o.box, o.score] for o in outs)
    total = time.perf_counter() - t_all
    hyp = np.array(rows, dtype=np.float64).reshape(-1, 7)
    gt = seq.mot_gt[seq.mot_gt[:, 0] <= len(seq.frames)]
    s = mot_scores(gt, hyp, frames=np.arange(1, len(seq.frames) + 1))
    rec = {"version": RESULT_VERSION, "tracker": job.tracker.label, "name": job.tracker.name,
           "params": dict(job.tracker.params), "sequence": job.sequence_name, "seed": job.seed, "protocol": "mot",
           "frames": len(seq.frames), **{k: v for k, v in s.as_dict().items()},
           "fps": len(seq.frames) / upd if upd > 0 else None, "e2e_fps": len(seq.frames) / total if total > 0 else None,
           "update_seconds": upd, "identities": int(len(np.unique(hyp[:, 1]))) if len(hyp) else 0,
           "auc": None, "precision": None, "mean_iou": None, "failures": None, "accuracy": None}
    for k, v in list(rec.items()):
        if isinstance(v, float) and not math.isfinite(v):
            rec[k] = None
    return rec


# ---------------------------------------------------------------------------------------------- runner

TIMING_FIELDS = ("fps", "update_seconds", "median_frame_ms", "e2e_fps")


def _atomic_write_json(path: Path, obj: dict) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(obj, fh, allow_nan=False)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def _load_cached(path: Path, job: Job) -> dict | None:
    try:
        with open(path, encoding="utf-8") as fh:
            rec = json.load(fh)
    except (OSError, json.JSONDecodeError):
        return None
    if (rec.get("version") != RESULT_VERSION or rec.get("tracker") != job.tracker.label
            or rec.get("sequence") != job.sequence_name or rec.get("seed") != job.seed
            or rec.get("protocol") != job.protocol or rec.get("params") != dict(job.tracker.params)):
        return None
    return rec


@dataclass
class Runner:
    """Runs jobs with caching in ``report_dir/runs`` (when given)."""

    report_dir: Path | None = None
    workers: int = 1
    scheduler: Any = None  # address string or a dask.distributed.Client
    progress: bool = True
    on_result: Callable[[dict], None] | None = None
    ran: int = field(default=0, init=False)
    reused: int = field(default=0, init=False)

    def _cache_path(self, job: Job) -> Path | None:
        if self.report_dir is None:
            return None
        d = Path(self.report_dir) / "runs"
        d.mkdir(parents=True, exist_ok=True)
        return d / f"{job.key}.json"

    def run(self, jobs: list[Job]) -> list[dict]:
        from tqdm import tqdm
        import sys

        results: dict[int, dict] = {}
        todo: list[int] = []
        for i, job in enumerate(jobs):
            p = self._cache_path(job)
            rec = _load_cached(p, job) if p is not None and p.exists() else None
            if rec is not None:
                results[i] = rec
                self.reused += 1
            else:
                todo.append(i)
        bar = tqdm(total=len(jobs), initial=len(results), desc="eval", unit="run", file=sys.stderr,
                   disable=not self.progress or None, leave=False)

        def done(i: int, rec: dict) -> None:
            results[i] = rec
            p = self._cache_path(jobs[i])
            if p is not None:
                _atomic_write_json(p, rec)
            self.ran += 1
            if self.on_result:
                self.on_result(rec)
            bar.update(1)

        try:
            if self.scheduler is not None:
                self._run_dask(jobs, todo, done)
            elif self.workers <= 1 or len(todo) <= 1:
                for i in todo:
                    done(i, run_job(jobs[i]))
            else:
                with ProcessPoolExecutor(max_workers=self.workers) as ex:
                    futs = {ex.submit(run_job, jobs[i]): i for i in todo}
                    try:
                        for fut in as_completed(futs):
                            done(futs[fut], fut.result())
                    except BaseException:
                        for f in futs:
                            f.cancel()
                        raise
        finally:
            bar.close()
        return [results[i] for i in range(len(jobs))]

    def _run_dask(self, jobs, todo, done) -> None:
        from dask.distributed import Client, as_completed as dask_completed

        client = self.scheduler if isinstance(self.scheduler, Client) else Client(self.scheduler)
        try:
            futs = {}
            for i in todo:
                fut = client.submit(run_job, jobs[i], pure=False, key=f"pftrack-{jobs[i].key}-{time.time_ns()}")
                futs[fut] = i
            for fut in dask_completed(list(futs)):
                done(futs[fut], fut.result())
        finally:
            if client is not self.scheduler:
                client.close()


def strip_timings(rec: dict) -> dict:
    """A record without its timing fields (for comparing runs across executors)."""
    return {k: v for k, v in rec.items() if k not in TIMING_FIELDS}
