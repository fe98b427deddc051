"""AT-2 phase-field fracture with the hybrid formulation (Eqs. 5-7 and 16, Ambati et al. 2015).

alpha is the crack phase field (0 intact, 1 broken). The displacement equation sees the whole
energy degraded by g(alpha); only the crack driving force uses the tensile part Psi_plus, through
the history H_n = max(H_{n-1}, Psi_plus(u_n)) (Eq. 7) that makes cracks irreversible.

Units: energy densities in MPa (N mm / mm^3), Gc in N/mm, l0 in mm.
"""
from __future__ import annotations

import ngsolve as ngs

__all__ = [
    "C_W",
    "degradation",
    "crack_function",
    "crack_surface_density",
    "fracture_energy_density",
    "alpha_driving_form",
]

#: Normalisation constant c_w of AT-2 (w(alpha) = alpha^2): c_w = 2.
C_W = 2.0


def degradation(alpha, residual: float = 0.0):
    """Degradation g(alpha) = (1 - alpha)^2 + residual (AT-2), dimensionless.

    ``residual`` keeps a fully broken element from becoming softer than the void (see MODEL.md:
    with 1e-8 broken elements collapsed, with 1e-6 they held)."""
    return (1 - alpha) ** 2 + residual


def crack_function(alpha):
    """Local dissipation function w(alpha) = alpha^2 (AT-2), dimensionless."""
    return alpha**2


def crack_surface_density(alpha, l0):
    """Crack surface density gamma_l = (w(alpha)/l0 + l0 |grad alpha|^2) / c_w, 1/mm.

    Integrated over a sharp crack of length a it gives about a (mm); times Gc it is the dissipated
    energy of Eq. 5 (N mm per mm thickness)."""
    return (crack_function(alpha) / l0 + l0 * ngs.InnerProduct(ngs.Grad(alpha), ngs.Grad(alpha))) / C_W


def fracture_energy_density(alpha, Gc, l0):
    """Density of W_f of Eq. 19, Gc (alpha^2/l0 + l0 |grad alpha|^2), MPa.

    Note: W_f has no 1/c_w and is twice the dissipated energy of AT-2. It is kept as published
    because the step rule (Eq. 20, constant k_u) is calibrated against it."""
    return Gc * (crack_function(alpha) / l0 + l0 * ngs.InnerProduct(ngs.Grad(alpha), ngs.Grad(alpha)))


def alpha_driving_form(alpha, beta, H, Gc, l0, dx_H, dx):
    """Bilinear and linear form of the phase-field equation with the history H fixed (Eq. 16).

    Minimising int g(alpha) H + Gc/c_w (alpha^2/l0 + l0 |grad alpha|^2) over alpha gives, with
    g = (1 - alpha)^2 and c_w = 2, the linear symmetric positive definite problem

        int (2 H + Gc/l0) alpha beta + Gc l0 grad alpha . grad beta = int 2 H beta.

    ``dx_H`` is the measure carrying the integration rule of the history space (terms with H
    must be integrated exactly at the history points), ``dx`` the plain measure.
    Returns (bilinear integrand, linear integrand) as a pair of NGSolve forms.
    """
    a = (2 * H * alpha * beta) * dx_H + (Gc / l0 * alpha * beta + Gc * l0 * ngs.InnerProduct(ngs.Grad(alpha), ngs.Grad(beta))) * dx
    f = (2 * H * beta) * dx_H
    return a, f
