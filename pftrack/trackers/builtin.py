"""The built-in trackers, as a table the registry reads on first use.

This module only lists; it imports no registry code, so the registry depends on
it and not the other way round.
"""

from __future__ import annotations

from .aniso_meanshift import AnisoMeanShift
from .block_matching import PISCTracker
from .color_pf import ColorPF
from .dssim import DSSIMTracker
from .flow_pf import FlowPF
from .fusion_pf import FusionPF
from .local_motion_pf import LocalMotionPF
from .lk_rls import LKRLS, LKRLSFuzzy
from .keypoint_meanshift import KeypointAMS
from .meanshift import KalmanMeanShift, MeanShift
from .opencv import OPENCV_TRACKERS, CamShift, opencv_available
from .sift_ransac import SiftRansac
from .ssim_pf import SSIMPF, HybridSSIMPF
from .switching import Switching
from .covariance_tracker import CovarianceTracker
from .cotrain_pf import CoTrainPF
from .fs_meanshift import FSMeanShift
from .template import TemplateTracker

_DETECTOR = ("detector",)

#: (name, class, summary, options for ``register``)
BUILTIN: list[tuple[str, type, str, dict]] = [
    ("fusion-pf", FusionPF,
     "pftrack's default: colour PF x background-aware contrast (x optional local motion), gated updates, "
     "loss detection and re-acquisition", {"extra_kwargs": _DETECTOR}),
    ("color-pf", ColorPF, "Adaptive colour-based particle filter (Nummiaro, Koller-Meier & Van Gool 2003)",
     {"extra_kwargs": _DETECTOR}),
    ("local-motion-pf", LocalMotionPF,
     "Colour particle filter fused with a local-motion (optical-flow) likelihood (Kristan et al. 2009)",
     {"extra_kwargs": _DETECTOR}),
    ("flow-pf", FlowPF,
     "Colour PF driven by optical flow: HSV histograms, EMD, template subspace, KLT motion energies, "
     "detection/tracking switching (Tung & Matsuyama)", {"extra_kwargs": _DETECTOR}),
    ("ssim-pf", SSIMPF,
     "Particle filter with a structural-similarity (SSIM) likelihood against a fixed reference patch; also runs "
     "the colour / edge / colour+edge cues of its comparison (book ch. 2)", {}),
    ("dssim", DSSIMTracker, "Deterministic gradient ascent on SSIM with +-5 % scale search (book ch. 2, Table 3)", {}),
    ("hybrid-ssim-pf", HybridSSIMPF,
     "SSIM particle filter whose particles are moved by DSSIM, with mixture-proposal weights (book ch. 2, Table 4)",
     {}),
    ("template", TemplateTracker,
     "Exhaustive template matching around the last position with one of six criteria (SSD, correlation, NCC, "
     "SAD, morphological correlation, mutual information), window enlarged on poor matches (book ch. 14)", {}),
    ("pisc", PISCTracker,
     "Block matching on peripheral increment sign codes: 9x9 blocks, common sub-pixel displacement anchored to "
     "the first frame's blocks, insensitive to monotonic brightness change (book ch. 1)", {}),
    ("fs-meanshift", FSMeanShift,
     "Mean shift on the back-projection of the two most discriminative of 9 colour/orientation/grey features, "
     "reselected online by Collins' variance ratio (the second by the pair's joint histogram), the mode refined on "
     "the Bhattacharyya coefficient, similarity-weighted model update (book ch. 6)", {}),
    ("keypoint-ams", KeypointAMS,
     "Hybrid of SIFT-RANSAC and anisotropic mean shift: the candidate (A, B or their rho-weighted mix) with the "
     "highest Bhattacharyya coefficient, reference learned from the best stable frame every 25 (book ch. 5)", {}),
    ("sift-ransac", SiftRansac,
     "SIFT foreground/background point sets matched by ratio test, RANSAC similarity, weighted point maintenance "
     "(book ch. 5, Tracker A)", {}),
    ("anisotropic-meanshift", AnisoMeanShift,
     "Mean shift with a full bandwidth matrix: location and Sigma steps, rotated box from its eigenvectors "
     "(book ch. 5, Tracker B)", {}),
    ("switching", Switching,
     "fs-meanshift locally, switched to a global foreground-covariance search (Log-Euclidean) on occlusion, sudden "
     "motion or distraction; lost when the global search finds nothing like the target (book ch. 6)", {}),
    ("covariance", CovarianceTracker,
     "Region-covariance matching over the whole frame (coarse to fine, 3 scales), Log-Euclidean distance and "
     "mean model update (book ch. 6; Porikli, Tuzel & Meer)", {}),
    ("lk-rls", LKRLS,
     "Lucas-Kanade points whose velocity is gated against an RLS AR(2) prediction, so they are carried through "
     "occlusions; box by median displacement and scale, lost when most points are predicted (book ch. 7)", {}),
    ("lk-rls-fuzzy", LKRLSFuzzy,
     "lk-rls with the gate gain k set every frame by the chapter's fuzzy controller (book ch. 7)", {}),
    ("cotrain-pf", CoTrainPF,
     "Particle filter on co-trained online real-AdaBoost confidence maps (colour and LTP texture views, opened "
     "and fused), SEIR evolutionary resampling, retraining from the box's core when confident (book ch. 3)", {}),
    ("meanshift", MeanShift, "Mean shift on kernel colour histograms, scale by best rho among ±5 % (Comaniciu et al.)",
     {"family": "baseline"}),
    ("kalman-meanshift", KalmanMeanShift, "Mean shift started from a Kalman prediction (Comaniciu & Ramesh)",
     {"family": "baseline"}),
    ("camshift", CamShift, "OpenCV CamShift on the hue back-projection (Bradski)", {"family": "baseline"}),
]

_SUMMARIES = {
    "csrt": "OpenCV CSRT (discriminative correlation filter with channel and spatial reliability)",
    "kcf": "OpenCV KCF (kernelized correlation filter)",
    "mil": "OpenCV MIL (multiple-instance learning)",
    "mosse": "OpenCV legacy MOSSE (minimum output sum of squared error filter)",
    "medianflow": "OpenCV legacy MedianFlow (forward-backward Lucas-Kanade)",
    "tld": "OpenCV legacy TLD (tracking-learning-detection)",
}
for _name, _cls in OPENCV_TRACKERS.items():
    _kind = _name.split("-", 1)[1]
    BUILTIN.append((_name, _cls, _SUMMARIES[_kind],
                    {"family": "opencv", "available": (lambda k=_kind: opencv_available(k))}))
