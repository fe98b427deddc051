"""Order 2 only where the regulariser acts ("model only what a scene needs", per element), and the
integration rules that the energy terms own (one rule per term, used by Newton, the energies and
the adjoint alike)."""
import dataclasses

import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from scenes import two_blocks


@pytest.fixture(scope="module")
def solvers():
    scene = dataclasses.replace(two_blocks(), fracture_regions="lower", variable_order=True)
    return ngtmc.Solver(scene), ngtmc.Solver(dataclasses.replace(scene, variable_order=False))


def test_order_two_only_on_the_void_elements_and_their_edges(solvers):
    var, uni = solvers
    mesh = var.mesh
    void_edges = {e.nr for el in mesh.Elements(ngs.VOL) if el.mat == "void" for e in el.edges}
    # VectorH1 order 2 on triangles: one dof per vertex and per (order-2) edge, per component
    assert var.fes_u.ndof == 2 * (mesh.nv + len(void_edges))
    assert uni.fes_u.ndof == 2 * (mesh.nv + mesh.nedge)
    assert var.fes_u.ndof < 0.6 * uni.fes_u.ndof
    # the history lives where the phase field lives: order-1 elements, 3 points per triangle
    assert var.ndof["history_points"] == 3 * mesh.ne
    assert uni.ndof["history_points"] == 6 * mesh.ne


def test_same_energies_for_fields_both_spaces_hold_exactly(solvers):
    """A linear field, and then a field quadratic inside the void (order 2 in both spaces), have
    the same elastic and regularisation energies in both spaces."""
    var, uni = solvers
    for s in (var, uni):
        s.u.Set(ngs.CF((2e-3 * ngs.x + 1e-3 * ngs.y, -3e-3 * ngs.y + 5e-4 * ngs.x)))
    e_var, e_uni = var.energies(), uni.energies()
    assert e_var["elastic_energy"] == pytest.approx(e_uni["elastic_energy"], rel=1e-12)
    assert e_var["regularisation_energy"] == pytest.approx(0.0, abs=1e-15)
    q = ngs.CF((0.0, 0.2 * (ngs.y - 0.4) ** 2))
    for s in (var, uni):
        s.u.Set(q, definedon=s.mesh.Materials("void"))
    assert var.energies()["regularisation_energy"] == pytest.approx(uni.energies()["regularisation_energy"], rel=1e-10)
    assert var.energies()["regularisation_energy"] > 0


def test_energies_use_the_rules_of_the_newton_energy(solvers):
    """energies() integrates every term with the measure the Variation of Newton uses: their sum
    equals a_u.Energy to round-off (thickness 1)."""
    for s in solvers:
        rng = np.random.default_rng(0)
        s.u.vec.FV().NumPy()[:] = 1e-3 * rng.standard_normal(s.fes_u.ndof)
        en = s.energies()
        assert en["elastic_energy"] + en["regularisation_energy"] == pytest.approx(s.a_u.Energy(s.u.vec), rel=1e-12)


def test_each_elastic_term_owns_its_rule(solvers):
    """Order-2 elements (the void): the rule of order 4 (6 points on a triangle; the folding trap
    of NGSOLVE_NOTES.md); order-1 elements: the rule of order 2 (3 points, the history points).
    Checked by integrating monomials: a rule of order k is exact up to degree k."""
    var, uni = solvers
    mesh = var.mesh
    regions = {reg for name, _, reg in var.energy_terms(var.u) if name == "elastic_vol"}
    assert regions == {"lower", "void", "upper"}

    def err(cf, reg, s):
        ours = ngs.Integrate(cf * s.energy_measure("elastic_vol", reg), mesh)
        exact = ngs.Integrate(cf, mesh, definedon=mesh.Materials(reg), order=12)
        return abs(ours - exact) / abs(exact)

    x4, x2 = (ngs.x - 0.3) ** 4, (ngs.x - 0.3) ** 2
    assert err(x4, "void", var) < 1e-12
    assert err(x2, "upper", var) < 1e-12 and err(x4, "upper", var) > 1e-9
    assert err(x2, "lower", var) < 1e-12 and err(x4, "lower", var) > 1e-9
    assert err(x4, "upper", uni) < 1e-12  # order 2 everywhere: 6 points everywhere


def test_real_compile_falls_back_cleanly_without_a_compiler(monkeypatch):
    """compile='real' needs NGSolve's ngscxx and a C++ compiler. Without them the run must not
    fail ('ngscxx: not found'): one RuntimeWarning, then the symbolic compilation, same residual."""
    import sys
    import sysconfig
    from ngtmc.discrete import spaces as discretisation
    monkeypatch.setattr(discretisation, "_REAL_COMPILE_FAILED", [])
    monkeypatch.setattr(sysconfig, "get_path", lambda name: "/nonexistent")
    monkeypatch.setattr(sys, "executable", "/nonexistent/python")
    monkeypatch.setenv("PATH", "/nonexistent")
    scene = two_blocks()
    with pytest.warns(RuntimeWarning, match="compile='real' is not available"):
        s = ngtmc.Solver(scene, compile="real")
    ref = ngtmc.Solver(scene, compile=True)
    for x in (s, ref):
        x.u.Set(ngs.CF((1e-3 * ngs.x * ngs.y, -2e-3 * ngs.y)))
    r, r_ref = s.u.vec.CreateVector(), ref.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, r)
    ref.a_u.Apply(ref.u.vec, r_ref)
    np.testing.assert_allclose(r.FV().NumPy(), r_ref.FV().NumPy(), rtol=1e-12, atol=1e-15)


def test_auto_compile_generates_code_only_for_large_meshes():
    from ngtmc.discrete.solver import AUTO_REAL_COMPILE_ELEMENTS
    s = ngtmc.Solver(two_blocks())
    assert s.mesh.ne < AUTO_REAL_COMPILE_ELEMENTS and s._compile is True
