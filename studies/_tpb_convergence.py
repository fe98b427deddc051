"""Mesh convergence of the three-point bending's peak force: the recorded peaks of the default
scheme at the three resolutions, and their extrapolation to h -> 0.

Two extrapolations, both from the recorded numbers (the study's records
``<resolution>_path_following``, ``studies/records/three_point_bending.json``), never tuned:

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

from ngtmc.study import records

__all__ = ["extrapolate", "observed_order", "mesh_convergence", "figure"]


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


def mesh_convergence(h_band: dict) -> dict:
    """Recorded peaks of the default scheme (path following) against h_band (``h_band``:
    resolution -> mm), from the study's records ``<resolution>_path_following``, with their
    extrapolations to h -> 0 (:func:`extrapolate`): h (mm), peak (N/mm), resolutions."""
    runs = records("three_point_bending")
    rows = [(float(h_band[r]), float(runs[f"{r}_path_following"]["figures"]["peak_force"]), r)
            for r in ("quick", "medium", "paper") if f"{r}_path_following" in runs]
    h, F, names = (list(v) for v in zip(*rows))
    return {"h": h, "peak_force": F, "resolutions": names, **extrapolate(h, F)}


def figure(mc: dict, ambati_peak: float) -> dict:
    """The report's figure of the mesh convergence ``mc`` (:func:`mesh_convergence`) against
    Ambati's peak (N/mm)."""
    h_max = max(mc["h"]) * 1.1
    xs = np.linspace(0.0, h_max, 23)
    series = [
        {"label": "this model, path following (recorded: " + ", ".join(mc["resolutions"]) + ")", "kind": "points",
         "x": mc["h"], "y": mc["peak_force"]},
        {"label": f"linear in h: {mc['linear']:.2f} N/mm at h = 0", "kind": "curve", "x": xs.tolist(),
         "y": (mc["linear"] + mc["linear_slope"] * xs).tolist()},
    ]
    if mc["richardson"] is not None:
        q, F0, C = mc["order"], mc["richardson"], mc["richardson_coefficient"]
        series.append({"label": f"F0 + C h^q, observed order q = {q:.2f}: {F0:.2f} N/mm at h = 0", "kind": "curve",
                       "x": xs.tolist(), "y": (F0 + C * xs ** q).tolist()})
    series.append({"label": f"Ambati et al. 2015, Fig. 22: {ambati_peak:g} N/mm (their mesh)", "kind": "curve",
                   "x": [0.0, h_max], "y": [ambati_peak, ambati_peak]})
    return {
        "title": "Peak force against the element size of the band (recorded, default scheme)",
        "x_title": "h_band (mm; l0 = 0.03 mm)", "y_title": "peak force (N/mm)",
        "caption": ("Peaks of the path-following runs recorded in the study (MEASURED) at quick, medium and paper "
                    "resolution, not computed in this run, with two extrapolations to h = 0: a straight line (the "
                    "AT-2 toughness on a mesh of size h is Gc (1 + h / (2 l0))) and F0 + C h^q with the order "
                    "observed from the three peaks. Look for: how far the extrapolated peak is from the paper "
                    f"resolution's and from Ambati's {ambati_peak:g} N/mm."),
        "series": series,
    }
