"""Multiple objects: detectors, per-target colour particle filters, occlusion reasoning, track life cycle."""

from .detectors import (
           DETECTORS,
           HOGDetector,
           MOG2Detector,
           MotionDetector,
           as_detector,
           create_detector,
)
from .tracker import (
           MULTI_TRACKERS,
           MultiPF,
           MultiPFParams,
           TrackOutput,
           create_multi_tracker,
)

__all__ = ["DETECTORS", "HOGDetector", "MOG2Detector", "MotionDetector", "as_detector", "create_detector",
           "MULTI_TRACKERS", "MultiPF", "MultiPFParams", "TrackOutput", "create_multi_tracker"]
