"""Energy splits (ngtmc.model.splits) against hand calculations, and their selection per Scene.

Hand states (plane strain, eps_33 = 0; K, G bulk and shear moduli, lambda = K - 2G/3,
M = K + 4G/3): hydrostatic eps = diag(e, e), uniaxial strain eps = diag(e, 0), pure shear
eps_12 = g. The finite-strain splits use F = (1 + e) I, F = diag(1 + e, 1) and the symmetric
F = I + g (e_1 e_2 + e_2 e_1)."""
import math

import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

import ngtmc
from ngtmc.model import splits
from ngtmc.model.materials import psi_bar, psi_plus
from scenes import tension_bar

K, G = 1234.5, 456.7
LAM, M = K - 2 * G / 3, K + 4 * G / 3


@pytest.fixture(scope="module")
def mesh():
    return ngs.Mesh(unit_square.GenerateMesh(maxh=0.5))


def _values(mesh, name, F):
    """(Psi_plus, Psi_minus) of split ``name`` at a homogeneous 2 x 2 deformation gradient F."""
    Fcf = ngs.CF(tuple(float(v) for v in np.ravel(F)), dims=(2, 2))
    plus, minus = splits.split_energy(name, Fcf, K, G)
    p = mesh(0.3, 0.4)
    return plus(p), minus(p)


def _neo_hooke(F):
    F3 = np.eye(3)
    F3[:2, :2] = F
    J = np.linalg.det(F3)
    return K / 2 * math.log(J) ** 2, G / 2 * (J ** (-2 / 3) * np.sum(F3 * F3) - 3), J


e, g = 0.01, 0.01
#: (split, F, Psi_plus by hand, Psi_minus by hand); small-strain splits: exact for these F
HAND = [
    # Amor et al. 2009 on the small strain: tr eps, eps_D : eps_D = eps : eps - tr^2 / 3
    ("vol-dev-small", np.diag([1 + e, 1 + e]), 2 * K * e**2 + 2 / 3 * G * e**2, 0.0),
    ("vol-dev-small", np.diag([1 - e, 1 - e]), 2 / 3 * G * e**2, 2 * K * e**2),
    ("vol-dev-small", np.diag([1 + e, 1.0]), M / 2 * e**2, 0.0),
    ("vol-dev-small", np.diag([1 - e, 1.0]), 2 / 3 * G * e**2, K / 2 * e**2),
    ("vol-dev-small", np.array([[1, g], [g, 1]]), 2 * G * g**2, 0.0),
    # Miehe et al. 2010: principal strains (e, e), (e, 0), (g, -g)
    ("spectral", np.diag([1 + e, 1 + e]), 2 * LAM * e**2 + 2 * G * e**2, 0.0),
    ("spectral", np.diag([1 - e, 1 - e]), 0.0, 2 * LAM * e**2 + 2 * G * e**2),
    ("spectral", np.diag([1 + e, 1.0]), M / 2 * e**2, 0.0),
    ("spectral", np.diag([1 - e, 1.0]), 0.0, M / 2 * e**2),
    ("spectral", np.array([[1, g], [g, 1]]), G * g**2, G * g**2),
    # Hencky strain: hydrostatic E = ln(1 + e) diag(1, 1, 0), E_D : E_D = 2/3 ln(1 + e)^2;
    # uniaxial E = ln(1 + e) diag(1, 0, 0), E_D : E_D = 2/3 ln(1 + e)^2
    ("vol-dev-log", np.diag([1 + e, 1 + e]), 2 * K * math.log(1 + e) ** 2 + 2 / 3 * G * math.log(1 + e) ** 2, 0.0),
    ("vol-dev-log", np.diag([1 - e, 1 - e]), 2 / 3 * G * math.log(1 - e) ** 2, 2 * K * math.log(1 - e) ** 2),
    ("vol-dev-log", np.diag([1 + e, 1.0]), K / 2 * math.log(1 + e) ** 2 + 2 / 3 * G * math.log(1 + e) ** 2, 0.0),
    ("vol-dev-log", np.diag([1 - e, 1.0]), 2 / 3 * G * math.log(1 - e) ** 2, K / 2 * math.log(1 - e) ** 2),
]


@pytest.mark.parametrize("name,F,plus,minus", HAND, ids=[f"{h[0]}-{i}" for i, h in enumerate(HAND)])
def test_split_matches_hand_calculation(mesh, name, F, plus, minus):
    p, m = _values(mesh, name, F)
    assert p == pytest.approx(plus, rel=1e-12, abs=1e-14)
    assert m == pytest.approx(minus, rel=1e-12, abs=1e-14)


def test_hencky_pure_shear_by_eigenvalues(mesh):
    """F = V symmetric with eigenvalues 1 +- g: E = diag(ln(1 + g), ln(1 - g), 0) in its axes."""
    for gg in (0.01, 0.3, 1e-5):
        F = np.array([[1, gg], [gg, 1]])
        a, b = math.log(1 + gg), math.log(1 - gg)
        tr = a + b
        dev2 = a * a + b * b - tr * tr / 3
        p, m = _values(mesh, "vol-dev-log", F)
        assert tr < 0
        assert p == pytest.approx(G * dev2, rel=1e-10)
        assert m == pytest.approx(K / 2 * tr**2, rel=1e-10)


def _reference(name, F):
    """Psi_plus, Psi_minus and the split's total energy with numpy (eigenvalues by eigvalsh)."""
    if name in ("vol-dev-J", "none"):
        vol, dev, J = _neo_hooke(F)
        if name == "none":
            return vol + dev, 0.0, vol + dev
        return (vol + dev, 0.0, vol + dev) if J > 1 else (dev, vol, vol + dev)
    if name == "vol-dev-log":
        ev = 0.5 * np.log(np.linalg.eigvalsh(F.T @ F))
    else:
        ev = np.linalg.eigvalsh(0.5 * (F + F.T) - np.eye(2))
    tr = ev.sum()
    dev2 = np.sum(ev**2) - tr**2 / 3
    if name == "spectral":
        pl = LAM / 2 * max(tr, 0) ** 2 + G * np.sum(np.maximum(ev, 0) ** 2)
        mi = LAM / 2 * min(tr, 0) ** 2 + G * np.sum(np.minimum(ev, 0) ** 2)
        return pl, mi, LAM / 2 * tr**2 + G * np.sum(ev**2)
    return K / 2 * max(tr, 0) ** 2 + G * dev2, K / 2 * min(tr, 0) ** 2, K / 2 * tr**2 + G * dev2


@pytest.mark.parametrize("name", splits.SPLITS)
def test_parts_sum_to_the_energy_on_random_states(mesh, name):
    """Psi_plus + Psi_minus = Psi (the split's energy), both >= 0, and the numpy reference on random
    deformation gradients (finite strains up to 20 %)."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        F = np.eye(2) + 0.2 * rng.uniform(-1, 1, (2, 2))
        p, m = _values(mesh, name, F)
        rp, rm, total = _reference(name, F)
        assert p >= 0 and m >= 0
        assert p == pytest.approx(rp, rel=1e-10, abs=1e-12)
        assert m == pytest.approx(rm, rel=1e-10, abs=1e-12)
        assert p + m == pytest.approx(total, rel=1e-10, abs=1e-12)


def test_default_split_is_the_papers_expression(mesh):
    F = ngs.CF((1.02, 0.1, -0.05, 0.97), dims=(2, 2))
    plus, minus = splits.split_vol_dev_J(F, K, G)
    p = mesh(0.5, 0.5)
    assert plus(p) == psi_plus(F, K, G)(p)
    assert plus(p) + minus(p) == pytest.approx(psi_bar(F, K, G)(p), rel=1e-14)
    assert splits.split_none(F, K, G)[0](p) == psi_bar(F, K, G)(p)


def test_scene_validates_split_and_formulation_names():
    with pytest.raises(ValueError, match=r"Scene.split = 'miehe' is not one of 'vol-dev-J', 'vol-dev-small', "
                                         r"'vol-dev-log', 'spectral', 'none'"):
        tension_bar(split="miehe")
    with pytest.raises(ValueError, match=r"Scene.formulation = 'isotropic' is not one of 'hybrid', 'anisotropic'"):
        tension_bar(formulation="isotropic")
    sc = tension_bar()
    assert (sc.split, sc.formulation) == ("vol-dev-J", "hybrid")


def test_two_dimensional_splits_are_refused_in_3d():
    from netgen.occ import X, Box, OCCGeometry, Pnt
    box = Box(Pnt(0, 0, 0), Pnt(1, 1, 1))
    box.faces.Min(X).name, box.faces.Max(X).name = "left", "right"
    mesh = ngs.Mesh(OCCGeometry(box).GenerateMesh(maxh=1.0))
    sc = ngtmc.Scene(mesh, {".*": ngtmc.Material(1000.0, 0.3)}, [ngtmc.Support("left", x=True, y=True, z=True)],
                     ngtmc.DisplacementLoad("right", "x"), split="spectral")
    with pytest.raises(ValueError, match="2D plane strain only; in 3D use one of 'vol-dev-J', 'vol-dev-small', 'none'"):
        sc.check()


def test_solver_default_unchanged_and_anisotropic_undamaged_energy():
    """The default pair builds the energy terms and the history of before (same names, same
    expressions); with alpha = 0 the anisotropic energy of the Neo-Hookean splits is Psi_bar."""
    s0 = ngtmc.Solver(tension_bar(maxh=0.2))
    assert [t[0] for t in s0.energy_terms(s0.u)] == ["elastic_vol", "elastic_dev"]
    s0.u.Set(ngs.CF((0.01 * ngs.x + 0.003 * ngs.y, -0.002 * ngs.y)))
    for split in ("vol-dev-J", "none"):
        s1 = ngtmc.Solver(tension_bar(maxh=0.2, split=split, formulation="anisotropic"))
        assert [t[0] for t in s1.energy_terms(s1.u)] == ["elastic_plus", "elastic_minus"]
        s1.u.vec.data = s0.u.vec
        assert s1.energies()["elastic_energy"] == pytest.approx(s0.energies()["elastic_energy"], rel=1e-12)
    s2 = ngtmc.Solver(tension_bar(maxh=0.2, split="vol-dev-J", formulation="hybrid"))
    s2.u.vec.data = s0.u.vec
    np.testing.assert_array_equal(s2.psi_plus_values(), s0.psi_plus_values())
