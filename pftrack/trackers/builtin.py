"""Registration of the built-in trackers (imported lazily by the registry)."""

from __future__ import annotations

from .color_pf import ColorPF
from .registry import register

register("color-pf", ColorPF,
         "Adaptive colour-based particle filter (Nummiaro, Koller-Meier & Van Gool 2003)",
         extra_kwargs=("detector",))
