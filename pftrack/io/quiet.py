"""OpenCV's own log output kept off the terminal around calls whose failure pftrack reports itself."""

from __future__ import annotations

from contextlib import contextmanager

import cv2


@contextmanager
def quiet_opencv():
    """OpenCV's log level lowered to errors for the block: its video backends print warnings for every device
    or container they fail to open, which would precede pftrack's one-line error."""
    log = getattr(getattr(cv2, "utils", None), "logging", None)
    if log is None:
        yield
        return
    level = log.getLogLevel()
    log.setLogLevel(min(level, log.LOG_LEVEL_ERROR))
    try:
        yield
    finally:
        log.setLogLevel(level)
