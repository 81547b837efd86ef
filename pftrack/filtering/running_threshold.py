"""A running ``mu + k sigma`` threshold of the confident frames' values (book ch. 6 §5, ch06.md §1.10 "online").

Used by the chapter 6 trackers (the switching tracker, the covariance tracker, FS mean shift, SIFT + RANSAC) to
flag a value unlike the recent confident ones; no images.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

__all__ = ["RunningThreshold"]


class RunningThreshold:
    """``mu + k sigma`` of the last ``window`` accepted values (book ch. 6 §5, ch06.md §1.10 "online").

    The chapter fits a Gaussian to the similarity scores of frames labelled occluded and puts
    the switching threshold 3 sigma from its mean; labels do not exist online, so this keeps the
    statistics of the *confident* frames instead and flags a value more than ``k`` spreads above
    their mean (a distance: larger is worse).  ``sd_floor`` keeps the spread from collapsing on a
    static scene; no value is flagged before ``seed`` values have been seen.
    """

    def __init__(self, *, window: int = 30, seed: int = 10, k: float = 3.0, sd_floor: float = 0.02):
        self.values: deque[float] = deque(maxlen=window)
        self.seed, self.k, self.sd_floor = seed, k, sd_floor

    @property
    def ready(self) -> bool:
        return len(self.values) >= self.seed

    @property
    def mean(self) -> float:
        return float(np.mean(self.values)) if self.values else 0.0

    @property
    def sd(self) -> float:
        return max(float(np.std(self.values)) if len(self.values) > 1 else 0.0, self.sd_floor)

    @property
    def threshold(self) -> float:
        return self.mean + self.k * self.sd if self.ready else math.inf

    def exceeds(self, value: float) -> bool:
        return not math.isfinite(value) or value > self.threshold

    def push(self, value: float) -> None:
        if math.isfinite(value):
            self.values.append(float(value))
