"""Dynamic (state-transition) models ``p(s_t | s_{t-1})``.

Every model here works in place on an ``(N, D)`` float64 state array and draws
its noise from an injected :class:`numpy.random.Generator`.  They contain no
image code.

State layouts
-------------
:class:`ConstantVelocityScale` (Nummiaro et al., Eq. 8)::

    s = {x, y, vx, vy, Hx, Hy, adot}

:class:`NCVRandomWalk` (Kristan et al., Eq. 10) uses the first six components
of the same layout, ``{x, y, vx, vy, Hx, Hy}``.  ``(x, y)`` is the ellipse
centre and ``(Hx, Hy)`` its half-axes, in pixels.
"""

from __future__ import annotations

import numpy as np

from .kernels import propagate_cv_scale, propagate_ncv_rw

X, Y, VX, VY, HX, HY, AD = range(7)
STATE_NAMES_7 = ("x", "y", "vx", "vy", "hx", "hy", "adot")
STATE_NAMES_6 = STATE_NAMES_7[:6]


class ConstantVelocityScale:
    """First-order model ``s_t = A s_{t-1} + w_{t-1}`` (Nummiaro et al., Eq. 9).

    ``A`` moves the region with constant velocity ``(vx, vy)`` and changes its
    size with the constant relative scale rate ``adot``::

        x += vx;  y += vy;  Hx *= (1 + adot);  Hy *= (1 + adot)

    (applying the scale change multiplicatively keeps the aspect ratio in the
    deterministic part).  ``w`` is zero-mean Gaussian with per-component standard
    deviations ``noise_std`` (shape ``(7,)`` or ``(N, 7)``), in pixels for
    position, pixels/frame for velocity, pixels for half-axes and 1/frame for
    ``adot``.

    The paper leaves the bounds open; we clip half-axes to
    ``[min_half_axis, max_half_axis]`` and ``|adot| <= max_scale_rate`` so that a
    scale random walk can never collapse a region to nothing or explode.

    With ``wide_fraction > 0`` the position part of ``w`` is heavy-tailed: each call a random
    ``wide_fraction`` of the samples take ``wide_factor`` times its standard deviation
    (:func:`widen_position_noise`), for targets that jump between frames. Off by default.

    With ``mix_fraction > 0`` each call a random ``mix_fraction`` of the samples take their step from a second
    model: ``mix_factors`` (shape ``(7,)``) times ``noise_std`` (:func:`mix_noise`), e.g. a faster velocity for
    targets that swing past look-alikes. Off by default.

    With ``velocity_step = b > 0`` each sample's velocity after the step keeps the share ``b`` of its whole
    displacement, noise included (:func:`step_velocity`): ``b = 1`` is the second-order autoregressive model of
    Isard & Blake's CONDENSATION, whose velocity is the last displacement. Off (0) by default: Eq. 9 as written.
    """

    dim = 7
    state_names = STATE_NAMES_7

    def __init__(self, *, min_half_axis: float = 2.0, max_half_axis: float = 1e5, max_scale_rate: float = 0.1,
                 scale_damping: float = 1.0, wide_fraction: float = 0.0, wide_factor: float = 1.0,
                 mix_fraction: float = 0.0, mix_factors: np.ndarray | None = None, velocity_step: float = 0.0):
        self.scale_damping = float(scale_damping)
        self.velocity_step = float(velocity_step)
        self.mix_fraction = float(mix_fraction)
        self.mix_factors = None if mix_factors is None else np.asarray(mix_factors, dtype=np.float64).reshape(7)
        self.wide_fraction = float(wide_fraction)
        self.wide_factor = float(wide_factor)
        self.min_half_axis = float(min_half_axis)
        self.max_half_axis = float(max_half_axis)
        self.max_scale_rate = float(max_scale_rate)
        self._noise: np.ndarray | None = None

    def transition(self, states: np.ndarray) -> np.ndarray:
        """Apply the deterministic part ``A s`` in place and return ``states``."""
        states[:, X] += states[:, VX]
        states[:, Y] += states[:, VY]
        f = 1.0 + states[:, AD]
        states[:, HX] *= f
        states[:, HY] *= f
        if self.scale_damping != 1.0:
            states[:, AD] *= self.scale_damping
        return states

    def propagate(self, states: np.ndarray, noise_std: np.ndarray, rng: np.random.Generator, *,
                  frame_size: tuple[int, int] | None = None) -> tuple[float, float, float, float]:
        """``s <- A s + w`` in place (compiled, see :mod:`pftrack.filtering.kernels`).

        With ``frame_size = (width, height)`` the centres are kept within one
        half-axis of the frame.  Returns the region ``(x0, y0, x1, y1)`` that the
        propagated ellipses cover.
        """
        if self._noise is None or self._noise.shape != states.shape:
            self._noise = np.empty_like(states)
        rng.standard_normal(out=self._noise)
        if self.wide_fraction > 0.0 and self.wide_factor != 1.0:
            widen_position_noise(self._noise, rng, self.wide_fraction, self.wide_factor)
        if self.mix_fraction > 0.0 and self.mix_factors is not None:
            mix_noise(self._noise, rng, self.mix_fraction, self.mix_factors)
        w, h = frame_size if frame_size is not None else (0.0, 0.0)
        before = states[:, X:Y + 1].copy() if self.velocity_step > 0.0 else None
        region = propagate_cv_scale(states, self._noise, noise_std, damping=self.scale_damping,
                                    min_half_axis=self.min_half_axis, max_half_axis=self.max_half_axis,
                                    max_scale_rate=self.max_scale_rate, width=w, height=h)
        if before is not None:
            step_velocity(states, before, self.velocity_step)
        return region

    def clip(self, states: np.ndarray) -> None:
        np.clip(states[:, HX], self.min_half_axis, self.max_half_axis, out=states[:, HX])
        np.clip(states[:, HY], self.min_half_axis, self.max_half_axis, out=states[:, HY])
        np.clip(states[:, AD], -self.max_scale_rate, self.max_scale_rate, out=states[:, AD])

    @property
    def matrix(self) -> np.ndarray:
        """``A`` for the position/velocity block (the scale part is ``diag(1 + adot)``)."""
        a = np.eye(7)
        a[X, VX] = a[Y, VY] = 1.0
        return a


def step_velocity(states: np.ndarray, before: np.ndarray, share: float) -> np.ndarray:
    """``v <- (1 - share) v + share (x - x_before)`` in place on the velocity columns of ``(N, 7)`` ``states``
    whose centres moved from ``before`` (``(N, 2)``); returns ``states``. ``share = 1``: the velocity is the last
    displacement (a second-order autoregressive model); 0: unchanged."""
    v = states[:, VX:VY + 1]
    v *= 1.0 - share
    v += share * (states[:, X:Y + 1] - before)
    return states


def widen_position_noise(noise: np.ndarray, rng: np.random.Generator, fraction: float, factor: float) -> np.ndarray:
    """A heavy-tailed proposal: multiply the position noise (columns ``X``, ``Y``) of a random ``fraction`` of the
    rows of standard-normal ``noise`` by ``factor``, in place (a two-component Gaussian mixture on the position
    step, each sample's component drawn afresh each frame); returns ``noise``."""
    wide = rng.random(noise.shape[0]) < fraction
    noise[wide, X] *= factor
    noise[wide, Y] *= factor
    return noise


def mix_noise(noise: np.ndarray, rng: np.random.Generator, fraction: float, factors: np.ndarray) -> np.ndarray:
    """A two-model proposal: multiply the rows of a random ``fraction`` of the rows of standard-normal ``noise``
    by ``factors`` (``(7,)``, per state component), in place: those samples step with the second model's noise
    standard deviations, each sample's model drawn afresh each frame; returns ``noise``."""
    rows = rng.random(noise.shape[0]) < fraction
    noise[rows] *= factors
    return noise


class NCVRandomWalk:
    """Nearly-constant-velocity position + random-walk size (Kristan et al., Eq. 10).

    ``x_t = F x_{t-1} + G w_t`` with, per axis, ``F~ = [[1, 1], [0, 1]]`` and
    ``G~ = [0.5, 1]^T``: the same white acceleration ``w ~ N(0, sigma_xy^2)`` moves the
    velocity by ``w`` and the position by ``w / 2``.  The half-axes follow a random
    walk.  Kristan et al. set its noise "such that the size of the target does not
    change between two time-steps by more than 15 %": we use a relative random walk
    ``H_t = H_{t-1} (1 + e)``, ``e ~ N(0, (max_size_change / 3)^2)`` clipped to
    ``±max_size_change``, so that the 15 % bound holds exactly (3 sigma before clipping).
    """

    dim = 6
    state_names = STATE_NAMES_6

    def __init__(self, *, sigma_xy: float = 1.0, max_size_change: float = 0.15, min_half_axis: float = 2.0,
                 max_half_axis: float = 1e5, keep_aspect: bool = False):
        self.sigma_xy = float(sigma_xy)
        self.max_size_change = float(max_size_change)
        self.min_half_axis = float(min_half_axis)
        self.max_half_axis = float(max_half_axis)
        self.keep_aspect = bool(keep_aspect)
        self._noise: np.ndarray | None = None

    def propagate(self, states: np.ndarray, rng: np.random.Generator, *,
                  frame_size: tuple[int, int] | None = None) -> tuple[float, float, float, float]:
        """Propagate in place; with ``frame_size`` keep centres within one half-axis of the frame.

        Returns the region ``(x0, y0, x1, y1)`` covered by the new ellipses.
        """
        n = states.shape[0]
        if self._noise is None or self._noise.shape != (n, 4):
            self._noise = np.empty((n, 4))
        rng.standard_normal(out=self._noise)
        w, h = frame_size if frame_size is not None else (0.0, 0.0)
        return propagate_ncv_rw(states, self._noise, sigma_xy=self.sigma_xy, max_size_change=self.max_size_change,
                                min_half_axis=self.min_half_axis, max_half_axis=self.max_half_axis,
                                keep_aspect=self.keep_aspect, width=w, height=h)


def lost_prediction(lost_at, frame_index: int, size) -> tuple[np.ndarray, float]:
    """Where a lost target would be ``frame_index - lost_at[0]`` frames after its last confident estimate
    ``lost_at = (frame index, position, velocity)``, moving on at its velocity, and the spread of that guess:
    half the mean of the half-axes ``size``, growing by a tenth of it a frame (the search's prediction)."""
    k = frame_index - lost_at[0]
    centre = np.asarray(lost_at[1], dtype=np.float64) + k * np.asarray(lost_at[2], dtype=np.float64)
    hx, hy = size
    return centre, 0.5 * (hx + hy) * (0.5 + 0.1 * k)


def reappearance_log_prior(positions: np.ndarray, centre, sd: float, area: float, eps: float, *,
                           cap: bool = True) -> np.ndarray:
    """Log prior odds of where a lost target reappears: ``log((1 - eps) A N(x; m, sd^2 I) + eps)``.

    ``m`` is the predicted centre (constant velocity from the last confident frame), ``sd`` the spread
    (growing with the time lost), ``A`` the frame's area and ``eps`` the chance that the target reappears
    anywhere (uniform over the frame), so the odds are relative to the uniform prior.  With ``cap`` the
    odds are at most 1: far candidates need more evidence, near ones no less than usual.  ``positions``:
    ``(M, 2)`` centres; returns ``(M,)``.
    """
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 2)
    d2 = ((p[:, 0] - centre[0]) ** 2 + (p[:, 1] - centre[1]) ** 2) / (sd * sd)
    dens = area * np.exp(-0.5 * d2) / (2.0 * np.pi * sd * sd)
    out = np.log((1.0 - eps) * dens + eps)
    return np.minimum(out, 0.0) if cap else out
