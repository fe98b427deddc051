"""Mesh convergence of the three-point bending's peak force: the recorded peaks of the default
scheme at the three resolutions, and their extrapolation to h -> 0.

Two extrapolations, both from the recorded numbers (``MEASURED`` of the study), never tuned:

* **linear in h** (least squares through the points): the AT-2 phase field on a mesh of size h
  has the effective toughness Gc (1 + h / (2 l0)) (Bourdin, Francfort and Marigo 2008), and the
  peak of a crack that starts from a notch scales with sqrt(Gc), so F(h) ~ F0 (1 + h / (4 l0))
  to first order in h / l0;
* **Richardson with the observed order** (three points): F(h) = F0 + C h^q with q solved from
  the three peaks, where they fall monotonically; q near 1 supports the linear model.

Units: h in mm, forces in N per mm of thickness.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["extrapolate", "observed_order"]


def observed_order(h, F, q_range=(0.05, 8.0)) -> float | None:
    """Order q of F = F0 + C h^q through three points (h in any unit, decreasing or not); None
    when the differences change sign (no monotone convergence) or no q in ``q_range`` fits."""
    h, F = (np.asarray(v, dtype=float) for v in (h, F))
    if h.size != 3:
        return None
    order = np.argsort(h)[::-1]  # coarse to fine
    h, F = h[order], F[order]
    d1, d2 = F[0] - F[1], F[1] - F[2]
    if d1 == 0 or d2 == 0 or (d1 > 0) != (d2 > 0):
        return None
    target = d1 / d2

    def mismatch(q):
        return (h[0] ** q - h[1] ** q) / (h[1] ** q - h[2] ** q) - target

    lo, hi = q_range
    if mismatch(lo) * mismatch(hi) > 0:
        return None
    for _ in range(200):  # bisection: the ratio is monotone in q for h0 > h1 > h2
        mid = 0.5 * (lo + hi)
        if mismatch(lo) * mismatch(mid) <= 0:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def extrapolate(h, F) -> dict:
    """Extrapolations of the peak F(h) to h = 0 (module docstring): ``linear`` (F0 and slope of the
    least-squares line, N/mm and N/mm per mm), and with three points ``order`` and ``richardson``
    (F0 of F0 + C h^q, None where the order is undefined), ``richardson_coefficient`` (its C)."""
    h, F = (np.asarray(v, dtype=float) for v in (h, F))
    if h.size < 2:
        raise ValueError("extrapolate needs peaks at two mesh sizes at least")
    slope, F0 = np.polyfit(h, F, 1)
    out = {"linear": float(F0), "linear_slope": float(slope), "order": None, "richardson": None,
           "richardson_coefficient": None}
    q = observed_order(h, F) if h.size == 3 else None
    if q is not None:
        i = int(np.argmin(h))
        j = int(np.argmax(h))
        C = (F[j] - F[i]) / (h[j] ** q - h[i] ** q)
        out["order"] = float(q)
        out["richardson"] = float(F[i] - C * h[i] ** q)
        out["richardson_coefficient"] = float(C)
    if not all(math.isfinite(v) for v in (out["linear"], out["linear_slope"])):
        raise ValueError("extrapolate: the peaks or mesh sizes are not finite")
    return out
