"""``fusion-pf``: pftrack's default tracker — colour, background-aware contrast and grey-patch structure, fused.

It is ``color-pf`` (Nummiaro et al.) with the ingredients that make a colour
particle filter hold on real footage, grey video and illumination change, each a
documented parameter with an ablation in ``docs/fusion-pf.md``:

* **Likelihood = product of cues** (independent observations), in the log domain:
  ``log p(y | x) = w_col log p_colour + contrast_gain c + w_str structure_gain r [+ log p_motion]`` where
  ``p_colour`` is Eq. 10 of Nummiaro et al. on the kernel histogram, ``c`` the object/surround
  contrast of the foreground-probability map (:mod:`pftrack.cues.contrast`; it also observes the
  target's extent), ``r`` the NCC of the particle's grey patch with the reference
  (:mod:`pftrack.cues.structure`; book ch. 14's criterion, blind to gain and offset), and
  ``p_motion`` the optional local-motion likelihood of Kristan et al. (Eq. 7).
* **Reliability weights** ``w``: each cue's separation ``d'`` between its target-score history
  and the upper tail of its background scores (the loss test's statistics), ``min(1, d'/reliability_d)``.
* **The lost flag on fused evidence**: :class:`~pftrack.filtering.loss.FusedLoss` adds the
  colour's and the structure's clipped log-likelihood ratios; the search scores its samples with
  every cue.
* **Gated model updates**: the colour model (Eqs. 11–12), the object/surround counts and the
  structural reference adapt only on confident frames (the reference also only while it still
  resembles the first frame's patch).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cues.contrast import (
    blend_counts,
    box_counts,
    contrast_scores_ellipses,
    foreground_lut,
    probability_integral,
)
from ..cues.intensity import channel_levels, gain_maps, is_gray
from ..cues.motion import LocalMotionCue, local_motion, to_gray
from ..cues.scale_search import aspect_factor, size_factor
from ..cues.structure import StructureCue
from ..cues.structure_hog import BestStructure, HogStructure
from ..cues.structure_light import LitStructure
from ..filtering.dynamics import HX, HY, VX, VY
from ..filtering.loss import FusedLoss
from ..geometry import box_to_ellipse, ellipse_to_box
from ..params import param
from .color_hooks import fused_supporters
from .color_pf import _ELL_COLS, ColorPF, ColorPFParams


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
    grey_scale_search: float = param(0.0, ge=0, le=0.5, doc=(
        "See ColorModelParams.grey_scale_search (color-pf's, with grey_check='fused'): off for fusion-pf, whose "
        "own option is scale_search."))
    grey_check: Literal["off", "structure"] = param("off", doc=(
        "See ColorModelParams.grey_check: off for fusion-pf, whose structural cue already scores every particle "
        "and enters its loss test."))
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
    contrast_shape: Literal["box", "ellipse"] = param("box", doc=(
        "Where a particle's contrast is scored: 'box', its bounding box against the rectangular ring around it; "
        "'ellipse', the ellipse against the elliptic annulus (half-axes 1 + 2 ring times), each read from the "
        "integral image as horizontal strips. A box's corners are background around an elliptic target, which "
        "pulls the box contrast toward smaller boxes (docs/robustness.md)."))
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
        "on the tune split ('max', before its 5 % dead zone) it re-acquired 0.69 against 0.67 but cost the real "
        "sequences 0.006 AUC; relit_colour above does the same for the one candidate the structure backs."))
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


class FusionPF(ColorPF):
    """Colour PF fused with a background-aware contrast cue and, optionally, local motion."""

    name = "fusion-pf"
    Params = FusionPFParams

    def __init__(self, params: FusionPFParams | None = None, *, rng=None, seed=None, detector=None):
        super().__init__(params, rng=rng, seed=seed, detector=detector)
        p = self.params
        self.motion_cue = LocalMotionCue(levels=p.lk_levels, max_features=p.max_features)
        self.structure = self._structure_cue(None)
        if self._fused:
            self.loss = FusedLoss(2, cue_clip=p.loss_cue_clip, cue_floor=p.loss_cue_floor,
                                  acquire_z=p.acquire_z, acquire_margin=p.acquire_margin,
                                  lost_frames=p.lost_frames,
                                  reacquire_margin=p.reacquire_margin,
                                  history_rate=p.history_rate, sd_floor_target=p.score_sd_floor,
                                  sd_floor_background=p.score_sd_floor, learn_z=p.history_z)
        self._obj = None
        self._sur = None
        self._lut = None
        self._ii: np.ndarray | None = None  # the integral image's buffer, reused between frames
        self._ii_of = None  # (frame index, features) the integral image was computed from
        self._prev_gray = None
        self._gray = None
        self._flow = None
        self.v_ref = None
        self._ref_levels: np.ndarray | None = None
        self._levels: tuple[int, np.ndarray] | None = None

    @property
    def _fused(self) -> bool:
        p = self.params
        return p.structure and p.fused_loss and p.loss_test == "likelihood"

    # ------------------------------------------------------------------ init
    def _structure_cue(self, frame):
        """A fresh structural cue for the input ``frame`` (None: unknown): on grey input with ``grey_structure`` other
        than 'levels', the quotient and grey-level pair of pftrack.cues.structure_light."""
        p = self.params
        if p.structure_features == "hog" or (p.structure_features == "hog-on-grey" and frame is not None
                                             and is_gray(frame)):
            return HogStructure(cells=p.hog_cells)
        if frame is not None and p.grey_structure != "levels" and p.illumination == "none" and is_gray(frame):
            ncc = LitStructure(p.structure_pixels, weighting=p.structure_weighting, sigma=p.illumination_sigma,
                               mode=p.grey_structure, gray_of=self._frame_gray)
        else:
            ncc = StructureCue(p.structure_pixels, weighting=p.structure_weighting)
        if p.structure_features in ("ncc", "hog-on-grey"):
            return ncc
        return BestStructure(ncc, HogStructure(cells=p.hog_cells))

    def _lit_structure(self) -> LitStructure | None:
        """The structural cue's quotient and grey-level pair, when it has one."""
        s = self.structure.primary if isinstance(self.structure, BestStructure) else self.structure
        return s if isinstance(s, LitStructure) else None

    def _grey_shared(self) -> bool:
        lit = self._lit_structure()
        return (self.cue.color_space == "gray" and lit is not None and lit.shares_gray) or super()._grey_shared()

    def _shared_quotient(self):
        """The grey structural cue's self-quotient image (same frames, same ``illumination_sigma``), when it has one;
        otherwise (the gradient cue on grey input) :meth:`ColorPF._shared_quotient`'s own."""
        lit = self._lit_structure()
        return lit._qf if lit is not None else super()._shared_quotient()

    def init_auto(self, frame, histogram, size, *, regions=None):
        """As :meth:`ColorPF.init_auto`; a known histogram gives no reference patch, so the structural cue
        stays off (no evidence) for this target."""
        self.structure = self._structure_cue(None)
        return super().init_auto(frame, histogram, size, regions=regions)

    def _init(self, frame, box):
        p = self.params
        if p.structure:  # before the colour init: its background statistics need the structural reference
            self.structure = self._structure_cue(frame)
            self.structure.init(frame, box_to_ellipse(box))
        st = super()._init(frame, box)
        if p.contrast:
            pitch = self.cue.step_for(box_to_ellipse(box).reshape(1, 4))
            feats = self.cue.prepare_frame(frame, pitch)
            self._obj, self._sur = box_counts(feats.bins, feats.x0, feats.y0, box, self.cue.feature_bins, ring=p.ring,
                                              pitch=pitch)
            self._lut = foreground_lut(self._obj, self._sur).astype(np.float64)  # exact: the integral's type
        self.v_ref = None
        self._prev_gray = to_gray(frame) if p.motion else None
        # the background statistics reduced this frame for the structural cue: the next frame must not reuse it
        self.structure.new_frame()
        return st

    # ------------------------------------------------------------------ observation
    def _propagate(self, states):
        x0, y0, x1, y1 = super()._propagate(states)
        if self.params.contrast:  # the rings must be inside the quantised region too
            r = self.params.ring
            mx = 2.0 * r * float(states[:, HX].max()) + 1.0
            my = 2.0 * r * float(states[:, HY].max()) + 1.0
            return x0 - mx, y0 - my, x1 + mx, y1 + my
        return x0, y0, x1, y1

    def _reliability(self) -> tuple[float, float]:
        """Reliability factors of the colour and structural cues (see ``reliability_d``)."""
        p = self.params
        if not self._fused or p.reliability_d <= 0:
            return 1.0, 1.0
        out = []
        for m in self.loss.members:
            d = (m.mu_t - m.mu_b) / max(m.sd_b, 1e-9)
            out.append(min(1.0, max(p.reliability_floor, d / p.reliability_d)))
        return out[0], out[1]

    def _fused_log_lik(self, frame, ell, log_lik, roi, feats):
        """The colour log-likelihood scaled by its reliability, plus the contrast and structural terms."""
        p = self.params
        w_col, w_str = self._reliability()
        if w_col != 1.0:
            log_lik = log_lik * w_col
        if p.contrast and self._lut is not None:
            if self._ii_of is not None and self._ii_of[0] == self.frame_index and self._ii_of[1] is feats:
                ii = self._ii  # the same quantised region again on this frame (the search's refined layer)
            else:
                ii = self._ii = probability_integral(feats.bins, self._lut, out=self._ii)
                self._ii_of = (self.frame_index, feats)
            c = contrast_scores_ellipses(ii, feats.x0, feats.y0, ell, ring=p.ring, pitch=feats.pitch,
                                         shape=p.contrast_shape)
            log_lik = log_lik + p.contrast_gain * c
        if p.structure and p.structure_gain > 0 and self.structure.ready:
            log_lik = log_lik + (w_str * p.structure_gain) * self.structure.scores(frame, roi, ell)
        return log_lik

    def _extra_log_lik(self, frame, states, log_lik, roi, feats):
        p = self.params
        log_lik = self._fused_log_lik(frame, self._ellipses(states), log_lik, roi, feats)
        if p.motion:
            self._gray = to_gray(frame)
            self._flow = self.motion_cue.prepare(self._prev_gray, self._gray, roi)
            if self.v_ref is not None:
                log_lik = log_lik + self.motion_cue.log_likelihood(self._flow, self._ellipses(states), self.v_ref)
        return log_lik

    def _background_stats(self, frame, exclude):
        super()._background_stats(frame, exclude)
        if self.params.relit_colour and self.cue.color_space == "rgb" and frame.ndim == 3 and self.mode == "tracking":
            self._ref_levels = channel_levels(frame, stride=16)  # the light while the target is seen

    def _relit_rho(self, frame: np.ndarray, ellipse: np.ndarray) -> float:
        """Colour rho of one ellipse with the frame's per-channel gain against ``_ref_levels`` undone."""
        if self._levels is None or self._levels[0] != self.frame_index:
            self._levels = (self.frame_index, channel_levels(frame, stride=16))
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        fh, fw = self._shape
        roi = (max(int(e[0, 0] - e[0, 2]) - 1, 0), max(int(e[0, 1] - e[0, 3]) - 1, 0),
               min(int(e[0, 0] + e[0, 2]) + 2, fw), min(int(e[0, 1] + e[0, 3]) + 2, fh))
        feats = self.cue.prepare(frame, roi, self.cue.step_for(e),
                                 lut=self.cue.mapped_lut(gain_maps(self._ref_levels, self._levels[1])))
        r, tot = self.cue.rho(feats, e, self._sqrt_q, reuse=False)
        return float(r[0]) if tot[0] > 0 else 0.0

    def _loss_scores(self, frame, ellipses, rho, roi):
        if not self._fused:
            return rho
        if not self.structure.ready:  # started from a histogram (init_auto): no reference patch, no evidence
            return np.column_stack([rho, np.full(len(rho), np.nan)])
        s = self.structure.scores(frame, roi, ellipses)
        s += 1.0
        s *= 0.5
        if (self.mode == "searching" and len(rho) == 1 and self.params.relit_colour and self._ref_levels is not None
                and frame.ndim == 3 and self.cue.color_space == "rgb"):
            col, st = self.loss.members
            # the colour would veto a candidate the structure alone could acquire: is it only the light?
            if ((float(rho[0]) - col.mu_t) / col.sd_t <= -col.learn_z
                    and st.evaluate(float(s[0])) - self.loss.cue_floor > self.loss.reacquire_margin):
                rho = np.maximum(rho, self._relit_rho(frame, ellipses[0]))
        out = np.empty((len(s), 2))
        out[:, 0] = rho
        out[:, 1] = s
        return out

    def _appearance_pass(self, rho, threshold, log_lik):
        if not self._fused:
            return rho > threshold
        return fused_supporters(log_lik)

    def _search_proposals(self, frame):
        k = self.params.search_proposals
        if k <= 0 or not self._fused or not self.structure.ready:
            return None
        return self.structure.proposals(frame, self.size, k)[0]

    def _search_log_lik(self, frame, states, log_lik, feats):
        if not self._fused:
            return log_lik
        return self._fused_log_lik(frame, self._ellipses(states), log_lik, feats.roi, feats)

    def _after_estimate(self, frame, estimate):
        p = self.params
        if p.scale_search > 0 and p.scale_search_rate > 0 and p.structure and self.structure.ready:
            self._search_scale(frame, estimate)
        if not p.motion or self._flow is None:
            return
        v_obs, defined = local_motion(self._flow, estimate[_ELL_COLS].reshape(1, 4))
        if defined[0]:
            self.v_ref = (v_obs[0].copy() if self.v_ref is None
                          else self.motion_cue.adapt(self.v_ref, estimate[[VX, VY]], v_obs[0]))

    def _search_scale(self, frame, estimate):
        """``scale_search``: move the estimate's and the particles' size (in place) toward the size whose grey
        patch best matches the structural references."""
        p = self.params
        self._scale_size(estimate, size_factor(self.structure, frame, estimate[_ELL_COLS], p.scale_search,
                                               p.scale_search_rate))
        if p.aspect_search > 0 and p.aspect_search_rate > 0 and self.loss.llr > self.loss.reacquire_margin:
            f = aspect_factor(self.structure, frame, estimate[_ELL_COLS], p.aspect_search, p.aspect_search_rate)
            if f != 1.0:
                estimate[HX] *= f
                estimate[HY] /= f
                self.ps.scale_columns(HX, HX + 1, f)
                self.ps.scale_columns(HY, HY + 1, 1.0 / f)

    def _update_models(self, frame, estimate, feats, rho_e):
        p = self.params
        if p.structure:
            self.structure.update(frame, estimate[_ELL_COLS], p.structure_rate, p.structure_anchor_gate)
        if not p.contrast or p.contrast_alpha <= 0:
            return
        box = ellipse_to_box(estimate[_ELL_COLS])
        obj, sur = box_counts(feats.bins, feats.x0, feats.y0, box, self.cue.feature_bins, ring=p.ring,
                              pitch=feats.pitch)
        # counts are compared as distributions scaled to the reference areas
        blended = blend_counts(self._obj, obj, self._sur, sur, p.contrast_alpha)
        if blended is not None:
            self._obj, self._sur, self._lut = blended
            self._ii_of = None  # an integral image of this frame was taken with the former table

    def _on_frame(self, frame):
        self.structure.new_frame()
        if self.params.motion:
            self._prev_gray = self._gray if self._gray is not None else to_gray(frame)
            self._gray = None
            self._flow = None
