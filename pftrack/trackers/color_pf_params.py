"""``color-pf``'s own defaults (:class:`ColorPFParams`): where they depart from the shared model's
(:class:`~pftrack.trackers.color_params.ColorModelParams`), each with the tune-split figures it was chosen on."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..params import param
from .color_params import ColorModelParams

__all__ = ["ColorPFParams"]


@dataclass(frozen=True, kw_only=True)
class ColorPFParams(ColorModelParams):
    """Parameters of ``color-pf``; defaults follow Nummiaro et al. where the paper gives them."""

    acquire_in_frame: float = param(0.5, ge=0, le=1, doc=(
        "See ColorModelParams.acquire_in_frame (off there). 0.5 for color-pf and fusion-pf, chosen on tune data "
        "(docs/robustness.md): the PETS walkers of frames 1-200 seen through four narrower views, and the tune split. "
        "Views' pooled lost recall over 6 seeds: fusion-pf 0.371 against 0.305 off (0.6: 0.410, 0.7: 0.439), "
        "color-pf 0.202 against 0.133; tune split re-acquisitions unchanged (74 and 80 of 90), false-lost 0.032 "
        "against 0.027 (color-pf 0.037 against 0.034), mean AUC 0.6900 against 0.6923 (0.5741 against 0.5766). "
        "0.6 and 0.7 re-acquired fewer (0.78 and 0.77 against 0.82). Report data, run once after the choice: views "
        "0.418 against 0.413 (color-pf 0.579 against 0.582), re-acquired 73 against 74 of 96 (76 both)."))
    acquire_early_frames: int = param(10, ge=0, doc=(
        "See ColorModelParams.acquire_early_frames (off there and for fusion-pf). 10 for color-pf, chosen on the "
        "tune data under a rule stated before the runs (docs/rules/acquire_early_rule.txt, docs/robustness.md): tune "
        "windows of the real sequences re-acquired 45 against 43 of 60, the tune split and the PETS tune views "
        "unchanged (mean AUC 0.572, 80 of 90, views' pooled lost recall 0.211); 20 frames re-acquired 44. fusion-pf "
        "failed the rule on the views (0.511 against 0.575). Report data, run once after the choice: windows 23 of "
        "36 both, views 0.597 against 0.595, split mean AUC 0.588 both, re-acquired 75 against 76 of 96."))
    enter_extent: int = param(30, ge=0, le=100_000, doc=(
        "See ColorModelParams.enter_extent (off there). 30 for color-pf and fusion-pf (and local-motion-pf), chosen "
        "on the tune data under a rule stated before its runs (docs/rules/enter_extent_grow_rule.txt; a first form "
        "that could narrow the box failed docs/rules/enter_extent_rule.txt), 3 run seeds: entering scenes seeds 0-7 "
        "mean AUC 0.901 against 0.168 (fusion-pf 0.813 against 0.186); PETS tune views 0.356 against 0.354 (0.428 "
        "against 0.427), tune windows 0.486 both (0.589 both), lost flag and re-acquisitions no worse; the main tune "
        "set identical run for run (no first box there touches an edge)."))
    dark_stretch: float = param(2.0, ge=0, le=8, doc=(
        "See ColorModelParams.dark_stretch (off there). 2 for color-pf and fusion-pf (and local-motion-pf), "
        "chosen under a rule stated before its runs (docs/rules/dark_stretch_rule.txt, docs/robustness.md): on 21 "
        "dark tune copies never run before (PETS people at gain 0.3 / noise 3 and 0.2 / 5, real sequences at "
        "0.2 / 5) mean AUC 0.438 against 0.371 (color-pf 0.343 against 0.195); the tune split, views and windows "
        "identical run for run (no frame there is dark enough)."))
    haze_stretch: float = param(1.8, ge=0, le=8, doc=(
        "See ColorModelParams.haze_stretch (off there and for fusion-pf). 1.8 for color-pf, chosen under a rule "
        "stated before its runs (docs/rules/haze_stretch_rule.txt, docs/robustness.md): 39 hazy tune copies never "
        "run (real sequences and PETS people through haze of 0.4, 0.6 and 0.8) mean AUC 0.372 against 0.343; the "
        "tune synthetic and photo scenes 0.669 against 0.659 (camouflage 0.266 against 0.122), re-acquired 172 of "
        "234 both; the tune real sequences, PETS people, views and windows read below 1.8 (identical)."))
    cast_jump: float = param(0.2, ge=0, le=3, doc=(
        "See ColorModelParams.cast_jump (off there; 0.2 for local-motion-pf under its own rule). 0.2 for color-pf "
        "and fusion-pf, chosen under a rule stated before its runs (docs/rules/cast_jump_rule.txt, "
        "docs/robustness.md): 26 tune copies never run whose white balance jumps (real sequences and PETS people, "
        "casts of 0.15 and 0.3) mean "
        "AUC 0.384 against 0.351 (color-pf, pooled false-lost 0.000 against 0.058) and 0.472 against 0.449 "
        "(fusion-pf, 0.005 against 0.013); the tune sequences as recorded read no jump of 0.2 (identical runs)."))
    light_jump: float = param(0.18, ge=0, le=3, doc=(
        "See ColorModelParams.light_jump (off there and for fusion-pf, whose still view's gain reads lamps). 0.18 "
        "for color-pf (and local-motion-pf), chosen under a rule stated before its runs "
        "(docs/rules/sot_light_jump_rule.txt, docs/robustness.md): 26 tune copies never run whose light jumps a "
        "third of the way through (real sequences and PETS people, light times 1.55 and 0.75), mean AUC 0.391 "
        "against 0.343, pooled false-lost 0.037 against 0.096; the tune sequences as recorded identical."))
    lost_frames: int = param(2, ge=1, le=1000, doc=(
        "'A couple of frames' (§6) of absence evidence before the target is declared lost. 2 for color-pf, "
        "chosen on the tune split (docs/robustness.md): against 3, lost recall 0.828 against 0.791, false-lost "
        "0.048 against 0.035, re-acquired 0.56 against 0.51, real AUC 0.508 against 0.503, every group equal or "
        "better. fusion-pf keeps 3."))
    relit_search: Literal["off", "replace", "max"] = param("max", doc=(
        "See ColorModelParams.relit_search (off there). 'max' for color-pf, chosen on the tune split "
        "(docs/robustness.md): re-acquired 0.51 of the reappearances against 0.38 off, vanish AUC 0.494 against "
        "0.431, real sequences 0.503 against 0.501; 'replace' 0.51 with real 0.494. fusion-pf keeps it off."))
    reenter_border: float = param(1.0, ge=0, le=100, doc=(
        "After the target left the view, re-acquire it only within this many target sizes of the edge it left "
        "through, a strip widening at the speed it left with; 0: off (ColorModelParams' default). 1 for color-pf "
        "and fusion-pf, chosen on the tune split "
        "with the PETS pedestrians (docs/robustness.md): leave AUC 0.617 against 0.582 (color-pf) and 0.726 "
        "against 0.666 (fusion-pf), lost recall 0.826 against 0.797 and 0.840 against 0.836; 0.5 and 2 within "
        "0.04 of 1."))
    reenter_outward: float = param(0.5, ge=0, le=100, doc=(
        "See ColorModelParams.reenter_outward (off there). 0.5 for color-pf and fusion-pf, chosen on the tune "
        "split's exit scenes (a target leaving in a flow of look-alikes, docs/robustness.md): color-pf AUC 0.783 "
        "against 0.757 off, lost recall 0.978 against 0.957 (0.25: the same; 1 and 2: no gain); fusion-pf and "
        "every other tune group unchanged."))
    grey_check: Literal["off", "structure", "fused"] = param("fused", doc=(
        "See ColorModelParams.grey_check. 'fused' for color-pf, chosen on the grey tune set (docs/robustness.md; "
        "without the size search): mean AUC 0.627 against 0.514 ('structure') and 0.501 ('off'), re-acquired 72 "
        "against 42 and 37 of 123 reappearances, lost recall 0.819 against 0.738 and 0.692, false-lost 0.053 against "
        "0.080. fusion-pf keeps it off (its structural cue is in every particle and in its loss test)."))
    grey_scale_search: float = param(0.03, ge=0, le=0.5, doc=(
        "See ColorModelParams.grey_scale_search. 0.03 for color-pf (fusion-pf's scale_search step), chosen on the "
        "tune data (docs/robustness.md; the grey levels' patches only): tune face proxies 0.891 against 0.744 mean "
        "AUC, dim and noisy 0.767 against 0.645; the grey tune set's reappearance scenes (8 seeds) 0.624 against "
        "0.628, re-acquired 184 against 179 of 328; tune split 0.555 against 0.549."))
    probation_llr: float = param(15.0, ge=0, le=50, doc=(
        "See ColorModelParams.probation_llr (0, off, there). 15 for color-pf (fusion-pf's value), with "
        "ColorModelParams' probation_frames 30 and probation_interval 1, chosen on the tune data "
        "(docs/robustness.md): 8 seeds of the tune reappearance scenes re-acquired 427 of 568 against 415 off (8: "
        "418, 25: 430, 40: 429); tune split mean AUC 0.568 against 0.566, PETS 0.305 against 0.296 (25: 0.569, "
        "PETS 0.287)."))
    persist_frames: int = param(3, ge=0, le=1000, doc=(
        "See ColorModelParams.persist_frames (0, off, there). 3 for color-pf and fusion-pf, with persist_z 2.5, "
        "chosen on the tune data (docs/robustness.md): tune split mean AUC 0.690 against 0.687 (fusion-pf; grey "
        "copies 0.534 against 0.511, grey + light 0.494 against 0.477) and 0.570 against 0.568 (color-pf); 8 seeds "
        "of the tune reappearance scenes re-acquired 440 and 427 of 568 against 439 and 427, lost recall 0.878 "
        "and 0.916 against 0.879 and 0.916. persist_z 4 and 3 took distractors in grey vanish scenes; 5 frames "
        "gained less on the grey copies."))
    grey_search_refine: float | None = param(0.5, ge=0, le=4, doc=(
        "See ColorModelParams.grey_search_refine and search_refine (off for color-pf on colour input). 0.5 for "
        "color-pf (fusion-pf's search_refine), chosen on the tune data (docs/robustness.md): 8 seeds of the tune "
        "reappearance scenes re-acquired 415 of 568 against 401 (1: 414; search_refine=0.5 on every input: 413), "
        "tune split mean AUC 0.566 against 0.565, grey face proxies unchanged."))
    grey_histogram: Literal["levels", "both"] = param("both", doc=(
        "Grey input: 'both' also keeps a histogram model of the self-quotient image, and while tracking every "
        "particle scores the better of its two coefficients (the search scores the grey levels alone); 'levels': "
        "the grey levels alone (ColorModelParams' default). 'both' for color-pf, chosen on the grey tune set "
        "(docs/robustness.md): mean AUC 0.499 against 0.458, face proxies 0.647 against 0.424 (no run of "
        "24 below 0.5, against 18), re-acquired 35 against 33 of 123, but vanish 0.419 against 0.457. fusion-pf "
        "keeps 'levels' (its structural cue has the quotient)."))
    grey_search_structure: bool = param(True, doc=(
        "See ColorModelParams.grey_search_structure (off there). On for color-pf, chosen on the tune data "
        "(docs/robustness.md): 8 seeds of the tune reappearance scenes re-acquired 471 of 568 against 436, mean AUC "
        "0.705 against 0.689, lost recall lower on the teleport scenes (0.895 against 0.957); the tune split "
        "0.576 against 0.570 mean AUC (grey copies 0.509 against 0.491, grey + light 0.486 against 0.461), "
        "false-lost 0.035 against 0.046. fusion-pf's search has its own structural cue."))
    search_retries: int = param(2, ge=0, le=20, doc=(
        "See ColorModelParams.search_retries (0 there). 2 for color-pf and fusion-pf, chosen on the tune data "
        "(docs/robustness.md): 8 seeds of the tune reappearance scenes re-acquired 436 of 568 (color-pf) and 444 "
        "(fusion-pf), against 435 and 444 with 0; the tune split unchanged. It acts only when a veto refuses a "
        "candidate."))
    reacquire_llr: float = param(20.0, ge=0, le=30, doc=(
        "See ColorModelParams.reacquire_llr (off there). 20 for color-pf, chosen on the tune data "
        "(docs/robustness.md): 8 seeds of the tune reappearance scenes re-acquired 474 of 568 against 471 (10: "
        "474), 120 more tune scenes 318 of 363 against 309 (mean AUC 0.675 against 0.655); the tune split 79 "
        "of 90 against 77, mean AUC 0.577 against 0.576; otb_dragonbaby, 10 seeds, 0.505 against 0.498 (5: "
        "0.485). It acts on colour input; the fused test of grey input has none."))
    distractor_frames: int = param(10, ge=0, le=100_000, doc=(
        "Distractor memory: after a gradual loss, a look-alike found beyond the target's reach during the first "
        "this many frames of the search is not acquired but remembered and followed (ColorModelParams."
        "distractor_frames; off there). 10 for color-pf and fusion-pf, chosen on the tune "
        "data (docs/robustness.md; 5 and 20 gave the same): grey vanish scenes of seeds 0-19, 3 seeds, "
        "re-acquired 17 / 60 against 12 (color-pf) and 29 / 60 against 25 (fusion-pf), lost recall 0.683 "
        "against 0.537 and 0.734 against 0.613; the tune split +0.0019 +- 0.0017 mean AUC and re-acquired 61 / "
        "90 against 59 (color-pf), unchanged (fusion-pf); colour vanish scenes unchanged. Report split "
        "(reports/final_r8): within +-0.001, re-acquired 66 / 96 (the same) and 74 / 96 (73)."))
    input_switch: int = param(0, ge=0, le=1000, doc=(
        "See ColorModelParams.input_switch. Off for color-pf: on the tune real sequences' 20 copies whose input turns "
        "grey mid-sequence, 1 gave mean AUC 0.501 against 0.486, short of its rule's 0.02 "
        "(docs/rules/input_switch_rule.txt), though its false-lost rate pooled fell from 0.083 to 0.024; 1 for "
        "fusion-pf and local-motion-pf. --param input_switch=1 turns it on."))
    reenter_memory: int = param(5, ge=0, le=1000, doc=(
        "See ColorModelParams.reenter_memory (0 there). 5 for color-pf and fusion-pf, chosen on the tune data under "
        "a rule stated before the runs (docs/rules/exit_memory_rule.txt, docs/robustness.md): PETS tune views' pooled "
        "lost recall 0.262 against 0.216 (fusion-pf 0.475 against 0.439); tune split unchanged; tune exit windows "
        "re-acquired 25 against 26 of 60 (10: 22)."))
    static_ncc: float = param(0.8, ge=0, le=1, doc=(
        "Background test (pftrack.trackers.static_lookalikes): a frame is kept (grey) every 30 confident frames; "
        "a search candidate that would end the loss, or the estimate while tracking (every 10th frame, not at the "
        "frame's edge), whose patch is found unchanged at the same place on it, every quarter correlating at this "
        "or more once the camera's noise is taken out, is a piece of the scene: the search takes its next "
        "candidate, and the estimate is lost. Abstains on flat patches, and near the target's box on that frame "
        "unless the frame kept before it answers. 0: off (local-motion-pf). 0.8 chosen on the tune data "
        "(docs/robustness.md): 8 seeds of the tune reappearance scenes re-acquired 439 of 568 (fusion-pf) and 401 "
        "(color-pf), against 401 and 364 off; report split 79 and 70 of 96."))
    position_noise: float = param(0.2, ge=0, le=10, doc=(
        "Std of the Gaussian noise w on x and y (Eq. 9), as a fraction of the mean half-axis "
        "(scale-invariant). The paper leaves it open."))
    velocity_noise: float = param(0.1, ge=0, le=10, doc=(
        "Std of the noise on the velocity (vx, vy) per frame, as a fraction of the mean half-axis."))
    velocity_step: float = param(0.0, ge=0, le=1, doc=(
        "The share of each sample's whole step (velocity plus position noise) that its velocity keeps after the "
        "dynamics of Eq. 9: v <- (1 - b) v' + b (x_t - x_(t-1)). 1 is the second-order autoregressive model of "
        "Isard & Blake's CONDENSATION (each sample's velocity its last displacement), so a sample whose noise "
        "moved it with the target keeps that motion when it is resampled. 0 (default): Eq. 9 as written."))
    wide_fraction: float = param(0.0, ge=0, le=1, doc=(
        "A heavy-tailed proposal for abrupt motion (a jerky camera, a low frame rate): each frame this share of "
        "the samples, drawn at random, takes wide_factor times the position noise of Eq. 9, so the set reaches a "
        "target that moved several noise spreads between two frames; the others move as usual. 0 (default): "
        "off, the paper's Gaussian; 0.1 and 0.2 failed docs/rules/wide_proposal_rule.txt (docs/robustness.md)."))
    wide_factor: float = param(3.0, ge=1, le=20, doc=(
        "With wide_fraction > 0: the factor on the position noise of the wide samples."))
    mix_fraction: float = param(0.0, ge=0, le=1, doc=(
        "A two-model proposal for targets that swing past look-alikes: each frame this share of the samples, drawn "
        "at random, steps with mix_position_noise and mix_velocity_noise instead of position_noise and "
        "velocity_noise (Eq. 9's noise, the same units), so some particles' velocities follow a quick change of "
        "direction while the rest keep the steady model (pftrack.filtering.dynamics.mix_noise). 0 (default): off; "
        "for fusion-pf 0.3 and 0.5 failed docs/rules/mix_dynamics_rule.txt: they gained look-alike crossings and "
        "lost the PETS walkers (docs/fusion-pf-selection.md, stage 11)."))
    mix_position_noise: float = param(0.2, ge=0, le=10, doc=(
        "With mix_fraction > 0: the second model's position noise, a fraction of the mean half-axis."))
    mix_velocity_noise: float = param(0.1, ge=0, le=10, doc=(
        "With mix_fraction > 0: the second model's velocity noise per frame, a fraction of the mean half-axis."))
    camera_motion: bool = param(False, doc=(
        "Move every sample by the camera's translation since the last frame before the dynamics (Eq. 9) spread "
        "them, read from the two frames' integral projections (pftrack.cues.camera_shift): for a hand-held camera "
        "or a low frame rate. A static camera gives no shift. False (default for color-pf): off; it failed "
        "docs/rules/camera_motion_rule.txt, camera_shake_rule.txt and motion_proposal_tre_rule.txt "
        "(docs/robustness-cameras.md). True for fusion-pf (motion_proposal_tre_rule.txt). A camera that pans to keep "
        "the target in view moves the background, not the target: the samples are then moved off it, and the "
        "likelihood brings them back (DAVIS report sequences: 0.02-0.03 lower)."))
    camera_share: float = param(1.0, gt=0, le=1, doc=(
        "With camera_motion: the share of the samples moved by the camera's shift, spread evenly over the set (every "
        "other one at 0.5); the others are left where they were. A camera that pans to keep the target in view moves "
        "the background and not the target, and a hand-held camera moves both: with both kinds of sample in the set "
        "the likelihood picks the one that holds. 1 (default): every sample."))
    camera_adapt: float = param(0.0, ge=0, le=1, doc=(
        "With camera_motion and camera_share < 1: each frame the share of the samples moved by the camera's shift "
        "moves toward the weight those samples took on the frame before, at this rate, between camera_share_min "
        "and camera_share: a hand-held camera over a still target raises it, a camera that pans to keep the target "
        "in view lowers it. 0 (default): the share is camera_share. fusion-pf with camera_share=0.9 and 0.2 failed "
        "docs/rules/camera_adapt_rule.txt on the tune windows (47 against 52 of 60 returns)."))
    camera_share_min: float = param(0.2, gt=0, le=1, doc=(
        "With camera_adapt > 0: the least share of the samples moved by the camera's shift."))
    camera_samples: int = param(256, ge=32, le=4096, doc=(
        "With camera_motion: the integral projections are read on a lattice of every k-th row and column, k the "
        "least that leaves at most this many samples along the frame's longer side (pftrack.cues.camera_shift."
        "lattice_step). Fewer samples read less of the frame (the pass is bound by memory) and give a coarser shift "
        "before its sub-sample refinement. 256 (default; 176 for fusion-pf, docs/rules/camera_samples_rule.txt)."))
    camera_max_shift: float = param(0.15, gt=0, le=0.5, doc=(
        "With camera_motion: the largest shift searched, as a fraction of the frame's width (along x) and height "
        "(along y)."))
    size_noise: float = param(0.0, ge=0, le=1, doc=(
        "Std of independent noise on the half-axes Hx, Hy, as a fraction of each half-axis. 0 (default) "
        "changes the size only through adot, which keeps the aspect ratio."))
    scale_rate_noise: float = param(0.005, ge=0, le=1, doc=(
        "Std of the noise on the scale-change rate adot (1/frame): about 0.5 % size change per frame."))
    grey_scale_rate_noise: float | None = param(None, ge=0, le=1, doc=(
        "scale_rate_noise on grey input (the cue's colour space 'gray'), where the histogram observes the size "
        "more weakly still; None (default): scale_rate_noise."))
    grey_velocity_noise: float | None = param(None, ge=0, le=10, doc=(
        "velocity_noise on grey input (the cue's colour space 'gray'); None (default): velocity_noise."))
    grey_velocity_step: float | None = param(None, ge=0, le=1, doc=(
        "velocity_step on grey input (the cue's colour space 'gray'), whose weaker likelihood lets a velocity "
        "learnt from the noise run further; None (default): velocity_step."))
    scale_damping: float = param(0.0, ge=0, le=1, doc=(
        "Factor kappa on the scale-change rate (adot_t = kappa adot_{t-1} + w). 1 is the paper's literal "
        "constant scale change; colour histograms observe scale weakly, so a persistent rate drifts the "
        "size away (measured on the dev set: docs/color-pf.md). The default 0 makes the size a random "
        "walk, as in Perez et al. and Kristan et al."))
    max_scale_rate: float = param(0.05, ge=0, le=1, doc=(
        "Bound on |adot|: at most this relative size change per frame from the deterministic part."))
    min_noise_px: float = param(1.0, ge=0, le=100, doc=(
        "Floor (pixels) for the position noise, so that tiny targets still explore."))
