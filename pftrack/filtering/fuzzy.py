"""The fuzzy controller that tunes the gate gain ``k`` of the flow/prediction gate (book ch. 7, Sect. 3).

Inputs (Eqs. 21–22): the error increment ``Δε_n = ε_n − ε_{n−1}``, with
``ε_n = |v^of_n − v^af_n|``, and the crisp flag ``qV`` (1 when the previous frame used
the optical-flow velocity, 0 when it used the RLS prediction).  Output: ``k ∈ [0.5, 1]``.

Rule table (L7054–7064)::

    EI \\ qV   0 (filter)   1 (flow)
    NB         H            L
    M          L            H
    PB         L            L

The membership functions of the book's Figs. 10–11 are lost; those used here are the
proposal of ch07.md §1.4:

* the input is normalised, ``e = Δε / max(|v_{n−1}|, v_floor)``, so the controller has
  no pixel scale (the gate's tolerance ``k·|v|`` is relative too);
* NB, M, PB form a Ruspini partition with breakpoints ±0.2 and ±0.6;
* the output sets L and H are whole triangles centred at 0.5 and 1.0 with half-width
  0.25 (not truncated, so their centroids and hence ``k`` span exactly [0.5, 1]);
* Mamdani inference (clip each consequent at its firing strength) and centre-of-sums
  defuzzification (L7006–7008): every clipped set counts separately, ``k* = Σ c_r A_r /
  Σ A_r`` with the clipped-triangle area ``A_r ∝ w_r (1 − w_r / 2)``.

The other three methods of L6998–7016 are available: ``coa`` (centroid of the union),
``mom`` (mean of the maxima of the union) and ``ca`` (centre average, ``Σ c_r w_r / Σ w_r``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DEFUZZ", "RULES", "FuzzyGain"]

DEFUZZ = ("cos", "coa", "mom", "ca")

#: (input set, qV, output set) for the six rules of the chapter's table.
RULES = (("NB", 0, "H"), ("NB", 1, "L"), ("M", 0, "L"), ("M", 1, "H"), ("PB", 0, "L"), ("PB", 1, "L"))


@dataclass(frozen=True)
class FuzzyGain:
    """``k = FuzzyGain()(delta_eps, v_prev_norm, qv)``; vectorised over points.

    ``breakpoints=(a, b)`` put the NB/M and M/PB crossovers on ``±a … ±b``; ``units='relative'``
    divides Δε by ``max(|v_{n−1}|, v_floor)`` first, ``units='px'`` uses Δε in pixels per
    frame (then ch07.md suggests breakpoints (0.5, 1.5)).
    """

    breakpoints: tuple[float, float] = (0.2, 0.6)
    out_centres: tuple[float, float] = (0.5, 1.0)
    out_halfwidth: float = 0.25
    defuzz: str = "cos"
    v_floor: float = 0.5
    units: str = "relative"

    def __post_init__(self):
        a, b = self.breakpoints
        if not 0 <= a < b:
            raise ValueError("breakpoints must satisfy 0 <= a < b")
        if self.defuzz not in DEFUZZ:
            raise ValueError(f"defuzz must be one of {', '.join(DEFUZZ)}")
        if self.units not in ("relative", "px"):
            raise ValueError("units must be 'relative' or 'px'")

    def normalise(self, delta_eps, v_prev_norm) -> np.ndarray:
        d = np.asarray(delta_eps, dtype=np.float64)
        if self.units == "px":
            return d
        return d / np.maximum(np.asarray(v_prev_norm, dtype=np.float64), self.v_floor)

    def memberships(self, e) -> dict[str, np.ndarray]:
        """μ_NB, μ_M, μ_PB of the normalised increment ``e`` (they sum to 1)."""
        e = np.asarray(e, dtype=np.float64)
        a, b = self.breakpoints
        nb = np.clip((-a - e) / (b - a), 0.0, 1.0)
        pb = np.clip((e - a) / (b - a), 0.0, 1.0)
        return {"NB": nb, "M": 1.0 - nb - pb, "PB": pb}

    def __call__(self, delta_eps, v_prev_norm, qv) -> np.ndarray:
        return self.from_normalised(self.normalise(delta_eps, v_prev_norm), qv)

    def from_normalised(self, e, qv) -> np.ndarray:
        e = np.nan_to_num(np.asarray(e, dtype=np.float64), nan=0.0, posinf=1e6, neginf=-1e6)
        cl, ch = self.out_centres
        w_l, w_h = self._rule_strengths(e, qv)
        if self.defuzz == "ca":
            num, den = cl * w_l.sum(0) + ch * w_h.sum(0), w_l.sum(0) + w_h.sum(0)
        elif self.defuzz == "cos":
            a_l, a_h = (w * (1.0 - w / 2.0) for w in (w_l, w_h))  # clipped-triangle areas / base
            num, den = cl * a_l.sum(0) + ch * a_h.sum(0), a_l.sum(0) + a_h.sum(0)
        else:
            return self._on_grid(w_l.max(0), w_h.max(0))
        with np.errstate(invalid="ignore", divide="ignore"):
            k = num / den
        return np.where(den > 0, k, 0.5 * (cl + ch))

    def _rule_strengths(self, e, qv) -> tuple[np.ndarray, np.ndarray]:
        """Per-rule strengths stacked as ``(rules_L, …)`` and ``(rules_H, …)`` (COS counts each rule)."""
        mu = self.memberships(e)
        q = np.asarray(qv).astype(bool)
        ls, hs = [], []
        for name, qv_r, out in RULES:
            w = np.where(q == bool(qv_r), mu[name], 0.0)
            (ls if out == "L" else hs).append(w)
        return np.stack(ls), np.stack(hs)

    def _on_grid(self, w_l: np.ndarray, w_h: np.ndarray, n: int = 2001) -> np.ndarray:
        """COA / MOM on the union of the clipped output sets, sampled on the extended universe."""
        cl, ch = self.out_centres
        hw = self.out_halfwidth
        u = np.linspace(min(cl, ch) - hw, max(cl, ch) + hw, n)
        tri_l = np.clip(1.0 - np.abs(u - cl) / hw, 0.0, None)
        tri_h = np.clip(1.0 - np.abs(u - ch) / hw, 0.0, None)
        wl, wh = np.atleast_1d(w_l)[..., None], np.atleast_1d(w_h)[..., None]
        agg = np.maximum(np.minimum(tri_l, wl), np.minimum(tri_h, wh))
        if self.defuzz == "coa":
            den = agg.sum(-1)
            k = (agg * u).sum(-1) / np.where(den > 0, den, 1.0)
        else:  # mom
            top = agg >= agg.max(-1, keepdims=True) - 1e-12
            k = (top * u).sum(-1) / top.sum(-1)
            den = agg.max(-1)
        k = np.where(den > 0, k, 0.5 * (cl + ch))
        return k.reshape(np.shape(w_l))
