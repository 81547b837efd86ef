"""Parameters of ``flow-pf`` (Tung & Matsuyama, ``shared/seeds/003_*.txt``; docs/flow-pf.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..params import Params, param


@dataclass(frozen=True, kw_only=True)
class FlowPFParams(Params):
    """Parameters of ``flow-pf``; defaults from Tung & Matsuyama §5 where given."""

    n_particles: int = param(200, ge=1, le=1_000_000, doc="P, the number of particles (§5: 200).")
    bins: int = param(10, ge=2, le=256, doc="N_h = N_s = N_v, bins of each of the three histograms (§5: 10).")
    kernel_levels: int = param(2, ge=1, le=16, doc=(
        "1: plain counts over the window (Eq. 5 as printed); L > 1: the mean of L nested boxes' histograms, a "
        "kernel density estimate weighting the centre more (the text calls q a kernel density estimate). 2 was "
        "selected on the dev sequences plus synthetic scenes (docs/flow-pf.md)."))
    templates: int = param(5, ge=1, le=1000, doc="k, the size of the colour-model subspace (§5: 5).")
    sigma2: float = param(0.1, gt=0, doc="sigma^2 of the likelihood exp(-E / sigma^2) (Eq. 4; §5: 0.1).")
    anchor: bool = param(True, doc=(
        "Keep the initial colour model in the subspace besides the last k - 1 responses (the drift correction of "
        "Matthews et al.'s template update problem); False is the paper's subspace of the last k responses."))
    distance: Literal["emd", "bhattacharyya"] = param("emd", doc=(
        "Colour distance D: the Earth Mover's Distance (§4.3), or the Bhattacharyya distance sqrt(1 - rho) "
        "(the ablation)."))
    grey_value_only: bool = param(True, doc=(
        "On grey input (the first frame's channels equal) the colour distance is V's alone: hue and saturation "
        "are 0 everywhere there (proposed; the paper's sequences are in colour)."))
    grey_bins: int = param(20, ge=0, le=256, doc=(
        "Bins of the histograms on grey input, where V alone is compared (grey_value_only); 0: `bins`. EMD is in "
        "bins, so finer bins also sharpen the likelihood and the gates. 20 chosen on the tune split's 64 grey "
        "sequences (docs/flow-pf.md): mean AUC 0.435 against 0.379 with 10, re-acquired 10 of 41 against 6, "
        "false-lost 0.033 against 0.005 (14: 0.412; 32: 0.437 with false-lost 0.065)."))
    motion: bool = param(True, doc="Add the motion energies E_m and E_d (§4.4); False for the ablation.")
    motion_weight: float = param(0.5, ge=0, doc=(
        "alpha of E_m = alpha ||x - y~|| per window size: a particle one window away from the flow-predicted "
        "position pays this energy. The paper tunes alpha to the frame size; per window keeps it scale-free. 0.5 was "
        "selected on the dev sequences plus synthetic scenes (docs/flow-pf.md)."))
    drift_weight: float = param(0.0, ge=0, doc=(
        "beta of E_d = beta C (Eq. 11), C in [0, 1] the share of a particle's features not among the tracked ones. "
        "0 by default: with the gated subspace update it no longer helped on the dev or synthetic sequences "
        "(docs/flow-pf.md); 0.2 was the best non-zero value."))
    position_noise: float = param(0.15, ge=0, le=10, doc="Std of the position noise, fraction of the window size.")
    velocity_noise: float = param(0.05, ge=0, le=10, doc="Std of the velocity noise, fraction of the window size.")
    klt_window: int = param(15, ge=3, le=101, doc="KLT window (px).")
    klt_levels: int = param(3, ge=1, le=6, doc="KLT pyramid levels.")
    max_features: int = param(300, ge=1, le=100_000, doc=(
        "Shi-Tomasi features per frame in the search region (the strongest, on a lattice; lambda_min > 1e-3)."))
    search: float = param(1.0, ge=0, le=10, doc=(
        "The features are detected in the previous window widened by this many window sizes (plus the last "
        "displacement) on every side: the region the particles reach."))
    flow_tolerance: float = param(1.0, gt=0, le=100, doc=(
        "A feature belongs to the tracked set Y_t when its displacement differs from the target's median "
        "displacement by at most this (px) plus 20 % of that displacement."))
    min_tracked: int = param(3, ge=1, le=10_000, doc=(
        "Fewest tracked features for a flow prediction y~; with fewer the particles move at constant velocity and "
        "E_m is left out."))
    update_distance: float = param(0.3, gt=0, doc=(
        "The estimate's model joins the subspace only when its colour distance to the nearest template is at most "
        "this (EMD, bins; a detection's always does) — the gated update of Nummiaro et al. applied to the subspace, "
        "so that a drifting estimate does not teach the subspace the background. The paper adds every frame's "
        "(set a large value); 0.3 was selected on the dev sequences plus synthetic scenes (docs/flow-pf.md)."))
    lost_distance: float = param(1.5, gt=0, doc=(
        "Report lost when the colour distance of the estimate to the nearest template exceeds this (bins for EMD; "
        "loss_test 'distance')."))
    loss_test: Literal["distance", "likelihood"] = param("distance", doc=(
        "'distance': lost while the estimate's colour distance d exceeds lost_distance, state.score = 1 / (1 + d). "
        "'likelihood': the colour PFs' two-class test (pftrack.filtering.loss) of the score 1 / (1 + d) against the "
        "target's own score history and the upper tail of the scores of background boxes of its size, on a grid "
        "away from the estimate, every background_every frames; lost after 3 frames below, found again above a "
        "margin, state.score its confidence. The tracks are the same either way (the grid is fixed)."))
    background_every: int = param(10, ge=1, le=1000, doc=(
        "Frames between two background statistics of the 'likelihood' loss test."))
    detector_min_iou: float = param(0.0, ge=0, le=1, doc=(
        "A detection replaces the response only if it overlaps the estimate by more than this (any overlap by "
        "default), so a detector does not jump between objects."))
    lost_search: Literal["off", "frame"] = param("off", doc=(
        "While lost, look for the target over the whole frame (pftrack's addition; pftrack.trackers.frame_search): "
        "boxes of its size on a grid of lost_search_step windows, scored by the particles' colour distance; the "
        "best one, when within lost_search_distance and nearer the models than the estimate, re-centres the "
        "particles after lost_search_frames frames in one place. 'off': the paper's filter, which finds a target "
        "only where its particles wait."))
    lost_search_distance: float = param(0.3, gt=0, doc=(
        "Largest colour distance (EMD bins, as lost_distance) of a whole-frame candidate the search takes."))
    lost_search_ratio: float = param(0.5, gt=0, le=1, doc=(
        "A whole-frame candidate is taken only when its distance is at most this fraction of the best distance at "
        "least one box away (a uniqueness test: among several look-alikes none is taken)."))
    lost_search_frames: int = param(2, ge=1, le=100, doc=(
        "Consecutive frames the best candidate must pass the gate within half a window of the frame before."))
    lost_search_step: float = param(0.25, gt=0, le=4, doc=(
        "Grid step of the whole-frame search, a fraction of the window size (the mean of the box's sides)."))
