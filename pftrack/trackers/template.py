"""``template``: exhaustive template matching in a window around the last position (book ch. 14).

Book *Object Tracking*, ch. 14 (``shared/book/ch14.md``): the grey template ``R`` cut from the
first box is compared with every offset of a search window ``S`` by one of the chapter's six
criteria (:mod:`pftrack.cues.template`); the best offset, refined to sub-pixel precision,
translates the box.  As the chapter prescribes, a match that is poor or that sits on the border
of the window (the main failure cause: a search area that is too small) is searched again in a
window ``enlarge`` times larger.  The template is fixed (the chapter's choice; its updated
variant drifts) unless ``template_update`` is set.

Large boxes are compared at reduced resolution: template and window are sampled on the same
grid of pitch ``f`` frame pixels (at most ``template_pixels`` template pixels), so the cost does
not grow with the target.

``lost`` is raised after ``lost_frames`` frames whose peak is unreliable: for the normalised criteria
a best score below ``lost_score``, for the others a peak-to-sidelobe ratio below ``lost_psr``.

A template of one flat colour has no structure for NCC or mutual information to find: its correlation with any
window is the noise's, about 0, and its entropy is 0. When the template's contrast, net of the camera's noise, is
below the noise (``flat_fallback``; the noise read from the first two frames by
:func:`pftrack.cues.noise.temporal_noise`), those criteria give way to SAD, which matches the level itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cues import ssim as S
from ..cues import template as T
from ..cues.noise import temporal_noise
from ..filtering.loss import LossDetector
from ..geometry import Box
from ..params import Params, param
from .base import Tracker, TrackState

Metric = Literal["ssd", "ccorr", "ncc", "ncc_uncentred", "sad", "morph", "morph_normed", "mi", "nmi"]
_BOUNDED = {"ncc", "ncc_uncentred"}
#: criteria that see a template's structure only, not its level: undefined on a flat template
_STRUCTURAL = {"ncc", "ncc_uncentred", "mi", "nmi"}


@dataclass(frozen=True, kw_only=True)
class TemplateParams(Params):
    """Parameters of ``template`` (ch. 14; values the text leaves open are ch14.md §2's proposals)."""

    metric: Metric = param("ncc", doc=(
        "Matching criterion: ssd (3), ccorr (4), ncc (5, the chapter's best), ncc_uncentred, sad (6), morph (7, sum "
        "of minima), morph_normed (7 normalised), mi (9, mutual information) or nmi (normalised MI)."))
    search_margin: float = param(0.5, gt=0, le=10, doc=(
        "Half-width of the search window beyond the box, as a fraction of the box's size (at least 8 px): "
        "the chapter's kmax, lmax 'greater or equal to the maximum movement'."))
    enlarge: float = param(2.0, ge=1, le=10, doc=(
        "When the peak is poor or on the window's border, search again in a window this much larger "
        "(the chapter: a too small search area is the main cause of failure)."))
    template_pixels: int = param(1600, ge=64, le=1_000_000, doc=(
        "Speed bound: the template keeps the box's aspect with at most this many pixels; larger boxes are "
        "matched on a coarser grid (template and window sampled alike)."))
    mi_bins: int = param(32, ge=2, le=256, doc=(
        "Grey-level bins of the mutual-information criteria (fixed binning, 0-255)."))
    template_update: float = param(0.0, ge=0, le=1, doc=(
        "Rate of the template update t <- (1 - a) t + a p on frames that are not lost; 0 keeps the chapter's "
        "fixed template (its updated variant drifts after one bad match)."))
    lost_psr: float = param(2.5, ge=0, le=1000, doc=(
        "For the other criteria (ssd, ccorr, sad, morph, morph_normed, mi, nmi): the peak-to-sidelobe ratio "
        "(sidelobe beyond +-5 template pixels) below which a match is unreliable. Correct matches measured 2.5-4 on "
        "synthetic scenes."))
    lost_score: float = param(0.5, ge=-1, le=1, doc=(
        "For ncc and ncc_uncentred: a best score below this is unreliable (ch14.md: NCC < 0.5)."))
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive unreliable frames before the target is declared lost.")
    reacquire_margin: float = param(1.0, ge=0, le=20, doc=(
        "Normalised criteria: the loss test of pftrack.filtering.loss compares the peak with the window's best "
        "clutter and with the target's history; a lost target is re-acquired when its LLR exceeds this."))
    search: Literal["local", "frame"] = param("local", doc=(
        "While lost: 'local' holds the box and searches a window enlarge times the usual one around it (the "
        "chapter's enlarged search); 'frame' matches the template over the whole frame, then judges the best place "
        "as a tracked frame would be judged (the loss test on its window), and holds the box where it was if that "
        "fails. Only for the bounded scores (ncc, ncc_uncentred, and the flat template's fallback); the others "
        "search locally."))
    flat_fallback: Literal["sad", "off"] = param("sad", doc=(
        "For ncc, ncc_uncentred, mi and nmi: when the template is flat (its grey levels' variance below twice the "
        "noise's, plus 1, the noise read from the first two frames), match by this criterion instead; 'off' keeps "
        "the metric. No first box of the development data falls back, nor of its copies with noise of 12 grey "
        "levels or dimmed to a quarter (the nearest at 2.1 times the bound; docs/template.md)."))


class TemplateTracker(Tracker):
    """Template matching tracker (deterministic: ``particles`` is None)."""

    name = "template"
    Params = TemplateParams
    stochastic = False

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        x, y, w, h = box
        self.size = (float(w), float(h))
        self.pitch = max(1.0, math.sqrt(w * h / p.template_pixels))
        self.tshape = (max(3, int(round(h / self.pitch))), max(3, int(round(w / self.pitch))))
        self.c = np.array([x + w / 2.0, y + h / 2.0])
        gray = S.to_gray(frame)
        self.template = self._sample(gray, self.c, self.tshape)
        self.metric = p.metric  # the criterion in use (flat_fallback may change it on the first update)
        self._levelled = 0.0  # with the fallback: the scale d of its score 1 - mean |R - S| / d
        self._first: np.ndarray | None = gray if p.metric in _STRUCTURAL and p.flat_fallback != "off" else None
        self.miss = 0
        self.lost = False
        self.loss = LossDetector(lost_frames=1, reacquire_margin=p.reacquire_margin, sd_floor_target=0.05,
                                 sd_floor_background=0.05)
        self.loss.reset(1.0, sd=0.2)
        return TrackState(box=tuple(float(v) for v in box), score=1.0, lost=False, info={"metric": self.metric})

    def _check_flat(self, gray: np.ndarray) -> None:
        """On the first update: fall back to ``flat_fallback`` if the template's variance is below twice the
        noise's variance plus 1 (its structure, net of the noise, below the noise: a flat template)."""
        first, self._first = self._first, None
        sigma = temporal_noise(first, gray)
        if float(self.template.var()) < 2.0 * sigma * sigma + 1.0:
            self.metric = self.params.flat_fallback
            self._levelled = 2.0 * max(float(first.std()), 1.0)

    @property
    def _bounded(self) -> bool:
        """Whether the scores are bounded (NCC's, or the fallback's mean absolute difference on the scale of
        the scene's contrast) and go through the loss test, rather than the peak-to-sidelobe ratio."""
        return self.metric in _BOUNDED or self._levelled > 0

    def _sample(self, gray: np.ndarray, centre: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
        st = np.array([[centre[0], centre[1], self.pitch]])
        return S.sample_patches(gray, st, shape)[0].astype(np.float64)

    def _match(self, gray: np.ndarray, margin_px: float) -> tuple[np.ndarray, T.Peak]:
        """Search the window of ``margin_px`` frame pixels around the current centre."""
        p = self.params
        mk = max(1, int(round(margin_px / self.pitch)))
        m, n = self.tshape
        window = self._sample(gray, self.c, (m + 2 * mk, n + 2 * mk))
        surface = T.match_surface(window, self.template, self.metric, bins=p.mi_bins)
        if self._levelled:  # -SAD as 1 - mean |R - S| / d, d twice the first frame's grey spread: a window of
            # the scene's clutter scores about 0.5, as it does by NCC (the peak-to-sidelobe ratio is unchanged)
            surface = 1.0 + surface / (self.template.size * self._levelled)
        peak = T.best_offset(surface)
        centre = self.c + np.array([(peak.l - mk) * self.pitch, (peak.k - mk) * self.pitch])
        self._surface = surface
        return centre, peak

    def _search_frame(self, gray: np.ndarray) -> np.ndarray:
        """The centre of the template's best match over the whole frame (sampled on the template's grid)."""
        p = self.params
        fh, fw = gray.shape[:2]
        m, n = self.tshape
        big_m, big_n = max(m, int(fh / self.pitch)), max(n, int(fw / self.pitch))
        cf = np.array([fw / 2.0, fh / 2.0])
        whole = S.sample_patches(gray, np.array([[cf[0], cf[1], self.pitch]]), (big_m, big_n))[0]
        surface = T.match_surface(whole.astype(np.float64), self.template, self.metric, bins=p.mi_bins)
        k, l = np.unravel_index(int(np.argmax(surface)), surface.shape)
        return cf + np.array([(l - (big_n - n) / 2.0) * self.pitch, (k - (big_m - m) / 2.0) * self.pitch])

    def _sidelobe(self, peak: T.Peak) -> np.ndarray:
        """Scores of the last surface at offsets that overlap the peak's window by less than half."""
        s = self._surface
        m, n = self.tshape
        k, l = int(round(peak.k)), int(round(peak.l))
        mask = np.ones(s.shape, dtype=bool)
        mask[max(k - m // 2, 0):k + m // 2 + 1, max(l - n // 2, 0):l + n // 2 + 1] = False
        return s[mask]

    def _reliable(self, peak: T.Peak) -> bool:
        """The bounded criteria are judged by their value, the others by the peak-to-sidelobe ratio."""
        p = self.params
        if self._bounded:
            return peak.value >= p.lost_score
        return peak.psr >= p.lost_psr

    def _score(self, peak: T.Peak) -> float:
        """A confidence in [0, 1]: the bounded criteria's value, else the PSR scaled (PSR 20 -> 1)."""
        if self._bounded:
            return float(np.clip(peak.value, 0.0, 1.0))
        return float(np.clip(peak.psr / 20.0, 0.0, 1.0)) if math.isfinite(peak.psr) else 1.0

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        gray = S.to_gray(frame)
        if self._first is not None:
            self._check_flat(gray)
        base = max(8.0, p.search_margin * max(self.size))
        held = None  # search="frame" while lost: where the box is held, the frame's best match tried instead
        if self.lost and p.search == "frame" and self._bounded:
            held, self.c = self.c, self._search_frame(gray)
        margin = base * (p.enlarge if self.lost and held is None else 1.0)
        centre, peak = self._match(gray, margin)
        surface = self._surface
        enlarged = False
        if (peak.on_border or not self._reliable(peak)) and p.enlarge > 1:
            # a wider window may hold the target (it moved further than the margin) or only clutter:
            # its peak replaces the first one only if it is reliable and better
            c2, pk2 = self._match(gray, margin * p.enlarge)
            surface2 = self._surface
            enlarged = True
            if self._reliable(pk2) and not pk2.on_border and pk2.value > peak.value:
                centre, peak, surface = c2, pk2, surface2
        self._surface = surface  # the surface of the chosen peak (for the sidelobe of the loss test)
        ok = self._reliable(peak) and not peak.on_border
        if self._bounded:
            # the loss test of the colour trackers: the peak against the best clutter of the window (absent
            # hypothesis) and against the peaks of confident frames (target history), with hysteresis
            side = self._sidelobe(peak)
            if side.size >= 3:
                self.loss.set_background(side)
            if self.lost:
                ok = ok and self.loss.acquire(peak.value)
            else:
                lost_now, _ = self.loss.step(peak.value)
                ok = ok and not lost_now and self.loss.llr >= 0
        self.miss = 0 if ok else self.miss + 1
        if ok:
            self.lost = False
        elif self.miss >= p.lost_frames:
            self.lost = True
        if ok or not self.lost:
            # follow the best match unless the target is judged gone (then hold and search wider)
            fh, fw = self._shape
            self.c = np.clip(centre, [0.0, 0.0], [fw, fh])
        elif held is not None:
            self.c = held
            if p.template_update > 0 and ok:
                patch = self._sample(gray, self.c, self.tshape)
                self.template = (1.0 - p.template_update) * self.template + p.template_update * patch
        w, h = self.size
        box = (float(self.c[0] - w / 2), float(self.c[1] - h / 2), float(w), float(h))
        info = {"metric": self.metric, "value": peak.value, "psr": peak.psr, "on_border": peak.on_border,
                "enlarged": enlarged}
        return TrackState(box=box, score=self._score(peak) if ok else min(self._score(peak), 0.5), lost=self.lost,
                          info=info)
