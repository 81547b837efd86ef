"""Events from video: directional line crossings, trackerless or from tracks (book ch. 10)."""

from .eval import EventScore, match_events, track_crossings
from .geometry import (
           Crossing,
           PatchLayout,
           build_patches,
           crossings_of_track,
           parse_polyline,
)
from .tripwire import (
           CrossingEvent,
           TrackerlessTripwire,
           TripwireParams,
           estimate_radius,
)

__all__ = ["Crossing", "CrossingEvent", "EventScore", "PatchLayout", "TrackerlessTripwire", "TripwireParams",
           "build_patches", "crossings_of_track", "estimate_radius", "match_events", "parse_polyline",
           "track_crossings"]
