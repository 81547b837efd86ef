"""A calibrated lost flag for any tracker: the colour particle filters' loss test on the boxes it reports.

Many trackers have no test of the target's absence: on six vanish scenes OpenCV's MIL, MedianFlow and TLD, the
mean-shift baselines and ``pisc`` never raise ``lost``, ``dssim`` raises it on 1 % of the hidden frames and CSRT on
16 % (docs/evaluation.md).  :class:`Monitored` wraps any tracker and judges each box the tracker reports with the
two-class test of :mod:`pftrack.filtering.loss`, which keeps Nummiaro et al.'s appearance condition (Eqs. 13–15) as
its background half:

* **the target model** is the kernel-weighted histogram of the first box's ellipse (Eqs. 3–5; grey features on grey
  input, as the cue chooses its features from the input), updated by Eq. 12 at rate ``alpha`` on the frames where the
  test is confident;
* **the score** of a frame is the best Bhattacharyya coefficient (Eq. 6) with the model among the reported box's
  ellipse and a few neighbours (shifted by a quarter of the half-axes, scaled by ±10 %): a particle filter's estimate
  is the best match near the target, and the absent hypothesis below is the best clutter;
* **the absent hypothesis** is the upper tail of the scores of ``background_positions`` ellipses of the target's
  size on a fixed grid away from the box (Eqs. 13–14), refreshed every ``background_interval`` confident frames
  (as in ``color-pf``: a target the colours cannot tell from its surroundings leaves the test abstaining);
* **hysteresis**: ``lost`` after ``lost_frames`` consecutive frames whose likelihood ratio is negative, and down
  again only when the ratio exceeds ``reacquire_margin``.

With ``cues="fused"`` (``monitor_cues=fused``) the test is ``fusion-pf``'s: the box neighbourhood's best structural
score joins the colour coefficient in :class:`~pftrack.filtering.loss.FusedLoss`, with ``fusion-pf``'s clip, floor
and acquisition bounds. The structural cue chooses its features from the input, as ``fusion-pf``'s
(:class:`~pftrack.trackers.structure_check.StructureCheck`, a first and a running reference): on colour input the NCC
of grey patches (the better of the grey levels' and of their self-quotient image's), on grey input histograms of
oriented gradients (``structure_features="hog-on-grey"``). It cuts the false alarms on targets coloured like their
surroundings and under light changes, and misses more hidden frames behind trackers that match grey structure
themselves (``template``, ``dssim``, ``ssim-pf``): their box on an occluder is the best structural match there
(docs/evaluation.md). It is an option: on the tune split it lowered the flag's recall more than the rule for a
default allowed.

With ``grey_histogram="both"`` (``monitor_grey_histogram=both``) a box on grey input scores the better of the grey
levels' histogram and ``color-pf``'s second one, of the self-quotient image (:mod:`pftrack.cues.lit_histogram`),
each against its own model: an option as well (docs/evaluation.md).

The tracker itself is not changed: its boxes, particles and information pass through, and the grid is fixed, so the
tracks are the same with or without the monitor. Unless ``search="frame"`` (``monitor_search=frame``): then, while the
test calls the target lost, the whole frame is searched with the test's model (:mod:`pftrack.trackers.frame_search`),
and a candidate that is unique in the frame, steady for ``search_frames`` frames and accepted by the test starts the
tracker again there (its ``init`` on that box; ``info["restarted"]``).

``lost`` is raised when the tracker or the test raises it; ``score`` is the test's posterior P(target | rho), at
most one half on a frame the test calls lost (the tracker's own score is ``info["tracker_score"]``).

    tracker = pftrack.create_tracker("opencv-csrt", monitor=True)      # or Monitored(create_tracker(...))
    pftrack eval SEQ --trackers "opencv-csrt,opencv-csrt[monitor=true]"
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np

from ..cues.color import blend_model, model_rho, normalized_model, reachable_roi
from ..cues.histogram_cue import ColorCue
from ..cues.lit_histogram import LitHistogram
from ..filtering.loss import FusedLoss, LossDetector, confidence
from ..geometry import Box, background_grid, box_to_ellipse, ellipse_to_box
from ..params import Params, param
from .base import Tracker, TrackState
from .frame_search import Persistence, Residents, exit_scan, frame_candidate
from .structure_check import ANCHOR_GATE, RATE, StructureCheck, fused_test

__all__ = ["LossMonitor", "MonitorParams", "Monitored", "WrapperOptions", "wrapper_options"]


@dataclass(frozen=True, kw_only=True)
class MonitorParams(Params):
    """The loss test's parameters: those of ``color-pf``'s test, whose defaults were chosen on the tune split."""

    alpha: float = param(0.05, ge=0, le=1, doc=(
        "Rate of the target model's update (Nummiaro et al. Eq. 12) on frames where the test is confident "
        "(0: the first box's histogram throughout)."))
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive frames with a negative ratio before lost is raised.")
    reacquire_margin: float = param(1.0, ge=0, le=20, doc=(
        "The ratio (log odds) a frame must exceed to end a loss, and to count as confident (hysteresis)."))
    history_rate: float = param(0.05, gt=0, le=1, doc="Weight of a confident score in the target's score history.")
    score_sd_floor: float = param(0.03, gt=0, le=1, doc="Floor on both classes' score spreads.")
    background_positions: int = param(100, ge=4, le=100_000, doc=(
        "Background ellipses of the target's size on a fixed grid (Eqs. 13-14)."))
    background_interval: int = param(10, ge=1, le=100_000, doc=(
        "Confident frames between refreshes of the background scores."))
    color_space: Literal["auto", "rgb", "hsv", "gray"] = param("auto", doc=(
        "Features of the histograms: 'auto' takes intensity x gradient orientation on grey input, RGB otherwise."))
    shift: float = param(0.25, ge=0, le=2, doc=(
        "The score is the best coefficient among the box's ellipse and its neighbours shifted by this many "
        "half-axes (as a particle filter's estimate is the best match near the target, and the absent hypothesis "
        "the best clutter); 0: the box's ellipse alone."))
    scale: float = param(0.1, ge=0, lt=1, doc="... and its neighbours scaled by 1 ± this.")
    max_pixels: int = param(1500, ge=0, le=10_000_000, doc=(
        "Pixels sampled per ellipse at most (a regular lattice on larger ones; 0: every pixel)."))
    grey_histogram: Literal["levels", "both"] = param("levels", doc=(
        "Grey input: 'levels' the histogram of the grey levels; 'both' also color-pf's histogram of the "
        "self-quotient image (pftrack.cues.lit_histogram, scale illumination_sigma), a box scoring the better of "
        "its two coefficients, each against its own model (a lamp or a shadow that lights the target differently "
        "from the frame changes the first, not the second). Tried as the default on the tune split and not kept: "
        "false-lost 0.077 against 0.082 over seven trackers, less than its rule asked (docs/evaluation.md)."))
    illumination_sigma: float = param(0.1, gt=0, le=2, doc=(
        "With grey_histogram='both': the self-quotient image's scale, a fraction of the frame's larger side."))
    cues: Literal["color", "fused"] = param("color", doc=(
        "'color': the histogram's coefficient alone; 'fused': with fusion-pf's structural score beside it "
        "(structure_features), both in fusion-pf's fused two-class test (pftrack.filtering.loss.FusedLoss). Fewer "
        "false alarms on camouflaged targets and under changing light, fewer hidden frames flagged behind trackers "
        "that match grey structure themselves (docs/evaluation.md: tune split, 7 trackers, false-lost 0.047 against "
        "0.082, lost recall 0.888 against 0.952)."))
    search: Literal["off", "frame"] = param("off", doc=(
        "While the test calls the target lost, look for it over the whole frame (pftrack.trackers.frame_search): "
        "ellipses of its size on a grid of a quarter window, scored by their coefficient with the model; the best, "
        "when the test would end the loss on it, when 1 - rho is at most search_ratio times the best one at least a "
        "box away and search_gap below it (unique in the frame) and when it stays in one place for search_frames "
        "frames, starts the tracker again there (its init on that box). 'off': the tracker alone decides where it "
        "looks."))
    search_ratio: float = param(0.5, gt=0, le=1, doc=(
        "The search's uniqueness test: the best 1 - rho at most this fraction of the runner-up's."))
    search_gap: float = param(0.02, ge=0, le=1, doc=(
        "... and the runner-up's 1 - rho at least this above the best's: with a fine model two look-alikes of one "
        "colour both score about 0, where a ratio alone tells nothing."))
    search_exit: bool = param(False, doc=(
        "When the tracker's last box before the loss lay within half its size of an edge of the frame (the target "
        "left through it), the search keeps to the band within 1.5 box sizes of that edge, where it comes back. "
        "Off: on the tune PETS views and windows it changed little (CSRT's pooled lost recall 0.341 against 0.313, "
        "template's re-acquisitions 8 against 9 of 22; docs/evaluation.md)."))
    search_frames: int = param(2, ge=1, le=100, doc=(
        "Consecutive frames the search's best candidate must pass in one place (within half a window)."))
    search_resident: int = param(0, ge=0, le=1000, doc=(
        "When the tracker's last box before the loss lay within half its size of an edge of the frame, the grey "
        "frames of the last search_resident search frames are kept, and a candidate is refused when its box, "
        "traced back through them, stayed inside the view on every one (another object, in view all the while the "
        "target was out; pftrack.trackers.frame_search.Residents); the search then passes over it. 0: off (on the "
        "tune views 15 raised the pooled lost recall and the false alarms; docs/evaluation.md)."))
    structure_features: Literal["ncc", "hog-on-grey"] = param("hog-on-grey", doc=(
        "With cues='fused', what the structural score correlates: 'ncc' grey patches (the better of the grey "
        "levels' and their self-quotient image's NCC) on every input; 'hog-on-grey' histograms of oriented "
        "gradients on grey input (fusion-pf's default there), 'ncc' on colour. Chosen on the tune split: false-lost "
        "0.047 against 0.051, lost recall 0.888 against 0.862 (docs/evaluation.md)."))


def neighbourhood(ell: np.ndarray, shift: float, scale: float) -> np.ndarray:
    """The ellipse ``(cx, cy, hx, hy)`` and its neighbours: shifted by ``shift`` half-axes in the 8 directions, and
    scaled by ``1 ± scale`` (11 ellipses; only the ellipse itself when both are 0)."""
    cx, cy, hx, hy = (float(v) for v in np.asarray(ell).reshape(4))
    out = [(cx, cy, hx, hy)]
    if shift > 0:
        out += [(cx + i * shift * hx, cy + j * shift * hy, hx, hy) for i in (-1, 0, 1) for j in (-1, 0, 1) if i or j]
    if scale > 0:
        out += [(cx, cy, hx * (1 + k * scale), hy * (1 + k * scale)) for k in (-1, 1)]
    return np.array(out)


class LossMonitor:
    """The test on its own: :meth:`start` on the first frame and box, then :meth:`check` each reported box."""

    def __init__(self, params: MonitorParams | None = None):
        self.params = p = params if params is not None else MonitorParams()
        self.cue = ColorCue(p.color_space, None, "nummiaro", p.max_pixels)
        test = dict(lost_frames=p.lost_frames, reacquire_margin=p.reacquire_margin, history_rate=p.history_rate,
                    sd_floor_target=p.score_sd_floor, sd_floor_background=p.score_sd_floor)
        self.loss: LossDetector | FusedLoss
        self.structure: StructureCheck | None = None
        if p.cues == "fused":
            self.loss = fused_test(**test)  # fusion-pf's fused test; its structural cue is chosen at start()
        else:
            self.loss = LossDetector(**test)
        self._test = test
        self.lit: LitHistogram | None = None  # grey_histogram="both" on grey input (decided at start())
        self.q: np.ndarray | None = None
        self._sqrt_q: np.ndarray | None = None
        self._half: tuple[float, float] = (1.0, 1.0)
        self._since_bg = 0
        self._searched = False  # find() ran the cue's per-frame preparation on the frame check() is given next

    def start(self, frame: np.ndarray, box: Box) -> None:
        self.cue.adapt_to(frame)
        self.cue.new_frame(frame)
        ell = box_to_ellipse(box)
        self._half = (float(ell[2]), float(ell[3]))
        self.q, self._sqrt_q = normalized_model(self.cue.histogram(frame, ell))
        self.loss.reset(1.0)
        self.lit = None
        if self.params.grey_histogram == "both" and self.cue.color_space == "gray":
            p = self.params
            self.lit = LitHistogram(sigma=p.illumination_sigma, gray_bins=self.cue.gray_bins, kernel="nummiaro",
                                    max_pixels=p.max_pixels, gradient_threshold=self.cue.gradient_threshold)
            self.lit.init(frame, ell)
        if self.params.cues == "fused":
            # the structural cue chooses its features from the input, as fusion-pf's; the check's own detector is
            # not used (each cue's statistics live in the fused test)
            hog = self.params.structure_features == "hog-on-grey" and self.cue.color_space == "gray"
            self.structure = StructureCheck(LossDetector(**self._test), fused=True, features="hog" if hog else "ncc")
            self.structure.init(frame, ell)
        self._background(frame, ell)

    def _background(self, frame: np.ndarray, ell: np.ndarray) -> None:
        h, w = frame.shape[:2]
        grid = background_grid(w, h, *self._half, self.params.background_positions, ell)
        self._since_bg = 0
        if grid.shape[0] < 2:
            return  # nothing left that is background: keep the previous statistics
        feats = self.cue.prepare(frame, (0, 0, w, h), self.cue.step_for(grid))
        rho, tot = self.cue.rho(feats, grid, self._sqrt_q, reuse=False)
        if self.lit is not None:  # the background scores as a box scores: the better of the two models
            rho = np.maximum(rho, self.lit.rho(feats.roi, feats.pitch, grid))
        if np.count_nonzero(tot > 0) >= 2:
            if self.structure is None:
                self.loss.set_background(rho[tot > 0])
            else:
                self.loss.set_background(np.column_stack([np.where(tot > 0, rho, np.nan),
                                                          self.structure.scores(frame, grid)]))

    def find(self, frame: np.ndarray, persist: Persistence, last: Box | None = None,
             residents: Residents | None = None, index: int = 0) -> Box | None:
        """While lost (``search="frame"``): the whole frame's best ellipse of the target's size, when the test would
        end the loss on it, it is unique in the frame and ``persist`` has seen it in one place long enough; its box,
        else None. The test's state does not change; :meth:`check` must follow on the same frame (the box it reports
        is checked as any other), and does not prepare the cue again. With ``residents`` (``search_resident``) and a
        ``last`` box at an edge, frame number ``index`` is kept and a resident candidate refused."""
        p = self.params
        self.cue.new_frame(frame)
        self._searched = True  # check() follows on this frame: its preparation is done
        h, w = frame.shape[:2]
        hx, hy = self._half
        step = 0.25 * (hx + hy)  # a quarter of the window (the mean of the box's sides)
        feats = self.cue.prepare(frame, (0, 0, w, h), self.cue.step_for(np.array([[0.0, 0.0, hx, hy]])))

        centres, residents = exit_scan(frame, (2 * hx, 2 * hy), step, last, p.search_exit, residents, index)

        def distance(c: np.ndarray) -> np.ndarray:
            e = np.column_stack([c, np.full(len(c), hx), np.full(len(c), hy)])
            rho, tot = self.cue.rho(feats, e, self._sqrt_q, reuse=False)
            return np.where(tot > 0, 1.0 - rho, np.inf)

        score = distance if residents is None else residents.passing_over(distance, 2 * hx, 2 * hy)
        best = frame_candidate(score, centres, (2 * hx, 2 * hy), step) if len(centres) else None
        gated = None
        if best is not None and best.unique(p.search_ratio, p.search_gap):
            rho = 1.0 - best.distance
            ell = np.array([best.centre[0], best.centre[1], hx, hy])
            s_in: float | list[float] = rho
            if self.structure is not None:
                self.structure.new_frame()
                s_in = [rho, float(self.structure.scores(frame, ell[None])[0])]
            if self.loss.would_acquire(s_in)[0]:
                gated = best.centre
        if not persist.offer(gated):
            return None
        box = tuple(float(v) for v in ellipse_to_box(np.array([gated[0], gated[1], hx, hy])).reshape(4))
        if residents is not None and residents.resident(box):
            return None  # another object, in view all the while the target was out
        return box

    def check(self, frame: np.ndarray, box: Box) -> tuple[bool, float, float]:
        """``(lost, score, rho)`` of the box reported on this frame (the test's state advances)."""
        if self.q is None:
            raise RuntimeError("LossMonitor: call start(frame, box) first")
        if not self._searched:
            self.cue.new_frame(frame)
        self._searched = False
        ell = box_to_ellipse(box)
        e = neighbourhood(ell, self.params.shift, self.params.scale)
        h, w = frame.shape[:2]
        feats = self.cue.prepare(frame, reachable_roi(e, w, h), self.cue.step_for(e))
        rhos, tots = self.cue.rho(feats, e, self._sqrt_q, reuse=False)
        if self.lit is not None:
            self.lit.new_frame(frame)
            rhos = np.maximum(rhos, self.lit.rho(feats.roi, feats.pitch, e))
        rhos = np.where(tots > 0, rhos, 0.0)
        best = int(np.argmax(rhos))
        hist, tot = self.cue.histograms(feats, e[best:best + 1], reuse=False)
        rho = model_rho(hist[0], self._sqrt_q) if tot[0] > 0 else 0.0
        if self.lit is not None and tot[0] > 0:
            rho = max(rho, self.lit.estimate_rho(feats.roi, feats.pitch, e[best]))
        score_in: float | list[float] = rho
        if self.structure is not None:
            # the structural score of the box's neighbourhood, its best box (as the colour's)
            self.structure.new_frame()
            ncc = self.structure.scores(frame, e)
            best_s = int(np.nanargmax(ncc)) if np.isfinite(ncc).any() else 0
            score_in = [rho, float(ncc[best_s])]
        if self.loss.lost:
            lost = not self.loss.acquire(score_in)
            score = confidence(self.loss.llr)
        else:
            lost, score = self.loss.step(score_in)
        if not lost and tot[0] > 0 and self.loss.confident(score_in):
            # as color-pf: the model and the background statistics follow the confident frames only, so a target
            # the colours cannot tell from its surroundings leaves the test abstaining (no evidence either way)
            if self.params.alpha > 0:
                self.q, self._sqrt_q = blend_model(self.q, hist[0], self.params.alpha)
                if self.lit is not None:
                    self.lit.learn(self.params.alpha)
            if self.structure is not None:  # fusion-pf's running reference, refreshed on confident frames
                self.structure.cue.update(frame, e[best_s], RATE, ANCHOR_GATE)
            self._since_bg += 1
            if self._since_bg >= self.params.background_interval:
                self._half = (float(e[best, 2]), float(e[best, 3]))
                self._background(frame, e[best])
        if lost:  # the score and the flag agree (as color-pf's): a loss never reports more than even odds
            score = min(score, 0.5)
        return lost, float(score), float(rho)


class Monitored(Tracker):
    """Any tracker with :class:`LossMonitor`'s lost flag (see the module docstring)."""

    Params = MonitorParams

    def __init__(self, inner: Tracker, params: MonitorParams | None = None):
        super().__init__(params if params is not None else MonitorParams())
        self.inner = inner
        self.name = f"{inner.name}+monitor"
        self.stochastic = inner.stochastic
        self.state_names = getattr(inner, "state_names", ())
        self.monitor = LossMonitor(self.params)
        self._persist: Persistence | None = None  # made at init, with the first box's size
        self._residents: Residents | None = None  # search_resident: made at init
        self._lost = False
        self._last_box: Box | None = None

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        st = self.inner.init(frame, box)
        self.monitor.start(frame, box)
        self._persist = Persistence(self.params.search_frames, 0.25 * (box[2] + box[3]))
        self._residents = Residents(self.params.search_resident) if self.params.search_resident else None
        self._lost = False
        self._last_box = box
        return replace(st, info={**st.info, "tracker_score": st.score, "tracker_lost": st.lost})

    def _update(self, frame: np.ndarray) -> TrackState:
        found = None
        if self.params.search == "frame" and self._lost:
            found = self.monitor.find(frame, self._persist, self._last_box, self._residents, self.frame_index)
        if found is not None:  # the tracker starts again on the found box (its own state is that of a first frame)
            st = self.inner.init(frame, found)
        else:
            st = self.inner.update(frame)
        box = st.info.get("box_full", st.box)
        lost, score, rho = self.monitor.check(frame, box)
        self._lost = bool(st.lost or lost)
        if not self._lost:
            self._persist.reset()
            if self._residents is not None:
                self._residents.reset()
            self._last_box = box  # the last box before a loss: the edge a target that left went through
        return replace(st, lost=self._lost, score=score,
                       info={**st.info, "tracker_score": st.score, "tracker_lost": st.lost, "monitor_rho": rho,
                             "monitor_llr": self.monitor.loss.llr, "restarted": found is not None})


@dataclass(frozen=True, kw_only=True)
class WrapperOptions(Params):
    """Options every registered tracker takes beside its own parameters (``create_tracker``, ``--param``, and eval's
    ``NAME[key=value]``)."""

    monitor: bool = param(False, doc=(
        "Judge the tracker's boxes with the colour PFs' loss test (pftrack.trackers.monitor): a calibrated lost flag "
        "for a tracker that has none of its own."))
    monitor_cues: Literal["color", "fused"] = param("color", doc=(
        "The monitor's cues (MonitorParams.cues): the histogram alone, or fused with fusion-pf's structural score. "
        "Setting it (or monitor_structure) turns the monitor on unless monitor=false is given."))
    monitor_structure: Literal["ncc", "hog-on-grey"] = param("hog-on-grey", doc=(
        "With monitor_cues=fused, the structural score's features (MonitorParams.structure_features)."))
    monitor_grey_histogram: Literal["levels", "both"] = param("levels", doc=(
        "The monitor's histograms on grey input (MonitorParams.grey_histogram)."))
    monitor_search: Literal["off", "frame"] = param("off", doc=(
        "While the monitor calls the target lost, search the whole frame with its colour model and start the tracker "
        "again on a unique, steady candidate the test accepts (MonitorParams.search): re-acquisition for any "
        "tracker, OpenCV's included."))
    monitor_search_exit: bool = param(False, doc=(
        "With monitor_search=frame, a target whose last box lay at an edge of the frame is looked for in the band "
        "along that edge (MonitorParams.search_exit)."))
    monitor_search_resident: int = param(0, ge=0, le=1000, doc=(
        "With monitor_search=frame, after an exit through an edge a candidate that stayed in view through the last "
        "this many search frames is refused and passed over (MonitorParams.search_resident). 0: off."))
    grey_restart: int = param(0, ge=0, le=1000, doc=(
        "Input that turns grey mid-sequence: after this many grey frames in a row, a tracker that started on colour "
        "frames is started again on the grey copy of the last frame where its target was seen, so that it chooses "
        "grey features (pftrack.trackers.input_switch.GreyRestarted). The colour particle filters have their own "
        "input_switch, which also goes on searching a lost target. Default 0 (off), but 1 for cotrain-pf, chosen "
        "on the tune data (docs/rules/grey_restart_rule.txt); ten other trackers missed that rule."))

    def monitor_params(self) -> MonitorParams:
        """The loss monitor's parameters these options set."""
        return MonitorParams(cues=self.monitor_cues, structure_features=self.monitor_structure,
                             grey_histogram=self.monitor_grey_histogram, search=self.monitor_search,
                             search_exit=self.monitor_search_exit, search_resident=self.monitor_search_resident)


def wrapper_options(*sources: Mapping[str, Any] | None) -> WrapperOptions:
    """The options every tracker takes from parameter mappings, a later one overriding an earlier one; a setting of
    the monitor's turns it on unless ``monitor`` is given."""
    values: dict[str, Any] = {}
    for source in sources:
        if source:
            values.update({k: source[k] for k in WrapperOptions.__dataclass_fields__ if k in source})
    if any(k.startswith("monitor_") for k in values) and "monitor" not in values:
        values["monitor"] = True  # the monitor's own settings ask for it (monitor=false still turns it off)
    return split_wrapper_options(values)[0]


def grey_restart_for(cls, *sources: Mapping[str, Any] | None) -> int:
    """The ``grey_restart`` a tracker of class ``cls`` runs with: the value given last in ``sources``, or the class's
    own default (``Tracker.grey_restart``)."""
    given = [s["grey_restart"] for s in sources if s and "grey_restart" in s]
    return WrapperOptions.from_mapping({"grey_restart": given[-1]}).grey_restart if given else int(cls.grey_restart)


def split_wrapper_options(values: dict[str, Any]) -> tuple[WrapperOptions, dict[str, Any]]:
    """The wrapper options of a parameter mapping, and the rest (for the tracker's own parameters)."""
    names = {f for f in WrapperOptions.__dataclass_fields__}
    own = {k: v for k, v in values.items() if k not in names}
    return WrapperOptions.from_mapping({k: v for k, v in values.items() if k in names}), own
