"""Assembled trackers and the registry."""

from .base import Tracker, TrackState
from .registry import create_tracker, get_spec, list_trackers, register, tracker_names

__all__ = ["Tracker", "TrackState", "create_tracker", "get_spec", "list_trackers", "register", "tracker_names"]
