"""Recursive least squares for dynamic AR(p) models of velocity series (book ch. 7, Sect. 2.2).

Each velocity component of a tracked point is a time series ``x_k`` modelled as an
AR(p) process with slowly varying coefficients (Eq. 11)::

    x_k = c_kᵀ a + ε_k,        c_k = [x_{k-1}, …, x_{k-p}],   a = [-(a_1), …, -(a_p)]

(the vector ``a`` stores the *negated* coefficients of Eq. 11, so a prediction is the
plain dot product ``cᵀa``).  The exponentially weighted cost of Eq. 13 has the batch
solution of Eq. 14 (:func:`rls_batch`) and the recursion of Eqs. 17–19::

    K = P c / (λ + cᵀ P c)
    P ← (P − K cᵀ P) / λ
    a ← a + K (x − cᵀ a)

Initialisation uses the first ``n_init`` samples (Eq. 14 on them).  Restored from
Haykin's δ-regularised start: ``P = [CᵀΛC + δI]⁻¹``, because ``CᵀΛC`` is singular for
a point at constant velocity (both AR(2) columns equal); the ridge solution then
predicts the constant exactly.  The one-step prediction uses the previous step's
coefficients, ``x̂_{N+1} = c_{N+1}ᵀ a_N`` (the book's Eq. 30 writes ``a_{N+1}``, which
is circular: ch07.md §1.2).

:class:`RLSAR` runs ``n`` independent series at once (one per point and velocity
component); :class:`JointRLSAR` is the stereo model of Eqs. 27–29, with one shared
regressor interleaving the channels and one coefficient column per channel.
Everything is NumPy on ``(n, q, q)`` stacks: the matrices are 2×2 or 4×4.
"""

from __future__ import annotations

import numpy as np

__all__ = ["RLSAR", "JointRLSAR", "regressors", "rls_batch", "stabilise"]


def stabilise(coef: np.ndarray) -> np.ndarray:
    """Project AR coefficients (rows, in the ``x̂ = cᵀa`` convention) onto the closed stability region.

    Proposed (ch07.md P7): while a point is hidden the filter is fed its own predictions,
    so an AR model fitted to a noisy near-constant velocity (its two AR(2) columns are
    almost collinear, so the fit along ``(1, −1)`` is noise) can have a root outside the
    unit circle and the extrapolation explodes.  Roots of modulus > 1 are pulled onto the
    unit circle; a model whose roots are all inside is returned unchanged.  For p = 2 the
    region is the triangle ``|a₂| ≤ 1, |a₁| ≤ 1 − a₂`` (vectorised, closed form).
    """
    coef = np.array(coef, dtype=np.float64, copy=True)
    p = coef.shape[-1]
    if p == 1:
        return np.clip(coef, -1.0, 1.0)
    if p == 2:
        a2 = np.clip(coef[..., 1], -1.0, 1.0)
        coef[..., 1] = a2
        coef[..., 0] = np.clip(coef[..., 0], a2 - 1.0, 1.0 - a2)
        return coef
    flat = coef.reshape(-1, p)
    for i, row in enumerate(flat):
        roots = np.roots(np.concatenate([[1.0], -row]))
        mod = np.abs(roots)
        if np.any(mod > 1.0):
            roots = np.where(mod > 1.0, roots / mod, roots)
            flat[i] = -np.real(np.poly(roots))[1:]
    return flat.reshape(coef.shape)


def regressors(x: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``c_k = [x_{k-1}, …, x_{k-p}]`` (Eq. 12) and targets ``x_k`` for ``k = p … N``.

    ``x`` is ``(T,)`` or ``(T, m)`` (m interleaved channels: the row is then
    ``[x_{k-1}[0], …, x_{k-1}[m-1], x_{k-2}[0], …]`` as in Eq. 27).  Returns ``C`` of
    shape ``(T-p, p·m)`` and ``X`` of shape ``(T-p,)`` or ``(T-p, m)``.
    """
    x = np.asarray(x, dtype=np.float64)
    single = x.ndim == 1
    xm = x[:, None] if single else x
    t = xm.shape[0]
    if t <= order:
        raise ValueError(f"need more than {order} samples, got {t}")
    cols = [xm[order - j - 1:t - j - 1] for j in range(order)]
    c = np.concatenate(cols, axis=1)
    target = xm[order:]
    return c, (target[:, 0] if single else target)


def rls_batch(x: np.ndarray, *, order: int = 2, forgetting: float = 0.99, ridge: float = 0.0) -> np.ndarray:
    """Eq. 14: ``a_N = [CᵀΛC + δI]⁻¹ CᵀΛX`` with ``Λ = diag(λ^{N-k})``.

    The exact weighted least-squares fit the recursion must reproduce (the test oracle).
    ``x`` as in :func:`regressors`; returns ``(p·m,)`` or ``(p·m, m)`` coefficients.
    """
    c, target = regressors(x, order)
    lam = forgetting ** np.arange(c.shape[0] - 1, -1, -1, dtype=np.float64)
    g = c.T @ (lam[:, None] * c) + ridge * np.eye(c.shape[1])
    return np.linalg.solve(g, c.T @ (lam[:, None] * target if target.ndim == 2 else lam * target))


def _prior(name: str, order: int) -> np.ndarray:
    """The coefficients the ridge pulls towards: ``zero`` (Haykin's δ-start), ``hold`` (x̂ = x_N)
    or ``mean`` (x̂ = mean of the last p samples); the last two predict a constant exactly."""
    if name == "zero":
        return np.zeros(order)
    if name == "hold":
        return np.eye(order)[0]
    if name == "mean":
        return np.full(order, 1.0 / order)
    raise ValueError("prior must be 'zero', 'hold' or 'mean'")


def _init_ridge(g: np.ndarray, ridge: float) -> np.ndarray:
    """δ = ridge · max(1, trace(G)/q) per series (ch07.md §2): scale-aware, never zero."""
    q = g.shape[-1]
    tr = np.trace(g, axis1=-2, axis2=-1) / q
    return ridge * np.maximum(1.0, tr)


class RLSAR:
    """``n`` independent exponentially weighted RLS AR(p) predictors (Eqs. 11–19).

    ``push(x)`` appends one sample per series (shape ``(n,)``); the first ``n_init``
    samples are collected and fitted in batch (Eq. 14 with the ridge), later ones run
    the recursion.  ``predict()`` is the a-priori one-step prediction ``c_{N+1}ᵀ a_N``.
    ``window`` (ch07.md P6) replaces the recursion by a batch refit on the last
    ``window`` samples at every push.  ``stable`` predicts with the :func:`stabilise`-projected
    coefficients (the fit itself is untouched).
    """

    def __init__(self, n: int = 1, *, order: int = 2, forgetting: float = 0.99, n_init: int = 7,
                 ridge: float = 1e-6, window: int | None = None, stable: bool = False, prior: str = "zero"):
        if order < 1:
            raise ValueError("order must be >= 1")
        if n_init < order + 1:
            raise ValueError(f"n_init must be > order ({order})")
        if not 0.0 < forgetting <= 1.0:
            raise ValueError("forgetting must be in (0, 1]")
        if window is not None and window < order + 1:
            raise ValueError(f"window must be > order ({order})")
        self.n, self.order, self.forgetting = int(n), int(order), float(forgetting)
        self.n_init, self.ridge, self.window = int(n_init), float(ridge), window
        self.stable = bool(stable)
        self.prior = _prior(prior, self.order)
        self.reset()

    def reset(self) -> None:
        p = self.order
        self._hist = np.zeros((self.n, 0))  # collected samples (all, until ready; the last max(p, window) after)
        self.coef = np.zeros((self.n, p))
        self.P = np.repeat(np.eye(p)[None], self.n, axis=0)
        self.count = 0

    @property
    def ready(self) -> bool:
        return self.count >= self.n_init

    def _regressor(self) -> np.ndarray:
        """``c_{N+1} = [x_N, …, x_{N-p+1}]`` from the newest samples, shape ``(n, p)``."""
        return self._hist[:, ::-1][:, :self.order]

    def predict(self) -> np.ndarray:
        """One-step prediction per series; before ``ready`` the last sample (constant velocity)."""
        if not self.ready:
            return self._hist[:, -1].copy() if self.count else np.zeros(self.n)
        coef = stabilise(self.coef) if self.stable else self.coef
        return np.einsum("np,np->n", self._regressor(), coef)

    def _fit_batch(self, samples: np.ndarray) -> None:
        t, p = samples.shape[1], self.order
        c = np.stack([samples[:, p - j - 1:t - j - 1] for j in range(p)], axis=2)  # (n, T-p, p): Eq. 12's rows
        target = samples[:, self.order:]
        lam = self.forgetting ** np.arange(c.shape[1] - 1, -1, -1, dtype=np.float64)
        g = np.einsum("ntp,t,ntq->npq", c, lam, c)
        delta = _init_ridge(g, self.ridge)
        g = g + delta[:, None, None] * np.eye(self.order)
        self.P = np.linalg.inv(g)
        rhs = np.einsum("ntq,t,nt->nq", c, lam, target) + delta[:, None] * self.prior
        self.coef = np.einsum("npq,nq->np", self.P, rhs)

    def push(self, x) -> None:
        """Add one sample per series (Eq. 15 regressor, Eqs. 18–19 update)."""
        x = np.broadcast_to(np.asarray(x, dtype=np.float64), (self.n,))
        if self.ready and self.window is None:
            c = self._regressor()
            pc = np.einsum("npq,nq->np", self.P, c)
            k = pc / (self.forgetting + np.einsum("np,np->n", c, pc))[:, None]
            self.P = (self.P - np.einsum("np,nq->npq", k, pc)) / self.forgetting
            self.coef = self.coef + k * (x - np.einsum("np,np->n", c, self.coef))[:, None]
        self._hist = np.concatenate([self._hist, x[:, None]], axis=1)
        self.count += 1
        keep = max(self.order, self.window or 0)
        if self.count == self.n_init and self.window is None:
            self._fit_batch(self._hist)
        elif self.window is not None and self.count >= self.n_init:
            self._fit_batch(self._hist[:, -self.window:])
        if self.count >= self.n_init:
            self._hist = self._hist[:, -keep:]

    def prime(self, rows, samples: np.ndarray) -> None:
        """Give the series in ``rows`` a fresh history ``samples`` (``(len(rows), T)``, T ≥ n_init).

        Used when a point is re-seeded: its filter starts from the motion its
        neighbours had, instead of waiting ``n_init`` frames.  Only once all series are
        ready (``count ≥ n_init``).
        """
        if not self.ready:
            raise ValueError("prime() needs an initialised filter")
        rows = np.asarray(rows)
        samples = np.atleast_2d(np.asarray(samples, dtype=np.float64))
        sub = RLSAR(samples.shape[0], order=self.order, forgetting=self.forgetting, n_init=samples.shape[1],
                    ridge=self.ridge)
        sub.prior = self.prior
        sub._fit_batch(samples)
        self.coef[rows], self.P[rows] = sub.coef, sub.P
        keep = self._hist.shape[1]
        self._hist[rows] = samples[:, -keep:]


class JointRLSAR:
    """Joint RLS AR(p) over ``m`` channels with a shared regressor (stereo, Eqs. 27–29).

    The regressor interleaves the channels, ``c = [xL_N, xR_N, xL_{N-1}, xR_{N-1}, …]``
    (length ``p·m``), and each channel has its own coefficient column (``coef`` has
    shape ``(p·m, m)``); ``K`` and ``P`` are shared, so one update serves all channels
    (``A += K ⊗ innovation``).  ``push`` takes ``(m,)``.  With ``xL ≡ xR`` the normal
    matrix is singular; the ridge keeps it solvable (ch07.md P4).
    """

    def __init__(self, channels: int = 2, *, order: int = 2, forgetting: float = 0.99, n_init: int = 7,
                 ridge: float = 1e-6, prior: str = "zero"):
        if n_init < order + 1:
            raise ValueError(f"n_init must be > order ({order})")
        self.m, self.order, self.forgetting = int(channels), int(order), float(forgetting)
        self.n_init, self.ridge = int(n_init), float(ridge)
        # the prior of each channel acts on its own lags only (interleaved rows j*m + channel)
        own = _prior(prior, self.order)
        self.prior = np.zeros((self.order * self.m, self.m))
        for ch in range(self.m):
            self.prior[ch::self.m, ch] = own
        self.reset()

    def reset(self) -> None:
        q = self.order * self.m
        self._hist = np.zeros((0, self.m))
        self.coef = np.zeros((q, self.m))
        self.P = np.eye(q)
        self.count = 0

    @property
    def ready(self) -> bool:
        return self.count >= self.n_init

    def _regressor(self) -> np.ndarray:
        return self._hist[::-1][:self.order].reshape(-1)

    def predict(self) -> np.ndarray:
        if not self.ready:
            return self._hist[-1].copy() if self.count else np.zeros(self.m)
        return self._regressor() @ self.coef

    def push(self, x) -> None:
        x = np.asarray(x, dtype=np.float64).reshape(self.m)
        if self.ready:
            c = self._regressor()
            pc = self.P @ c
            k = pc / (self.forgetting + c @ pc)
            self.P = (self.P - np.outer(k, pc)) / self.forgetting
            self.coef = self.coef + np.outer(k, x - c @ self.coef)
        self._hist = np.vstack([self._hist, x[None]])
        self.count += 1
        if self.count == self.n_init:
            c, target = regressors(self._hist, self.order)
            lam = self.forgetting ** np.arange(c.shape[0] - 1, -1, -1, dtype=np.float64)
            g = c.T @ (lam[:, None] * c)
            delta = _init_ridge(g, self.ridge)
            g = g + delta * np.eye(g.shape[0])
            self.P = np.linalg.inv(g)
            self.coef = self.P @ (c.T @ (lam[:, None] * target) + delta * self.prior)
        if self.count >= self.n_init:
            self._hist = self._hist[-self.order:]
