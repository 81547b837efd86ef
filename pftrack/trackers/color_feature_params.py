"""The first parameters shared by the colour particle filters: the sample count and the features ``h(x)`` the colour
model is built on (colour space, bins, the frame's normalisation, light and grey handling).

:class:`~pftrack.trackers.color_params.ColorModelParams` derives from it, so these fields come first in every colour
tracker's parameters.  Each field cites the equation of Nummiaro et al. (``shared/seeds/004_*``) it comes from, or
says that the paper leaves it open and what raising or lowering it does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..params import Params, param

__all__ = ["ColorFeatureParams"]


@dataclass(frozen=True, kw_only=True)
class ColorFeatureParams(Params):
    """The sample count and the colour model's features, shared by the colour PFs."""

    n_particles: int = param(100, ge=1, le=1_000_000, doc=(
        "N, the number of samples (§4, Fig. 2; the paper uses 100). More samples: a smoother, more "
        "accurate estimate at linear cost."))
    color_space: Literal["auto", "rgb", "hsv", "gray"] = param("auto", doc=(
        "Features of h(x) (§3): 'rgb' (8x8x8 bins), 'hsv' (8x8x4, less sensitive to V), 'gray' (equalised "
        "intensity x gradient orientation, for frames without colour) or 'auto': 'gray' when the first frame "
        "is grey, else 'rgb'. On grey input an RGB histogram collapses onto 8 diagonal bins."))
    bins: tuple[int, ...] = param((), ge=1, le=256, doc=(
        "Colour bins per channel; empty for the paper's 8,8,8 (RGB) or 8,8,4 (HSV). Fewer bins: more tolerant "
        "to noise and lighting, less discriminative."))
    gray_bins: tuple[int, ...] = param((16, 8), ge=1, le=256, doc=(
        "Grey features: (intensity bins after global equalisation, gradient-orientation bins); one more bin "
        "holds flat pixels. More intensity bins: more discriminative, less tolerant to local lighting."))
    histogram_parts: int = param(1, ge=1, le=2, doc=(
        "2: two-part histograms (Pérez et al., ECCV 2002; Okuma et al., ECCV 2004): the features of the rows "
        "above and below the ellipse's centre count in separate halves of every histogram (the model, the "
        "particles', the loss test's and the search's), so the model keeps the colours' layout (a walker's jacket "
        "over their trousers); Eq. 6's coefficient is then about the mean of the two parts'. 1: one histogram "
        "over the ellipse (the paper; default). An option: on fusion-pf's tune data it tracked a little better "
        "(mean AUC 0.698 against 0.690) but raised the flag on far fewer of the frames after real exits among "
        "look-alike walkers (0.16 against 0.40); on the report data, run once, it was as good or better on both "
        "(docs/robustness.md)."))
    color_normalize: Literal["none", "gain", "adaptive", "equalize", "still"] = param("none", doc=(
        "RGB features under changing light: 'gain' divides each channel by its gain relative to the "
        "initialisation frame (per-channel medians of the frame, von Kries adaptation); 'adaptive' relative to "
        "a reference that follows the confident frames at normalize_rate and freezes while the target is "
        "unseen; 'equalize' equalises each channel over the frame; 'still' divides each channel by the frame's "
        "gain against the initialisation frame, measured on the same pixels (the median of their log-ratios) and "
        "taken only while the view is still (their median absolute deviation at most 0.1), held otherwise "
        "(pftrack.cues.still_gain; an exposure that settles, lights coming on); 'none': raw colours (the paper)."))
    dark_stretch: float = param(0.0, ge=0, le=8, doc=(
        "RGB features of a dark camera: when the initialisation frame's bright end (its 99.5th percentile over "
        "the channels) needs a gain of at least this to reach level 255, the 8x8x8 bins are spread over the "
        "levels the camera uses (gain at most 8; pftrack.cues.quantize.level_gain), so that a night camera's "
        "colours do not crowd into the lowest two or three bins of each channel. 0: never (the paper's bins over "
        "0-255). Frames of ordinary exposure reach 228-255 there and are never stretched at 2."))
    dark_percentile: float = param(99.5, ge=50, le=100, doc=(
        "dark_stretch: the percentile of the initialisation frame's levels (every channel, every fourth pixel) "
        "that the gain brings to 255; the brighter rest (lamps, headlights) falls into the top bins."))
    denoise: float = param(0.0, ge=0, le=255, doc=(
        "A noisy camera: when the noise that differs between the first two frames (pftrack.cues.noise."
        "temporal_noise, grey levels) exceeds this, the tracker starts again on the smoothed first frame and every "
        "frame is smoothed by a denoise_kernel Gaussian before its features are read (pftrack.trackers.denoise). "
        "Clean cameras read 0-2.6 levels, white noise of 12 levels after JPEG 7.9-9.8. 0: never (the paper). "
        "An option: at 5 and at 7.5 it failed its rules on noisy tune copies (fusion-pf +0.004 and +0.001 mean AUC, "
        "color-pf +0.011 and +0.005, +0.015 asked): it helps the real sequences at 14-16 levels of noise and "
        "hurts the small PETS walkers (docs/robustness.md)."))
    denoise_kernel: int = param(5, ge=3, le=15, doc=(
        "denoise: the side of the Gaussian kernel (odd; OpenCV's sigma for that size, 1.1 at 5)."))
    haze_stretch: float = param(0.0, ge=0, le=8, doc=(
        "RGB features of a hazy camera (fog, smoke, a misted lens): when the initialisation frame is not dark "
        "enough for dark_stretch but its levels between the 0.5th and 99.5th percentiles (dark_percentile) span at "
        "most 255 / haze_stretch, the 8x8x8 bins are spread over that span (pftrack.cues.quantize.level_range), so "
        "that a veiled scene's colours do not crowd into the top three or four bins of each channel. 0: never. "
        "Clean real frames span a gain of 1.0-1.21 (windows cut into one part of a scene up to 1.65); a uniform haze "
        "of half the light 1.96-2.45."))
    cast_jump: float = param(0.0, ge=0, le=3, doc=(
        "RGB features under a white balance that jumps (a cloud, a door opening onto lamps, daylight to tungsten): "
        "a frame whose chromatic jump against the previous frame (the largest minus the smallest of the channels' "
        "median log-ratios on a lattice of every 16th pixel, pftrack.cues.still_gain.frame_jump) is at least this, "
        "with the log-ratios' MADs at most 0.4, multiplies a per-channel gain by the jump's, which the 8x8x8 bins "
        "undo from then on (with color_normalize='still' together with the gain of the last still view). With "
        "color_normalize 'none' or 'still'. 0: never. Consecutive frames of the tune sequences read at most 0.13, "
        "a cast of B and R times 1 -/+ 0.2 0.37-0.42 (scripts/jump_readings.py)."))
    light_jump: float = param(0.0, ge=0, le=3, doc=(
        "The same for lamps switched on or off: a frame whose channels' median log-ratios are at least this on "
        "average, in size (every channel at once), takes that jump into cast_jump's gain. 0: never. The tune "
        "sequences read at most 0.110 (an exposure settling), lamps times 1.3 0.26 "
        "(docs/rules/sot_light_jump_rule.txt)."))
    normalize_rate: float = param(0.05, ge=0, le=1, doc=(
        "'adaptive' normalisation: how fast the reference levels follow the frames the loss test trusts."))
    illumination: Literal["none", "quotient"] = param("none", doc=(
        "Grey input under changing light: 'quotient' divides every grey frame by its own smoothed copy (the "
        "self-quotient image, pftrack.cues.illumination; Wang et al. 2004, a single-scale Retinex), so that a "
        "lamp or shade that changes the target's grey levels differently from the rest of the frame cancels; "
        "'none' uses the grey levels as they are (global equalisation only). Colour input is never changed, nor are "
        "the frames of a tracker started by init_auto or init_detect (a given histogram or detector sees the frames "
        "as they are). Off by default (docs/robustness.md): under a drifting lamp it gained 0.04-0.14 AUC on both "
        "splits, but the report split's re-acquisitions fell from 0.74 to 0.63 (fusion-pf)."))
    illumination_sigma: float = param(0.1, gt=0, le=2, doc=(
        "'quotient': std of the Gaussian illumination estimate, as a fraction of the frame's larger side (the "
        "light must be smooth at this scale for Q = I / (G * I) to cancel it)."))
    illumination_check: bool = param(True, doc=(
        "'quotient': re-acquisition also asks a grey histogram model of the untransformed frames, learned on the "
        "confident frames with its own background statistics and history (pftrack.trackers.raw_check): a "
        "candidate it calls background is refused. The quotient also divides out the scene's own shading, so "
        "background patches can resemble the target more than they did."))
    grey_check: Literal["off", "structure", "fused"] = param("off", doc=(
        "Grey input: 'structure' also keeps reference grey patches of the target (fusion-pf's structural cue, "
        "pftrack.trackers.structure_check), learned on the confident frames with their own background statistics "
        "and score history; a search candidate whose normalised cross-correlation the two-class test calls "
        "background is refused. Tracking frames keep the histogram's likelihood and loss test. 'fused': the same "
        "check with patches of the grey levels and of their self-quotient image (the better NCC r of the two), and r "
        "also weighs every particle (exp(10 r), fusion-pf's structural likelihood) and joins the loss test "
        "(fusion-pf's fused test on the coefficient and the NCC). 'off': the histogram alone decides "
        "(ColorModelParams' default)."))
    grey_check_features: Literal["ncc", "hog", "both"] = param("ncc", doc=(
        "With grey_check='fused': what the check's references describe. 'ncc': grey patches of the grey levels and "
        "of their self-quotient image; 'hog': histograms of oriented gradients, each cell normalised by its own "
        "contrast (pftrack.cues.structure_hog, fusion-pf's structural cue on grey input); 'both': each kept, a box "
        "scored by the better of the two. 'ncc' for color-pf: 'hog' and 'both' failed their rules on the tune data "
        "(docs/robustness.md)."))
    grey_scale_search: float = param(0.0, ge=0, le=0.5, doc=(
        "Grey input with grey_check='fused': after each estimate its box is scored by the structural cue at the "
        "sizes 1/(1+s), 1 and 1+s, and the estimate and every particle move a quarter of the way toward the vertex "
        "of the parabola through the three NCCs (fusion-pf's scale_search); skipped while the largest box is not "
        "inside the frame. 0: off (ColorModelParams' default)."))
    grey_search_refine: float | None = param(None, ge=0, le=4, doc=(
        "search_refine on grey input (the cue's features are grey levels); None: search_refine, whatever the "
        "input (ColorModelParams' default)."))
    grey_histogram: Literal["levels", "both"] = param("levels", doc=(
        "Grey input with illumination='none': 'both' keeps a second grey histogram model of the self-quotient "
        "image (pftrack.cues.lit_histogram, its scale illumination_sigma) beside the model of the grey levels, "
        "each learned on the same confident frames; while tracking, every particle, the estimate and the "
        "background statistics score the better of the two coefficients (as fusion-pf's grey_structure does for "
        "its structural cue), and the search scores the grey levels alone (with the quotient it acquired "
        "clutter). 'levels': the grey levels alone. Colour input is unchanged."))
    gradient_threshold: float = param(40.0, ge=0, le=2000, doc=(
        "Grey features: Sobel magnitude (equalised levels) below which a pixel counts as flat."))
