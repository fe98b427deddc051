"""Finite-difference checks of residual (first derivative) and tangent (second derivative) of every
energy term, on a random displacement field."""
import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

from ngtmc.model import regularisation as creg
from ngtmc.model import fracture
from ngtmc.model import psi_dev, psi_vol


@pytest.fixture(scope="module")
def mesh():
    return ngs.Mesh(unit_square.GenerateMesh(maxh=0.25))


def _random_state(fes, scale, seed):
    rng = np.random.default_rng(seed)
    gf = ngs.GridFunction(fes)
    gf.vec.FV().NumPy()[:] = scale * rng.standard_normal(fes.ndof)
    return gf


def fd_check(fes, density_of, u_state, seed=1, eps=1e-6):
    """Return (residual rel. error, tangent rel. error) for the energy int density_of(u) dx."""
    a = ngs.BilinearForm(fes, symmetric=True)
    a += ngs.Variation(density_of(fes.TrialFunction()) * ngs.dx)
    v = _random_state(fes, 1.0, seed + 10).vec
    u = u_state.vec
    r = u.CreateVector()
    a.Apply(u, r)
    up, um = u.CreateVector(), u.CreateVector()
    up.data = u + eps * v
    um.data = u - eps * v
    dE = (a.Energy(up) - a.Energy(um)) / (2 * eps)
    err_r = abs(dE - ngs.InnerProduct(r, v)) / max(abs(dE), 1e-30)
    rp, rm = u.CreateVector(), u.CreateVector()
    a.Apply(up, rp)
    a.Apply(um, rm)
    a.AssembleLinearization(u)
    Kv = u.CreateVector()
    Kv.data = a.mat * v
    fd = (rp.FV().NumPy() - rm.FV().NumPy()) / (2 * eps)
    err_K = np.linalg.norm(fd - Kv.FV().NumPy()) / np.linalg.norm(Kv.FV().NumPy())
    return err_r, err_K


@pytest.mark.parametrize("order", [1, 2])
def test_volumetric_and_deviatoric_terms(mesh, order):
    fes = ngs.VectorH1(mesh, order=order)
    u = _random_state(fes, 0.02, 3)
    for term in (lambda w: psi_vol(ngs.Id(2) + ngs.Grad(w), 1000.0), lambda w: psi_dev(ngs.Id(2) + ngs.Grad(w), 300.0)):
        err_r, err_K = fd_check(fes, term, u)
        assert err_r < 1e-7
        assert err_K < 1e-6


def test_degraded_term_with_fixed_phase_field(mesh):
    fes = ngs.VectorH1(mesh, order=1)
    alpha = ngs.GridFunction(ngs.H1(mesh, order=1))
    alpha.vec.FV().NumPy()[:] = np.random.default_rng(5).uniform(0, 1, alpha.space.ndof)
    u = _random_state(fes, 0.02, 4)
    g = fracture.degradation(alpha, 1e-6)
    err_r, err_K = fd_check(fes, lambda w: g * (psi_vol(ngs.Id(2) + ngs.Grad(w), 1e3) + psi_dev(ngs.Id(2) + ngs.Grad(w), 300.0)), u)
    assert err_r < 1e-7 and err_K < 1e-6


@pytest.mark.parametrize("damping", ["none", "exp"])
def test_regularisation_term(mesh, damping):
    fes = ngs.VectorH1(mesh, order=2)
    u = _random_state(fes, 0.02, 6)
    err_r, err_K = fd_check(fes, lambda w: creg.phi_bar(w, 2.0, indicator=0.7, damping=damping), u)
    assert err_r < 1e-7 and err_K < 1e-6


def test_phase_field_equation_is_the_derivative_of_its_energy(mesh):
    """The linear alpha system (Eq. 16 with H fixed) is the gradient of
    int (1 - alpha)^2 H + Gc/c_w (alpha^2/l0 + l0 |grad alpha|^2)."""
    from ngsolve.comp import IntegrationRuleSpace
    irs = IntegrationRuleSpace(mesh, order=2)
    dxH = ngs.dx(intrules=irs.GetIntegrationRules())
    H = ngs.GridFunction(irs)
    H.vec.FV().NumPy()[:] = np.random.default_rng(7).uniform(0, 3, irs.ndof)
    fes = ngs.H1(mesh, order=1)
    a_, b_ = fes.TnT()
    Gc, l0 = 0.54, 0.1
    bil, lin = fracture.alpha_driving_form(a_, b_, H, Gc, l0, dxH, ngs.dx)
    A = ngs.BilinearForm(bil).Assemble()
    f = ngs.LinearForm(lin).Assemble()
    E = ngs.BilinearForm(fes)
    w = fes.TrialFunction()
    E += ngs.Variation(fracture.degradation(w) * H * dxH + Gc * fracture.crack_surface_density(w, l0) * ngs.dx)
    alpha = _random_state(fes, 0.3, 8)
    r = alpha.vec.CreateVector()
    E.Apply(alpha.vec, r)
    lin_res = alpha.vec.CreateVector()
    lin_res.data = A.mat * alpha.vec - f.vec
    assert np.linalg.norm(r.FV().NumPy() - lin_res.FV().NumPy()) < 1e-10 * np.linalg.norm(r.FV().NumPy())


# ---------------------------------------------------------------------- energy splits (ngtmc.model.splits)
from ngtmc.model import splits as _splits  # noqa: E402


@pytest.mark.parametrize("name", _splits.SPLITS)
@pytest.mark.parametrize("part", [0, 1], ids=["plus", "minus"])
def test_split_parts_on_random_states(mesh, name, part):
    """Residual and tangent of int Psi_plus and int Psi_minus (what the anisotropic formulation puts
    into Newton) on a random field: at its quadrature points the principal strains, tr eps and
    ln J take both signs, so every branch of the splits is crossed."""
    if (name, part) == ("none", 1):
        pytest.skip("Psi_minus of 'none' is identically zero")
    fes = ngs.VectorH1(mesh, order=2)
    u = _random_state(fes, 0.02, 13)
    err_r, err_K = fd_check(fes, lambda w: _splits.split_energy(name, ngs.Id(2) + ngs.Grad(w), 1000.0, 300.0)[part], u)
    assert err_r < 1e-7
    assert err_K < 1e-5


@pytest.mark.parametrize("name", ["spectral", "vol-dev-log"])
@pytest.mark.parametrize("stretch", [0.0, 0.01, -0.01])
def test_split_derivatives_at_equal_eigenvalues(mesh, name, stretch):
    """u = stretch (x, y): equal principal strains at every point (stretch = 0: the undeformed
    state Newton starts from). Residual and tangent stay finite; those of Psi_plus + Psi_minus
    match finite differences (each part alone has a kink in its second derivative at u = 0)."""
    fes = ngs.VectorH1(mesh, order=1)
    u = ngs.GridFunction(fes)
    u.Set(ngs.CF((stretch * ngs.x, stretch * ngs.y)))

    def total(w):
        plus, minus = _splits.split_energy(name, ngs.Id(2) + ngs.Grad(w), 1000.0, 300.0)
        return plus + minus

    err_r, err_K = fd_check(fes, total, u, eps=1e-7)
    assert np.isfinite(err_r) and np.isfinite(err_K)
    assert err_r < 1e-6 or stretch == 0.0  # at u = 0 the energy and its gradient vanish
    assert err_K < 1e-5
    for part in (0, 1):
        a = ngs.BilinearForm(fes, symmetric=True)
        a += ngs.Variation(_splits.split_energy(name, ngs.Id(2) + ngs.Grad(fes.TrialFunction()), 1000.0, 300.0)[part] * ngs.dx)
        a.AssembleLinearization(u.vec)
        r = u.vec.CreateVector()
        a.Apply(u.vec, r)
        assert np.all(np.isfinite(r.FV().NumPy()))
        assert np.all(np.isfinite(a.mat.AsVector().FV().NumPy()))


@pytest.mark.parametrize("name", ["vol-dev-J", "spectral"])
def test_anisotropic_degraded_energy_with_fixed_phase_field(mesh, name):
    """g(alpha) Psi_plus + Psi_minus, the fracture regions' energy of the anisotropic formulation."""
    fes = ngs.VectorH1(mesh, order=1)
    alpha = ngs.GridFunction(ngs.H1(mesh, order=1))
    alpha.vec.FV().NumPy()[:] = np.random.default_rng(5).uniform(0, 1, alpha.space.ndof)
    u = _random_state(fes, 0.02, 4)
    g = fracture.degradation(alpha, 1e-6)

    def energy(w):
        plus, minus = _splits.split_energy(name, ngs.Id(2) + ngs.Grad(w), 1000.0, 300.0)
        return g * plus + minus

    err_r, err_K = fd_check(fes, energy, u)
    assert err_r < 1e-7 and err_K < 1e-5
