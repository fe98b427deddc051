"""Linear-elastic reference of the three-point-bending beam (``studies/three_point_bending.py``),
and the measure of the rising branch (:func:`elastic_slope`) it is compared with.

Small strain, plane strain, isotropic (E, nu of the study), the unbroken beam: no phase field,
no void, no indenter. The beam of the study's mesh with ``loading = "window"`` (the notch as
``notch_shape``, or none with ``notch_depth = 0``) is loaded on the window of the beam top by a
downward displacement (tangential free), pin and roller as in the study. This is the stiffness of
the beam alone: the window variant's measured slope, less any damage before 25 % of the peak, and
the indenter variant's, less the indenter's and the void's compliance.

The file name starts with an underscore: it is a helper, not a study.
"""
from __future__ import annotations

import numpy as np


def linear_elastic_stiffness(p: dict, order: int = 2) -> dict:
    """Stiffness of the unbroken beam under the window load, from one linear solve.

    p: the study's parameter dict (mm, MPa; a resolution's mesh sizes); the mesh is that of
    ``loading = "window"`` whatever ``p["loading"]``. order: polynomial order of the displacement
    (1 is the study's in the beam).

    Returns a dict: ``slope`` (N/mm per micrometre): the window's reaction per unit thickness per
    unit imposed displacement, the quantity the study's ``elastic_slope`` measures;
    ``slope_mid_height`` (N/mm per micrometre): the same force per unit deflection of the
    mid-height line at mid-span relative to the mean of the same line above the support centres,
    (x, H/2) at x = L/2 against x = s/2 and L - s/2 (s = support_length): the deflection of beam
    theory; ``mid_height_ratio`` and ``support_ratio``: that relative deflection and the mean
    deflection of the mid-height line above the supports, per unit window displacement (-);
    ``ndof`` and ``elements`` of the solve."""
    import ngsolve as ngs

    from . import _tpb_geometry as geometry

    q = dict(p, loading="window", indenter_exclusion=0.0)
    mesh = geometry.build_mesh(q)
    E, nu = float(p["E"]), float(p["nu"])
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))  # plane strain
    fes = ngs.VectorH1(mesh, order=int(order), dirichletx="support_left",
                       dirichlety="support_left|support_right|load")
    u, v = fes.TnT()

    def eps(w):
        return ngs.Sym(ngs.Grad(w))

    def sigma(w):
        return lam * ngs.Trace(eps(w)) * ngs.Id(2) + 2 * mu * eps(w)

    a = ngs.BilinearForm(ngs.InnerProduct(sigma(u), eps(v)) * ngs.dx).Assemble()
    gfu = ngs.GridFunction(fes)
    delta = 1e-3  # mm imposed on the window (linear: any value)
    gfu.Set(ngs.CoefficientFunction((0.0, -delta)), definedon=mesh.Boundaries("load"))
    r = gfu.vec.CreateVector()
    r.data = -(a.mat * gfu.vec)
    gfu.vec.data += a.mat.Inverse(fes.FreeDofs(), inverse="sparsecholesky") * r
    r.data = a.mat * gfu.vec
    force = ngs.InnerProduct(r, gfu.vec) / delta  # = reaction on the window, N per mm thickness (only u_y imposed)
    L, H, s = float(p["beam_length"]), float(p["beam_height"]), float(p["support_length"])

    def w(x):
        return -gfu(mesh(x, H / 2))[1]

    w_support = 0.5 * (w(s / 2) + w(L - s / 2))
    w_mid = w(L / 2) - w_support
    return {"slope": force / delta / 1e3, "slope_mid_height": force / w_mid / 1e3,
            "mid_height_ratio": w_mid / delta, "support_ratio": w_support / delta,
            "ndof": fes.ndof, "elements": mesh.ne}


def beam_theory_slope(p: dict, shear_coefficient: float = 5.0 / 6.0) -> float:
    """Euler-Bernoulli bending plus Timoshenko shear of the unnotched beam, plane strain, N/mm per
    micrometre: P / w = 1 / (S^3 / (48 E' I) + S / (4 k G H)) with S = beam_length - support_length
    (between the centres of the support segments), E' = E / (1 - nu^2), G = E / (2 (1 + nu)),
    I = H^3 / 12 per unit thickness, k the shear coefficient. Beam theory has no local compression
    under the load and the supports: compare it with ``slope_mid_height``."""
    E, nu, H = float(p["E"]), float(p["nu"]), float(p["beam_height"])
    S = float(p["beam_length"]) - float(p["support_length"])
    Ep, G = E / (1 - nu ** 2), E / (2 * (1 + nu))
    compliance = S ** 3 / (48 * Ep * H ** 3 / 12) + S / (4 * shear_coefficient * G * H)
    return 1.0 / compliance / 1e3


def elastic_slope(load, force, lo: float = 0.25, hi: float = 0.60) -> float:
    """Secant slope of the rising branch, N/mm per micrometre of load, between the first points
    where the force reaches ``lo`` and ``hi`` times the peak (loads linearly interpolated; so the
    coarse digitised references are measured the same way). With the indenter both lie after
    contact: the void carries at most 1.3 % of the peak. NaN if the curve has no rising branch."""
    x, y = np.asarray(load, dtype=float), np.asarray(force, dtype=float)
    i = int(np.nanargmax(y))

    def crossing(level):
        j = int(np.argmax(y[: i + 1] >= level))
        if j == 0:
            return float("nan")
        return x[j - 1] + (level - y[j - 1]) * (x[j] - x[j - 1]) / (y[j] - y[j - 1])

    a, b = crossing(lo * y[i]), crossing(hi * y[i])
    return float((hi - lo) * y[i] / (1e3 * (b - a)))
