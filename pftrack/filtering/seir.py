"""SEIR: sequential evolutionary importance resampling (book ch. 3, §4.2, Algorithm 3).

After the particles are weighted, and while the effective sample size is below
``n_target`` (at most ``max_loops`` times; ch03.md P7 reads the text's loop condition so):

1. COPY every particle (Eq. 8);
2. CROSSOVER ``N`` children: a parent ``i`` drawn ∝ its weight and a parent ``j`` drawn ∝
   ``1 − ṽ_j``; the child ``X_j + μ (X_i − X_j)``, ``μ ~ U(0, 1)``, lies between the weaker
   parent and the stronger one (Eq. 9);
3. MUTATION ``X_i + λ ν``, ``ν ~ N(0, I)`` (Eq. 10; ``mutation_std`` gives ``λ`` per dimension);
4. weight the ``2N`` new particles (the copies keep their likelihoods) and SELECT ``N`` of the
   ``3N`` by systematic resampling on the normalised likelihoods; the selected particles keep
   their own likelihoods, renormalised (L2528–2529), so the ESS rises as they crowd the mode.

SEIR is an optimiser, not an unbiased sampler (ch03.md P8): reselecting on the same
likelihood sharpens the posterior, and the ESS it reports measures concentration.  All
randomness comes from the injected generator.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .particles import effective_sample_size, weights_from_log
from .resampling import systematic

__all__ = ["SEIRInfo", "seir"]


@dataclass
class SEIRInfo:
    """ESS before the loop and after each loop, and the number of loops run."""

    ess: list[float] = field(default_factory=list)
    loops: int = 0


def seir(states: np.ndarray, log_lik: np.ndarray, log_lik_fn: Callable[[np.ndarray], np.ndarray],
         rng: np.random.Generator, *, n_target: float | None = None, max_loops: int = 10,
         mutation_std=1.0) -> tuple[np.ndarray, np.ndarray, SEIRInfo]:
    """Run the SEIR loop on ``N`` weighted particles.

    Parameters
    ----------
    states : ``(N, D)`` particle states.
    log_lik : ``(N,)`` their log-likelihoods (their log-weights after prediction).
    log_lik_fn : scores a ``(M, D)`` batch of new states, returns ``(M,)`` log-likelihoods.
    n_target : the ESS to reach (default 0.8 N, ch03.md §2).
    max_loops : T_max (default 10).
    mutation_std : λ, a scalar or one value per dimension.

    Returns the ``N`` states, their log-likelihoods (normalise them for the weights) and an
    :class:`SEIRInfo`.
    """
    x = np.asarray(states, dtype=np.float64).copy()
    ll = np.asarray(log_lik, dtype=np.float64).copy()
    n, d = x.shape
    n_target = 0.8 * n if n_target is None else float(n_target)
    lam = np.broadcast_to(np.asarray(mutation_std, dtype=np.float64), (d,))
    info = SEIRInfo()
    w = weights_from_log(ll)
    ess = effective_sample_size(w)
    info.ess.append(float(ess))
    while ess < n_target and info.loops < max_loops:
        # crossover: i ∝ v, j ∝ 1 - v
        inv = np.clip(1.0 - w, 0.0, None)
        inv = inv / inv.sum() if inv.sum() > 0 else np.full(n, 1.0 / n)
        i = rng.choice(n, size=n, p=w)
        j = rng.choice(n, size=n, p=inv)
        mu = rng.random((n, 1))
        cross = x[j] + mu * (x[i] - x[j])
        mut = x + lam * rng.standard_normal((n, d))
        new = np.vstack([cross, mut])
        pool_x = np.vstack([x, new])
        pool_ll = np.concatenate([ll, np.asarray(log_lik_fn(new), dtype=np.float64)])
        pool_w = weights_from_log(pool_ll)
        keep = systematic(pool_w, rng, n)  # N of the 3N
        x, ll = pool_x[keep], pool_ll[keep]
        w = weights_from_log(ll)
        ess = effective_sample_size(w)
        info.loops += 1
        info.ess.append(float(ess))
    return x, ll, info
