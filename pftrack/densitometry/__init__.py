"""Densitometry along a cross-sectional line that follows a tracked artery segment (book ch. 14)."""

from .profile import (
                      background_line,
                      densitometric_area,
                      line_points,
                      profile_along,
                      translate_line,
                      vessel_edges,
)
from .run import DensitometrySink, run_densitometry

__all__ = ["DensitometrySink", "background_line", "densitometric_area", "line_points", "profile_along",
           "run_densitometry", "translate_line", "vessel_edges"]
