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


class _Saddle:
    """Two dofs, E(u) = E_REF + 1/2 u.K u - f.u with K = diag(1, -1) N/mm (a saddle, as the squeezed
    void's tangent at the paper L-panel's stall) plus a round-off term of 1e-8 N mm that follows
    no rule (as the summed energy of a large mesh), here chosen to favour the trial states."""

    E_REF = 27.0   # N mm, the paper L-panel's stored energy at that stall

    def __init__(self):
        import numpy as np
        self.np = np
        vec = lambda: ngs.la.CreateVVector(2)
        self.u, self.r, self.du, self.w, self.tmp, self.u0 = (vec() for _ in range(6))
        self.K = np.diag([1.0, -1.0])
        self.f = np.array([1e-6, 0.0])       # equilibrium at u = (1e-6, 0); the start u = 0
        self.free = np.array([True, True])
        self.calls = 0

    def exact(self, v):
        x = v.FV().NumPy()
        return self.E_REF + 0.5 * x @ self.K @ x - self.f @ x

    def energy(self, v):
        self.calls += 1
        return self.exact(v) - 1e-8 * (self.calls > 1)   # every evaluation after the first 1e-8 N mm low

    def apply(self, v, out):
        out.FV().NumPy()[:] = self.K @ v.FV().NumPy() - self.f

    def problem(self):
        from types import SimpleNamespace as NS
        ranks = NS(masked_norm=lambda v, mask: float(self.np.linalg.norm(v.FV().NumPy()[mask])))
        return NS(u=NS(vec=self.u), vectors=(self.r, self.du, self.w, self.tmp, self.u0), energy=lambda v: self.energy(v),
                  admissible=lambda: True, form=NS(Apply=self.apply), ranks=ranks, free=self.free)


def test_where_the_energy_cannot_resolve_a_step_the_residual_decides_and_no_step_is_lengthened():
    """A Levenberg direction along the saddle's unstable dof: the energy changes by its slope only
    (-1e-9 N mm, below the round-off), while the residual grows from 1e-6 N to 1.4e-3 N. Before,
    the Armijo test passed on round-off and the step was then doubled as a step along negative
    curvature: at the paper L-panel's stall (resumed from step 241) the displacement relaxation's
    residual rose from 1.27e-3 to 1.99e-3 N that way. Now the round-off is measured first, the
    residual decides, and the step accepted (if any) reduces the residual."""
    from ngtmc.discrete.newton import NewtonOptions
    z = _Saddle()
    p = z.problem()
    np = z.np
    z.u.FV().NumPy()[:] = 0.0
    z.u0.FV().NumPy()[:] = 0.0
    z.apply(z.u, z.r)
    res0 = np.linalg.norm(z.r.FV().NumPy())
    z.du.FV().NumPy()[:] = [1e-3, 1e-3]
    slope = float(z.r.FV().NumPy() @ z.du.FV().NumPy())
    assert slope == pytest.approx(-1e-9)
    E0 = z.energy(z.u)
    opt = NewtonOptions(levenberg_expansion=4)
    accepted, switched = dn.energy_line_search(p, opt, z.du, E0, slope, res0, False, expand_full_step=True)
    z.apply(z.u, z.tmp)
    res = np.linalg.norm(z.tmp.FV().NumPy())
    assert res <= res0
    assert switched == 1
    if not accepted:
        assert np.all(z.u.FV().NumPy() == 0.0)


def test_a_step_the_energy_resolves_is_still_taken_on_the_energy_and_lengthened():
    """The same saddle without round-off and with a slope the energy resolves (1e-3 N mm): the
    Armijo test accepts the full step and a Levenberg step along negative curvature is doubled."""
    from ngtmc.discrete.newton import NewtonOptions
    z = _Saddle()
    z.energy = z.exact
    z.f[:] = [1.0, 0.0]
    p = z.problem()
    np = z.np
    z.u.FV().NumPy()[:] = 0.0
    z.u0.FV().NumPy()[:] = 0.0
    z.apply(z.u, z.r)
    z.du.FV().NumPy()[:] = [1e-3, 1e-1]
    slope = float(z.r.FV().NumPy() @ z.du.FV().NumPy())
    E0 = z.energy(z.u)
    accepted, switched = dn.energy_line_search(p, NewtonOptions(levenberg_expansion=2), z.du, E0, slope, 1.0, False,
                                               expand_full_step=True)
    assert accepted and switched == 0
    # E(s du) - E0 = s slope + s^2 (1e-6 - 1e-2)/2 < 0.9 s slope for s = 2 and 4: doubled twice
    assert z.u.FV().NumPy() == pytest.approx(4 * z.du.FV().NumPy())
