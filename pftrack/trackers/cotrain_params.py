"""Parameters of ``cotrain-pf`` (book ch. 3, ``shared/book/ch03.md``; docs/cotrain.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..params import Params, param


@dataclass(frozen=True, kw_only=True)
class CoTrainPFParams(Params):
    """Parameters of ``cotrain-pf`` (ch03.md §2; values the text leaves open are proposed there or selected
    on the tune split, docs/cotrain.md)."""

    n_particles: int = param(300, ge=1, le=100_000, doc="N (ch. 3's experiments: 300, L2647).")
    resampler: Literal["seir", "systematic", "multinomial"] = param("seir", doc=(
        "'seir': sequential evolutionary importance resampling (Algorithm 3, Eqs. 8-10); 'systematic' or "
        "'multinomial': plain SIR resampling every frame (the chapter's comparison)."))
    seir_target: float = param(0.8, gt=0, le=1, doc="N_thr / N: SEIR loops while N_eff < N_thr (ch03.md §2).")
    seir_max_loops: int = param(10, ge=0, le=100, doc="T_max of Algorithm 3 (ch03.md §2).")
    mutation: float = param(0.5, ge=0, le=10, doc="lambda of Eq. 10, as a multiple of the random-walk std.")
    position_noise: float = param(0.15, gt=0, le=5, doc=(
        "sigma_rw of Eq. 4, as a fraction of the box's mean side (ch03.md §2: 0.15)."))
    scale_noise: float = param(0.005, ge=0, le=1, doc=(
        "Std of the log-scale random walk (the (x, y, s) extension, ch03.md P10). Small: the map is learned "
        "from the box, so a fast-moving size feeds back into what is learned (tune split, docs/cotrain.md)."))
    likelihood: Literal["contrast", "window"] = param("contrast", doc=(
        "'window': Eq. 13, the window sum of max(conf, 0) times the gate (the chapter's); 'contrast': the "
        "fraction of fused-positive pixels in the box minus that in the ring around it, as a log-likelihood "
        "scaled by contrast_gain, times the gate (peaked in position and size; docs/cotrain.md)."))
    fusion: Literal["vote", "sum"] = param("sum", doc=(
        "How the two opened maps are fused for the likelihood: 'vote' (Algorithm 2: object only where both "
        "classifiers agree, the contrast counts positive pixels) or 'sum' (the two views as independent "
        "evidence: log-odds conf_c + conf_t, the contrast averages the posterior sigmoid(conf_c + conf_t))."))
    forgetting: float = param(1.0, gt=0, le=1, doc=(
        "beta: the weak learners' block counts are multiplied by beta once per retraining (ch03.md P4: 1 in "
        "the text)."))
    contrast_gain: float = param(20.0, gt=0, le=1000, doc="Log-likelihood per unit of contrast ('contrast').")
    inner: float = param(0.6, gt=0, le=1, doc=(
        "The contrast's inside term is the map's mean over the box scaled by this factor (its centre): the "
        "positives are learned from the box's core, so the map covers less than the box, and a whole-box mean "
        "would pull the box's size down to the map's extent."))
    ring: float = param(0.25, gt=0, le=2, doc="Width of the contrast ring, as a fraction of the box per side.")
    gate_sigma: float = param(0.5, ge=0, le=20, doc=(
        "sigma_g of the Gaussian gate g(X; mu, sigma_g) of Eq. 13, as a multiple of the box's larger side "
        "(ch03.md §2: 0.5); mu is the previous estimate. 0 disables the gate."))
    anchor: float = param(0.5, ge=0, le=1, doc=(
        "Weight of a frozen copy of the first frame's classifiers in each view's confidence (0: the chapter's "
        "purely online maps). 0.5, selected on the tune split: 0.3-0.85 all gave 0.44-0.45 mean AUC over its 15 "
        "real and grey sequences, 0 and 1 gave 0.42 (docs/cotrain.md)."))
    margin: float = param(0.5, ge=0, le=5, doc="Candidate-region margin m on each side, in box sizes (ch03.md §2).")
    work_area: int = param(1600, ge=100, le=1_000_000, doc=(
        "The candidate region is resampled so that the target covers about this many pixels (never enlarged): "
        "the cost per frame does not grow with the target."))
    n_selectors: int = param(10, ge=1, le=200, doc="Selectors per classifier (Algorithm 1; ch03.md §2: 10).")
    colour_blocks: int = param(32, ge=2, le=256, doc="Blocks per colour feature (ch03.md §2: 32).")
    ltp_t: float = param(5.0, ge=0, le=255, doc="LTP threshold t of Eq. 2 (grey levels; ch03.md §2: 5).")
    texture: Literal["pairs", "radii"] = param("pairs", doc=(
        "The texture view on colour input: 'pairs', the chapter's nine cross-channel LTP_{8,1} codes; 'radii', "
        "LTP codes of the grey image at radii 1-3 and thresholds t/2, t, 2t (the grey-input set)."))
    grey_features: Literal["auto", "on", "off"] = param("auto", doc=(
        "On grey input the chapter's 13 features collapse (R = G = B = Y; the nine channel pairs give one LTP "
        "code). 'auto' switches to the grey set when the first frame has no colour: Y, two smoothed Y, the "
        "gradient magnitude, and LTP codes at radii 1-3 and thresholds t/2, t, 2t (cues.boosting.grey_features)."))
    eps: float = param(1.0, gt=0, le=100, doc="epsilon of the weak learners' log-odds (ch03.md §2: 1.0).")
    error_weighting: Literal["confidence", "count"] = param("confidence", doc=(
        "Error accumulators weighted by |h| (the text's reading) or counted (Grabner)."))
    replace: Literal["update", "sample"] = param("update", doc=(
        "Replace each selector's worst weak learner once per frame ('update', ch03.md P3) or after every "
        "sample (the text's literal rule)."))
    opening: int = param(3, ge=1, le=15, doc="Side of the grey-level opening of each map (ch03.md §2: 3).")
    label_mode: Literal["fused", "cross", "blob", "self"] = param("fused", doc=(
        "Positives of each retraining, inside the core of the estimated box: 'fused' (both classifiers learn "
        "the pixels the fused map calls object, Algorithm 2), 'cross' (Blum & Mitchell co-training: each "
        "learns the pixels the other one calls object; a blind view then starves the other), 'blob' (the "
        "most confident half of the fused map's best blob, the text's rule), 'self' (the whole core)."))
    label_confidence: float = param(0.5, ge=0, lt=1, doc=(
        "label_mode='fused': a core pixel is a positive when the object map exceeds this (0.5: the fused "
        "decision)."))
    core: float = param(0.6, gt=0, le=1, doc="Positives come from the ellipse of this fraction of the box.")
    max_samples: int = param(300, ge=10, le=100_000, doc="Positives and negatives per classifier per frame (cap).")
    min_negatives: int = param(30, ge=0, le=100_000, doc=(
        "Negatives per retraining: as many as the positives, at least this many (class balance)."))
    calibrate: bool = param(True, doc=(
        "Re-centre each classifier's decision at every retraining: the offset halfway between the median "
        "confidence of the positives and of the negatives just learned (not in the chapter, whose sign rule "
        "leaves most of a target negative after the first frame; docs/cotrain.md)."))
    init_passes: int = param(3, ge=1, le=20, doc="Training passes over the first frame (ch03.md §2: 3).")
    update_gate: float = param(0.25, ge=0, le=1, doc=(
        "Retrain only when the estimate's contrast is at least this fraction of the median of the last 10 "
        "accepted contrasts (ch03.md §2's acceptance rule on A(B*), on the contrast)."))
    lost_gate: float = param(0.15, ge=0, le=1, doc=(
        "A frame counts as a miss when the contrast is below this fraction of the running median."))
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive misses before lost is raised.")
    lost_spread: float = param(2.0, ge=1, le=10, doc="Random-walk std multiplier while lost (re-acquisition).")
    scale_search: Literal["ncc", "none"] = param("none", doc=(
        "How the box's size follows the target. 'none': the particles' scale alone. 'ncc': after the filter's "
        "estimate, the sizes 1/(1+scale_step), 1 and 1+scale_step around it are compared with grey reference "
        "patches by zero-mean NCC (DSST-style, cues.scale_search), and the best moves the estimate and the "
        "particles. The contrast of the object map is flat over a range of sizes (the map covers the learned "
        "core), so on its own the size drifts. 'ncc' gained 0.014 mean AUC on the tune split and lost on the "
        "report split (docs/cotrain.md), so it is an option, not the default."))
    colour_weight: float = param(1.5, ge=0, le=100, doc=(
        "Weight of a kernel colour histogram term in each particle's log-likelihood: colour_weight * "
        "-(1 - rho) / (2 colour_sigma^2), rho the Bhattacharyya coefficient of the particle's ellipse with the "
        "model (color-pf's cue, Nummiaro et al. Eq. 10; intensity x orientation on grey input). Not in the "
        "chapter. 0: the object map alone. 1.5 selected on the tune split, 6 seeds: 1, 1.5 and 2 gave 0.559, "
        "0.571 and 0.569 mean AUC over its real, grey and synthetic sequences, 0 gave 0.516 (docs/cotrain.md)."))
    colour_sigma: float = param(0.1, gt=0, le=10, doc="sigma of the colour term (color-pf's default).")
    colour_pixels: int = param(400, ge=0, le=1_000_000, doc=(
        "The colour term samples each ellipse on a lattice of at most about this many pixels (0: every pixel; "
        "color-pf's max_pixels)."))
    colour_rate: float = param(0.05, ge=0, le=1, doc=(
        "The colour model is blended with the estimate's histogram at this rate on frames that pass update_gate."))
    scale_step: float = param(0.05, gt=0, le=0.5, doc="Relative size step of the NCC scale search per frame.")
    scale_margin: float = param(0.04, ge=0, le=1, doc=(
        "A size other than the current one is taken only when its NCC beats the current size's by more than this "
        "(tune split: 0.01, 0.02, 0.03 and 0.04 tried; docs/cotrain.md)."))
    scale_interpolate: bool = param(False, doc=(
        "The size between the three compared ones: the vertex of the parabola through their NCC in log-scale "
        "(cues.scale_search.vertex_ratio), so that noise moves the size by a fraction of a step. Tried on the tune "
        "split and not kept: the fractional steps drifted (docs/cotrain.md)."))
    scale_contrast_tol: float = param(0.02, ge=-1, le=2, doc=(
        "A new size is taken only when the object map's contrast at it is at least the current size's minus this "
        "(-1: not checked). The contrast is flat over the sizes that fit the map and falls for a box far too large "
        "or too small, so the NCC chooses within the sizes the map allows."))
    scale_rate: float = param(0.05, ge=0, le=1, doc=(
        "Blending rate of the scale search's running grey reference, on frames that pass update_gate (the first "
        "frame's patch is kept as a second reference)."))
    lost_search: Literal["off", "frame"] = param("frame", doc=(
        "While lost, look for the target over the whole frame (pftrack's addition; pftrack.trackers.frame_search): "
        "ellipses of the box's size on a grid of lost_search_step windows, scored by the colour term's coefficient "
        "rho; the best one, when 1 - rho is within lost_search_distance, below the estimate's, at most "
        "lost_search_ratio times the best 1 - rho at least one box away, and in one place for lost_search_frames "
        "frames, moves the particles and the box there (the best and the runner-up refined on a finer grid). "
        "'off': the particles only spread about where the target was lost. 'frame' chosen under "
        "docs/rules/cotrain_frame_search_confirm_rule.txt: fresh synthetic scenes mean AUC 0.699 against 0.646, "
        "re-acquired 97 against 83 of 150 with the tune views and windows (docs/cotrain.md). Needs the colour term "
        "(colour_weight > 0)."))
    lost_search_distance: float = param(0.3, gt=0, le=1, doc=(
        "Largest 1 - rho (the colour term's Bhattacharyya coefficient) of a whole-frame candidate the search takes."))
    lost_search_ratio: float = param(0.5, gt=0, le=1, doc=(
        "A whole-frame candidate's 1 - rho must be at most this fraction of the best one at least one box away."))
    lost_search_frames: int = param(2, ge=1, le=100, doc=(
        "Consecutive frames the best candidate must pass the gates within half a window of the frame before."))
    lost_search_exit: bool = param(False, doc=(
        "When the last sure box lay within half its size of an edge of the frame (the target left through it), "
        "the whole-frame search keeps to the band within 1.5 box sizes of that edge, where it comes back. Off: it "
        "failed its rule on the tune views (pooled lost recall 0.406 against 0.413; docs/cotrain.md)."))
    lost_search_resident: int = param(0, ge=0, le=1000, doc=(
        "When the last sure box lay within half its size of an edge of the frame (the target left through it), the "
        "grey frames of the last lost_search_resident search frames are kept, and a candidate about to be taken is "
        "refused when its box, traced back through them, stayed inside the view on every one (another object that "
        "was in view all the while; frame_search.Residents). 0: off; 15 failed its rule on the tune views' pooled "
        "lost recall (0.428 against 0.413, bar +0.02; docs/cotrain.md)."))
    lost_search_step: float = param(0.25, gt=0, le=4, doc=(
        "Grid step of the whole-frame search, a fraction of the window (the mean of the box's sides)."))
