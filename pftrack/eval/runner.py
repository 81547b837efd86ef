"""The evaluation runner: trackers × sequences × seeds, in parallel, resumable.

Each (tracker, sequence, seed, protocol) run is a :class:`Job`.  A job opens its
sequence, decodes frames, times only ``update`` (decode excluded), scores the
trajectory and returns a plain dict (JSON-serialisable).  With a report folder
every finished run is written atomically to ``DIR/runs/<key>.json``; a later
call finds it and skips the run, so an interrupted evaluation resumes where it
stopped.  Each cached run records the fingerprint of the package code that made it (:func:`code_fingerprint`);
runs reused from other code are counted (``Runner.reused_other_code``) so that the caller can say so, and
``fresh=True`` ignores the cache.

Executors: in-process (``workers=1``), local processes (``workers>1``,
``concurrent.futures``) or a Dask distributed cluster (``scheduler=ADDRESS`` or
a ``dask.distributed.Client``).  Every worker pins OpenCV to ``threads`` threads
(1 by default) so speeds are per core.  Results other than timings are identical
whatever the executor (tested).

Tracker specs: ``NAME`` or ``NAME[key=value;key=value]`` (also ``,`` inside the
brackets), e.g. ``local-motion-pf[motion=false]``; the whole spec is the label.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import re
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

from ..errors import ParameterError
# one run lives in .jobs; these names are re-exported here, where callers have always found them
from .jobs import (ONE_PASS, RESULT_VERSION, SRE_PERTURBATIONS, TRE_SEGMENTS, Job, TrackerConfig,  # noqa: F401
                   failed, perturb, perturbed_box, run_job, tre_starts)


# ---------------------------------------------------------------------------------------------- specs

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
    from ..trackers.monitor import split_wrapper_options
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
        spec.params_cls.from_mapping(split_wrapper_options(dict(params))[1])  # validate now, not in a worker
        if not spec.available():
            raise ParameterError(f"tracker '{name}' is not available in this installation")
        configs.append(TrackerConfig(item, name, tuple(params)))
    if not configs:
        raise ParameterError("no trackers given")
    labels = [c.label for c in configs]
    if len(set(labels)) != len(labels):
        raise ParameterError("a tracker is listed twice")
    return configs


def build_jobs(sequences: Iterable, trackers: list[TrackerConfig], *, seeds: int, protocol: str,
               threads: int = 1) -> list[Job]:
    from ..trackers.registry import get_spec

    jobs = []
    for seq in sequences:
        for cfg in trackers:
            if protocol == "sre":  # every tracker once from each perturbed first box
                runs = len(SRE_PERTURBATIONS)
            elif protocol == "tre":  # every tracker once from each start frame
                runs = TRE_SEGMENTS
            else:
                stochastic = True if protocol == "mot" else get_spec(cfg.name).cls.stochastic
                runs = seeds if stochastic else 1
            for seed in range(runs):
                jobs.append(Job(cfg, str(seq.path), seq.name, seed, protocol, threads, target=seq.target))
    return jobs


# ---------------------------------------------------------------------------------------------- runner

TIMING_FIELDS = ("fps", "update_seconds", "median_frame_ms", "e2e_fps")


def _atomic_write_json(path: Path, obj: dict) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(obj, fh, allow_nan=False)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """A short hash of the package's Python source (every ``pftrack/**/*.py``, by relative path and content): two
    runs with the same fingerprint were made by the same code."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha1()
    for f in sorted(root.rglob("*.py")):
        h.update(f.relative_to(root).as_posix().encode())
        h.update(b"\0")
        h.update(f.read_bytes())
    return h.hexdigest()[:12]


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
    """Runs jobs with caching in ``report_dir/runs`` (when given).

    A run whose tracker raised is returned as a failed record (:func:`pftrack.eval.jobs.failed`) and written to
    ``report_dir/failed`` instead, so that the next call runs it again."""

    report_dir: Path | None = None
    workers: int = 1
    scheduler: Any = None  # address string or a dask.distributed.Client
    progress: bool = True
    on_result: Callable[[dict], None] | None = None
    #: seconds a run may take; set, every run has a process of its own and one that takes longer, or whose process
    #: dies, is recorded as failed (:mod:`.isolate`); None: runs share the worker processes, without a limit
    timeout: float | None = None
    #: compute every run again, ignoring (and replacing) the runs cached in ``report_dir``
    fresh: bool = False
    ran: int = field(default=0, init=False)
    reused: int = field(default=0, init=False)
    #: of the reused runs, those made by other code than this (another :func:`code_fingerprint`, or none recorded)
    reused_other_code: int = field(default=0, init=False)

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
        code = code_fingerprint()
        for i, job in enumerate(jobs):
            p = None if self.fresh else self._cache_path(job)
            rec = _load_cached(p, job) if p is not None and p.exists() else None
            if rec is not None:
                results[i] = rec
                self.reused += 1
                self.reused_other_code += rec.get("code") != code
            else:
                todo.append(i)
        bar = tqdm(total=len(jobs), initial=len(results), desc="eval", unit="run", file=sys.stderr,
                   disable=not self.progress or None, leave=False)

        def done(i: int, rec: dict) -> None:
            rec["code"] = code
            results[i] = rec
            p = self._cache_path(jobs[i])
            if p is not None:  # a failed run is kept apart, with its traceback, and run again next time
                failed_path = p.parent.parent / "failed" / p.name
                if failed(rec):
                    failed_path.parent.mkdir(parents=True, exist_ok=True)
                    _atomic_write_json(failed_path, rec)
                else:
                    failed_path.unlink(missing_ok=True)
                    _atomic_write_json(p, rec)
            self.ran += 1
            if self.on_result:
                self.on_result(rec)
            bar.update(1)

        try:
            if self.scheduler is not None:
                self._run_dask(jobs, todo, done)
            elif self.timeout is not None:
                from .isolate import run_isolated

                run_isolated(jobs, todo, done, workers=self.workers, timeout=self.timeout)
            elif self.workers <= 1 or len(todo) <= 1:
                for i in todo:
                    done(i, run_job(jobs[i]))
            else:
                from .isolate import fork_safe, process_context

                with fork_safe(), ProcessPoolExecutor(max_workers=self.workers, mp_context=process_context()) as ex:
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
