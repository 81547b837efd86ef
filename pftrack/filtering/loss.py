"""Loss detection: is the estimate on the target, or has the target gone?

Nummiaro et al. (§6, Eqs. 13-15) decide with the *appearance condition*: a sample
is target-like when its Bhattacharyya coefficient ``rho`` exceeds ``mu + 2 sigma`` of
the coefficients measured at background positions, and the target is lost when
fewer than ``b N`` samples pass "for a couple of frames".  That test has two
weaknesses on real and varied video:

* the background statistics collapse when the model does not discriminate (grey
  frames, a flat scene): ``sigma -> 0`` and nothing passes, so the target is "lost"
  while the estimate sits on it;
* it knows only the background: a clutter patch or a similar-hued distractor that
  beats ``mu + 2 sigma`` keeps the flag down while the target is hidden.

This module keeps the appearance condition as the background half of a two-class
test and adds what it needs to generalise:

* **background statistics that do not collapse**: ``sigma_b`` has a floor;
* **a target score history**: the mean and spread of the estimate's score while
  it was confidently tracked (exponentially weighted), whose spread grows while
  the target is unobserved, so a changed target can still be re-acquired;
* **a likelihood ratio**: ``LLR(s) = log N(s; mu_t, sigma_t) - log N(s; mu_b, sigma_b)``
  with the score clamped to ``[mu_b, mu_t]`` (the test is one-sided on both ends,
  so a score better than the history is never evidence of absence);
* **hysteresis**: lost after ``lost_frames`` consecutive frames with ``LLR < 0``,
  found again only when ``LLR > reacquire_margin``.

The **confidence** reported to the user is the posterior ``P(target | s) =
sigmoid(LLR)`` with equal priors, so ``score < 0.5`` on ``lost_frames`` frames is
exactly what raises ``lost`` (the flag and the score agree).

Pure functions (:func:`score_llr`, :func:`robust_background`) and small state
holders: :class:`LossDetector` for one score, :class:`FusedLoss` for several cues'
scores fused as independent evidence (the sum of their clipped ratios); no images.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

_LOG_CLIP = 30.0


def robust_background(scores: np.ndarray, *, sd_floor: float) -> tuple[float, float]:
    """Mean and spread of background scores (Eqs. 13-14) with a floor on the spread.

    The spread is the larger of the standard deviation and ``1.4826 MAD`` (so a few
    outlying background positions do not shrink it), and at least ``sd_floor``.
    """
    s = _finite(scores)
    if s.size == 0:
        return 0.0, sd_floor
    mu, sd = _mean_std(s)
    mad = 1.4826 * _median(np.abs(s - _median(s)))
    return mu, max(sd, mad, sd_floor)


def _finite(scores) -> np.ndarray:
    """The finite scores, float64 (the array itself when all are)."""
    s = np.asarray(scores, dtype=np.float64)
    fin = np.isfinite(s)
    return s if fin.all() else s[fin]


def _mean_std(s: np.ndarray) -> tuple[float, float]:
    """``(s.mean(), s.std())`` of a non-empty 1-D float64 array, the same numbers: the same ufunc reductions and
    steps as NumPy's ``_mean`` and ``_var``, without their per-call overhead."""
    n = s.size
    mu = float(np.add.reduce(s)) / n
    d = s - mu
    d *= d
    return mu, math.sqrt(float(np.add.reduce(d)) / n)


def _median(x: np.ndarray) -> float:
    """``np.median`` of a short 1-D array, the same number, without its per-call overhead (the background
    statistics are refreshed every few frames on about a hundred scores)."""
    v = np.sort(x)
    n = v.size
    h = n // 2
    return float(v[h]) if n % 2 else float((v[h - 1] + v[h]) / 2.0)


def absent_distribution(scores: np.ndarray, *, tail: float, sd_floor: float) -> tuple[float, float]:
    """Mean and spread of the score the estimate has when the target is absent.

    With the target gone, the particles settle on the best-matching clutter near
    them, so the estimate's score is not a typical background score but one from
    the upper tail of the background's: the mean and spread of the top ``tail``
    fraction (at least three positions) of the background scores, spread floored.
    """
    s = np.sort(_finite(scores))
    if s.size == 0:
        return 0.0, sd_floor
    k = max(3, int(math.ceil(tail * s.size)))
    mu, sd = _mean_std(s[-k:])
    return mu, max(sd, sd_floor)


def score_llr(s: float, mu_t: float, sd_t: float, mu_b: float, sd_b: float) -> float:
    """Log-likelihood ratio target vs background of a score ``s`` (clamped to ``[mu_b, mu_t]``).

    ``s`` above the target mean counts as the target mean and below the background
    mean as the background mean, so the ratio is monotone in ``s``.  When the
    target history is not above the background (``mu_t <= mu_b``) the ratio is
    0: the score does not discriminate.  The same holds when the two means are too close for their
    spreads, so that the ratio does not change sign between them (a score at the target's own mean
    would count against it when the target's spread is the wider, as on a camouflaged target).
    """
    if not math.isfinite(s):
        return -_LOG_CLIP
    if mu_t <= mu_b:
        return 0.0
    log_sd = math.log(sd_b / sd_t)
    if not (log_sd - 0.5 * ((mu_t - mu_b) / sd_t) ** 2 < 0.0 < log_sd + 0.5 * ((mu_t - mu_b) / sd_b) ** 2):
        return 0.0
    x = min(max(s, mu_b), mu_t)
    zt = (x - mu_t) / sd_t
    zb = (x - mu_b) / sd_b
    llr = -0.5 * zt * zt - math.log(sd_t) + 0.5 * zb * zb + math.log(sd_b)
    return float(min(max(llr, -_LOG_CLIP), _LOG_CLIP))


def confidence(llr: float) -> float:
    """``P(target | s) = 1 / (1 + exp(-LLR))`` with equal priors."""
    return 1.0 / (1.0 + math.exp(-llr))


@dataclass
class LossDetector:
    """Two-class loss test with a score history and hysteresis (see the module docstring).

    Parameters
    ----------
    lost_frames : consecutive frames with ``LLR < 0`` before the target is declared lost.
    reacquire_margin : ``LLR`` a candidate must exceed to end a loss (hysteresis).
    history_rate : weight of a new score in the exponentially weighted target history.
    sd_floor_target, sd_floor_background : floors on the two spreads (scores in [0, 1]).
    unseen_growth, unseen_max : while the target is not confidently observed, ``sigma_t``
        grows by ``unseen_growth`` per frame, up to ``unseen_max`` (its appearance may have
        changed meanwhile).
    background_tail : the absent hypothesis is the top fraction of the background scores.
    learn_z : a score more than this many spreads below the history's mean is not
        learned and does not re-acquire (see :meth:`confident`).
    acquire_z : with a value > 0, the bound of :meth:`acquire` instead of ``learn_z`` (the learning bound
        stays ``learn_z``).
    acquire_llr : with a value > 0, a candidate whose ratio reaches it is acquired whatever its distance below
        the history (far above the background, but changed while unseen).
    """

    lost_frames: int = 3
    reacquire_margin: float = 1.0
    history_rate: float = 0.05
    sd_floor_target: float = 0.03
    sd_floor_background: float = 0.03
    unseen_growth: float = 0.001
    unseen_max: float = 0.1
    background_tail: float = 0.1
    learn_z: float = 2.0
    acquire_z: float = 0.0
    acquire_llr: float = 0.0

    def __post_init__(self) -> None:
        self.reset(1.0)

    def reset(self, initial_score: float, *, sd: float = 0.1) -> None:
        """Start a new target whose expected score is ``initial_score`` with spread ``sd`` (a vague prior
        that the history narrows as confident scores arrive)."""
        self.mu_t = float(initial_score)
        self.var_t = max(float(sd), self.sd_floor_target) ** 2
        self.unseen = 0
        self.learned = False  # no score learned since this reset: the history is still the prior
        self.refused: list[float] = []  # scores of confident frames refused while the history is the prior
        self.mu_b = self.app_mu = 0.0
        self.sd_b = self.app_sd = self.sd_floor_background
        self.miss = 0
        self.lost = False
        self.frozen = False
        self.llr = _LOG_CLIP

    @property
    def sd_t(self) -> float:
        return math.sqrt(self.var_t) + min(self.unseen * self.unseen_growth, self.unseen_max)

    def set_background(self, scores: np.ndarray) -> None:
        """Background scores of the current frame: the appearance statistics (Eqs. 13-14) and the
        absent hypothesis (their upper tail)."""
        self.app_mu, self.app_sd = robust_background(scores, sd_floor=self.sd_floor_background)
        self.mu_b, self.sd_b = absent_distribution(scores, tail=self.background_tail,
                                                   sd_floor=self.sd_floor_background)

    def threshold(self) -> float:
        """The score at which ``LLR = 0`` (for display; the test itself uses :meth:`evaluate`)."""
        lo, hi = self.mu_b, self.mu_t
        if hi <= lo:
            return lo
        for _ in range(40):  # bisection on a monotone function
            mid = 0.5 * (lo + hi)
            if score_llr(mid, self.mu_t, self.sd_t, self.mu_b, self.sd_b) < 0:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    def evaluate(self, s: float) -> float:
        """``LLR`` of a score under the current statistics (no state change)."""
        return score_llr(s, self.mu_t, self.sd_t, self.mu_b, self.sd_b)

    def step(self, s: float) -> tuple[bool, float]:
        """Feed the estimate's score of a tracked frame; returns ``(lost, confidence)``.

        The target history learns from the score only while it is clearly
        target-like (``LLR > reacquire_margin``) and consistent with the history
        (no lower than ``learn_z`` spreads below its mean), so the history does not
        follow the score down while the target is being covered.
        """
        llr = self.evaluate(s)
        self.llr = llr
        if llr < 0.0:
            self.miss += 1
        else:
            self.miss = 0
        self.learn(s, self.confident(s))
        self.lost = self.miss >= self.lost_frames
        return self.lost, confidence(llr)

    def toward_absent(self, s: float, w: float) -> float:
        """``s`` with a share ``1 - w`` replaced by the absent hypothesis's mean score (:func:`toward_background`)."""
        return w * float(s) + (1.0 - w) * self.mu_b

    def learn(self, s: float, ok: bool) -> None:
        """Blend ``s`` into the target history when ``ok`` (exponential mean and variance); otherwise one
        more frame unseen.  Nothing changes while ``frozen`` (a candidate on probation)."""
        if self.frozen:
            return
        if ok:
            a = self.history_rate
            d = s - self.mu_t
            self.mu_t += a * d
            self.var_t = max((1.0 - a) * (self.var_t + a * d * d), self.sd_floor_target ** 2)
            self.unseen = 0
            self.learned = True
        else:
            self.unseen += 1

    def seed(self, s: float) -> None:
        """Start the history at ``s``, keeping the prior's spread: what the target scores when the prior (a
        self-match at the first frame) did not hold for it (see :meth:`FusedLoss._learn`)."""
        if self.frozen:
            return
        self.mu_t = float(s)
        self.unseen = 0
        self.learned = True
        self.refused = []

    def confident(self, s: float, *, llr: float | None = None, z: float | None = None) -> bool:
        """Is ``s`` clearly the target's (its ratio ``llr``, default the last one computed, above
        ``reacquire_margin``) and consistent with its history (no more than ``z`` spreads below it, default
        ``learn_z``)?

        The same condition gates the model update of the trackers, so the update and
        the loss test never disagree."""
        return (math.isfinite(s) and (self.llr if llr is None else llr) > self.reacquire_margin
                and (s - self.mu_t) / self.sd_t > -(self.learn_z if z is None else z))

    def _acquire_bound(self, llr: float) -> float:
        if 0.0 < self.acquire_llr <= llr:
            return math.inf
        return self.acquire_z if self.acquire_z > 0 else self.learn_z

    def acquire(self, s: float, log_prior: float = 0.0) -> bool:
        """While lost: does a candidate with score ``s`` end the loss (hysteresis margin)?  ``log_prior``: the
        log prior odds of the candidate's position, added to its ratio (posterior odds)."""
        self.unseen_frame()
        self.llr = self.evaluate(s) + log_prior
        if self.confident(s, z=self._acquire_bound(self.llr)):
            self.lost = False
            self.miss = 0
            return True
        return False

    def unseen_frame(self) -> None:
        """A search frame with no candidate to test: one more frame unseen, as :meth:`acquire` counts it."""
        self.unseen += 1

    def would_acquire(self, s: float, log_prior: float = 0.0) -> tuple[bool, float]:
        """:meth:`acquire`'s answer and ratio for a candidate (this frame counted unseen, as there), with no
        change of state."""
        self.unseen += 1
        try:
            llr = self.evaluate(s) + log_prior
            return self.confident(s, llr=llr, z=self._acquire_bound(llr)), llr
        finally:
            self.unseen -= 1


#: Confident frames on which a cue's score is refused, its history never having learned, before their median
#: replaces the history's prior (:meth:`FusedLoss._learn`).
SEED_AFTER = 10


class FusedLoss:
    """The two-class test of :class:`LossDetector` on several cues' scores, fused as independent evidence.

    Each cue ``c`` keeps its own background (absent) statistics and target history; the
    fused log-likelihood ratio is the naive-Bayes sum ``LLR = sum_c LLR_c(s_c)``.  A cue
    that does not discriminate in the current scene (its history is not above its
    background's upper tail) contributes ``LLR_c = 0`` by :func:`score_llr`'s rule, so
    the fusion weighs each cue by how well it separates the target from this
    background without any tuned weight.  Hysteresis, the confidence
    ``sigmoid(LLR)`` and the learning rule are those of :class:`LossDetector`, applied
    to the fused ratio; each cue's history learns only from its own consistent scores.

    Each cue's ratio is clipped to ``[-cue_floor, cue_clip]`` before the sum (Gaussian score
    models are over-confident in their tails: one cue far above its background must not
    outvote another that sees the target gone; and a single cue's score drops for many
    reasons besides absence — deformation, clutter passing behind a thin target, blur — so
    its evidence *against* the target may be capped lower), and a cue's history learns only from
    scores its own ratio calls target-like (a confident colour cue must not drag the
    structure history onto an occluder).

    Scores are vectors ``(C,)`` (one per cue, each in [0, 1]); background scores ``(M, C)``.
    The first cue's appearance statistics (``app_mu``, ``app_sd``) are the colour
    tracker's Eqs. 13-14 threshold.
    """

    def __init__(self, n_cues: int, *, cue_clip: float = 10.0, cue_floor: float | None = None,
                 acquire_z: float = 0.0, acquire_margin: float | None = None, history_miss_z: float = 0.0,
                 **kwargs):
        self.members = [LossDetector(**kwargs) for _ in range(int(n_cues))]
        self.acquire_z = float(acquire_z)
        self.history_miss_z = float(history_miss_z)
        self.acquire_margin = acquire_margin
        self.cue_clip = float(cue_clip)
        self.cue_floor = float(cue_clip if cue_floor is None else cue_floor)
        self.lost_frames = self.members[0].lost_frames
        self.reacquire_margin = self.members[0].reacquire_margin
        self.reset(1.0)

    def reset(self, initial_score: float, *, sd: float = 0.1) -> None:
        for m in self.members:
            m.reset(initial_score, sd=sd)
        self.miss = 0
        self.lost = False
        self.frozen = False
        self.llr = _LOG_CLIP

    @property
    def app_mu(self) -> float:
        return self.members[0].app_mu

    @property
    def app_sd(self) -> float:
        return self.members[0].app_sd

    def set_background(self, scores: np.ndarray) -> None:
        s = np.asarray(scores, dtype=np.float64).reshape(-1, len(self.members))
        for c, m in enumerate(self.members):
            if np.isfinite(s[:, c]).any():
                m.set_background(s[:, c])

    def _vector(self, s) -> list[float]:
        """The score vector as ``C`` Python floats (a scalar is broadcast): the test runs once per frame on a
        handful of numbers, where NumPy's per-call overhead would dominate."""
        v = np.asarray(s, dtype=np.float64).ravel().tolist()
        if len(v) == len(self.members):
            return v
        if len(v) == 1:
            return v * len(self.members)
        raise ValueError(f"expected {len(self.members)} scores, got {len(v)}")

    def toward_absent(self, s, w: float) -> np.ndarray:
        """Each cue's score with a share ``1 - w`` replaced by that cue's absent mean (:func:`toward_background`)."""
        return np.array([w * v + (1.0 - w) * m.mu_b for v, m in zip(self._vector(s), self.members)])

    def evaluate(self, s) -> float:
        """Fused ratio of a score vector; a NaN cue (not available) gives no evidence; all NaN is absence."""
        return self._ratios(self._vector(s))[0]

    def _ratios(self, s: list[float]) -> tuple[float, list[float | None]]:
        """The fused ratio of the score list ``s`` and each cue's own ratio (None for a NaN cue)."""
        own = [m.evaluate(v) if math.isfinite(v) else None for m, v in zip(self.members, s)]
        if all(r is None for r in own):
            return -_LOG_CLIP, own
        lo, hi = -self.cue_floor, self.cue_clip
        llr = sum(min(max(r, lo), hi) for r in own if r is not None)
        return float(min(max(llr, -_LOG_CLIP), _LOG_CLIP)), own

    def _learn(self, s: list[float], own: list[float | None]) -> None:
        """Each cue learns its score when the fused ratio is confident, the score within ``learn_z`` of its history
        and its own ratio (``own``, computed on the same statistics) target-like.

        A cue's history starts as a prior: the score of the first frame's box against itself (1 for a correlation
        or a Bhattacharyya coefficient). A target whose structure does not repeat from frame to frame (a patch of
        one colour: its correlation is 0 on every frame, or sensor noise on such a patch) never scores near that
        prior, so its history could never learn, and it would veto every model update and every re-acquisition
        for good. So once the usual rule has refused a cue's scores on :data:`SEED_AFTER` confident frames
        before its history ever learned, their median starts the history; from then on the usual rule holds. (On
        the development sequences a history that learns does so after at most two refusals.) A cue whose history
        then equals its background's discriminates nothing and adds no evidence (:func:`score_llr`)."""
        if self.frozen:
            return
        confident = self.llr > self.reacquire_margin
        for m, v, r in zip(self.members, s, own):
            ok = confident and r is not None and (v - m.mu_t) / m.sd_t > -m.learn_z and r >= 0.0
            m.learn(v, ok)
            if confident and not ok and not m.learned and r is not None:
                m.refused.append(v)
                if len(m.refused) >= SEED_AFTER:
                    m.seed(float(np.median(m.refused)))

    def unlike_history(self, s: list[float]) -> bool:
        """With ``history_miss_z`` > 0: at least two cues are available and every available cue's score lies more
        than ``history_miss_z`` of its own spreads below its target history. Such a box is like nothing the target
        has shown, whatever each cue's ratio against this scene's background says (an occluder or a look-alike of
        the target's colours whose clutter the background statistics never sampled)."""
        k = self.history_miss_z
        if k <= 0.0:
            return False
        zs = [(v - m.mu_t) / m.sd_t for m, v in zip(self.members, s) if math.isfinite(v)]
        return len(zs) >= 2 and max(zs) <= -k

    def step(self, s) -> tuple[bool, float]:
        """As :meth:`LossDetector.step`, on the fused ratio of the score vector ``s``; a score vector
        :meth:`unlike_history` counts as a miss, its fused ratio taken as at most -1."""
        s = self._vector(s)
        self.llr, own = self._ratios(s)
        if self.unlike_history(s):
            self.llr = min(self.llr, -1.0)
        self.miss = self.miss + 1 if self.llr < 0.0 else 0
        self._learn(s, own)
        self.lost = self.miss >= self.lost_frames
        return self.lost, confidence(self.llr)

    def confident(self, s, *, veto_z: float = 0.0, margin: float | None = None, llr: float | None = None) -> bool:
        """The fused ratio (``llr``, default the last one computed) is clearly the target's, and no cue vetoes
        it: a cue vetoes when its score is far below its own history (``learn_z`` spreads) *and* its own ratio
        says background, or (``veto_z`` > 0) when it is more than ``veto_z`` spreads below its history,
        whatever its ratio."""
        s = self._vector(s)
        llr = self.llr if llr is None else llr
        if not any(math.isfinite(v) for v in s) or llr <= (self.reacquire_margin if margin is None else margin):
            return False
        for m, v in zip(self.members, s):
            if math.isfinite(v):
                z = (v - m.mu_t) / m.sd_t
                if (z <= -m.learn_z and m.evaluate(v) < 0.0) or (veto_z > 0.0 and z <= -veto_z):
                    return False
        return True

    def acquire(self, s, log_prior: float = 0.0) -> bool:
        """While lost: does a candidate with score vector ``s`` end the loss?  (``log_prior`` as in
        :meth:`LossDetector.acquire`.)  With ``acquire_z`` > 0 every cue's score must also be within
        ``acquire_z`` spreads of its own history: a candidate the fused ratio favours because one cue is far
        above the background, while another sees it far below the target as last seen, is not taken."""
        s = self._vector(s)
        self.unseen_frame()
        self.llr = self.evaluate(s) + log_prior
        if self.confident(s, veto_z=self.acquire_z, margin=self.acquire_margin):
            self.lost = False
            self.miss = 0
            return True
        return False

    def unseen_frame(self) -> None:
        """A search frame with no candidate to test: one more frame unseen for every cue, as :meth:`acquire`
        counts it."""
        for m in self.members:
            m.unseen += 1

    def would_acquire(self, s, log_prior: float = 0.0) -> tuple[bool, float]:
        """:meth:`acquire`'s answer and fused ratio for a candidate (this frame counted unseen, as there), with
        no change of state."""
        for m in self.members:
            m.unseen += 1
        try:
            llr = self.evaluate(s) + log_prior
            return self.confident(s, veto_z=self.acquire_z, margin=self.acquire_margin, llr=llr), llr
        finally:
            for m in self.members:
                m.unseen -= 1


def toward_background(loss, s, w: float):
    """The estimate's score(s) ``s`` with a share ``1 - w`` of each replaced by the mean score the loss test expects
    when the target is absent (``mu_b``, per cue for a :class:`FusedLoss`): the part of a box outside the frame
    shows nothing of the target, and a sliver inside that matches is weak evidence (``edge_share``).  ``w`` is
    clipped to ``[0, 1]``; ``s`` is returned as it is for ``w >= 1``."""
    if w >= 1.0:
        return s
    return loss.toward_absent(s, max(float(w), 0.0))
