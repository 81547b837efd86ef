"""Decoding ahead: a background thread that produces the next few items of an iterator.

Frame decoders (FFmpeg through OpenCV or PyAV, image codecs) release the GIL, so a source read on a
second thread overlaps the tracker's work on the first.  Used by the file sources (videos, image
folders, compressed-domain videos); live cameras are read in the caller's thread, since frames queued
ahead would be stale. A process that may run on one CPU only (``taskset -c 0``, a one-core container) reads in the
caller's thread too (:func:`default_depth`): there is no second core to decode on, and the thread's switches would
interrupt the tracker's timed work.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Iterator

#: frames decoded ahead when a second CPU is there to decode them
DEPTH = 4


def usable_cpus() -> int:
    """The CPUs this process may run on (its affinity where the system tells it, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def default_depth() -> int:
    """How many frames the file sources decode ahead: :data:`DEPTH`, or 0 (the caller's thread) on one CPU."""
    return DEPTH if usable_cpus() > 1 else 0


def prefetch(items: Iterator, depth: int = DEPTH) -> Iterator:
    """Yield ``items`` in order while a background thread produces up to ``depth`` of them ahead.

    FFmpeg decodes and converts with the GIL released, so the decoding overlaps the caller's work on a
    second core.  An exception in the producer is raised in the caller; closing the generator stops the
    producer.  ``depth`` 0 iterates in the caller's thread."""
    if depth <= 0:
        yield from items
        return
    q: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()
    done = object()

    def put(item) -> bool:
        while not stop.is_set():
            try:
                q.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def produce() -> None:
        try:
            for item in items:
                if not put((None, item)):
                    return
        except BaseException as exc:  # noqa: BLE001 - handed to the consumer
            put((exc, None))
            return
        finally:
            close = getattr(items, "close", None)
            if stop.is_set() and close is not None:
                close()
        put((None, done))

    worker = threading.Thread(target=produce, name="pftrack-prefetch", daemon=True)
    worker.start()
    try:
        while True:
            exc, item = q.get()
            if exc is not None:
                raise exc
            if item is done:
                return
            yield item
    finally:
        stop.set()
        worker.join(timeout=5.0)
