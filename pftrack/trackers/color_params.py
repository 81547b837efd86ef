"""Parameters shared by the colour particle filters (``color-pf``, ``fusion-pf``, ``local-motion-pf``).

Each field cites the equation of Nummiaro et al. (``shared/seeds/004_*``) it comes
from, or says that the paper leaves it open and what raising or lowering it does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..cues.histogram_cue import check_gray_bins
from ..errors import ParameterError
from ..params import param
from .color_feature_params import ColorFeatureParams


@dataclass(frozen=True, kw_only=True)
class ColorModelParams(ColorFeatureParams):
    """Colour model, weighting, model update and appearance-condition parameters shared by the colour PFs (the
    sample count and the features come first, from
    :class:`~pftrack.trackers.color_feature_params.ColorFeatureParams`)."""

    kernel: Literal["nummiaro", "epanechnikov"] = param("nummiaro", doc=(
        "Pixel weighting inside the ellipse: 'nummiaro' is k(||y-x||/a) = 1 - r^2 with "
        "a = sqrt(Hx^2 + Hy^2) (Eqs. 2-3); 'epanechnikov' normalises r by the ellipse itself."))
    max_pixels: int = param(1500, ge=0, le=10_000_000, doc=(
        "Speed bound for large targets: an ellipse with more pixels than this is sampled on a regular "
        "lattice (pitch ceil(sqrt(area / max_pixels)), anchored to the image grid) instead of at every "
        "pixel. 1500 leaves targets up to ~44x44 px exact; measured on the dev set, 0 (every pixel, Eq. 3 "
        "literally), 4000 and 1500 give the same accuracy (docs/color-pf.md)."))
    sigma: float = param(0.1, gt=0, le=10, doc=(
        "sigma of the weighting pi ∝ exp(-(1 - rho)/(2 sigma^2)) (Eq. 10). Smaller: sharper weights, "
        "faster collapse onto the best sample; larger: flatter posterior."))
    adaptive_sigma: bool = param(False, doc=(
        "Book ch. 4 variant: set sigma^2 = d_min^2 / 2 each frame from the smallest Bhattacharyya "
        "distance among the samples, so the likelihood adapts to how well the best sample matches."))
    min_half_axis: float = param(2.0, ge=0.5, le=1000, doc="Smallest half-axis a sample may have (pixels).")
    resampler: Literal["multinomial", "systematic", "stratified", "residual", "seir"] = param("multinomial", doc=(
        "Selection step (Fig. 2, step 1): 'multinomial' is the paper's cumulative sums + binary search. 'seir' "
        "adds book ch. 3's sequential evolutionary importance resampling after the weighting (copy, crossover, "
        "mutation, selection of N from 3N while N_eff < 0.8 N, at most 10 loops; pftrack.filtering.seir), then "
        "selects systematically."))
    seir_mutation: float = param(0.5, gt=0, le=10, doc=(
        "With resampler='seir': the mutation std lambda (Eq. 10) as a multiple of the position and size noise."))
    resample_ess: float = param(1.0, gt=0, le=1, doc=(
        "Resample when N_eff < resample_ess * N. 1 resamples every frame, as in Fig. 2."))
    alpha: float = param(0.05, ge=0, le=1, doc=(
        "alpha of the model update q <- (1 - alpha) q + alpha p_E[S] (Eq. 12); 0 disables adaptation. "
        "The paper leaves it open; larger adapts faster but drifts more easily."))
    update_gate: Literal["confident", "threshold", "lambda", "never"] = param("confident", doc=(
        "When to update the model: 'confident' updates while the loss test is sure the estimate is on the "
        "target (LLR > reacquire_margin), so the update and the loss test never disagree under a lighting "
        "drift; 'threshold' is Eq. 11 (pi_E[S] > pi_T); 'lambda' is the book's ch. 4 running gate "
        "lambda = (1 - alpha_u) lambda + alpha_u pi_est; 'never' keeps the first model."))
    update_rho: float = param(0.8, ge=0, le=1, doc=(
        "pi_T of Eq. 11, stated as the Bhattacharyya coefficient rho_T it corresponds to: since pi (Eq. 10) "
        "increases with rho, pi_E > pi_T <=> rho_E > rho_T. Stated on rho so it does not move with sigma."))
    lambda_rate: float = param(0.1, gt=0, le=1, doc="alpha_u of the 'lambda' update gate (book ch. 4).")
    kickoff_fraction: float = param(0.1, gt=0, le=1, doc=(
        "b, the kick-off fraction (§6): tracking starts when more than b*N samples satisfy the "
        "appearance condition, and the target is lost when fewer do for lost_frames frames."))
    appearance_k: float = param(2.0, ge=0, le=10, doc=(
        "The appearance condition rho > mu + k sigma_bg (Eq. 15; k = 2 gives ~95 % confidence that a "
        "sample is not background)."))
    lost_frames: int = param(3, ge=1, le=1000, doc=(
        "'A couple of frames' (§6): consecutive frames of absence evidence before the target is declared "
        "lost. Larger: fewer false alarms, later detection."))
    min_in_frame: float = param(0.0, ge=0, le=1, doc=(
        "Report the target absent (lost, score <= 0.5) while less than this fraction of the estimate's box lies "
        "inside the frame: a target leaving the view still matches on its last visible sliver. The filter tracks "
        "on (no search is started, so it is at the border when the target comes back) and the models do not "
        "learn from those frames. 0: off (default). On the tune split (leave and vanish scenes, real sequences; "
        "docs/robustness.md) fusion-pf's lost recall rose 0.885 -> 0.903 / 0.904 / 0.907 at 0.25 / 0.4 / 0.5 and "
        "its false-lost rate 0.026 -> 0.044 / 0.052 / 0.063, because the synthetic ground truth counts a target "
        "10 % visible as present; for color-pf the false alarms grew more than the recall, so it stays off. "
        "Datasets that mark a target absent once it is mostly out of the frame (TLD) favour about 0.4."))
    enter_extent: int = param(0, ge=0, le=100_000, doc=(
        "A first box touching the frame's edge may hold only the part of a target coming in: for at most this many "
        "frames its extent across that edge, never narrower than the box followed, is measured and reported; once "
        "it has left the edge the tracker restarts from it if 1.25x wider (trackers.entering, cues.extent). 0: off."))
    enter_grey: bool = param(False, doc=(
        "enter_extent on grey input: read the extent on what changed against the first frame, restarting once it is "
        "1.25x the box followed (cues.extent.change_mask). Off: failed docs/rules/enter_extent_grey_rule.txt."))
    edge_share: float = param(0.0, ge=0, le=1, doc=(
        "With loss_test='likelihood': while less than this fraction of the estimate's box lies inside the frame, "
        "the loss test scores it as the in-frame fraction / edge_share of its score plus the rest of the mean score "
        "of the absent hypothesis (per cue): a box sliding out of the view keeps matching on its last sliver, which "
        "is weak evidence; the flag then rises, the search starts (at the edge the target left by, with "
        "reenter_border), and nothing is learned from the sliver. 0: off (default; 0.5 for fusion-pf)."))
    acquire_in_frame: float = param(0.0, ge=0, le=1, doc=(
        "With loss_test='likelihood', while lost: the search's best candidate is not acquired while less than this "
        "fraction of its box lies inside the frame; the search waits (no other candidate is taken on that frame). "
        "At the view's edge a sliver of a box can match the legs or shadow of someone walking along the edge, or "
        "ground the model was learned with; a target coming back is taken once half of it is in. "
        "0: off (default here; 0.5 for color-pf and fusion-pf)."))
    acquire_early_frames: int = param(0, ge=0, doc=(
        "With acquire_in_frame, after an exit (reenter_border): for this many frames after the search began, a "
        "candidate needs only acquire_in_frame_early of its box inside the frame. A target that has just left "
        "through an edge is the likeliest thing to show there again, part of it first. 0: off (default)."))
    acquire_in_frame_early: float = param(0.25, ge=0, le=1, doc=(
        "The in-frame share asked of a candidate in the first acquire_early_frames frames after an exit."))
    acquire_sliver_frames: int = param(0, ge=0, le=1000, doc=(
        "With acquire_in_frame: a best candidate that passes the loss test with too little of its box inside the "
        "frame is not refused for that when the best candidates of the K - 1 search frames before it did the same, "
        "each overlapping the next (IoU >= 0.3 within the frame, at most 2 frames apart): a target that stays at "
        "the edge, a sliver of it in view, is there to take. The vetoes still apply. 0: off (default). On the tune "
        "data (docs/rules/acquire_sliver_rule.txt) K = 3 re-acquired 45 of fusion-pf's 60 tune-window returns "
        "against 30, and cost the PETS tune views' pooled lost recall 0.575 -> 0.431 (5: 0.520, 8: 0.550): "
        "other walkers partly in view along a window's edge are found at one place too (docs/robustness.md)."))
    acquire_sliver_llr: float = param(0.0, ge=0, le=1000, doc=(
        "With acquire_in_frame: a best candidate that passes the loss test with too little of its box inside the "
        "frame is not refused for that when its fused log-likelihood ratio (with the position prior, as the "
        "acquisition test computes it) is at least this: a sliver is weak evidence, taken only where it is "
        "unambiguous. The vetoes still apply. 0: off (default; docs/rules/acquire_sliver_llr_rule.txt)."))
    acquire_unique: bool = param(False, doc=(
        "With loss_test='likelihood', while lost: a candidate is not acquired while another one elsewhere in the frame "
        "(beyond two half-axes each way, not the still scene) passes the acquisition test too: two look-alikes, and "
        "the search waits for one to stand alone (Lowe's ratio test; pftrack.trackers.vetoes). False: off."))
    acquire_unique_hold: int = param(0, ge=0, le=10_000, doc=(
        "With acquire_unique: after a frame with two such candidates, none is acquired for this many more frames."))
    acquire_unique_margin: float = param(0.0, ge=0, le=100, doc=(
        "With acquire_unique: m > 0, a rival counts only when its ratio is within m of the candidate's. 0: any."))
    acquire_unique_refine: bool = param(False, doc=(
        "With acquire_unique: a best sample elsewhere that fails is scored again on fixed grids around it (an option "
        "for fusion-pf too: tune views' recall up, re-acquisitions down; docs/robustness.md)."))
    loss_test: Literal["likelihood", "appearance"] = param("likelihood", doc=(
        "'likelihood': the estimate's rho is tested against two distributions, the background's (Eqs. 13-14, "
        "spread floored) and the target's own score history, LLR = log N(rho; mu_t, s_t) - log N(rho; mu_b, "
        "s_b); lost after lost_frames frames with LLR < 0, found again when a candidate has LLR > "
        "reacquire_margin (pftrack.filtering.loss). 'appearance': the paper's test, fewer than b N samples "
        "with rho > mu + k sigma."))
    search_size_frames: int = param(30, ge=0, le=10000, doc=(
        "The size a search looks for: the largest box (by area) the loss test was confident on over the last "
        "this many frames before the loss; 0: the last confident size (the former rule). A target that walks "
        "behind an occluder is followed on its visible part, so the estimate shrinks while the test stays "
        "confident, and the target was searched for, and re-acquired, at that shrunken size. 30 chosen on the "
        "tune split (docs/robustness.md): fusion-pf re-acquired 244 of 300 tune reappearances against 230 "
        "(10 seeds), color-pf 198 against 187; 15 and 45 re-acquired fewer."))
    static_ncc: float = param(0.0, ge=0, le=1, doc=(
        "Background test of the search (pftrack.trackers.static_lookalikes): a candidate that would end the loss "
        "and whose grey patch is found again at the same place (2 px of play), every quarter of it at this "
        "normalised correlation or more, in a frame kept while the target was tracked confidently elsewhere, is "
        "part of the scene (an occluder's edge, clutter), and the search takes its next best candidate. "
        "Abstains on flat patches, and near the target's box on that frame unless the frame kept before it (the "
        "target elsewhere then) answers; with a moving camera nothing matches. Each quarter's correlation is "
        "divided by its ceiling under the camera's noise, measured between that frame and the next confident one. "
        "While tracking, the estimate is tested the same way on every 10th frame (not at the frame's edge): an "
        "estimate that is an unchanged piece of the scene is lost, and the "
        "search starts. 0: off."))
    static_quarters: int = param(4, ge=1, le=4, doc=(
        "With static_ncc: how many of a patch's four quarters (2 x 2; all of the non-flat ones when fewer) must be "
        "found again unchanged for the background test (and the persistence's still test) to call it the scene's; "
        "4 (default): every one. A railing whose top quarter walkers pass over is the scene's by three of them "
        "(docs/rules/static_quarters_rule.txt)."))
    static_leave_refresh: int = param(0, ge=0, le=1000, doc=(
        "With static_ncc: the frame kept for the background test is also replaced as soon as the target's box has "
        "left the one it had on that frame (overlapping it by 10 % of its area or less), at least this many frames "
        "after it, not only every 30 confident frames; the estimate is tested before, as then. Early in a track "
        "the first frame is otherwise the only one kept, and the place the target started from, its background "
        "the first model saw, cannot be tested there. 0 (default): every 30 frames only."))
    probation_llr: float = param(0.0, ge=0, le=50, doc=(
        "Probation after a weak re-acquisition (pftrack.trackers.probation): an acquisition whose loss-test "
        "ratio is below this starts a probation, during which the tracker follows the candidate without "
        "learning from it (models and score histories frozen) while the search goes on beside it; a candidate "
        "elsewhere that passes the acquisition test probation_margin above it takes over. Probation ends on the "
        "first frame whose ratio reaches this, after probation_frames frames, or on a loss. 0: off. Likelihood "
        "loss test only."))
    probation_frames: int = param(30, ge=0, le=100_000, doc="Longest probation, in frames (see probation_llr).")
    probation_interval: int = param(1, ge=1, le=1000, doc=(
        "On probation, the search beside the track runs on every this many frames (its cost: one search each)."))
    probation_lost_llr: float = param(0.0, ge=0, le=100, doc=(
        "t > 0: while on probation (probation_llr) a frame whose fused log-likelihood ratio is below t reports "
        "the target absent (lost, score at most 0.5); the candidate is still followed and the search beside it "
        "goes on. 0: off (a candidate on probation is reported as the target). An option: 5 raised fusion-pf's flag "
        "on more of the frames after real exits among look-alikes, but on grey input also on right re-acquisitions "
        "(docs/robustness.md)."))
    probation_lost_exit_only: bool = param(False, doc=(
        "With probation_lost_llr: only after a loss in which the target left the view through the frame's edge "
        "(reenter_border's exit strip), where a look-alike walking there is the likelier candidate. An option: with "
        "probation_lost_llr=5 it passed fusion-pf's tune rule, but on the report data it lost 2 of 96 "
        "re-acquisitions (docs/robustness.md)."))
    probation_margin: float = param(3.0, ge=0, le=50, doc=(
        "Ratio by which a candidate found beside a track on probation must beat the followed one to take over."))
    persist_frames: int = param(0, ge=0, le=1000, doc=(
        "Re-acquisition by persistence (pftrack.trackers.persistence): after this many searches in a row whose "
        "best candidate stays within one half-axis of the last one (the first within 3 half-axes of where the "
        "target was lost), its histogram calling it the target rather than the background and no cue scoring it "
        "more than persist_z spreads below that cue's history, the tracker starts afresh on it, unless its grey "
        "patch is unchanged since the first of those searches (a still piece of the scene). A target that "
        "changed while lost (a head that turned, a camera that panned) is otherwise refused by every acquisition "
        "test. 0: off; 1 acts as 2 (the still test compares two searches). Likelihood loss test only."))
    persist_z: float = param(2.5, gt=0, le=50, doc="See persist_frames: how far below its history a cue may score.")
    reacquire_margin: float = param(1.0, ge=0, le=20, doc=(
        "Hysteresis of the loss test: LLR a candidate must exceed to end a loss (and, with the 'confident' "
        "gate, for the model to update). Larger: fewer false re-acquisitions on distractors, slower recovery."))
    history_rate: float = param(0.05, gt=0, le=1, doc=(
        "Weight of a new confident score in the target's score history (mean and spread of rho)."))
    history_z: float = param(2.0, gt=0, le=20, doc=(
        "A score more than this many spreads below the target history's mean is not learned, does not update "
        "the model and does not re-acquire. Smaller: stricter re-acquisition, more false 'lost' on fast "
        "appearance change."))
    reacquire_z: float = param(0.0, ge=0, le=20, doc=(
        "With the likelihood loss test: a search candidate more than this many spreads below the target "
        "history's mean does not re-acquire (0: history_z, the learning bound; the fused test of fusion-pf and of "
        "color-pf on grey input has acquire_z instead). An option: 3 for color-pf gained on the synthetic tune "
        "scenes (8 seeds: 472 of 568 re-acquired against 471; 120 more tune scenes: 315 of 363 against 309) but "
        "lost on the tune sequence otb_dragonbaby (10 seeds: 0.483 against 0.498 mean AUC) and lowered lost recall "
        "(docs/robustness.md)."))
    reacquire_llr: float = param(0.0, ge=0, le=30, doc=(
        "With the likelihood loss test (single cue): a search candidate whose ratio reaches this value "
        "re-acquires however far below the target history's mean its score lies (reacquire_z then does not "
        "apply): a target far above the background whose colours changed while it was hidden. 0: off."))
    score_sd_floor: float = param(0.03, gt=0, le=1, doc=(
        "Floor on the spreads of the background and target score distributions, so neither collapses "
        "(grey or flat scenes)."))
    background_positions: int = param(100, ge=4, le=100_000, doc=(
        "At most this many ellipses on a grid over the background give mu and sigma_bg (Eqs. 13-14)."))
    background_interval: int = param(10, ge=0, le=100_000, doc=(
        "Recompute the background statistics every this many frames while tracking (0: only at "
        "initialisation), so they follow the adapting model and a moving camera."))
    search: bool = param(True, doc=(
        "Detect loss with the appearance condition and search for the target (initialisation mode). "
        "False: always track, never report lost."))
    search_particles: int = param(0, ge=0, le=1_000_000, doc=(
        "Samples used while searching; 0 chooses enough to place about four samples per target-sized "
        "cell of the frame (between N and 10 N)."))
    search_keep: float = param(0.1, ge=0, lt=1, doc=(
        "Fraction of search samples drawn from the previous search posterior; the rest are spread "
        "uniformly (stratified) over the frame or the entry regions."))
    search_refine: float = param(0.0, ge=0, le=4, doc=(
        "A second layer of search samples on the same frame, this fraction of the first layer's count: drawn "
        "from the first layer's posterior (likelihood times the position prior) and moved by a quarter of the "
        "target's half-axes, then scored like the others (one layer of annealing). The likelihood peak is "
        "narrower than the target, so a uniform layer seldom lands on it; the refined layer finds its top and "
        "the supporters the acquisition test counts. 0: off."))
    search_predict: float = param(0.5, ge=0, le=1, doc=(
        "Fraction of the new search samples drawn around the position predicted from the target's last "
        "confident velocity (constant-velocity extrapolation, spread growing with the time lost); the rest "
        "are spread over the frame. 0: uniform search only (the paper)."))
    search_interval: int = param(1, ge=1, le=1000, doc=(
        "Once a loss has lasted search_dense frames, search only on every search_interval-th frame; the frames "
        "between report the last search's result (still lost). A target that reappears after a long absence is "
        "found up to search_interval - 1 frames later; the search is most of a lost frame's cost. 1: search "
        "every frame."))
    search_dense: int = param(15, ge=0, le=100_000, doc=(
        "Frames after a loss (or after the start of an automatic initialisation) that are all searched, "
        "whatever search_interval: a target coming out of a short occlusion is looked for on every frame."))
    relit_search: Literal["off", "replace", "max"] = param("off", doc=(
        "While searching on colour input after the light changed (a channel's level more than 5 % away from the "
        "last background refresh while the target was seen), score the samples with the frame's per-channel "
        "gain undone (von Kries): a target whose colours drifted with the light while it was hidden is "
        "re-acquired. 'replace' scores the relit frame only; 'max' the better of relit and raw (twice the "
        "search's cost). Tracking is unchanged (fusion-pf has its own relit_colour)."))
    relit_gain: Literal["frame", "blocks", "still"] = param("frame", doc=(
        "How the relit search reads the light: 'frame', the ratio of the whole frame's channel medians; "
        "'blocks', the median ratio of a 3 x 3 grid of blocks, taken as a change of the light only when two "
        "thirds of the blocks agree with it within 5 % (cues.intensity.light_gain): content passing through "
        "part of the view (cars, walkers in a narrow window) is then not mistaken for light; 'still', the same "
        "over the blocks whose grey layout is unchanged (thumbnail NCC >= 0.8, cues.intensity.still_blocks), "
        "two thirds of all blocks: a moving camera is not mistaken for light either."))
    grey_relit_shift: int = param(0, ge=0, le=8, doc=(
        "k > 0: on grey input the search scores each sample by the best of its grey histogram's coefficients with "
        "the model's intensity bins shifted by -k..k (cues.intensity.shifted_rho): a target whose own light "
        "changed while it was unseen is ranked and acquired. 0 (default): tried on the tune data (docs/robustness.md): "
        "fusion-pf re-acquired 93 against 86 of 136 fresh grey reappearances and 452 against 444 of the 568, but the "
        "grey copy of otb_dragonbaby lost its restarts by persistence (0.322 against 0.421 mean AUC, 10 seeds)."))
    reenter_border: float = param(0.0, ge=0, le=100, doc=(
        "A target that left the view comes back through the border: once the loss is declared with the last "
        "confident position, moved on at the mean displacement of the last confident frames, mostly (over half "
        "its box) outside the frame, the search samples and accepts only candidates whose box lies within this "
        "many target widths "
        "(heights, for the top and bottom edges) of that edge, plus the distance it could have walked in since at "
        "the speed it left with, until the target is re-acquired. Without "
        "it, a person of similar colours elsewhere in the view is acquired the moment the target has gone. "
        "0: off. Not applied with entry regions (init_auto's regions say where targets enter)."))
    reenter_grow: float = param(1.0, ge=0, le=100, doc=(
        "With reenter_border: the strip widens at this many times the speed the target left with, from the start "
        "of the search (0: a fixed strip, which a target coming back must cross). An option: 0 gained on fusion-pf's "
        "synthetic tune scenes but lost a real report sequence whose pedestrian comes back (docs/robustness.md)."))
    reenter_exit_share: float = param(0.5, gt=0, le=1, doc=(
        "With reenter_border: the loss is an exit when less than this share of the box lies inside the frame at the "
        "last confident position moved on at the last confident frames' speed. 0.5: over half outside; higher "
        "values also take an estimate that stayed on the edge as the target slid out for an exit. An option: 0.95 "
        "raised fusion-pf's flag on the PETS views but missed its tune rule on false-lost, and on the report split "
        "lost a pedestrian lost near the edge while still in view (docs/robustness.md)."))
    input_switch: int = param(0, ge=0, le=1000, doc=(
        "Input that turns grey mid-sequence (a camera turning monochrome at dusk): after this many grey frames in a "
        "row, colour features give way to grey ones, started on the grey copy of the last frame where the target "
        "was seen (pftrack.trackers.input_switch); they stay if colour comes back. 0: the features chosen on the "
        "first frame stay (docs/rules/input_switch_rule.txt)."))
    input_switch_return: int = param(0, ge=0, le=1, doc=(
        "With input_switch: when the switch to grey features comes while the target is lost, a copy of the tracker "
        "as it was (colour features, its model, its search) goes on with every frame beside the grey-featured one, "
        "as without the switch; once input_switch colour frames in a row have come, the tracker goes on as that "
        "copy, whatever the grey search found meanwhile, and keeps colour features. The copy costs a second "
        "tracker's time per frame until then. 0: grey features stay after any switch "
        "(docs/rules/input_switch_return_rule.txt)."))
    reenter_memory: int = param(0, ge=0, le=1000, doc=(
        "With reenter_border: the loss is also an exit when the estimate's box was less than half inside the frame "
        "on one of this many tracked frames before the loss was declared (the edge that box was beyond): a tracker "
        "that slid back onto a companion as the target left loses it inside the view, and its last confident "
        "position says no exit. 0: off (docs/rules/exit_memory_rule.txt)."))
    reenter_reach: float = param(0.0, ge=0, le=100, doc=(
        "With reenter_border: the strip widens no deeper than this many target widths (heights, for the top and "
        "bottom edges) from the edge, however long the target has been out; 0: no limit. A look-alike walking in "
        "the view long after the exit lies deep in a strip that has grown over it (docs/robustness.md)."))
    reenter_outward: float = param(0.0, ge=0, le=100, doc=(
        "With reenter_border: a target coming back through the edge it left by moves into the view, not out. A "
        "candidate of the exit strip whose own motion since the previous frame (its patch found again in the "
        "previous frame by normalised correlation) carries it towards that edge faster than this many times the "
        "speed the target left with (at least 1 px/frame) is another object on its way out, and is not acquired. "
        "0: off."))
    reenter_along: float = param(0.0, ge=0, le=100, doc=(
        "With reenter_outward: a candidate of the exit strip moving along the exit edge faster than this many exit "
        "speeds (at least 1 px/frame) and over twice as fast as across it is passing by, not coming back, and is "
        "not acquired; 0: off (docs/rules/reenter_along_rule.txt)."))
    reenter_resident: int = param(0, ge=0, le=10_000, doc=(
        "With reenter_border: a target coming back entered the view since it left. A candidate of the exit strip "
        "traced back (the central part of its box found again frame by frame) over the frames since the search "
        "began, at most this many, with at least 90 % of its box inside the view on every one of them, stayed in "
        "view while the target was out: another object, not acquired. 0: off."))
    reenter_resident_reach: float = param(0.0, ge=0, le=10, doc=(
        "With reenter_resident: the trace back searches at least this many of the candidate's half-widths around "
        "it (besides three exit speeds, at least 8 px), so that a walker faster than the target left is followed; "
        "0: off (docs/rules/resident_reach_rule.txt)."))
    reenter_min_llr: float = param(0.0, ge=0, le=1000, doc=(
        "With reenter_border: while the search is confined to the exit strip, a candidate is acquired only when its "
        "fused log-likelihood ratio (the acquisition test's, log prior included) is at least this; a weaker one is "
        "refused like a vetoed one. 0: off, for both trackers (10, chosen for fusion-pf on the tune data, cost the "
        "report split 8 of its 78 re-acquisitions: docs/robustness.md)."))
    search_prior: float = param(0.0, ge=0, le=1, doc=(
        "Re-acquisition with a position prior: a candidate's ratio gets the log prior odds of its position, "
        "log((1 - e) A N(x; m, s^2) + e), m the constant-velocity prediction from the last confident frame and s "
        "the search spread; e is the chance the target reappears anywhere. A candidate far from where the target "
        "can be needs 1/e times the odds (log(1/e) more in its ratio). 0: off (no prior)."))
    search_prior_cap: bool = param(False, doc=(
        "With search_prior, only penalise (the log prior odds capped at 0): a candidate near the prediction "
        "needs the usual evidence, not less."))
    distractor_frames: int = param(0, ge=0, le=100_000, doc=(
        "Distractor memory (pftrack.trackers.distractors). After a gradual loss (frames of doubt between the "
        "last confident estimate and the loss), a candidate that passes the acquisition test during the first "
        "this many frames of the search but lies beyond the target's reach is another object of its appearance. "
        "The reach is four spreads of search_prior's position model plus the distance covered at the fastest "
        "speed seen, from the prediction and from the last confident position. Such a look-alike is not "
        "acquired; it is remembered and followed, and the search picks its candidate among the other samples, "
        "for up to 6 times this many frames. 0: off."))
    distractor_follow: float = param(1.0, gt=0, le=4, doc=(
        "The distractor memory follows a look-alike to the best search sample within this many target sizes "
        "(half-axes hx + hy) of where it was last seen, plus twice the target's speed for every frame since "
        "(pftrack.trackers.distractors.follow_radius). Smaller: a look-alike passing close to the target coming "
        "back does not hand its place in the memory over to the target."))
    distractor_gradual: Literal["frames", "scores"] = param("frames", doc=(
        "How the distractor memory tells a gradual loss (a target being covered or leaving where it was) from an "
        "abrupt one (a jump, a cut: the target may be anywhere). 'frames': frames of doubt between the last "
        "confident estimate and the loss. 'scores' (likelihood loss test): also when the score was already "
        "falling, below 0.95 on the last confident frame or above 0.05 on the frame after it; only a fall from "
        "sure to absent within one frame is abrupt (pftrack.trackers.distractors.score_gradual)."))
    grey_search_structure: bool = param(False, doc=(
        "With grey_check='fused' on grey input: the search ranks its samples by the same likelihood as the tracked "
        "particles, the histogram's and the structural cue's, instead of the histogram's alone (the candidate it "
        "tests must pass the fused loss test of both)."))
    search_retries: int = param(0, ge=0, le=20, doc=(
        "With the likelihood loss test: a search candidate that would end the loss but is refused by a veto "
        "(reenter_outward, the raw or grey structure check, the distractor memory) gives way to the next best "
        "candidate away from it, tested the same way, up to this many more a frame (pftrack.trackers.vetoes). "
        "0: the frame's search ends with the refusal."))
    acquire_samples: int = param(3, ge=1, le=1_000_000, doc=(
        "With the likelihood loss test: search samples near the best candidate that must pass the appearance "
        "condition before the candidate is tested against the target's history (at most the paper's b N)."))
    search_method: Literal["appearance", "variance"] = param("appearance", doc=(
        "Acquisition test: 'appearance' (Eq. 15 with the kick-off fraction b), or the book's ch. 4 "
        "'variance' test (particle-position variance below variance_threshold)."))
    variance_threshold: float = param(10.0, gt=0, doc=(
        "Book ch. 4: tracking is declared when the weighted variance of the particle positions (px^2, "
        "mean of x and y) falls below this value."))
    detector_interval: int = param(1, ge=1, le=100_000, doc=(
        "While searching with a detector, run it every this many frames."))

    def validate(self) -> None:
        if self.bins and len(self.bins) != 3:
            raise ParameterError(f"parameter 'bins' must have 3 values (one per channel), got {self.bins}")
        check_gray_bins(self.gray_bins)
        if self.denoise_kernel % 2 == 0:
            raise ParameterError(f"parameter 'denoise_kernel' must be odd, got {self.denoise_kernel}")
        if self.histogram_parts > 1 and self.grey_relit_shift > 0:
            raise ParameterError("grey_relit_shift shifts the bins of one-part histograms: use histogram_parts=1")
        if (self.cast_jump > 0 or self.light_jump > 0) and self.color_normalize not in ("none", "still"):
            raise ParameterError(f"cast_jump and light_jump work with color_normalize 'none' or 'still', not "
                                 f"{self.color_normalize!r}")
