"""The displacement Newton's line search where the stored energy's round-off hides the decrease of
a Newton step (ngtmc.discrete.energy_search.NOISE_FRACTION).

A stiff, thick scene (the L-panel's concrete, E = 25800 MPa, 100 mm thick) whose upper block is
pushed into a 6 mm void: the force is tiny, but the energy sums densities of the size of E over
the volume, so its evaluation error (about 1e-8 N mm here) exceeds the decrease a converging Newton
step predicts (about 1e-10 N mm). With the Armijo test alone, measured 2026-12-03 on this scene:
44 iterations for the 20 steps below and 2 Levenberg shifts (full steps rejected at random, half
steps taken); with the round-off measured and the residual deciding: 40, no shift."""
from __future__ import annotations

import ngsolve as ngs
import pytest

import ngtmc
import ngtmc.discrete.energy_search as dn
from scenes import two_blocks


def _squeezed_void_scene(maxh=2.0):
    return two_blocks(gap=6.0, gamma0=1e-6, maxh=maxh, void_maxh=maxh, kbar_r=None, width=100.0, height=40.0,
                      E=25800.0, nu=0.18, order=1, thickness=100.0)


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
    """energy_noise is |E(u0 + e du) + E(u0 - e du) - 2 E(u0)|: zero truncation error for a
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
    noise = dn.energy_noise(s._energy, s.u.vec, u0, du, E0)
    # exact: 2 e^2 E(du) for the quadratic part (e = NOISE_STEP), plus round-off
    assert noise == pytest.approx(2 * dn.NOISE_STEP ** 2 * E_du, rel=0.05)
    g.Set(ngs.CF((-3.0 / dn.NOISE_STEP * ngs.x, 0.0)))   # e du stretches x by -3: J < 0
    du.data = g.vec
    assert dn.energy_noise(s._energy, s.u.vec, u0, du, E0) == float("inf")
