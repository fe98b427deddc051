"""Reaction forces: residual-dot-indicator against the traction integral, equilibrium, rigid motions."""
import math

import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from ngtmc.model.materials import psi_bar
from scenes import bar_mesh


def compressed_block(order, maxh=0.1, clamped=True):
    """Block 1 x 0.5 pushed down 0.05 mm on top. clamped: bottom and top held in x too
    (non-homogeneous, singular corners); otherwise rollers (homogeneous state)."""
    mesh = bar_mesh(length=1.0, height=0.5, maxh=maxh)
    supports = ([ngtmc.Support("bottom", x=True, y=True)] if clamped
                else [ngtmc.Support("bottom", y=True), ngtmc.Support("left", x=True)])
    scene = ngtmc.Scene(mesh, {"bar": ngtmc.Material(1000.0, 0.3)}, supports=supports,
                        load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=clamped), order=order)
    s = ngtmc.Solver(scene)
    assert s.solve_displacement(0.05).converged
    return s


def traction_force(s, boundary):
    """-int (P n)_y ds on the boundary: force in -y exerted on the device, N."""
    F = (ngs.Id(2) + ngs.Grad(s.u)).MakeVariable()
    P = psi_bar(F, s.K, s.G).Diff(F)
    t = ngs.BoundaryFromVolumeCF(P) * ngs.specialcf.normal(2)
    return -ngs.Integrate(t[1], s.mesh, definedon=s.mesh.Boundaries(boundary), order=6)


@pytest.mark.parametrize("order", [1, 2])
def test_reaction_by_residual_equals_traction_integral_homogeneous(order):
    s = compressed_block(order, clamped=False)
    F = s.reaction()
    assert F > 0
    assert F == pytest.approx(traction_force(s, "top"), rel=1e-8)


def test_traction_integral_converges_to_residual_reaction():
    """With clamped edges the traction has corner singularities: the pointwise traction
    integral converges to the (variationally consistent) residual reaction as h falls, slowly
    (about h^0.25, as a corner singularity allows). Measured with the elastic energy integrated
    at the history points: 5.3e-3, 4.4e-3, 3.8e-3 for h = 0.1, 0.05, 0.025 mm."""
    diffs = []
    for maxh in (0.1, 0.05, 0.025):
        s = compressed_block(2, maxh=maxh)
        diffs.append(abs(traction_force(s, "top") - s.reaction()) / s.reaction())
    assert diffs[0] < 1e-2
    assert diffs[1] < 0.9 * diffs[0] and diffs[2] < 0.9 * diffs[1], diffs


def test_equilibrium_of_opposite_supports():
    s = compressed_block(2)
    e_bottom = ngs.GridFunction(s.fes_u)
    e_bottom.components[1].Set(1.0, definedon=s.mesh.Boundaries("bottom"))
    r = s.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, r)
    assert ngs.InnerProduct(r, e_bottom.vec) == pytest.approx(s.reaction(), rel=1e-9)


def test_trap_summing_boundary_residual_entries_is_wrong_for_order_2():
    """NGSOLVE_NOTES trap: edge dofs of order >= 2 are no partition of unity."""
    s = compressed_block(2)
    r = s.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, r)
    # y-component dofs of the top boundary: indicator with ALL boundary dofs set to one
    naive = ngs.GridFunction(s.fes_u)
    for el in s.mesh.Boundaries("top").Elements():
        for d in s.fes_u.components[1].GetDofNrs(el):
            naive.components[1].vec[d] = 1.0
    wrong = -ngs.InnerProduct(r, naive.vec)
    assert abs(wrong - s.reaction()) > 0.01 * abs(s.reaction())


def test_rigid_motion_gives_no_stress_and_no_reaction():
    mesh = bar_mesh(length=1.0, height=0.5, maxh=0.2)
    scene = ngtmc.Scene(mesh, {"bar": ngtmc.Material(1000.0, 0.3)},
                        supports=[ngtmc.Support("bottom", x=True, y=True)],
                        load=ngtmc.DisplacementLoad("top", "-y"), order=2)
    s = ngtmc.Solver(scene)
    c, sn = math.cos(0.5), math.sin(0.5)
    s.u.Set(ngs.CF(((c - 1) * ngs.x - sn * ngs.y + 0.3, sn * ngs.x + (c - 1) * ngs.y - 0.2)))
    r = s.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, r)
    assert np.max(np.abs(r.FV().NumPy())) < 1e-9
    assert abs(s.reaction()) < 1e-9
    assert abs(s.energies()["elastic_energy"]) < 1e-9


def test_free_translation_under_displacement_control_transmits_no_force():
    """Only the loaded edge holds y: the imposed displacement translates the body rigidly."""
    mesh = bar_mesh(length=1.0, height=0.5, maxh=0.2)
    scene = ngtmc.Scene(mesh, {"bar": ngtmc.Material(1000.0, 0.3)},
                        supports=[ngtmc.Support("left", x=True)],
                        load=ngtmc.DisplacementLoad("top", "-y"))
    res = ngtmc.simulate(scene, 0.3, ngtmc.AdaptiveStepControl(du_max=0.1))
    assert np.all(np.abs(res.history["force"]) < 1e-9)
    assert np.all(np.abs(res.history["elastic_energy"]) < 1e-9)
    uy = res.solver.u.components[1]
    assert uy(mesh(0.5, 0.1)) == pytest.approx(-0.3, abs=1e-10)
