"""Graph-cut tracking with segmentation masks (book ch. 9).

- :mod:`.graphcut` — the energy's terms, temporal seeding, hard seeds, the max-flow/min-cut (pure functions);
- :mod:`.tracker` — the ``graphcut`` tracker (mask in ``info["mask"]``), registered from here.
"""

from .graphcut import (
           color_bins,
           color_hist,
           energy,
           graph_size,
           hard_capacity,
           min_cut,
           nlink_weights,
           seed_maps,
           tlink_caps,
)

__all__ = ["color_bins", "color_hist", "energy", "graph_size", "hard_capacity", "min_cut", "nlink_weights", "seed_maps",
           "tlink_caps"]
