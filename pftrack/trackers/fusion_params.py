"""The parameters of ``fusion-pf`` (:mod:`.fusion_pf`): colour-pf's, plus the fusion ingredients, with the
defaults chosen for it and where they were chosen."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..params import param
from .color_pf_params import ColorPFParams

__all__ = ["FusionPFParams"]


@dataclass(frozen=True, kw_only=True)
class FusionPFParams(ColorPFParams):
    """Parameters of ``fusion-pf`` (colour-pf's plus the fusion ingredients)."""

    grey_histogram: Literal["levels", "both"] = param("both", doc=(
        "See ColorModelParams.grey_histogram; with 'both' the quotient image is shared with the structural cue of "
        "grey_structure. 'both' for fusion-pf, chosen with scale_search on the tune data (docs/fusion-pf.md): "
        "8 seeds of the tune reappearance scenes, re-acquired 365 against 345 of 568, lost recall 0.789 against "
        "0.767; grey tune set 0.633 against 0.592 mean AUC, dim tune face proxies 0.872 against 0.727. (An earlier "
        "round had kept 'levels' after seeing the grey report set: the report's real grey copies fell, grey 0.473 "
        "against 0.502.) About 14 % slower on grey input."))
    edge_share: float = param(0.5, ge=0, le=1, doc=(
        "See ColorModelParams.edge_share (off there and for color-pf). 0.5 for fusion-pf, chosen on the tune split "
        "and on real exits, PETS walkers of frames 1-200 seen through four narrower views "
        "(scripts/make_pets_views.py; docs/robustness.md): the highest lost recall whose tune-split mean AUC is "
        "within 0.002 of off and whose false-lost rate stays within 0.05. Views' lost recall (pooled) 0.318 against "
        "0.137 off, split 0.918 against 0.901, false-lost 0.027 against 0.025, mean AUC 0.6923 against 0.6927 (0.3: "
        "0.188 and 0.913; 0.7: mean AUC 0.6906). Report split, run once: lost recall on its five real sequences with "
        "absences 0.804 against 0.681 (mean over the five), real AUC 0.578 against 0.566, re-acquired 74 against 77 "
        "of 96. color-pf's tune gain was smaller and its report run lost (0.632 against 0.750): off there."))
    haze_stretch: float = param(0.0, ge=0, le=8, doc=(
        "See ColorModelParams.haze_stretch. Off for fusion-pf (1.8 for color-pf): under its rule "
        "(docs/rules/haze_stretch_rule.txt) 39 hazy tune copies gained 0.468 against 0.466 mean AUC, +0.015 asked; "
        "the PETS people through haze of 0.6 fell to 0.383 against 0.420. Its structural cue and box contrast "
        "already read a veiled target (on copies through haze of 0.5 and 0.7 it kept 0.55 of its 0.58 on the real "
        "sequences)."))
    light_jump: float = param(0.0, ge=0, le=3, doc=(
        "See ColorModelParams.light_jump. Off for fusion-pf (0.18 for color-pf), not judged: its still view's gain "
        "(color_normalize='still') reads lamps switched on or off (synthetic vanish scenes with the light times 1.3 "
        "or 0.7: mean IoU 0.517 and 0.521 against 0.515 as rendered; docs/rules/sot_light_jump_rule.txt)."))
    camera_motion: bool = param(True, doc=(
        "See ColorPFParams.camera_motion (off for color-pf). On for fusion-pf, chosen on the tune data under a rule "
        "stated before the runs (docs/rules/motion_proposal_tre_rule.txt, docs/robustness-cameras.md): the tune "
        "real sequences from 20 starts each (TRE) 0.624 against 0.609 mean AUC; tune split 0.708 against 0.705 "
        "(real 0.599 against 0.582, grey 0.591 against 0.573, grey + light 0.496 against 0.483, PETS and synthetic "
        "scenes the same), lost recall and re-acquisitions the same; tune stride copies 0.403 against 0.395; windows "
        "and views the same; 0.96x the update rate (0.92x on the real sequences). color-pf lost 12 of the windows' "
        "45 returns and 9 % of its rate: off. Report data, run once after the choice: split 0.717 against 0.713 "
        "(real 0.580 against 0.590, grey 0.538 against 0.507, grey + light 0.498 against 0.443), windows 24 against "
        "26 of 36 returns, TRE 0.623 against 0.629, stride copies 0.536 against 0.506."))
    camera_samples: int = param(176, ge=32, le=4096, doc=(
        "See ColorPFParams.camera_samples (256 there). 176 for fusion-pf, chosen on the tune data under a rule "
        "stated before the runs (docs/rules/camera_samples_rule.txt): every 5th pixel of 854 x 480 instead of every "
        "4th. Tune split 0.712 against 0.708 mean AUC (real 0.612 against 0.599, grey 0.612 against 0.591), windows "
        "52 against 47 of 60 returns, TRE 0.625 against 0.624, stride copies 0.405 against 0.403, pan probe the "
        "same; 1.06x the update rate on the tune real sequences. 128 lost 0.031 on the grey copies."))
    acquire_early_frames: int = param(0, ge=0, doc=(
        "See ColorModelParams.acquire_early_frames. Off for fusion-pf (10 for color-pf): on the tune data it took "
        "12 more of the windows' 60 returns, but the PETS tune views' pooled lost recall fell to 0.511 against "
        "0.575, outside its rule (docs/rules/acquire_early_rule.txt, docs/robustness.md)."))
    reenter_resident: int = param(15, ge=0, le=10_000, doc=(
        "See ColorModelParams.reenter_resident (off there and for color-pf). 15 for fusion-pf, chosen on the tune "
        "data under a rule stated before the runs (docs/rules/resident_rule.txt, docs/robustness.md): PETS tune views' "
        "pooled lost recall 0.276 against 0.240 off; tune split mean AUC 0.7025 against 0.7011, re-acquired 78 of "
        "90 both, false-lost 0.019 both. color-pf gained 0.026 there, under the rule's 0.03: off."))
    acquire_unique: bool = param(True, doc=(
        "See ColorModelParams.acquire_unique (off there and for color-pf). On for fusion-pf, chosen on the tune data "
        "under a rule stated before the runs (docs/rules/acquire_unique_rule.txt, docs/robustness.md): PETS tune "
        "views' pooled lost recall 0.319 against 0.276 off; tune split and tune real-exit windows unchanged (mean "
        "AUC 0.7025, re-acquired 78 of 90 and 20 of 60, false-lost 0.019). color-pf gained 0.022 on the views, under "
        "the rule's 0.03, and lost 10 of its 26 exit re-acquisitions: off."))
    acquire_unique_hold: int = param(15, ge=0, le=10_000, doc=(
        "See ColorModelParams.acquire_unique_hold (0 there). 15 for fusion-pf, chosen on the tune data under a rule "
        "stated before the runs (docs/rules/acquire_hold_rule.txt, docs/robustness.md): PETS tune views' pooled lost "
        "recall 0.403 against 0.319 with 0 (5: 0.370); tune split and tune real-exit windows unchanged. The views' "
        "own re-acquisitions fell from 6 to 4 of 18."))
    reenter_along: float = param(1.0, ge=0, le=100, doc=(
        "See ColorModelParams.reenter_along (0 there and for color-pf). 1 for fusion-pf, chosen on the tune data under "
        "a rule stated before the runs (docs/rules/reenter_along_rule.txt, docs/robustness.md): PETS tune views' "
        "pooled lost recall 0.587 against 0.475 (2: 0.526); tune split mean AUC 0.7042 against 0.7041, re-acquired 78 "
        "of 90 both; tune exit windows 19 against 20 of 60."))
    acquire_sliver_llr: float = param(19.5, ge=0, le=1000, doc=(
        "See ColorModelParams.acquire_sliver_llr (off there and for color-pf). 19.5 for fusion-pf (the fused ratio's "
        "cap is 2 x loss_cue_clip = 20: both cues at their clip; move it with loss_cue_clip), chosen on the tune "
        "data under a rule stated before the runs (docs/rules/acquire_sliver_llr_rule.txt, docs/robustness.md): "
        "tune real-exit windows re-acquired 45 of 60 against 30, false-lost 0.028 against 0.059; PETS tune views' "
        "pooled lost recall 0.575 both; tune split mean AUC 0.7042 against 0.7041, re-acquired 78 of 90 both (15 "
        "and 18 gained the same 45; 15 cost the views 0.003). Report data, run once after: unchanged (windows 26 of "
        "36, views 0.668, split 78 of 96)."))
    input_switch: int = param(1, ge=0, le=1000, doc=(
        "See ColorModelParams.input_switch (0 there and for color-pf). 1 for fusion-pf, chosen on the tune data under "
        "a rule stated before the runs (docs/rules/input_switch_rule.txt, docs/robustness.md): the tune real "
        "sequences' 20 copies whose input turns grey mid-sequence, mean AUC 0.550 against 0.521, false-lost pooled "
        "0.014 against 0.024 (3: 0.483). Input that never turns grey is tracked as before."))
    input_switch_return: int = param(1, ge=0, le=1, doc=(
        "See ColorModelParams.input_switch_return (0 there and for color-pf). 1 for fusion-pf, chosen on the tune data "
        "under a rule stated before the runs (docs/rules/input_switch_return_rule.txt, docs/robustness.md): the "
        "tune synthetic vanish and leave scenes' 64 copies turning grey, mean AUC 0.574 against 0.561, false-lost "
        "pooled 0.066 against 0.068; the 20 tune real copies unchanged (no switch there came during a search)."))
    reenter_memory: int = param(5, ge=0, le=1000, doc=(
        "See ColorModelParams.reenter_memory (0 there). 5 for fusion-pf, chosen on the tune data under a rule stated "
        "before the runs (docs/rules/exit_memory_rule.txt, docs/robustness.md): PETS tune views' pooled lost recall "
        "0.475 against 0.439; tune split and tune exit windows unchanged (10 gave the same)."))
    static_quarters: int = param(3, ge=1, le=4, doc=(
        "See ColorModelParams.static_quarters (4 there and for color-pf). 3 for fusion-pf, chosen on the tune data "
        "under a rule stated before the runs (docs/rules/static_quarters_rule.txt, docs/robustness.md): PETS tune "
        "views' pooled lost recall 0.439 against 0.403 with 4; tune split mean AUC 0.7041 against 0.7025, "
        "re-acquired 78 of 90 both, false-lost 0.023 against 0.019; tune real-exit windows 20 of 60 both. "
        "color-pf's views did not gain (0.214 against 0.216): 4."))
    grey_scale_search: float = param(0.0, ge=0, le=0.5, doc=(
        "See ColorModelParams.grey_scale_search (color-pf's, with grey_check='fused'): off for fusion-pf, whose "
        "own option is scale_search."))
    grey_check: Literal["off", "structure"] = param("off", doc=(
        "See ColorModelParams.grey_check: off for fusion-pf, whose structural cue already scores every particle "
        "and enters its loss test."))
    color_normalize: Literal["none", "gain", "adaptive", "equalize", "still"] = param("still", doc=(
        "See ColorModelParams.color_normalize ('none' there and for color-pf). 'still' for fusion-pf: the frame's "
        "gain against the first frame, measured on the same pixels while the view is still, undone in the colour "
        "bins. Chosen under a rule stated before its runs (docs/rules/still_gain_rule.txt, docs/robustness.md): 21 "
        "tune copies whose exposure settles, never run before, mean AUC 0.412 against 0.306; the tune split 0.706 "
        "against 0.705 (real sequences 0.584 both, re-acquired 79 against 80 of 90), views and windows' lost recall "
        "0.610 against 0.611, re-acquired 52 against 53 of 66. color-pf failed the rule on the views and windows' "
        "returns (40 against 48)."))
    contrast: bool = param(True, doc=(
        "Multiply in the background-aware contrast likelihood exp(contrast_gain * c), c = mean foreground "
        "probability inside the box minus in the surrounding ring."))
    position_noise: float = param(0.3, ge=0, le=10, doc=(
        "Std of the position noise, as a fraction of the mean half-axis (color-pf: 0.2); chosen by "
        "leave-one-sequence-out selection (docs/fusion-pf-selection.md)."))
    velocity_noise: float = param(0.025, ge=0, le=10, doc=(
        "Std of the velocity noise per frame, as a fraction of the mean half-axis (color-pf: 0.1). With the "
        "peaked structural likelihood a noisier velocity lets the constant-velocity prediction run away; "
        "chosen on the tune split (docs/fusion-pf-selection.md, stage 5)."))
    scale_rate_noise: float = param(0.01, ge=0, le=1, doc=(
        "Std of the noise on the scale rate (color-pf: 0.005). The contrast cue observes the extent, so "
        "the size may explore more."))
    grey_scale_rate_noise: float | None = param(None, ge=0, le=1, doc=(
        "scale_rate_noise on grey input (ColorPFParams.grey_scale_rate_noise); None (default): scale_rate_noise. "
        "0 (the size moved by the structural size search alone) gained on the grey tune set (64 sequences, 6 "
        "seeds: mean AUC 0.680 against 0.668, grey + light copies 0.523 against 0.487, re-acquired 189 against 184 "
        "of 246) but not on the grey report set, run once (62 sequences, 3 seeds: 0.672 against 0.676, "
        "re-acquired 85 against 90 of 129; docs/robustness.md), so it is an option."))
    scale_search: float = param(0.03, ge=0, le=0.5, doc=(
        "s > 0: after each tracked frame's estimate, its box at the sizes 1/(1+s), 1 and 1+s is compared with the "
        "structural cue's references by NCC (DSST-style, cues.scale_search), and the estimate and every particle "
        "move toward the vertex of the parabola through the three scores by scale_search_rate of it (in log "
        "scale). The colour and contrast cues observe the size weakly: without it a shrinking face keeps its first "
        "size. Skipped while the largest box is not inside the frame. 0: the particles' scale alone. 0.03 (default) "
        "with rate 0.25, chosen with grey_histogram='both' on the tune data (docs/fusion-pf.md): tune split mean "
        "AUC 0.684 against 0.664 over its 213 runs, PETS people 0.422 against 0.357; 8 seeds of the tune "
        "reappearance scenes 0.658 against 0.630, re-acquired 365 against 345 of 568."))
    scale_search_rate: float = param(0.25, ge=0, le=1, doc=(
        "Fraction (in log scale) of the scale search's vertex applied per frame: at most (1+s)^rate, 0.75 % with "
        "s = 0.03 and this default, so noise in the three scores moves the size little."))
    scale_search_reference: Literal["both", "anchor"] = param("both", doc=(
        "The references the size search compares the three sizes with: 'both' (default), the better of the first "
        "frame's patch and the running mean, as the cue scores the samples; 'anchor', the first frame's patch "
        "alone, so a size the running mean learnt from a drifted box does not hold the box there. An option: it "
        "failed its rule on the tune data (docs/rules/scale_anchor_rule.txt, docs/fusion-pf-selection.md: PETS "
        "people 0.407 against 0.427, split mean AUC 0.703 against 0.705)."))
    mass_size: float = param(0.1, ge=0, le=1, doc=(
        "r > 0: on each frame the models learn from (the loss test confident), the object's area is read from the "
        "mass of the contrast cue's foreground-probability map around the estimate's box, CamShift's zeroth moment "
        "(cues.mass_size: the mass of a window twice the box above the level of the ring around it, counted in "
        "object pixels), and once the models took the estimate's box, it and every particle move toward the size "
        "that area implies against the first reading, by r of the ratio in log scale (clipped to 0.8-1.25). Only "
        "where the map separates the object from its surround by mass_gate and the window lies in the quantised "
        "region. The box contrast and the NCC prefer a box inside an elliptic target of little texture, whose box "
        "then shrinks (docs/robustness-cameras.md). 0: off. 0.1 (default), chosen on the tune data under "
        "docs/rules/mass_size_rule2.txt (3 run seeds, the former default 0 beside it): the scene kinds the main set "
        "does not hold (simple, illumination, occlusion, full occlusion, entering, crossing, waving; tune seeds "
        "0-7) 0.747 against 0.701 mean AUC; the main tune set 0.717 against 0.712 (real 0.611 against 0.612, PETS "
        "people 0.419 against 0.427), re-acquired 81 against 79 of 90; stride copies 0.408 against 0.405; windows "
        "and views the same; TRE 0.630 against 0.625. 0.25 passed too (O 0.744)."))
    mass_gate: float = param(0.8, ge=0, le=1, doc=(
        "The least separation (the mean foreground probability of the box's core minus that of the ring around "
        "the window) at which mass_size reads the map."))
    mass_frame: bool = param(False, doc=(
        "With mass_size: the window whose mass is read must lie in the quantised region only where it is inside "
        "the frame; beyond the frame's edge there is nothing to count. False (default): the whole window (twice "
        "the box), so a target within a box's height of the edge of a small frame is not read."))
    aspect_search: float = param(0.0, ge=0, le=0.5, doc=(
        "a > 0: after the size search, the estimate's box at the shapes (hx/(1+a), hy(1+a)), (hx, hy) and "
        "(hx(1+a), hy/(1+a)) (the same area) is compared with the structural cue's references by NCC, and the "
        "estimate and every particle move their width and height apart toward the vertex of the parabola through "
        "the three scores, by aspect_search_rate of it (cues.scale_search.aspect_factor): a target that turns or "
        "bends changes its aspect, which the particles' scale keeps. Only after a frame the loss test was "
        "confident on, and skipped while the widest or tallest box is not inside the frame. 0: the first frame's "
        "aspect is kept."))
    aspect_search_rate: float = param(0.25, ge=0, le=1, doc=(
        "Fraction (in log scale) of the aspect search's vertex applied per frame."))
    max_pixels: int = param(1000, ge=0, le=10_000_000, doc=(
        "Larger ellipses are sampled on a lattice with about this many pixels (color-pf: 4000). With "
        "N = 100 particles, more particles beat more pixels per particle at the same cost."))
    contrast_gain: float = param(10.0, gt=0, le=1000, doc=(
        "Sharpness of the contrast likelihood; c lies in [-1, 1]. Larger trusts the contrast more than the "
        "colour histogram."))
    ring: float = param(0.5, gt=0, le=3, doc=(
        "Width of the surrounding ring on each side, as a fraction of the box size (for the contrast and the "
        "surround colour counts)."))
    contrast_shape: Literal["box", "ellipse", "ellipse-box"] = param("box", doc=(
        "Where a particle's contrast is scored: 'box', its bounding box against the rectangular ring around it; "
        "'ellipse', the ellipse against the elliptic annulus (half-axes 1 + 2 ring times), each read from the "
        "integral image as horizontal strips. A box's corners are background around an elliptic target, which "
        "pulls the box contrast toward smaller boxes (docs/robustness.md); 'ellipse-box', the ellipse against the "
        "box's rectangular ring (the corners between them in neither)."))
    contrast_alpha: float = param(0.02, ge=0, le=1, doc=(
        "Learning rate of the object and surround colour counts, updated with the colour model's gate."))
    motion: bool = param(False, doc=(
        "Multiply in the local-motion likelihood of Kristan et al. (flow features in the particles' region). "
        "Helps when a similar object crosses the target; costs ~0.5 ms per frame."))
    structure: bool = param(True, doc=(
        "Add the structural cue of pftrack.cues.structure: structure_gain * r, with r the NCC in [-1, 1] of the "
        "particle's grey patch with the reference (book ch. 14's NCC; gain/offset invariant, so it sees "
        "grey targets and survives illumination drift)."))
    structure_gain: float = param(10.0, ge=0, le=1000, doc=(
        "Sharpness of the structural likelihood exp(structure_gain * r)."))
    structure_weighting: Literal["kernel", "uniform"] = param("uniform", doc=(
        "Pixel weights of the NCC: 'kernel' is the Epanechnikov profile of the ellipse inscribed in the box "
        "(the colour cue's region; the box's corners are mostly background), 'uniform' the whole box."))
    structure_pixels: int = param(256, ge=16, le=4096, doc="Pixels of the grey reference patch (box aspect).")
    structure_rate: float = param(0.02, ge=0, le=1, doc=(
        "Learning rate of the running reference patch, updated with the colour model's gate; the first "
        "frame's patch is kept as an anchor (score = the better of the two)."))
    structure_anchor_gate: float = param(0.5, ge=-1, le=1, doc=(
        "The running reference patch learns only from estimates whose NCC with the first frame's patch is at "
        "least this (template-drift correction); -1 learns from every gated estimate."))
    fused_loss: bool = param(True, doc=(
        "With the structural cue on, the loss test fuses the colour rho and the NCC as independent evidence "
        "(pftrack.filtering.loss.FusedLoss: the sum of the two cues' likelihood ratios), and the search scores "
        "its samples with every cue; off: the colour rho alone, as in color-pf."))
    reliability_d: float = param(3.0, ge=0, le=100, doc=(
        "With the fused loss test, each cue's log-likelihood (colour, structure) is scaled by its online "
        "reliability min(1, d'/reliability_d), d' = (target history mean - background upper-tail mean) / "
        "background spread of that cue (its separation in this scene, from the loss test's statistics), "
        "floored at reliability_floor. 0 turns the scaling off."))
    reliability_floor: float = param(0.1, ge=0, le=1, doc="Smallest reliability factor of a cue.")
    loss_cue_clip: float = param(10.0, gt=0, le=30, doc=(
        "With the fused loss test, each cue's log-likelihood ratio is clipped to at most loss_cue_clip before "
        "the sum: the most odds e^clip one cue alone can give for the target."))
    loss_cue_floor: float = param(2.0, gt=0, le=30, doc=(
        "Lower clip of each cue's log-likelihood ratio in the fused loss test: the most odds one cue alone can "
        "give against the target (a single cue also drops for reasons other than absence)."))
    loss_history_z: float = param(0.0, ge=0, le=50, doc=(
        "Fused loss test while tracking: a frame on which both cues' scores lie more than loss_history_z of their "
        "own spreads below their target histories counts as a miss (fused ratio at most -1), whatever their ratios "
        "against the background say: the estimate has settled on something like nothing the target showed (an "
        "occluder of the target's colours that the background statistics never sampled). 0: off; 2.5 and 3 missed "
        "the gain their rule asked on the tune data (docs/rules/loss_history_z_rule.txt)."))
    acquire_z: float = param(4.0, ge=0, le=50, doc=(
        "Re-acquisition with the fused loss test: a cue also vetoes a candidate whose score is more than "
        "acquire_z spreads below that cue's target history, even when its own ratio favours the target (a "
        "look-alike whose shape matches and whose colours are far off, but still far above this scene's "
        "background). 0 (off): a cue vetoes only when it is history_z spreads below its history and its ratio "
        "says background. Chosen on the tune split (docs/fusion-pf.md): vanish AUC 0.561 against 0.529, every "
        "other group within 0.001; 2 and 3 cost the exit scenes or lost recall."))
    reacquire_llr: float = param(0.0, ge=0, le=30, doc=(
        "See ColorModelParams.reacquire_llr: off for fusion-pf, whose fused loss test bounds each cue by "
        "acquire_z instead (it would act only with fused_loss=false)."))
    acquire_margin: float | None = param(2.0, doc=(
        "LLR a candidate must exceed to end a loss with the fused loss test; None: reacquire_margin (which also "
        "gates the model update). The refined search (search_refine) tests the top of the best peak, clutter's "
        "too, so the test asks for more than the tracking gate. Chosen on the tune split (docs/fusion-pf.md): 2 "
        "against None (1): lost recall 0.867 against 0.854, re-acquired 0.77 against 0.76, vanish 0.569 against "
        "0.555, real 0.589 against 0.593; 3 gave real 0.578."))
    search_refine: float = param(0.5, ge=0, le=4, doc=(
        "color-pf's refined search layer (ColorModelParams.search_refine; color-pf: off on colour input, 0.5 on grey "
        "input, grey_search_refine). Chosen on the tune "
        "split (docs/fusion-pf.md): with acquire_z = 4, real AUC 0.593 against 0.582, PETS 0.369 against 0.364, "
        "teleport 0.645 against 0.601, leave 0.746 against 0.726; 1 gave less. It costs speed on lost frames "
        "only, and the report split's lost recall after an exit (a look-alike met at its exact peak)."))
    grey_search_refine: float | None = param(None, ge=0, le=4, doc=(
        "See ColorModelParams.grey_search_refine; None: search_refine on every input (fusion-pf)."))
    visible_structure: bool = param(False, doc=(
        "The loss test of a box partly outside the frame (the search's candidate to acquire, and the estimate while "
        "tracking) takes its structural score over the part of the box inside the frame, against the same part of "
        "the references, when that is higher (a box partly outside the frame samples the frame's border there, or "
        "empty gradient cells, which the references do not hold): a target that comes back and stays at the edge "
        "is neither refused nor reported lost by the structure for that. Off: search only, neutral on the tune data "
        "(docs/rules/visible_structure_rule.txt); with the estimate too, docs/rules/visible_tracking_rule.txt."))
    acquire_shape_step: float = param(0.15, ge=0, le=1, doc=(
        "While searching, the loss test of the candidate to acquire takes its structural score as the best over "
        "its box's shape and the shapes whose half-axes are 1/(1+step) or 1+step times its own, each axis on its "
        "own (9 shapes), when the largest is inside the frame: a target that came back larger, smaller or turned "
        "(a couple walking toward the camera) is not refused by the structure because the search looks for it at "
        "the size it had when lost. 0: off. 0.15 chosen on the tune data under docs/rules/acquire_shape_step_rule.txt "
        "(tune windows: 50 of 60 returns re-acquired against 45; docs/robustness.md)."))
    relit_colour: bool = param(True, doc=(
        "While searching, when the colour cue would veto the best candidate that the structural cue alone could "
        "acquire, its colour score is retaken after undoing a global per-channel gain (von Kries: the frame's "
        "channel medians against those of the last background refresh, when the target was seen), and the "
        "better of the two is used: a target whose colours drifted with the light while it was hidden is not "
        "vetoed for that. Colour RGB input only."))
    lost_frames: int = param(3, ge=1, le=1000, doc=(
        "Frames of absence evidence before lost (color-pf: 2). 2 raised fusion-pf's lost recall on the tune "
        "split (0.845 -> 0.882) but cost its real sequences 0.019 AUC (docs/fusion-pf.md)."))
    relit_search: Literal["off", "replace", "max"] = param("off", doc=(
        "color-pf's relit search (every search sample rescored under the undone light; ColorModelParams). Off: "
        "'max' re-acquired 387 against 377 of 432 tune reappearances in colour scenes, but after real exits (tune "
        "views and windows) the flag's pooled recall fell 0.625 -> 0.598, since a window's channel medians move "
        "with what passes through it; with relit_gain='blocks' the recall held but 3 re-acquisitions of 33 were "
        "lost; with relit_gain='still' the exits were untouched and 390 of 432 re-acquired, but one tune return came "
        "a frame past the 15-frame window (docs/robustness.md). relit_colour above does the same for the one "
        "candidate the structure backs."))
    probation_llr: float = param(15.0, ge=0, le=50, doc=(
        "See ColorModelParams.probation_llr (0, off, there; 15 for color-pf). 15 for fusion-pf, with probation_frames "
        "60, chosen on the tune data (docs/robustness.md, 'fusion-pf doubts a weak re-acquisition'): on the 568 tune "
        "reappearances (8 seeds) re-acquired 402 against 365 with the defaults (416 with the search beside the track "
        "on every frame: grey scenes 273 against 223 of 408, colour 143 against 142 of 160), mean AUC 0.681 against "
        "0.658, lost recall 0.805 against 0.789; 4, 6, 10, 20 and 30 gave 375-409 (30 frames, every frame). Tune "
        "split: mean AUC 0.687 against 0.684, re-acquired 73 / 90 against 70."))
    probation_frames: int = param(60, ge=0, le=100_000, doc=(
        "See ColorModelParams.probation_frames. 60 (tune reappearances, the search beside the track on every frame: "
        "15 and 30 re-acquired 379 and 407, 60 416, 120 and 250 the same 416)."))
    probation_interval: int = param(4, ge=1, le=1000, doc=(
        "See ColorModelParams.probation_interval. 4 for fusion-pf: on the tune reappearances 402 re-acquired "
        "against 416 (every frame) and 407 (every 2nd), at about a quarter of the cost: on otb_dragonbaby, whose "
        "target is lost and found again often, 1786 update fps against 1070 (every frame) and 2237 without "
        "probation (one worker)."))
    search_prior: float = param(0.05, ge=0, le=1, doc=(
        "Re-acquisition with a position prior (color-pf: 0, off): a candidate far from the constant-velocity "
        "prediction needs e^3 more evidence (see ColorModelParams.search_prior). Chosen on the tune split "
        "(docs/fusion-pf.md): re-acquired 48 / 72 against 44 / 72, real sequences unchanged; 0.01 and 0.001 gave "
        "the same, 0.2 less."))
    search_proposals: int = param(0, ge=0, le=1000, doc=(
        "While searching, the structural cue's references are matched over the whole frame (OpenCV "
        "matchTemplate, zero-mean NCC, at the reference's resolution; book ch. 14) and its best this many "
        "separated peaks join the search samples, scored with every cue like the others: a small or relit "
        "target is found even when no uniform sample lands on it. 0: off."))
    search_prior_cap: bool = param(True, doc=(
        "Only penalise far candidates (color-pf: False). Uncapped, a candidate near the prediction needed less "
        "evidence and the real tune sequences lost 0.005 AUC."))
    grey_structure: Literal["levels", "quotient", "both"] = param("both", doc=(
        "Grey input with the grey-patch NCC (structure_features 'ncc' or 'both'): the image the structural cue "
        "correlates. 'levels': the grey levels; 'quotient': the "
        "self-quotient image (illumination_sigma), where a lamp or shadow across the target cancels; 'both': two "
        "cues, each with its references, and a box scores the better NCC (pftrack.cues.structure_light). The "
        "histogram cue and the search see the grey levels either way. Chosen on the tune split "
        "(docs/robustness.md): on its grey scenes mean AUC 0.593 against 0.588 ('levels'), face proxy 0.779 against "
        "0.720 (lowest run 0.695 against 0.471); 'quotient' lost the grey + light copies (0.359 against 0.469)."))
    structure_features: Literal["ncc", "hog", "both", "hog-on-grey"] = param("hog-on-grey", doc=(
        "What the structural cue correlates. 'ncc': grey patches (on grey input as grey_structure says); 'hog': "
        "histograms of oriented gradients, each cell normalised by its own contrast (pftrack.cues.structure_hog; "
        "Dalal & Triggs, CVPR 2005), which a light that varies across the target changes less; 'both': a box "
        "scores the better of the two, each with its own references; 'hog-on-grey': 'hog' on grey input, 'ncc' on "
        "colour. The gain, rates and gates are shared. Chosen on the tune data under a rule stated beforehand "
        "(docs/robustness.md): on the grey tune set mean AUC 0.701 against 0.667 ('ncc'), re-acquired 102 against "
        "91 of 123, false-lost 0.022 against 0.040; 'hog' on colour input too lost the tune views' flag (pooled "
        "recall 0.344 against 0.400) and 17 % of the speed; 'both' gained nothing on grey (0.669)."))
    hog_cells: int = param(16, ge=4, le=100, doc=(
        "With the gradient cue (structure_features 'hog', 'both', or 'hog-on-grey' on grey input): about this many "
        "cells a box, in its aspect (each at least 8 reduced pixels a side)."))
    lk_levels: int = param(2, ge=1, le=6, doc="Pyramid levels of the flow when motion is on.")
    max_features: int = param(150, ge=1, le=1_000_000, doc="Flow features per frame when motion is on.")
