"""Look-alikes that are part of the scene: a background test for the colour trackers' search and estimate.

Most of ``fusion-pf``'s missed reappearances on the tune scenes that probation left (docs/robustness.md, "The
search passes over what was in view before") were not moving distractors: the search had taken a piece of the
*scene* that looks like the target (an occluder's edge with the target's two grey levels, a patch of textured
clutter) and followed it, motionless, while the target came back elsewhere.  Such a look-alike was in view,
unchanged, while the target was still tracked somewhere else; the target coming back was not there then.  With
a still camera, a reference frame taken while the target was tracked tells the two apart without any appearance
model: the candidate's grey patch now is compared, by normalised correlation (insensitive to a change of gain
and offset), with the same place in the reference.

* While the target is tracked confidently, :class:`SceneReference` keeps the grey frame of every ``REFRESH``-th
  such frame, with the target's box on it.
* A search candidate that would end the loss is tested before it is taken: its patch is found again within
  ``SHIFT`` px of its place in the reference, and it is the scene's when every quarter of it (2 x 2) correlates
  at ``static_ncc`` or more at that shift (a target half out from behind its occluder is not: the quarter where
  it is differs).  The samples near a candidate of the scene leave the ranking and the next best is taken (up to
  ``TRIES`` a frame).  A patch longer than ``PATCH`` px is compared in block means.  Nothing is remembered: a
  target that passes over such a place later is tested afresh there.
* The newest reference on which the whole candidate is clear of the target's box answers; where the target stood on
  the newest, the reference before it (the one it replaced) answers instead, the target was elsewhere then: an
  estimate left behind where the target last stood, as it turned to go behind something or jumped away, is a piece
  of the scene on that older frame.  A new reference keeps the one before when the target has not left the
  outgoing one's box, so that an estimate that stays put does not leave the test with two references of itself.
* When the candidate overlaps the target's box on both references, only its part clear of such a box is compared
  (the box cut along the side that keeps most of it, :func:`clear_part`, on the reference where that part is
  largest, if it is at least ``CLEAR`` of the box): a strip of the target on the reference would spoil a quarter's
  correlation.  The kept box is the estimate's, which can fall short of the target, so the cut is the fallback.
* The test abstains (the candidate is kept) where the references cannot answer: a flat patch, a patch at the frame's
  edge, a candidate mostly on the target's box of both references.  A moving camera makes every patch differ from
  the reference, so the test then abstains in effect.
* The camera's pixel noise is measured between the reference and the next confident frame (:func:`noise_sd`), and
  each quarter's correlation is divided by the ceiling that noise puts on it: a nearly plain piece of the scene
  (an occluder's face) does not correlate with itself near 1 under noise.
* While tracking, the estimate is tested the same way (every ``CHECK_EVERY``-th frame, and before the reference is
  replaced): an estimate that is an unchanged piece of the scene, where the target was not, is lost.

The correlation and the noise are pure functions (:func:`scene_correlation`, :func:`noise_sd`, :func:`overlaps`);
:class:`SceneReference` holds the reference and :class:`SceneTestMixin` puts the test in the search and the tracking.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from ..cues.lk import gray_of
from ..geometry import ellipse_to_box, intersection_area
from .vetoes import near_mask

#: A reference is taken on every this many confident frames: its cost, a grey conversion of the frame (about
#: 70 us at 854 x 480, 3-4 % of color-pf's time per frame when taken every 10th frame), spread over them.
REFRESH = 30

#: The candidate's patch is looked for this many pixels around its place in the reference (jitter, rounding).
SHIFT = 2

#: While tracking, the estimate is tested on every this many frames (and before the reference is replaced).
CHECK_EVERY = 10

#: At most this many candidates a search frame are tested.
TRIES = 3

#: A larger patch is compared at a reduced resolution, block means of k x k pixels, so that its longer side is at most
#: this many blocks (the test's cost stays bounded: 0.74 ms for a 160 x 240 box at full resolution, 3 px shifts).
PATCH = 32

#: A patch whose grey levels vary less than this (standard deviation, the noise's taken out) is flat: the
#: correlation says nothing.
FLAT_SD = 2.0

#: The noise is measured on a regular grid of at most this many pixels (60 us at 854 x 480, once a reference).
NOISE_SAMPLES = 10000

#: A candidate box overlapping the target's reference box by more than this fraction of its area: the target has
#: not left the reference's box (a new reference then keeps the one before).
OVERLAP = 0.1

#: At least this fraction of a candidate's box must lie clear of the target's box on a reference for that reference
#: to answer (:func:`clear_part`).
CLEAR = 0.5


def overlaps(box, ref_box, fraction: float = OVERLAP) -> bool:
    """Does ``box`` (x, y, w, h) cover ``ref_box`` by more than ``fraction`` of its own area?"""
    return float(intersection_area(box, ref_box)) > fraction * max(float(box[2]) * float(box[3]), 1e-9)


def clear_part(box, ref_box, fraction: float = CLEAR):
    """The part of ``box`` (x, y, w, h) clear of ``ref_box``: the box itself when they do not intersect, else the
    largest of the four cuts of ``box`` by ``ref_box``'s sides (left of it, right of it, above, below); None when
    that part is less than ``fraction`` of the box."""
    x, y, w, h = (float(v) for v in box)
    rx, ry, rw, rh = (float(v) for v in ref_box)
    if min(x + w, rx + rw) <= max(x, rx) or min(y + h, ry + rh) <= max(y, ry):
        return (x, y, w, h)
    right, below = max(rx + rw, x), max(ry + rh, y)
    parts = ((x, y, min(rx - x, w), h), (right, y, x + w - right, h),
             (x, y, w, min(ry - y, h)), (x, below, w, y + h - below))
    best = max(parts, key=lambda p: max(p[2], 0.0) * max(p[3], 0.0))
    return best if best[2] > 0 and best[3] > 0 and best[2] * best[3] >= fraction * w * h else None


def noise_sd(gray: np.ndarray, next_gray: np.ndarray) -> float:
    """The standard deviation of a still camera's pixel noise, from two consecutive grey frames (or the same grid
    of pixels of each): the median absolute difference over 0.6745 sqrt(2). What moves between the two frames is a
    minority of the pixels and leaves the median alone; a single frame cannot tell fine texture from noise."""
    d = np.asarray(next_gray, np.float32) - np.asarray(gray, np.float32)
    return float(np.median(np.abs(d))) / (0.6745 * math.sqrt(2.0)) if d.size else 0.0


def noise_grid(shape) -> int:
    """The step of the regular grid of at most ``NOISE_SAMPLES`` pixels the noise is measured on."""
    return max(1, math.ceil(math.sqrt(shape[0] * shape[1] / NOISE_SAMPLES)))


def scene_correlation(gray: np.ndarray, ref_gray: np.ndarray, box, shift: int = SHIFT, noise: float = 0.0,
                      quarters: int = 4) -> float:
    """How well ``gray``'s patch under ``box`` (x, y, w, h, clipped to the frame) is found again in ``ref_gray``
    within ``shift`` px of the same place: the normalised correlation of each quarter of the patch (2 x 2) at the
    patch's best shift, the lowest of the quarters that are not flat, so that a patch only partly the scene's (a
    target coming out from behind an occluder) is not.  NaN when the patch is flat, smaller than 4 x 4 px, or has
    no room to shift within the frame.

    ``noise``: the standard deviation of independent pixel noise in both images.  Two noisy views of one unchanged
    quarter of variance ``v`` correlate at ``1 - noise**2 / v`` only, which is far below 1 on a nearly flat quarter
    (an occluder's plain face: 0.78 at a standard deviation of 4.3 with noise of 2). Each quarter's correlation is
    divided by that ceiling (at most 1), and a quarter is flat when its variance less the noise's is below
    ``FLAT_SD**2``.

    ``quarters`` < 4: the ``quarters``-th highest of the non-flat quarters' correlations instead of the lowest (all
    of them when fewer are not flat), so that that many quarters unchanged make the patch the scene's."""
    h, w = gray.shape[:2]
    bx, by, bw, bh = (float(v) for v in box)
    x0, y0 = max(int(round(bx)), shift), max(int(round(by)), shift)
    x1, y1 = min(int(round(bx + bw)), w - shift), min(int(round(by + bh)), h - shift)
    if x1 - x0 < 4 or y1 - y0 < 4:
        return float("nan")
    patch = gray[y0:y1, x0:x1].astype(np.float32)
    n2 = float(noise) ** 2
    if float(patch.var()) - n2 < FLAT_SD ** 2:
        return float("nan")
    area = ref_gray[y0 - shift:y1 + shift, x0 - shift:x1 + shift].astype(np.float32)
    score = cv2.matchTemplate(area, patch, cv2.TM_CCOEFF_NORMED)
    dy, dx = np.unravel_index(int(np.argmax(score)), score.shape)
    ref = area[dy:dy + patch.shape[0], dx:dx + patch.shape[1]]
    vp, vr, cov, n = _quarter_moments(patch, ref)
    ok = vp - n2 >= FLAT_SD ** 2  # the quarters that are not flat
    if not ok.any():
        return float("nan")
    den = n * np.sqrt(np.maximum(vp * vr, 0.0))  # as cues.lk.ncc: 0 where the reference is flat there (changed)
    r = np.where(den > 1e-9, n * cov / np.where(den > 1e-9, den, 1.0), 0.0)
    q = np.minimum(r[ok] / (1.0 - n2 / vp[ok]), 1.0)
    if quarters >= 4 or q.size <= 1:
        return float(q.min())
    return float(np.sort(q)[::-1][min(int(quarters), q.size) - 1])


def _quarter_moments(patch: np.ndarray, ref: np.ndarray):
    """Each quarter's (2 x 2) variances of ``patch`` and ``ref``, their covariance and pixel count, as (2, 2) arrays:
    the sums of the five moments over the four quarters at once."""
    ph, pw = patch.shape
    p = patch.astype(np.float64)
    q = ref.astype(np.float64)
    m = np.add.reduceat(np.add.reduceat(np.stack((p, q, p * p, q * q, p * q)), (0, ph // 2), axis=1), (0, pw // 2),
                        axis=2)
    n = np.outer((ph // 2, ph - ph // 2), (pw // 2, pw - pw // 2)).astype(np.float64)
    mp, mq = m[0] / n, m[1] / n
    return m[2] / n - mp * mp, m[3] / n - mq * mq, m[4] / n - mp * mq, n


class SceneReference:
    """The grey frame of a recent confident frame and the target's box on it; :meth:`is_scene` tests a
    candidate against it.  ``threshold`` <= 0: off (nothing is kept, nothing is the scene)."""

    __slots__ = ("_noise", "_previous", "box", "frame_index", "gray", "leave_refresh", "quarters", "threshold")

    def __init__(self, threshold: float, quarters: int = 4, leave_refresh: int = 0):
        self.threshold = float(threshold)
        self.quarters = int(quarters)
        self.leave_refresh = int(leave_refresh)
        self.clear()

    def clear(self) -> None:
        self.gray: np.ndarray | None = None
        self.box = None
        self.frame_index = -REFRESH
        self._noise: float | None = None
        self._previous: tuple | None = None  # the reference before: (grey frame, target's box)

    def refresh(self, frame: np.ndarray, box, frame_index: int, *, grey=None) -> None:
        """A confident frame: keep it (grey) with the target's ``box`` when ``REFRESH`` frames have passed; on the
        confident frame right after, estimate the noise (:func:`noise_sd`).  ``grey``: the caller's cached
        ``frame -> grey image`` (not modified later), instead of converting here."""
        if self.threshold <= 0:
            return
        if self.due(box, frame_index):
            prev = self._previous
            # the one before is kept while the target has not left the outgoing reference's box, and had left it
            stayed = prev is not None and overlaps(box, self.box) and not overlaps(box, prev[1])
            if self.gray is not None and not stayed:
                self._previous = (self.gray, self.box)
            g = (grey or gray_of)(frame)
            self.gray = g.copy() if g is frame or g.base is not None else g
            self.box = tuple(float(v) for v in box)
            self.frame_index = frame_index
            self._noise = None
        elif self._noise is None and frame_index == self.frame_index + 1 and self.gray.shape == frame.shape[:2]:
            k = noise_grid(self.gray.shape)
            self._noise = noise_sd(self.gray[::k, ::k], gray_of(np.ascontiguousarray(frame[::k, ::k])))

    def due(self, box, frame_index: int) -> bool:
        """Is a new reference due on a confident frame with the target at ``box``: ``REFRESH`` frames after the
        newest, or with ``leave_refresh`` > 0 as soon as the target has left the newest's box (it overlaps it by
        ``OVERLAP`` of its area or less), ``leave_refresh`` frames or more after it? Early in a track the newest
        reference is then no longer the first frame, on which the target covered the place it started from: a
        look-alike there (the start's background, which the first model saw) can be tested once the target has
        moved on."""
        age = frame_index - self.frame_index
        if age >= REFRESH:
            return True
        return 0 < self.leave_refresh <= age and self.box is not None and not overlaps(box, self.box)

    @property
    def noise(self) -> float:
        """The pixel noise of the reference's camera (0 until it is known: the correlation is then taken as is)."""
        return 0.0 if self._noise is None else self._noise

    def is_scene(self, frame: np.ndarray, box) -> bool:
        """Was the candidate under ``box`` (x, y, w, h) already in view, unchanged, on a reference frame, away from
        the target?  The newest reference on which the whole candidate is clear of the target's box answers; if
        there is none, the candidate's part clear of the target's box is compared on the reference where that part
        is largest, when it is at least ``CLEAR`` of the box.  The reference before the newest answers where the
        target stood on the newest (it was elsewhere then, if it moved): an estimate left behind on the place the
        target last stood, or a candidate there, is not passed for want of a reference."""
        refs = []
        for gray, ref_box in ((self.gray, self.box), self._previous or (None, None)):
            if gray is None or gray.shape[:2] != frame.shape[:2]:
                break
            if float(intersection_area(box, ref_box)) <= 0.0:
                # one camera: the noise measured last stands for both references
                return unchanged_patch(frame, box, gray, self.threshold, self.noise, self.quarters)
            part = clear_part(box, ref_box)
            if part is not None:
                refs.append((part[2] * part[3], part, gray))
        if not refs:
            return False
        _, part, gray = max(refs, key=lambda r: r[0])
        return unchanged_patch(frame, part, gray, self.threshold, self.noise, self.quarters)


def unchanged_patch(frame: np.ndarray, box, ref_gray: np.ndarray, threshold: float, noise: float,
                    quarters: int = 4) -> bool:
    """Is the patch of ``frame`` under ``box`` found again, correlating at ``threshold`` or more (every quarter, or
    ``quarters`` of them, the ``noise`` taken out), in the grey reference frame ``ref_gray``?"""
    bx, by, bw, bh = (float(v) for v in box)
    h, w = frame.shape[:2]
    k = max(1, math.ceil(max(bw, bh) / PATCH))  # block size of the comparison
    m = (SHIFT + 1) * k
    x0, y0 = max(int(bx) - m, 0), max(int(by) - m, 0)
    x1, y1 = min(int(bx + bw) + m + 1, w), min(int(by + bh) + m + 1, h)
    x1, y1 = x0 + (x1 - x0) // k * k, y0 + (y1 - y0) // k * k
    if x1 - x0 < 4 * k or y1 - y0 < 4 * k:
        return False
    sub = gray_of(np.ascontiguousarray(frame[y0:y1, x0:x1]))
    ref = ref_gray[y0:y1, x0:x1]
    if k > 1:
        size = ((x1 - x0) // k, (y1 - y0) // k)
        sub = cv2.resize(sub, size, interpolation=cv2.INTER_AREA)
        ref = cv2.resize(ref, size, interpolation=cv2.INTER_AREA)
    r = scene_correlation(sub, ref, ((bx - x0) / k, (by - y0) / k, bw / k, bh / k), noise=noise / k,
                          quarters=quarters)
    return bool(r >= threshold)


class SceneTestMixin:
    """The background test of :class:`pftrack.trackers.color_pf.ColorParticleFilter` (``static_ncc``): the
    reference is kept on confident frames, the search's best candidates are tested, and so is the estimate."""

    _scene: SceneReference

    def _keep_scene(self, frame: np.ndarray, box) -> None:
        """A confident frame with the target at ``box``."""
        sf = self._structure_frame(frame)
        self._scene.refresh(sf, box, self.frame_index, grey=self._frame_gray if sf is frame else None)

    def _on_scene(self, frame: np.ndarray, box, keep: bool = False) -> bool:
        """While tracking: is the estimate's ``box`` a piece of the scene, unchanged since the reference, where the
        target was not? Then what is tracked is not the target (it went behind something and the estimate stayed on
        its occluder, or slid onto clutter that looks like it). Tested on every ``CHECK_EVERY``-th frame after the
        reference, and on a frame that would replace it (``keep``: the caller's confidence, when a new reference is
        due, :meth:`SceneReference.due`), against the outgoing one: a reference is never taken of the estimate on the
        scene without the estimate being tested first. Not tested within half the box's size of the frame's edge: an
        estimate left behind there by a target that walked out is where it comes back (``min_in_frame``,
        ``reenter_border``)."""
        sc = self._scene
        if sc.gray is None:
            return False
        x, y, w, h = box
        fh, fw = frame.shape[:2]
        if x < 0.5 * w or y < 0.5 * h or x + 1.5 * w > fw or y + 1.5 * h > fh:
            return False
        age = self.frame_index - sc.frame_index
        if age % CHECK_EVERY and not (keep and sc.due(box, self.frame_index)):
            return False
        return sc.is_scene(self._structure_frame(frame), box)

    def _skip_scene(self, frame: np.ndarray, ell: np.ndarray, rank: np.ndarray, best: int, scores):
        """The best-ranked sample that is not the scene, and its ``scores(i)`` (loss-test scores, log prior): a
        candidate that would end the loss (``loss.would_acquire``) is tested, and when it is the scene's, the samples
        near it (within two half-axes each way) leave the ranking and the next best is taken, up to ``TRIES``
        times. A candidate that would not end the loss is not tested (nothing would be acquired). ``ell``: the
        samples' ellipses; ``rank`` is changed in place."""
        s = scores(best)
        if self._scene.gray is None:
            return best, s
        view = self._structure_frame(frame)
        for _ in range(TRIES):
            if (not np.isfinite(rank[best]) or not self.loss.would_acquire(*s)[0]
                    or not self._scene.is_scene(view, ellipse_to_box(ell[best]))):
                return best, s
            x, y, hx, hy = ell[best]
            rank[near_mask(ell, (x, y), (hx, hy))] = -np.inf
            if not np.isfinite(rank).any():
                return best, s
            best = int(np.argmax(rank))
            s = scores(best)
        return best, s
