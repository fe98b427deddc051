"""The secant predictor of the displacement: a load step's Newton starts from the extrapolation
through the last two accepted states instead of the last one (the lagged and monolithic schemes'
steps, :mod:`ngtmc.stepping.schemes`, and path following, :mod:`ngtmc.stepping.predictor`).

Units: mm.
"""
from __future__ import annotations

import numpy as np

__all__ = ["secant_displacement", "SECANT_DAMPING", "SECANT_MAX_RATIO"]


#: Fractions of the secant extrapolation tried, in turn, by :func:`secant_displacement`: the first
#: that keeps J > 0 everywhere is taken; if none does, the solve starts from the last accepted
#: state. Where the void under a contact is squeezed to J of about 1e-3, the full secant inverts
#: elements there (the 3D hemisphere under path following, which then took 7-13 Newton iterations
#: per step; docs/three-d.md).
SECANT_DAMPING = (1.0, 0.5, 0.25)

#: Largest ratio of the new load increment to the last one that the secant extrapolates over.
SECANT_MAX_RATIO = 2.0


def secant_displacement(solver, u_n: np.ndarray, u_prev: np.ndarray, ratio: float, load: float):
    """Set the solver's u to the secant predictor u_n + f ratio (u_n - u_prev), with the boundary
    values of ``load`` (mm) on the Dirichlet dofs, for the first fraction f of SECANT_DAMPING
    that keeps every element's J > 0. ``u_n``, ``u_prev``: the last two accepted displacements
    (dof arrays, mm); ``ratio``: (load increment of this step) / (that of the last step). Returns
    f ratio, or None (u unchanged) when ``ratio`` is outside
    (0, SECANT_MAX_RATIO] or every fraction inverts an element. The one owner of the secant
    predictor of u: the lagged and monolithic schemes' steps (:mod:`ngtmc.stepping.schemes`) and path
    following (:mod:`ngtmc.stepping.path`) call it."""
    if not (0.0 < ratio <= SECANT_MAX_RATIO) or u_prev.shape != u_n.shape:
        return None
    s = solver
    uN = s.u.vec.FV().NumPy()
    keep = uN.copy()
    dirm = s._dir_np
    target = s.dirichlet_target(load)[dirm]
    for damping in SECANT_DAMPING:
        uN[:] = u_n + damping * ratio * (u_n - u_prev)
        uN[dirm] = target
        if s.ranks.all_finite(uN) and s.min_J() > 0.0:
            s._r_valid = False
            return damping * ratio
    uN[:] = keep
    return None
