"""Tension/compression splits of the elastic energy and the two ways they enter the model.

A split writes an elastic energy density as Psi = Psi_plus + Psi_minus, Psi_plus the part that
drives the crack (and that damage may degrade), Psi_minus the part that a crack cannot release
(compression). Every split below is one small function ``(F, K, G) -> (Psi_plus, Psi_minus)`` of
NGSolve CoefficientFunctions (MPa), with F the deformation gradient (2 x 2 for plane strain, 3 x 3
in 3D) and K, G the bulk and shear moduli (MPa, times gamma(rho) where the density varies).

Splits (``Scene.split``):

* ``"vol-dev-J"`` (default, the paper's Eq. 6): on the Neo-Hookean energy of Eq. 2,
  Psi_plus = Psi_vol + Psi_dev if J >= 1, else Psi_dev.
* ``"vol-dev-small"``: Amor, Marigo, Maurini 2009 (J. Mech. Phys. Solids 57, 1209), Eq. 13, on
  the small-strain energy Psi = K/2 tr(eps)^2 + G eps_D : eps_D, eps = sym(F) - I:
  Psi_plus = K/2 <tr eps>_+^2 + G eps_D : eps_D, Psi_minus = K/2 <tr eps>_-^2.
* ``"vol-dev-log"``: the same split on the logarithmic (Hencky) strain E = ln V = 1/2 ln C,
  Psi = K/2 (tr E)^2 + G E_D : E_D with tr E = ln J. With the model's Neo-Hookean deviatoric energy
  in place of G E_D : E_D it would be the paper's split itself (ln J >= 0 iff J >= 1); with the
  Hencky deviatoric energy it differs from it at finite shear strain. 2D plane strain only.
* ``"spectral"``: Miehe, Hofacker, Welschinger 2010 (Comput. Methods Appl. Mech. Engrg. 199,
  2765), Eq. 3.12 (also Ambati et al. 2015, Eq. 10), on the small strain:
  Psi_plus = lambda/2 <tr eps>_+^2 + mu sum_i <eps_i>_+^2, eps_i the principal strains, lambda =
  K - 2G/3, mu = G. 2D plane strain only (eps_33 = 0 is a principal strain that stores nothing).
* ``"none"``: Psi_plus = Psi_bar (Eq. 2), Psi_minus = 0: the whole energy drives the crack.

<x>_+ = max(x, 0), <x>_- = min(x, 0). At a tie (a principal strain, tr eps or ln J exactly zero)
the term is counted in Psi_minus, so that the undeformed state has the full elastic tangent in
either part's sum (Newton starts from u = 0).

Formulations (``Scene.formulation``):

* ``"hybrid"`` (default, Ambati, Gerasimov, De Lorenzis 2015, Comput. Mech. 55, 383, Eq. 20; the
  paper's Eqs. 6-7): the displacement equation uses the whole Neo-Hookean energy g(alpha) Psi_bar;
  only the history H_n = max(H_{n-1}, Psi_plus(u_n)) uses the split.
* ``"anisotropic"`` (Miehe et al. 2010, Eq. 3.13; Amor et al. 2009, Eq. 14): the energy of the
  fracture regions is g(alpha) Psi_plus + Psi_minus of the split's own energy, so a crack pushed
  shut carries the compressive part undegraded. For the small-strain splits that energy is
  linear elasticity (not invariant under large rotations; meant for the small strains of fracture
  benchmarks), for ``"vol-dev-log"`` the Hencky energy; for ``"vol-dev-J"`` and ``"none"`` it is
  the model's Neo-Hookean energy. Outside the fracture regions the energy is Eq. 2 unchanged.

Defaults: "vol-dev-J" with "hybrid", the paper's model, so that results reproduce it unchanged.
What the choice changes for a closed crack (``tests/test_crack_closure.py``: a fully broken band
across a bar in uniaxial strain, pushed shut): the compressive stiffness is 2.5e-5 of the intact
one in the hybrid formulation (any split; a closed crack carries load only once its smeared band
is squeezed, like the third medium), 0.948 with an anisotropic vol-dev split (the bulk modulus
carries the load across the band) and 1.000 with the anisotropic spectral split, each within 1 %
of its hand estimate.

Smoothness for Newton: every part is C^1 in F (its second derivative jumps only where a principal
strain, tr eps or ln J changes sign). The closed-form eigenvalues of the 2 x 2 strain use a square
root that appears only in branches where the two eigenvalues differ by a finite amount; at equal
eigenvalues the branch taken is a polynomial in eps, so the symbolic derivatives stay finite.

Units: energy densities in MPa (N mm / mm^3).
"""
from __future__ import annotations

import ngsolve as ngs

from ngtmc.model.materials import _J_and_normF2, psi_bar, psi_plus, psi_vol

__all__ = [
    "SPLITS",
    "FORMULATIONS",
    "DEFAULT_SPLIT",
    "DEFAULT_FORMULATION",
    "SPLITS_2D_ONLY",
    "check_split",
    "small_strain",
    "split_vol_dev_J",
    "split_vol_dev_small",
    "split_vol_dev_log",
    "split_spectral",
    "split_none",
    "split_energy",
]

#: Names accepted by ``Scene.split``; the first is the default.
SPLITS = ("vol-dev-J", "vol-dev-small", "vol-dev-log", "spectral", "none")
#: Names accepted by ``Scene.formulation``; the first is the default.
FORMULATIONS = ("hybrid", "anisotropic")
DEFAULT_SPLIT = SPLITS[0]
DEFAULT_FORMULATION = FORMULATIONS[0]
#: Splits with closed-form principal values of 2 x 2 tensors only (plane strain).
SPLITS_2D_ONLY = ("vol-dev-log", "spectral")


def check_split(split: str, formulation: str, dim: int | None = None):
    """Raise ValueError unless ``split`` is one of :data:`SPLITS` and ``formulation`` one of
    :data:`FORMULATIONS` (and, with ``dim`` = 3, the split exists in 3D)."""
    if split not in SPLITS:
        raise ValueError(f"Scene.split = {split!r} is not one of {', '.join(map(repr, SPLITS))}")
    if formulation not in FORMULATIONS:
        raise ValueError(f"Scene.formulation = {formulation!r} is not one of {', '.join(map(repr, FORMULATIONS))}")
    if dim == 3 and split in SPLITS_2D_ONLY:
        allowed = ", ".join(repr(s) for s in SPLITS if s not in SPLITS_2D_ONLY)
        raise ValueError(f"Scene.split = {split!r} is implemented for 2D plane strain only; in 3D use one of {allowed}")


def _pos_sq(x):
    """<x>_+^2 (0 at x = 0)."""
    return ngs.IfPos(x, x * x, 0.0)


def _neg_sq(x):
    """<x>_-^2 (x^2 at x = 0: ties count as compression)."""
    return ngs.IfPos(x, 0.0, x * x)


def small_strain(F) -> ngs.CoefficientFunction:
    """Small strain eps = (F + F^T)/2 - I (d x d), dimensionless; in 2D plane strain eps_33 = 0."""
    d = F.dims[0]
    return 0.5 * (F + F.trans) - ngs.Id(d)


def _small_strain_invariants(F):
    """tr eps and eps_D : eps_D = eps : eps - (tr eps)^2 / 3 (3D-consistent; plane strain eps_33 = 0)."""
    eps = small_strain(F)
    tr = ngs.Trace(eps)
    return tr, ngs.InnerProduct(eps, eps) - tr * tr / 3.0


def split_vol_dev_J(F, K, G):
    """The paper's J-based volumetric-deviatoric split (Ciceri et al. 2026, Eq. 6), MPa.

    Psi_plus = Psi_vol + Psi_dev if J >= 1 else Psi_dev; Psi_minus = Psi_vol if J <= 1 else 0, with
    Psi_vol = K/2 (ln J)^2 and Psi_dev = G/2 (J^(-2/3) ||F||^2 - 3) of Eq. 2. Psi_plus is the very
    expression of :func:`ngtmc.model.materials.psi_plus`. Returns (Psi_plus, Psi_minus)."""
    J, _ = _J_and_normF2(F)
    return psi_plus(F, K, G), ngs.IfPos(J - 1, 0.0, psi_vol(F, K))


def split_vol_dev_small(F, K, G):
    """Amor et al. 2009 volumetric-deviatoric split on the small strain (their Eq. 13), MPa.

    With eps = sym(F) - I, eps_D = eps - tr(eps)/3 I (plane strain: eps_33 = 0):
    Psi_plus = K/2 <tr eps>_+^2 + G eps_D : eps_D, Psi_minus = K/2 <tr eps>_-^2; their sum is the
    linear-elastic energy K/2 (tr eps)^2 + G eps_D : eps_D. Returns (Psi_plus, Psi_minus)."""
    tr, dev2 = _small_strain_invariants(F)
    return K / 2 * _pos_sq(tr) + G * dev2, K / 2 * _neg_sq(tr)


def _atanh_sqrt_squared(s, s0=1e-3):
    """f(s) = artanh(sqrt(s))^2 for s in [0, 1), smooth at s = 0: below s0 its series
    s + 2/3 s^2 + 23/45 s^3 + 44/105 s^4 (relative truncation error < 1e-12 there)."""
    series = s * (1.0 + s * (2.0 / 3.0 + s * (23.0 / 45.0 + s * 44.0 / 105.0)))
    x = ngs.sqrt(ngs.IfPos(s - s0, s, s0))  # the argument stays >= s0 in the unused branch too
    exact = (0.5 * ngs.log((1.0 + x) / (1.0 - x))) ** 2
    return ngs.IfPos(s - s0, exact, series)


def split_vol_dev_log(F, K, G):
    """Amor et al. 2009 volumetric-deviatoric split on the Hencky strain E = 1/2 ln C, MPa (2D
    plane strain only).

    Psi = K/2 (tr E)^2 + G E_D : E_D with tr E = ln J; Psi_plus = K/2 <ln J>_+^2 + G E_D : E_D,
    Psi_minus = K/2 <ln J>_-^2. With c_1,2 = p +- q the eigenvalues of the in-plane C = F^T F
    (p = tr C / 2, q^2 = ((C_11 - C_22)/2)^2 + C_12^2) and E_33 = 0:
    E : E = 1/2 ((ln J)^2 + artanh(q/p)^2), so E_D : E_D = (ln J)^2 / 6 + artanh(q/p)^2 / 2,
    with artanh(q/p)^2 a smooth function of s = q^2/p^2 (series near equal eigenvalues).
    Returns (Psi_plus, Psi_minus)."""
    if F.dims[0] != 2:
        raise ValueError("split 'vol-dev-log' is implemented for 2D plane strain only")
    C = F.trans * F
    p = 0.5 * (C[0, 0] + C[1, 1])
    q2 = (0.5 * (C[0, 0] - C[1, 1])) ** 2 + C[0, 1] ** 2
    lnJ = ngs.log(ngs.Det(F))
    dev2 = lnJ * lnJ / 6.0 + 0.5 * _atanh_sqrt_squared(q2 / (p * p))
    return K / 2 * _pos_sq(lnJ) + G * dev2, K / 2 * _neg_sq(lnJ)


def split_spectral(F, K, G):
    """Miehe et al. 2010 spectral split on the small strain (their Eq. 3.12), MPa (2D plane strain).

    Psi_plus = lambda/2 <tr eps>_+^2 + mu (<eps_1>_+^2 + <eps_2>_+^2),
    Psi_minus = lambda/2 <tr eps>_-^2 + mu (<eps_1>_-^2 + <eps_2>_-^2), lambda = K - 2G/3, mu = G;
    eps_1,2 = m +- r, m = tr eps / 2, r = sqrt(((eps_11 - eps_22)/2)^2 + eps_12^2) (eps_33 = 0 adds
    nothing). Branches: both eigenvalues > 0: sum <eps_i>_+^2 = 2 m^2 + 2 r^2 (a polynomial);
    eps_2 <= 0 < eps_1: (m + r)^2, where r > 0; both <= 0: 0 (and the mirror for Psi_minus).
    Their sum is the linear-elastic energy lambda/2 (tr eps)^2 + mu eps : eps. Returns
    (Psi_plus, Psi_minus)."""
    if F.dims[0] != 2:
        raise ValueError("split 'spectral' is implemented for 2D plane strain only")
    eps = small_strain(F)
    tr = eps[0, 0] + eps[1, 1]
    m = 0.5 * tr
    r2 = (0.5 * (eps[0, 0] - eps[1, 1])) ** 2 + eps[0, 1] ** 2
    r = ngs.sqrt(r2)
    e1, e2 = m + r, m - r
    both = 2.0 * (m * m + r2)
    plus_sq = ngs.IfPos(e2, both, ngs.IfPos(e1, e1 * e1, 0.0))
    minus_sq = ngs.IfPos(e2, 0.0, ngs.IfPos(e1, e2 * e2, both))
    lam = K - 2.0 / 3.0 * G
    return lam / 2 * _pos_sq(tr) + G * plus_sq, lam / 2 * _neg_sq(tr) + G * minus_sq


def split_none(F, K, G):
    """No split: Psi_plus = Psi_bar = Psi_vol + Psi_dev (Eq. 2), Psi_minus = 0, MPa: the whole
    energy drives the crack (Bourdin, Francfort, Marigo 2000). Returns (Psi_plus, Psi_minus)."""
    return psi_bar(F, K, G), ngs.CF(0.0)


_SPLIT_FUNCTIONS = {
    "vol-dev-J": split_vol_dev_J,
    "vol-dev-small": split_vol_dev_small,
    "vol-dev-log": split_vol_dev_log,
    "spectral": split_spectral,
    "none": split_none,
}


def split_energy(split: str, F, K, G):
    """(Psi_plus, Psi_minus) of the split named ``split`` (one of :data:`SPLITS`), MPa."""
    if split not in _SPLIT_FUNCTIONS:
        raise ValueError(f"split = {split!r} is not one of {', '.join(map(repr, SPLITS))}")
    return _SPLIT_FUNCTIONS[split](F, K, G)
