"""Hyperelastic third-medium material: the Neo-Hookean energy of Eq. 2 and the interpolation of Eqs. 17-18.

Unit system of the whole package: **mm, N, MPa (= N/mm^2)**; energies in N mm, energy densities in
MPa (= N mm / mm^3), critical energy release rates in N/mm. Published values given in kN/mm are
converted where they enter (1 kN/mm = 1000 N/mm).

Every energy term is a small function of NGSolve CoefficientFunctions named after the paper's term
(Ciceri et al. 2026, "A differentiable variational model for structural self-contact and
fracture", Engineering with Computers), so that the equations can be read next to the code.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import ngsolve as ngs

__all__ = [
    "Material",
    "deformation_gradient",
    "full_deformation_gradient",
    "psi_vol",
    "psi_dev",
    "psi_bar",
    "psi_plus",
    "gamma_interpolation",
    "gc_interpolation",
]


@dataclass(frozen=True)
class Material:
    """Solid material parameters of one region.

    Parameters
    ----------
    E : float
        Young's modulus of the fully dense solid, MPa. Must be > 0.
    nu : float
        Poisson's ratio, dimensionless, in (-1, 0.5).
    Gc : float
        Critical energy release rate of the fully dense solid, N/mm (1 kN/mm = 1000 N/mm). Must be > 0.
        Only used where fracture may happen.
    l0 : float
        Phase-field length scale, mm. Must be > 0. Only used where fracture may happen.
    """

    E: float
    nu: float
    Gc: float = 1.0
    l0: float = 1.0

    def __post_init__(self):
        _check_positive("E", self.E, "MPa")
        check_number("Material parameter nu", self.nu, "dimensionless")
        if not (-1.0 < float(self.nu) < 0.5):
            raise ValueError(f"Material parameter nu (Poisson's ratio) = {self.nu!r} is outside the allowed range (-1, 0.5)")
        _check_positive("Gc", self.Gc, "N/mm")
        _check_positive("l0", self.l0, "mm")

    @property
    def K0(self) -> float:
        """Bulk modulus K0 = E / (3 (1 - 2 nu)), MPa."""
        return self.E / (3.0 * (1.0 - 2.0 * self.nu))

    @property
    def G0(self) -> float:
        """Shear modulus G0 = E / (2 (1 + nu)), MPa."""
        return self.E / (2.0 * (1.0 + self.nu))

    def plane_strain_modulus(self) -> float:
        """E' = E / (1 - nu^2), MPa: the small-strain uniaxial-strain-free-lateral plane-strain modulus."""
        return self.E / (1.0 - self.nu**2)


def check_number(what: str, value, unit: str):
    """Raise TypeError unless ``value`` is a real number (int or float, not a bool or a string);
    ``what`` names the parameter and ``unit`` its unit in the message."""
    import numbers
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        hint = " (a string: write the number without quotes)" if isinstance(value, str) else ""
        raise TypeError(f"{what} must be a number ({unit}), got {type(value).__name__} {value!r}{hint}")


def _check_positive(name: str, value, unit: str):
    check_number(f"Material parameter {name}", value, unit)
    v = float(value)
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"parameter {name} = {value!r} {unit} is outside the allowed range: it must be finite and > 0")
    if not (1e-100 <= v <= 1e100):   # products and quotients of such numbers leave double precision
        raise ValueError(f"parameter {name} = {value!r} {unit} is outside the range the solver can represent "
                         "(1e-100 to 1e100); are its units mm, N, MPa?")


def deformation_gradient(u) -> ngs.CoefficientFunction:
    """F = I + grad u (d x d) of a displacement field u (mm), dimensionless."""
    d = u.dim
    return ngs.Id(d) + ngs.Grad(u)


def full_deformation_gradient(F) -> ngs.CoefficientFunction:
    """3 x 3 deformation gradient: F itself in 3D; in 2D plane strain, F with F33 = 1 appended."""
    if F.dims[0] == 3:
        return F
    return ngs.CF((F[0, 0], F[0, 1], 0, F[1, 0], F[1, 1], 0, 0, 0, 1), dims=(3, 3))


def _J_and_normF2(F):
    """J = det F and ||F||^2 = tr(F^T F) of the 3D-consistent deformation gradient."""
    d = F.dims[0]
    J = ngs.Det(F)
    normF2 = ngs.InnerProduct(F, F) + (1.0 if d == 2 else 0.0)  # plane strain: F33 = 1
    return J, normF2


def psi_vol(F, K) -> ngs.CoefficientFunction:
    """Volumetric energy density Psi_vol = K/2 (ln J)^2 (Eq. 2), MPa.

    F: deformation gradient (2 x 2 for plane strain, 3 x 3 in 3D); K: bulk modulus, MPa.
    """
    J, _ = _J_and_normF2(F)
    return K / 2 * ngs.log(J) ** 2


def psi_dev(F, G) -> ngs.CoefficientFunction:
    """Isochoric energy density Psi_dev = G/2 (J^(-2/3) ||F||^2 - 3) (Eq. 2), MPa.

    In 2D plane strain ||F||^2 = tr(F^T F) + 1 (F33 = 1). G: shear modulus, MPa.
    """
    J, normF2 = _J_and_normF2(F)
    return G / 2 * (J ** (-2.0 / 3.0) * normF2 - 3)


def psi_bar(F, K, G) -> ngs.CoefficientFunction:
    """Undegraded Neo-Hookean energy density Psi_bar = Psi_vol + Psi_dev (Eq. 2), MPa."""
    return psi_vol(F, K) + psi_dev(F, G)


def psi_plus(F, K, G) -> ngs.CoefficientFunction:
    """Tensile part that drives the crack (Eq. 6), MPa: Psi_vol + Psi_dev if J >= 1, else Psi_dev."""
    J, _ = _J_and_normF2(F)
    return ngs.IfPos(J - 1, psi_vol(F, K), 0) + psi_dev(F, G)


def gamma_interpolation(rho, gamma0: float):
    """Stiffness interpolation gamma(rho) = gamma0 + (1 - gamma0) rho (Eq. 17), dimensionless.

    rho is the pseudo-density (1 solid, 0 void), a CoefficientFunction or a number; gamma0 in (0, 1).
    """
    return gamma0 + (1.0 - gamma0) * rho


def gc_interpolation(rho, a: float = 10.0, b: float = 100.0):
    """Fracture toughness factor Gc(rho)/Gc0 = a / (1 + exp(b rho)) + rho (Eq. 18), dimensionless.

    Tends to a/2 in the void (rho = 0) and to 1 (+ a/(1+e^b)) in the solid: the void is made too tough to
    crack. Works on numbers (numpy) and on NGSolve CoefficientFunctions.
    """
    if isinstance(rho, ngs.CoefficientFunction):
        return a / (1 + ngs.exp(b * rho)) + rho
    import numpy as np

    rho = np.asarray(rho, dtype=float)
    return a / (1 + np.exp(np.minimum(b * rho, 700.0))) + rho   # exp(700) ~ 1e304: no overflow warning
