"""The displacement Newton's line search where the stored energy's round-off hides the decrease of
a Newton step (ngtmc.displacement_newton.NOISE_FRACTION).

A stiff, thick scene (the L-panel's concrete, E = 25800 MPa, 100 mm thick) whose upper block is
pushed into a 6 mm void: the force is tiny, but the energy sums densities of the size of E over
the volume, so its evaluation error (about 1e-8 N mm here) exceeds the decrease a converging Newton
step predicts (about 1e-10 N mm). With the Armijo test alone, measured 2026-12-03 on this scene:
44 iterations for the 20 steps below and 2 Levenberg shifts (full steps rejected at random, half
steps taken); with the round-off measured and the residual deciding: 40, no shift."""
from __future__ import annotations

import ngsolve as ngs
import pytest
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, Y

import ngtmc
import ngtmc.displacement_newton as dn


def _squeezed_void_scene(maxh=2.0):
    W, hb, gap = 100.0, 40.0, 6.0
    low = Rectangle(W, hb).Face()
    low.faces.name = "lower"
    void = MoveTo(0, hb).Rectangle(W, gap).Face()
    void.faces.name = "void"
    up = MoveTo(0, hb + gap).Rectangle(W, hb).Face()
    up.faces.name = "upper"
    shape = Glue([low, void, up])
    shape.edges.Min(Y).name = "bottom"
    shape.edges.Max(Y).name = "top"
    mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))
    return ngtmc.Scene(mesh, {".*": ngtmc.Material(25800.0, 0.18)},
                       supports=[ngtmc.Support("bottom", x=True, y=True)],
                       load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True), density={"void": 0.0},
                       gamma0=1e-6, regulariser=None, order=1, thickness=100.0)


def test_round_off_of_the_energy_does_not_cost_iterations():
    s = ngtmc.Solver(_squeezed_void_scene(), compile=False)
    steps = 20
    results = [s.solve_displacement(0.05 * k) for k in range(1, steps + 1)]
    assert all(r.converged for r in results)
    # every step: the step onto the new boundary values and one Newton step, no Levenberg shift
    assert sum(r.iterations for r in results) == 2 * steps
    assert sum(r.shifted for r in results) == 0
    # the energy could not resolve some of those steps: the residual decided there
    assert s.energy_noise_switches >= 1


def test_the_round_off_is_measured_by_a_second_difference():
    """_energy_noise is |E(u0 + e du) + E(u0 - e du) - 2 E(u0)|: zero truncation error for a
    quadratic energy up to e^2 du.K.du. On the unstressed scene along a smooth field it is far below
    the energy of that field, and it is infinite where a trial state inverts an element."""
    s = ngtmc.Solver(_squeezed_void_scene(maxh=5.0), compile=False)
    u0 = s.u.vec.CreateVector()
    u0[:] = 0.0
    du = s.u.vec.CreateVector()
    g = ngs.GridFunction(s.fes_u)
    g.Set(ngs.CF((1e-3 * ngs.x, 0.0)))   # a uniform stretch of 1e-3 in x
    du.data = g.vec
    s.u.vec.data = du
    E_du = s._energy(s.u.vec)
    E0 = s._energy(u0)
    noise = s._energy_noise(u0, du, E0)
    # exact: 2 e^2 E(du) for the quadratic part (e = NOISE_STEP), plus round-off
    assert noise == pytest.approx(2 * dn.NOISE_STEP ** 2 * E_du, rel=0.05)
    g.Set(ngs.CF((-3.0 / dn.NOISE_STEP * ngs.x, 0.0)))   # e du stretches x by -3: J < 0
    du.data = g.vec
    assert s._energy_noise(u0, du, E0) == float("inf")
