"""Parameters of ``multi-pf`` (Sugandi et al., ``shared/seeds/001_*``; see :mod:`pftrack.multi.tracker`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..cues.foreground import DARK_NOISE_LIMIT, GREY_SHADOW_THRESHOLD
from ..params import Params, param

__all__ = ["MultiPFParams"]


@dataclass(frozen=True, kw_only=True)
class MultiPFParams(Params):
    """Parameters of ``multi-pf``; the paper gives none of the numbers, so each is chosen and documented."""

    detector: Literal["mog2", "motion", "hog"] = param("mog2", doc=(
        "Built-in detector (a callable given as detector_fn overrides it)."))
    object_aspect: float = param(0.4, ge=0, le=10, doc=(
        "Expected width/height of one target (0.4: standing people); the blob detectors split wider blobs "
        "(people walking together). 0 disables splitting."))
    grey_shadow_threshold: float = param(GREY_SHADOW_THRESHOLD, ge=0, le=1, doc=(
        "mog2's shadow threshold on grey frames, where its shadow test cannot tell a shadow from a target up to "
        "twice as dark as the ground: a darker pixel is a shadow only above this fraction of the background's "
        "brightness (1: none; 0.5: OpenCV's, as on colour frames; 0.85 chosen on the grey tune frames of PETS: "
        "MOTA 0.472 against 0.275 with 0.5; pftrack.cues.foreground)."))
    dark_stretch: float = param(2.0, ge=0, le=8, doc=(
        "mog2 on a dark camera: when the first frame's 99.5th percentile needs a gain of at least this to reach 255, "
        "the detector's frames are multiplied by that gain (at most 8) before MOG2 (pftrack.multi.detectors). 0: "
        "never. 2, chosen under a rule stated before its runs (docs/rules/mog2_dark_stretch_rule.txt, docs/mot.md): "
        "the PETS tune half from a dark camera (gain 0.2, noise 5), MOTA 0.342 against 0.057, IDF1 0.412 against "
        "0.323; the ordinary tune half identical run for run."))
    dark_denoise: float = param(DARK_NOISE_LIMIT, ge=0, le=255, doc=(
        "mog2 under dark_stretch: its frames are smoothed (3 x 3 Gaussian) before the stretch when the first frame's "
        "noise times the gain exceeds this many grey levels (pftrack.multi.detectors.MOG2DetectorParams."
        "dark_denoise); 0: never. 8.66 = sqrt(75), the spread of MOG2's ceiling on a pixel's variance, chosen under "
        "a rule stated before its runs (docs/rules/mog2_dark_denoise_rule.txt, docs/mot.md): four dark cameras of "
        "the PETS tune half never run before, mean MOTA 0.523 against 0.332, IDF1 0.624 against 0.512; the ordinary "
        "tune half identical run for run."))
    cast_jump: float = param(0.2, ge=0, le=3, doc=(
        "A white balance that jumps (lamps switched, daylight to tungsten): a frame whose chromatic jump against the "
        "previous frame (the largest minus the smallest of the channels' median log-ratios on a lattice of every 16th "
        "pixel, pftrack.cues.still_gain.CastUndo) is at least this multiplies a per-channel gain by the jump's, and "
        "every frame is divided by that gain before the detector and the colour models see it, so that the "
        "background subtraction does not take the whole view for foreground. 0: never. 0.2, as color-pf's, chosen "
        "under a rule stated before its runs (docs/rules/mot_cast_jump_rule.txt, docs/mot.md): the PETS tune half "
        "with casts of 0.15 and 0.35, mean MOTA 0.460 against 0.290, IDF1 0.669 against 0.390; the tune half as "
        "recorded identical run for run."))
    light_jump: float = param(0.18, ge=0, le=3, doc=(
        "Lamps switched on or off: a frame whose channels' median log-ratios against the previous frame are at least "
        "this on average, in size (every channel at once; their MADs at most 0.4, as cast_jump), takes that jump "
        "into the gain that every frame is divided by before the detector and the colour models "
        "(pftrack.cues.still_gain.CastUndo). 0: never. 0.18 (a jump of a fifth), chosen under a rule stated before "
        "its runs (docs/rules/light_jump_rule.txt, docs/mot.md): the PETS tune half with its light times 1.25, 1.5 "
        "and 0.7, mean MOTA 0.501 against 0.338, IDF1 0.671 against 0.461; the tune half as recorded identical."))
    light_jump_grey: bool = param(True, doc=(
        "light_jump between grey frames too (a grey camera's lamps); a switch between a colour and a grey frame reads "
        "no jump either way. Alone it failed a rule (docs/rules/grey_light_rule.txt: a grey copy with its light "
        "times 1.5 lost MOTA, its clipped levels flat once undone); with clip_fill it passed "
        "docs/rules/clip_fill_rule.txt (docs/mot.md)."))
    clip_fill: bool = param(True, doc=(
        "Once a jump is undone, a level clipped at 255 in a brightened channel (known only to be at least 255 / "
        "gain) takes the level seen there just before the jump when that is higher "
        "(pftrack.cues.still_gain.CastUndo), so that a bright background clipped by lamps switched on is not taken "
        "for foreground. Chosen with light_jump_grey under a rule stated before its runs "
        "(docs/rules/clip_fill_rule.txt, docs/mot.md): the PETS tune half with its light times 1.35, 1.45 and 0.65 "
        "in colour and in grey and a cast of 0.3, mean MOTA 0.498 against 0.400, IDF1 0.650 against 0.547; the "
        "grey and colour tune halves as recorded identical."))
    bootstrap_frames: int = param(0, ge=0, le=10_000, doc=(
        "mog2: the caller (pftrack mot, pftrack eval) reads this many first frames ahead and the detector's "
        "background starts from them with their moving pixels replaced by the per-pixel median (MultiPF.prime, "
        "pftrack.cues.foreground.still_frames); 0: MOG2 starts from the first frame and takes its people for "
        "background. An option: on the PETS tune half 56 frames raised MOTA from 0.550 to 0.580 but IDF1 fell from "
        "0.705 to 0.671 (docs/mot.md)."))
    n_particles: int = param(100, ge=1, le=100_000, doc="Particles per target.")
    max_pixels: int = param(600, ge=0, le=1_000_000, doc=(
        "Colour histograms of larger boxes are sampled on a lattice of about this many pixels (speed)."))
    sigma: float = param(0.2, gt=0, le=10, doc="sigma of the colour weighting (Eq. 10).")
    contrast_gain: float = param(10.0, ge=0, le=1000, doc=(
        "Weight of fusion-pf's background-aware contrast cue (object vs surrounding-ring colour probabilities, "
        "pftrack.cues.contrast) in each target's likelihood; it observes the target's extent and sharpens the "
        "boxes. 0 disables it (the paper's colour-only likelihood)."))
    ring: float = param(0.5, gt=0, le=3, doc="Surrounding ring width of the contrast cue, fraction of the box size.")
    foreground_gain: float = param(0.0, ge=0, le=1000, doc=(
        "Weight of the foreground cue: mean of the detector's foreground mask inside a particle's box minus in "
        "its surrounding ring (the same contrast form as the colour contrast). It lets several targets share "
        "one merged blob while the colour models tell them apart. 0 disables it."))
    position_noise: float = param(0.1, ge=0, le=10, doc=(
        "Std of the position noise xi_x (Eq. 4), fraction of the box width."))
    velocity_noise: float = param(0.05, ge=0, le=10, doc="Std of the speed noise xi_xdot, fraction of the box width.")
    size_noise: float = param(0.02, ge=0, le=1, doc="Std of the size noise xi_w, fraction of the size.")
    size_rate_noise: float = param(0.005, ge=0, le=1, doc="Std of the size-rate noise xi_wdot, fraction of the size.")
    alpha_x: float = param(0.8, ge=0, le=1, doc="Adaptation rate of the position (Eq. 12).")
    alpha_v: float = param(0.3, ge=0, le=1, doc="Adaptation rate of the speed (Eq. 12).")
    alpha_w: float = param(0.3, ge=0, le=1, doc="Adaptation rate of the size (Eq. 12).")
    alpha_vw: float = param(0.1, ge=0, le=1, doc="Adaptation rate of the size rate (Eq. 12).")
    alpha_q: float = param(0.05, ge=0, le=1, doc="Learning rate of the colour model (Eq. 13).")
    alpha_u: float = param(0.1, gt=0, le=1, doc="Learning rate of the expected likelihood lambda (Eq. 14).")
    normalize: Literal["per-target", "global"] = param("per-target", doc=(
        "Weight normalisation: 'per-target' to 1/L (Eq. 11), or 'global' over the pooled samples (ablation)."))
    occlusion: bool = param(True, doc=(
        "Occlusion handling: the merged-detection reasoning (group_merges) and, if occlusion_predict, the "
        "predicted-occlusion state of §3.7. False turns both off (the ablation)."))
    group_merges: Literal["auto", "on", "off"] = param("auto", doc=(
        "With occlusion: a detection that covers group_cover of two or more distinct targets' predicted boxes is "
        "one blob for targets occluding each other. It is the detection of none of them (it would pull one box "
        "over the whole group and leave the others without support); its members are reported and kept for up "
        "to max_occluded frames, each following its own colour with its size frozen, until the blob splits. "
        "'auto': on, except with the motion detector, whose blobs are fragments of objects rather than whole "
        "ones (there it measured worse, docs/mot.md)."))
    group_cover: float = param(0.5, gt=0, le=1, doc=(
        "Fraction of a target's predicted box inside a detection for the target to be part of that detection's "
        "group."))
    group_fit: float = param(0.6, gt=0, le=1, doc=(
        "A member whose predicted box overlaps a group's detection by at least this IoU explains it alone: it is "
        "in front and takes the detection; the other members are behind it."))
    occlusion_predict: bool = param(False, doc=(
        "With occlusion: also the predicted-occlusion state of §3.7 (Eq. 15 and the likelihood test below). Off by "
        "default: on PETS it did not reduce identity switches, alone or with group_merges (docs/mot.md)."))
    occlusion_radius: float = param(0.8, gt=0, le=10, doc=(
        "R of Eq. 15 as a fraction of the pair's mean box width: occlusion is predicted when the predicted "
        "centres are closer than R."))
    occlusion_drop: float = param(0.6, gt=0, le=1, doc=(
        "A target in a predicted occlusion is occluded when its maximum sample likelihood falls below this "
        "fraction of its recent history; it recovers when it exceeds it again."))
    report_occluded: bool = param(False, doc=(
        "Also report occluded targets at their coasting position (annotations such as MOTChallenge's include "
        "hidden people). Off by default: on PETS the coasting boxes were more often wrong than right (docs/mot.md)."))
    history_rate: float = param(0.1, gt=0, le=1, doc="Rate of the running mean of each target's maximum likelihood.")
    detection_sigma: float = param(0.15, gt=0, le=10, doc=(
        "Std of the detection term: position and size offsets from the associated detection, as fractions of "
        "the detection's size."))
    detection_proposal: float = param(0.5, ge=0, le=1, doc=(
        "Fraction of a target's particles drawn around its associated detection instead of from the dynamics "
        "(a mixture proposal, as in the boosted particle filter of Okuma et al. 2004), so that samples exist "
        "near a detection the prediction missed."))
    match_iou: float = param(0.2, ge=0, le=1, doc="Minimum IoU to associate a detection with a track.")
    appearance_weight: float = param(1.0, ge=0, le=100, doc=(
        "Weight of the colour dissimilarity 1 - rho(q_track, p_detection) beside 1 - IoU in the association cost "
        "(Hungarian assignment among the pairs with IoU >= match_iou); 0 associates by overlap alone."))
    birth_frames: int = param(3, ge=1, le=1000, doc=(
        "k: frames a detection must stay unexplained before a track is born."))
    max_misses: int = param(12, ge=1, le=10_000, doc="m: a track dies after this many frames without a detection.")
    max_occluded: int = param(40, ge=1, le=10_000, doc="... or this many while it is occluded or in a group.")
    report_misses: int = param(1, ge=0, le=10_000, doc=(
        "Tracks are reported while they matched a detection within this many frames, or are in a group (or "
        "occluded, with report_occluded)."))
    min_size: float = param(6.0, gt=0, doc="Smallest box side (pixels) of a track.")
    exit_fraction: float = param(0.4, ge=0, le=1, doc=(
        "A track whose box is less than this fraction inside the image dies."))
    identify: bool = param(False, doc=(
        "Book ch. 1 identification: a new track takes the identity of an ended one when their upper/lower-body "
        "colour and spatial features are similar enough (pftrack.multi.identify; reconstructed Eqs. 16-19)."))
    identify_threshold: float = param(0.8, ge=0, le=1, doc="Least similarity (Eq. 16) to give an old identity back.")
    identify_memory: int = param(300, ge=1, le=1_000_000, doc="Frames an ended identity is remembered.")
