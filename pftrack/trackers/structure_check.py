"""A structural cue for the colour PFs on grey input (``grey_check``): a second opinion on re-acquisition, and with
``"fused"`` a term of every particle's likelihood and a cue of the loss test.

On grey frames a histogram of equalised intensity and gradient orientation keeps little of a
target's layout: a dark disc and the dark, noisy inside of an occluder give nearly the same
histogram, and ``color-pf``'s search acquired such a patch while the target was in view
elsewhere (docs/robustness.md). ``fusion-pf`` weighs the normalised cross-correlation (NCC) of
small grey patches into every particle and into its loss test. :class:`StructureCheck` gives
``color-pf`` that evidence where it is cheap and decisive: at re-acquisition only. Tracking
frames keep the histogram's likelihood and loss test; they add one NCC (the estimate's) and, on
every 5th confident frame, one patch resampling for the running reference.

The check keeps the reference patches of :class:`~pftrack.cues.structure.StructureCue` (the
first frame's and a running mean, drift-corrected), learned on the frames the tracker is
confident on, with their own background statistics and score history
(:class:`~pftrack.filtering.loss.LossDetector`, the two-class test of the colour PFs). A search
candidate is refused when that test calls background (``LLR < 0``) the NCC of every box of a small
grid around it (:func:`neighbourhood`: the histogram's candidate is often off the target by a
fraction of its size, and tracking would pull it on), as
:class:`~pftrack.trackers.raw_check.RawGreyCheck` refuses one by the untransformed frames'
histogram. Like that check, its history learns from every frame the tracker is confident on.
Learning only from the scores the check itself calls target-like (the rule of
:class:`~pftrack.filtering.loss.FusedLoss`'s cues) refused true re-acquisitions of real grey
targets whose appearance had changed (docs/robustness.md).

With ``grey_check="fused"`` the same references also weigh every particle, ``exp(GAIN r)`` with ``r``
the NCC in [-1, 1] (``fusion-pf``'s structural likelihood at its default ``structure_gain``), and the
loss test becomes ``fusion-pf``'s :class:`~pftrack.filtering.loss.FusedLoss` on the histogram's
coefficient and the NCC score (:func:`fused_loss`). A structural term in the likelihood alone pulls the
particles where the histogram scores lower, and the histogram's test alone then declared a deforming
target lost (the grey copy of ``vot_bag``); the two cues must be weighed and tested together. The
fused check keeps patches of the grey levels and of their self-quotient image, scores a box by the
better of the two (``fusion-pf``'s ``grey_structure="both"``), refreshes the running references on
every confident frame, and gives the box's size a search after each estimate (:meth:`StructureCheck.scale_factor`,
``grey_scale_search``).
"""

from __future__ import annotations

import math

import numpy as np

from ..cues.scale_search import scale_candidates, size_factor
from ..cues.structure import StructureCue
from ..cues.structure_hog import BestStructure, HogStructure
from ..cues.structure_light import LitStructure
from ..filtering.loss import FusedLoss, LossDetector

#: fusion-pf's defaults for its structural cue (structure_pixels, structure_rate, structure_anchor_gate).
TEMPLATE_PIXELS, RATE, ANCHOR_GATE = 256, 0.02, 0.5
#: the running reference is refreshed on every this many confident frames, at the rate that gives the same time
#: constant (the refresh is most of the check's cost; every frame re-acquired as many of the grey tune set's
#: reappearances)
UPDATE_EVERY = 5
#: sharpness of the structural likelihood exp(GAIN r) with grey_check="fused" (fusion-pf's structure_gain)
GAIN = 10.0
#: the share of the parabola's vertex the size moves by a frame with grey_scale_search (fusion-pf's scale_search_rate)
SCALE_RATE = 0.25
#: fusion-pf's defaults for its fused loss test (loss_cue_clip, loss_cue_floor, acquire_z, acquire_margin)
CUE_CLIP, CUE_FLOOR, ACQUIRE_Z, ACQUIRE_MARGIN = 10.0, 2.0, 4.0, 2.0


def ncc_score(ncc: np.ndarray) -> np.ndarray:
    """NCC in [-1, 1] as a score in [0, 1] (the scale of the loss test's floors), as ``fusion-pf`` maps it."""
    return (np.asarray(ncc, dtype=np.float64) + 1.0) * 0.5


#: offsets of the boxes a candidate is checked with, in half-axes (a 5 x 5 grid reaching one half-axis each way)
OFFSETS = (-1.0, -0.5, 0.0, 0.5, 1.0)


def neighbourhood(ellipse: np.ndarray, offsets=OFFSETS) -> np.ndarray:
    """Ellipses ``(len(offsets)^2, 4)`` of the candidate's size centred on a grid of offsets around it (the scale
    search's candidates at the one ratio 1)."""
    shifts = np.array([(a, b) for b in offsets for a in offsets], dtype=np.float64)
    return scale_candidates(np.asarray(ellipse, dtype=np.float64).ravel()[:4], np.ones(1), shifts)


def fused_test(**members) -> FusedLoss:
    """``fusion-pf``'s two-cue loss test (colour coefficient, structural score): its clip, floor and acquisition
    bounds, each cue's :class:`~pftrack.filtering.loss.LossDetector` built with ``members``."""
    return FusedLoss(2, cue_clip=CUE_CLIP, cue_floor=CUE_FLOOR, acquire_z=ACQUIRE_Z, acquire_margin=ACQUIRE_MARGIN,
                     **members)


def fused_loss(p) -> FusedLoss:
    """:func:`fused_test` with the colour PF's parameters ``p``."""
    return fused_test(lost_frames=p.lost_frames, reacquire_margin=p.reacquire_margin, history_rate=p.history_rate,
                      sd_floor_target=p.score_sd_floor, sd_floor_background=p.score_sd_floor, learn_z=p.history_z)


class StructureCheck:
    """Reference grey patches, their background statistics and score history (see the module docstring).

    ``fused``: the references also score every particle (:meth:`log_lik`) and join the loss test
    (:meth:`loss_scores`); they are kept for the grey levels and for their self-quotient image, and the running
    references are refreshed on every confident frame."""

    def __init__(self, detector: LossDetector, *, fused: bool = False, template_pixels: int = TEMPLATE_PIXELS,
                 rate: float = RATE, anchor_gate: float = ANCHOR_GATE, sigma: float = 0.1, gray_of=None,
                 features: str = "ncc"):
        # fused: the patches of the grey levels and of their self-quotient image (scale sigma), the better of the
        # two (fusion-pf's grey_structure="both"): a lamp or a shadow across a face lowered the grey levels' NCC
        # alone until the fused test declared the face lost (docs/robustness.md); or (features="hog") histograms
        # of oriented gradients, fusion-pf's structural cue on grey input; or (features="both") the better of the two
        if features not in ("ncc", "hog", "both"):
            raise ValueError(f"features must be 'ncc', 'hog' or 'both', got {features!r}")
        if fused and features == "hog":
            self.cue = HogStructure()
        elif fused:
            self.cue = LitStructure(template_pixels, weighting="uniform", sigma=sigma, mode="both", gray_of=gray_of)
            if features == "both":
                self.cue = BestStructure(self.cue, HogStructure())
        else:
            self.cue = StructureCue(template_pixels, anchor=True, weighting="uniform")
        self.detector = detector
        self.fused = bool(fused)
        self.update_every = 1 if self.fused else UPDATE_EVERY
        self.rate = float(rate)
        self.anchor_gate = float(anchor_gate)
        self._learned = 0  # confident frames learned since init (the reference is refreshed on every UPDATE_EVERY-th)

    @classmethod
    def for_params(cls, p, *, gray_of=None) -> "StructureCheck":
        """The check a colour PF's parameters ``p`` ask for (``grey_check``), its test with their history settings
        (``gray_of``: the tracker's cached grey image of the frames the check sees, for the quotient image)."""
        return cls(LossDetector(history_rate=p.history_rate, sd_floor_target=p.score_sd_floor,
                                sd_floor_background=p.score_sd_floor, learn_z=p.history_z),
                   fused=p.grey_check == "fused", sigma=p.illumination_sigma, gray_of=gray_of,
                   features=p.grey_check_features)

    def init(self, frame: np.ndarray, ellipse: np.ndarray) -> None:
        self.cue.init(frame, np.asarray(ellipse, dtype=np.float64).reshape(1, 4))
        self.detector.reset(1.0)
        self._learned = 0

    def new_frame(self) -> None:
        """A new frame begins (its reduced grey region is computed when first needed)."""
        self.cue.new_frame()

    def scores(self, frame: np.ndarray, ellipses: np.ndarray) -> np.ndarray:
        """Scores in [0, 1] of a batch of ellipses against the references (the better of the two)."""
        e = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
        roi = None if e.shape[0] == 1 else (0, 0, frame.shape[1], frame.shape[0])
        return ncc_score(self.cue.scores(frame, roi, e))

    def log_lik(self, frame: np.ndarray, roi, ellipses: np.ndarray) -> np.ndarray:
        """The structural log-likelihood ``GAIN r`` of a batch of particles' ellipses (``roi`` covers them)."""
        return GAIN * self.cue.scores(frame, roi, ellipses)

    def scale_factor(self, frame: np.ndarray, ellipse, step: float) -> float:
        """The factor the half-axes of ``ellipse`` move by toward the size whose patch best matches the references
        (``grey_scale_search``, as ``fusion-pf``'s ``scale_search``; :func:`~pftrack.cues.scale_search.size_factor`,
        ``SCALE_RATE`` of the way; 1 while the largest box is not inside the frame)."""
        return size_factor(self.cue, frame, ellipse, step, SCALE_RATE)

    def loss_scores(self, frame: np.ndarray, roi, ellipses: np.ndarray, rho: np.ndarray) -> np.ndarray:
        """``(M, 2)`` scores of the fused loss test: the histogram's coefficient and the NCC score in [0, 1]."""
        out = np.empty((len(rho), 2))
        out[:, 0] = rho
        out[:, 1] = ncc_score(self.cue.scores(frame, roi, ellipses))
        return out

    def learn(self, frame: np.ndarray, ellipse: np.ndarray) -> None:
        """A confident frame: the estimate's score joins the history, and its patch the running reference (unless
        it drifted from the first frame's)."""
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        s = float(self.scores(frame, e)[0])
        if math.isfinite(s):
            self.detector.learn(s, True)
        self._learned += 1
        if self._learned % self.update_every == 0:
            self.cue.update(frame, e[0], 1.0 - (1.0 - self.rate) ** self.update_every, self.anchor_gate)

    def set_background(self, frame: np.ndarray, ellipses: np.ndarray) -> None:
        """Background statistics from boxes away from the target (the colour PF's background grid)."""
        s = self.scores(frame, ellipses)
        s = s[np.isfinite(s)]
        if s.size >= 2:
            self.detector.set_background(s)

    def vetoes(self, frame: np.ndarray, ellipse: np.ndarray) -> bool:
        """Does the structural evidence call this candidate, and every box around it, background?

        The histogram's best candidate is often off the target by a fraction of its size (a histogram hardly
        changes when half the box slides off the target onto similar clutter), and tracking would pull it on;
        the NCC of such a box is low. So the candidate stands if any box of a grid around it
        (:func:`neighbourhood`) scores as the target."""
        s = self.scores(frame, neighbourhood(ellipse))
        s = s[np.isfinite(s)]
        return bool(s.size and self.detector.evaluate(float(s.max())) < 0.0)
