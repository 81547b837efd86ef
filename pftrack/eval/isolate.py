"""Runs in processes of their own, with a time limit (``pftrack eval --timeout``).

A tracker can hang inside native code (OpenCV's MIL did on a 4 x 4 box) or crash its process (a fault in a C
extension).  Neither can be stopped from the same process.  Here every run gets a process of its own (forked where
the platform allows: :func:`process_context`, :func:`fork_safe`), at most ``workers`` at a time.  A run still going
after ``timeout`` seconds is killed, and a process that dies without a result is noted; both become failed runs
(:func:`pftrack.eval.jobs.failed`) and the evaluation goes on.  Bad input found by a run (an unreadable frame, a
sequence without ground truth) still stops the evaluation with its own error, as without a time limit.
"""

from __future__ import annotations

import multiprocessing as mp
import signal
import time
import traceback
from contextlib import contextmanager
from multiprocessing.connection import wait
from typing import Callable

from ..errors import PftrackError
from .jobs import Job, failure_record, run_job


def process_context():
    """The start method of the runs' processes: fork where the platform has it (nothing is imported again, and a
    script needs no ``__main__`` guard), else spawn.  Fork only inside :func:`fork_safe`."""
    return mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")


@contextmanager
def fork_safe():
    """OpenCV's thread pool stopped in this process while runs' processes are forked, then restored.

    Once a process has used that pool (any OpenCV call that runs in parallel), a child forked from it waits forever
    on the pool's threads, which it does not have, at its first OpenCV call that touches the pool.  With the pool
    stopped first, the child starts without it and builds its own."""
    import cv2

    n = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(n)


def _child(conn, job: Job) -> None:
    """Run ``job`` and send ``("ok", record)``, or ``("input", exception)`` for bad input, or ``("error", text)``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle: it stops the children
    try:
        msg = ("ok", run_job(job))
    except PftrackError as exc:
        msg = ("input", exc)
    except BaseException as exc:  # noqa: BLE001 - anything else is the run's failure
        msg = ("error", f"{type(exc).__name__}: {exc}", traceback.format_exc())
    try:
        conn.send(msg)
    except Exception:  # noqa: BLE001 - an exception that cannot be pickled: its text will do
        conn.send(("input", PftrackError(str(msg[1]))) if msg[0] == "input" else ("error", str(msg[1]), ""))
    conn.close()


def _died(code: int | None) -> str:
    if code is not None and code < 0:
        try:
            return f"the run's process was killed by signal {signal.Signals(-code).name}"
        except ValueError:
            return f"the run's process was killed by signal {-code}"
    return f"the run's process ended with exit code {code} and no result"


def run_isolated(jobs: list[Job], todo: list[int], done: Callable[[int, dict], None], *, workers: int,
                 timeout: float) -> None:
    """Run ``jobs[i]`` for ``i`` in ``todo``, each in a process of its own, ``workers`` at a time; ``done(i, record)``
    gets every result, failed runs included (a run killed after ``timeout`` seconds, or whose process died)."""
    ctx = process_context()
    pending = list(todo)
    active: dict = {}  # connection -> (index, process, deadline)
    with fork_safe():
        try:
            _serve(ctx, jobs, pending, active, done, workers, timeout)
        finally:
            for conn, (_, proc, _) in active.items():  # interrupted, or bad input: the other runs stop
                proc.kill()
                proc.join()
                conn.close()


def _serve(ctx, jobs: list[Job], pending: list[int], active: dict, done, workers: int, timeout: float) -> None:
    """Start runs while fewer than ``workers`` are active, and collect results, failures and overruns, until
    ``pending`` and ``active`` are empty."""
    while pending or active:
        while pending and len(active) < max(1, workers):
            i = pending.pop(0)
            recv, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_child, args=(send, jobs[i]), daemon=True)
            proc.start()
            send.close()
            active[recv] = (i, proc, time.monotonic() + timeout)
        now = time.monotonic()
        ready = wait(list(active), timeout=max(0.0, min(d for _, _, d in active.values()) - now))
        for conn in ready:
            i, proc, _ = active.pop(conn)
            try:
                msg = conn.recv()
            except EOFError:  # the process died without a word
                proc.join()
                done(i, failure_record(jobs[i], _died(proc.exitcode)))
                continue
            finally:
                conn.close()
            proc.join()
            if msg[0] == "ok":
                done(i, msg[1])
            elif msg[0] == "input":
                raise msg[1]
            else:
                done(i, failure_record(jobs[i], msg[1], trace=msg[2]))
        now = time.monotonic()
        for conn, (i, proc, deadline) in list(active.items()):
            if now >= deadline:
                proc.kill()
                proc.join()
                conn.close()
                del active[conn]
                done(i, failure_record(jobs[i], f"timed out after {timeout:g} s"))
