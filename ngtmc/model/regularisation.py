"""Hessian regularisation of the third medium (Eq. 3).

The void ("third medium") is so soft that its elements distort without limit as bodies approach.
The regulariser penalises the second gradient of u there,

    Phi_bar(u) = k_r / 2 ( Hu : Hu - 1/d  Lu . Lu ) I_void,        k_r = kbar_r L^2 K0,

with Hu the Hessian of u (third-order tensor), Lu the vector Laplacian and d the dimension. The
combination vanishes for linear (and rigid) fields and penalises bending and kinking of the void
elements but not its uniform compression. It needs displacement elements of order >= 2.

Optional damping: ``damping="exp"`` multiplies the *energy* density by exp(-5 J), so the term
fades where the medium is stretched and acts fully where it is squeezed. This is the energy
variant: its tangent stays symmetric. (The variant in the literature puts exp(-5 J) into the
weak form only, which makes the tangent non-symmetric; it is not implemented here.)

Units: k_r in N (MPa mm^2); Phi_bar in MPa.
"""
from __future__ import annotations

import ngsolve as ngs

__all__ = ["hessian", "laplacian", "phi_bar", "regularisation_stiffness"]


def hessian(u):
    """Hessian of a vector field u as an NGSolve CF of shape (d, d*d), 1/mm: row i = d^2 u_i / dx_j dx_k."""
    return u.Operator("hesse")


def laplacian(u):
    """Vector Laplacian Lu (d,), 1/mm: trace of each row of the Hessian."""
    Hu = hessian(u)
    d = u.dim
    return ngs.CF(tuple(sum(Hu[i, j * d + j] for j in range(d)) for i in range(d)))


def regularisation_stiffness(kbar_r: float, length: float, K0: float) -> float:
    """k_r = kbar_r L^2 K0, N: kbar_r dimensionless (1e-6 in the literature), L a characteristic
    length of the structure (mm), K0 the bulk modulus of the dense material (MPa)."""
    return kbar_r * length**2 * K0


def phi_bar(u, k_r, indicator=1.0, damping: str = "none"):
    """Regularisation energy density Phi_bar of Eq. 3, MPa.

    u: displacement (order >= 2); k_r: stiffness (N); indicator: I_void, 1 in the void and 0 in
    the solid (a CF, e.g. 1 - rho); damping: "none" or "exp" (energy density times exp(-5 J)).
    """
    d = u.dim
    Hu = hessian(u)
    Lu = laplacian(u)
    phi = k_r / 2 * (ngs.InnerProduct(Hu, Hu) - 1.0 / d * ngs.InnerProduct(Lu, Lu)) * indicator
    if damping == "exp":
        J = ngs.Det(ngs.Id(d) + ngs.Grad(u))
        phi = ngs.exp(-5 * J) * phi
    elif damping != "none":
        raise ValueError(f"regulariser damping = {damping!r} is not one of the allowed values 'none', 'exp'")
    return phi
