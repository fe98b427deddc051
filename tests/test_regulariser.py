"""The Hessian regulariser of Eq. 3 on known fields."""
import numpy as np
import ngsolve as ngs
import pytest
from netgen.csg import unit_cube
from netgen.geom2d import unit_square

import ngtmc
from ngtmc.model.regularisation import hessian, laplacian, phi_bar, regularisation_stiffness


@pytest.fixture(scope="module")
def mesh():
    m = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    return m


def test_hessian_operator_layout_and_values(mesh):
    """u = (a x^2, b x y): row 0 = (2a, 0, 0, 0), row 1 = (0, b, b, 0) (columns d11, d12, d21, d22)."""
    a, b = 0.3, -0.7
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=2))
    u.Set(ngs.CF((a * ngs.x**2, b * ngs.x * ngs.y)))
    H = np.array(hessian(u)(mesh(0.37, 0.61))).reshape(2, 4)
    np.testing.assert_allclose(H, [[2 * a, 0, 0, 0], [0, b, b, 0]], atol=1e-10)
    np.testing.assert_allclose(laplacian(u)(mesh(0.2, 0.2)), [2 * a, 0.0], atol=1e-10)


def test_quadratic_field_energy_by_hand(mesh):
    """Hu:Hu = 4a^2 + 2b^2, |Lu|^2 = 4a^2, so Phi = k_r/2 (4a^2 + 2b^2 - 2a^2) = k_r (a^2 + b^2) in 2D."""
    a, b, k_r = 0.3, -0.7, 2.5
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=2))
    u.Set(ngs.CF((a * ngs.x**2, b * ngs.x * ngs.y)))
    assert phi_bar(u, k_r)(mesh(0.4, 0.4)) == pytest.approx(k_r * (a**2 + b**2), rel=1e-9)
    assert ngs.Integrate(phi_bar(u, k_r, indicator=0.5), mesh) == pytest.approx(0.5 * k_r * (a**2 + b**2), rel=1e-9)


def test_pure_laplacian_field_is_not_penalised_beyond_its_deviator(mesh):
    """u = (x^2 + y^2, 0): Hu:Hu = 8, |Lu|^2 = 16, Phi = k_r/2 (8 - 8) = 0: uniform 'bulging' is free."""
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=2))
    u.Set(ngs.CF((ngs.x**2 + ngs.y**2, 0)))
    assert abs(phi_bar(u, 1.0)(mesh(0.3, 0.3))) < 1e-10


def test_zero_on_linear_and_rigid_fields(mesh):
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=2))
    c, s = np.cos(0.4), np.sin(0.4)
    u.Set(ngs.CF(((c - 1) * ngs.x - s * ngs.y + 0.3 + 0.2 * ngs.y, s * ngs.x + (c - 1) * ngs.y - 0.1 * ngs.x)))
    assert abs(ngs.Integrate(phi_bar(u, 10.0), mesh)) < 1e-16


def test_three_dimensional_hessian():
    mesh = ngs.Mesh(unit_cube.GenerateMesh(maxh=0.6))
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=2))
    u.Set(ngs.CF((ngs.x * ngs.z, 0, 0)))
    # Hu:Hu = 2 (d13 = d31 = 1), Lu = 0: Phi = k_r/2 * 2
    assert phi_bar(u, 3.0)(mesh(0.3, 0.3, 0.3)) == pytest.approx(3.0, rel=1e-9)


def test_exp_damping_is_the_energy_variant():
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=2))
    u.Set(ngs.CF((0.1 * ngs.x**2, 0)))
    p = mesh(0.5, 0.5)
    J = 1 + 0.2 * 0.5
    assert phi_bar(u, 1.0, damping="exp")(p) == pytest.approx(np.exp(-5 * J) * phi_bar(u, 1.0)(p), rel=1e-12)
    with pytest.raises(ValueError, match="damping"):
        phi_bar(u, 1.0, damping="weak")


def test_stiffness_scaling():
    assert regularisation_stiffness(1e-6, 8.0, 17333.0) == pytest.approx(1e-6 * 64 * 17333.0)


def test_constant_regulariser_tangent_is_added_not_reassembled():
    """The regulariser energy is quadratic in u, so the solver assembles its tangent once and adds
    it; residual, energy and tangent equal those of one form holding every term."""
    import dataclasses
    from scenes import two_blocks
    s = ngtmc.Solver(dataclasses.replace(two_blocks(), variable_order=False))
    assert type(s.a_u).__name__ == "QuadraticPlus"
    ref = ngs.BilinearForm(s.fes_u, symmetric=True)
    uT = s.fes_u.TrialFunction()
    for name, dens, reg in s.energy_terms(uT):
        ref += ngs.Variation(dens * s.energy_measure(name, reg))
    rng = np.random.default_rng(1)
    s.u.vec.FV().NumPy()[:] = 1e-3 * rng.standard_normal(s.fes_u.ndof)
    r1, r2 = s.u.vec.CreateVector(), s.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, r1)
    ref.Apply(s.u.vec, r2)
    np.testing.assert_allclose(r1.FV().NumPy(), r2.FV().NumPy(), rtol=0, atol=1e-12 * np.abs(r2.FV().NumPy()).max())
    assert s.a_u.Energy(s.u.vec) == pytest.approx(ref.Energy(s.u.vec), rel=1e-12)
    for _ in range(2):  # the constant part is added after every assembly, not accumulated
        s.a_u.AssembleLinearization(s.u.vec)
    ref.AssembleLinearization(s.u.vec)
    v = s.u.vec.CreateVector()
    v.FV().NumPy()[:] = rng.standard_normal(s.fes_u.ndof)
    k1, k2 = v.CreateVector(), v.CreateVector()
    k1.data = s.a_u.mat * v
    k2.data = ref.mat * v
    np.testing.assert_allclose(k1.FV().NumPy(), k2.FV().NumPy(), rtol=0, atol=1e-10 * np.abs(k2.FV().NumPy()).max())


def test_constant_regulariser_tangent_follows_the_design():
    """The constant tangent depends on the density (indicator 1 - rho) and on K0 (E, nu): a change
    of either between two solves (an optimisation step, a finite-difference check) re-assembles it."""
    from scenes import two_blocks
    s = ngtmc.Solver(two_blocks())
    s.u.Set(ngs.CF((0.0, 0.05 * (ngs.y - 0.4) ** 2)))
    r0, r1 = s.u.vec.CreateVector(), s.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, r0)
    s.rho.vec.FV().NumPy()[:] *= 0.5  # void rho 0 stays 0, solids go to 0.5: indicator changes there
    s.rho.vec.FV().NumPy()[:] += 0.25
    for par in s.material_parameters.values():
        par["E"].Set(2 * par["E"].Get())
    s.a_u.Apply(s.u.vec, r1)
    ref = ngs.BilinearForm(s.fes_u, symmetric=True)
    for name, dens, reg in s.energy_terms(s.fes_u.TrialFunction()):
        ref += ngs.Variation(dens * s.energy_measure(name, reg))
    r2 = s.u.vec.CreateVector()
    ref.Apply(s.u.vec, r2)
    assert np.linalg.norm(r1.FV().NumPy() - r0.FV().NumPy()) > 0.1 * np.linalg.norm(r0.FV().NumPy())
    np.testing.assert_allclose(r1.FV().NumPy(), r2.FV().NumPy(), rtol=0, atol=1e-12 * np.abs(r2.FV().NumPy()).max())
