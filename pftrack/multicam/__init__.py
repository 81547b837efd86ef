"""Several cameras: brightness transfer functions, appearance (the chapter's channel histograms and joint colour
histograms) and hand-over between disjoint views (book ch. 11)."""

from .appearance import FEATURES, region_histograms, similarity, similarity_matrix
from .btf import apply_btf_hist, apply_btf_image, btf_from_hists, cbtf, mbtf
from .handover import (
           HISTOGRAMS,
           TrackAppearance,
           cooccur_threshold,
           describe_tracks,
           fit_btf,
           link_tracks,
           new_threshold,
           similarities,
)
from .joint import joint_histogram, joint_similarity_matrix, push_joint

__all__ = ["FEATURES", "HISTOGRAMS", "TrackAppearance", "apply_btf_hist", "apply_btf_image", "btf_from_hists",
           "cbtf", "cooccur_threshold", "describe_tracks", "fit_btf", "joint_histogram", "joint_similarity_matrix",
           "link_tracks", "mbtf", "new_threshold", "push_joint", "region_histograms", "similarities", "similarity",
           "similarity_matrix"]
