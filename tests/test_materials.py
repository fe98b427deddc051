"""Energy densities against hand calculations, the tension/compression split, the interpolation."""
import math

import numpy as np
import ngsolve as ngs
import pytest
from netgen.csg import unit_cube
from netgen.geom2d import unit_square

from ngtmc import Material
from ngtmc.model.materials import gamma_interpolation, gc_interpolation, psi_bar, psi_dev, psi_plus, psi_vol


@pytest.fixture(scope="module")
def mesh2():
    return ngs.Mesh(unit_square.GenerateMesh(maxh=0.5))


@pytest.fixture(scope="module")
def mesh3():
    return ngs.Mesh(unit_cube.GenerateMesh(maxh=0.6))


def hand_energy(F3, K, G):
    """Psi_vol, Psi_dev of Eq. 2 for a 3x3 deformation gradient, by hand with numpy."""
    J = np.linalg.det(F3)
    vol = K / 2 * math.log(J) ** 2
    dev = G / 2 * (J ** (-2 / 3) * np.sum(F3 * F3) - 3)
    return J, vol, dev


def homogeneous(mesh, F):
    """GridFunction u = (F - I) x, exact in any order."""
    d = mesh.dim
    fes = ngs.VectorH1(mesh, order=1)
    u = ngs.GridFunction(fes)
    X = (ngs.x, ngs.y, ngs.z)[:d]
    u.Set(ngs.CF(tuple(sum((F[i][j] - (i == j)) * X[j] for j in range(d)) for i in range(d))))
    return u


K, G = 1234.5, 456.7


@pytest.mark.parametrize("F", [[[1.1, 0.2], [0.05, 0.95]], [[0.7, -0.1], [0.3, 0.8]], [[1.0, 0.0], [0.0, 1.0]]])
def test_energy_2d_plane_strain_matches_hand_calculation(mesh2, F):
    u = homogeneous(mesh2, F)
    Fcf = ngs.Id(2) + ngs.Grad(u)
    F3 = np.eye(3)
    F3[:2, :2] = F
    J, vol, dev = hand_energy(F3, K, G)
    p = mesh2(0.3, 0.4)
    assert psi_vol(Fcf, K)(p) == pytest.approx(vol, rel=1e-12, abs=1e-12)
    assert psi_dev(Fcf, G)(p) == pytest.approx(dev, rel=1e-12, abs=1e-12)
    assert psi_bar(Fcf, K, G)(p) == pytest.approx(vol + dev, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("F", [[[1.1, 0.2, 0.0], [0.05, 0.95, 0.1], [0.0, -0.1, 1.2]], [[0.8, 0, 0], [0, 0.9, 0], [0, 0, 0.95]]])
def test_energy_3d_matches_hand_calculation(mesh3, F):
    u = homogeneous(mesh3, F)
    Fcf = ngs.Id(3) + ngs.Grad(u)
    J, vol, dev = hand_energy(np.array(F), K, G)
    p = mesh3(0.3, 0.4, 0.5)
    assert psi_vol(Fcf, K)(p) == pytest.approx(vol, rel=1e-12)
    assert psi_dev(Fcf, G)(p) == pytest.approx(dev, rel=1e-12)


def test_undeformed_and_rotated_states_store_no_energy(mesh2):
    c, s = math.cos(0.7), math.sin(0.7)
    for F in ([[1, 0], [0, 1]], [[c, -s], [s, c]]):
        u = homogeneous(mesh2, F)
        Fcf = ngs.Id(2) + ngs.Grad(u)
        assert abs(psi_bar(Fcf, K, G)(mesh2(0.2, 0.7))) < 1e-10


def test_split_switches_at_J_equal_one(mesh2):
    """Psi_plus = Psi_vol + Psi_dev for J >= 1, Psi_dev only for J < 1 (Eq. 6)."""
    p = mesh2(0.5, 0.5)
    for stretch in (1.05, 1.0001, 0.9999, 0.95):
        F = [[stretch, 0.1], [0.0, 1.0]]
        u = homogeneous(mesh2, F)
        Fcf = ngs.Id(2) + ngs.Grad(u)
        expected = psi_vol(Fcf, K)(p) + psi_dev(Fcf, G)(p) if stretch >= 1 else psi_dev(Fcf, G)(p)
        assert psi_plus(Fcf, K, G)(p) == pytest.approx(expected, rel=1e-12)
        if stretch < 1:
            assert psi_plus(Fcf, K, G)(p) < psi_bar(Fcf, K, G)(p)


def test_interpolation_limits():
    g0 = 1e-5
    assert gamma_interpolation(1.0, g0) == pytest.approx(1.0)
    assert gamma_interpolation(0.0, g0) == pytest.approx(g0)
    assert gamma_interpolation(0.5, g0) == pytest.approx(g0 + 0.5 * (1 - g0))
    # Gc(rho)/Gc0 -> a/2 in the void and -> 1 in the solid (Eq. 18)
    assert gc_interpolation(0.0, a=10, b=100) == pytest.approx(5.0)
    assert gc_interpolation(1.0, a=10, b=100) == pytest.approx(1.0, abs=1e-40)
    assert gc_interpolation(0.0, a=4, b=50) == pytest.approx(2.0)
    # monotone drop from a/2 towards rho in between
    rho = np.linspace(0, 1, 101)
    v = gc_interpolation(rho)
    assert v[0] > v[5] > v[10]
    assert np.all(v >= rho)


def test_interpolation_as_coefficient_functions_matches_numpy(mesh2):
    for r in (0.0, 0.03, 0.2, 1.0):
        assert gc_interpolation(ngs.CF(r), 10, 100)(mesh2(0.1, 0.1)) == pytest.approx(float(gc_interpolation(r, 10, 100)))


def test_material_moduli():
    m = Material(E=20.8e3, nu=0.3)
    assert m.K0 == pytest.approx(20.8e3 / (3 * 0.4))
    assert m.G0 == pytest.approx(20.8e3 / 2.6)
