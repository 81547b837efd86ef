"""Several cameras: brightness transfer functions, appearance and hand-over between disjoint views (book ch. 11)."""

from .appearance import FEATURES, region_histograms, similarity, similarity_matrix
from .btf import apply_btf_hist, apply_btf_image, btf_from_hists, cbtf, mbtf
from .handover import (
           TrackAppearance,
           cooccur_threshold,
           describe_tracks,
           fit_btf,
           link_tracks,
           new_threshold,
)

__all__ = ["FEATURES", "TrackAppearance", "apply_btf_hist", "apply_btf_image", "btf_from_hists", "cbtf",
           "cooccur_threshold", "describe_tracks", "fit_btf", "link_tracks", "mbtf", "new_threshold",
           "region_histograms",
           "similarity",
           "similarity_matrix"]
