"""The displacement Newton where its tangent is indefinite (ngtmc.discrete.newton): the Levenberg
direction, accepted at full length, is lengthened while the energy keeps falling
(``NewtonOptions.levenberg_expansion``).

The scene: a field u on the unit square with the double-well energy
E(u) = int eps |grad u|^2 / 2 + (u^2 - 1)^2 / 4 dx, u = 0 on the left edge, started just off
the maximum u = 0. Its tangent eps K + (3 u^2 - 1) M is negative in the bulk there, so the Newton
direction ascends and the shifted one creeps away from the maximum, as the paper three-point
bending's displacement relaxation crept away from a squeezed void's unstable equilibrium at
contact onset (25 iterations without convergence; docs/performance.md). The minimum it must reach
is u = +-1 away from the edge: the residual vanishes and the tangent is positive definite there.
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

import ngtmc.discrete.newton as dn
from ngtmc.scene.distributed import Ranks

EPS = 1e-3


def _problem(mu0: float = 1e-2):
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.1))
    fes = ngs.H1(mesh, order=1, dirichlet="left")
    gfu = ngs.GridFunction(fes)
    u = fes.TrialFunction()
    density = lambda w: EPS / 2 * ngs.grad(w) * ngs.grad(w) + (w * w - 1) ** 2 / 4
    form = ngs.BilinearForm(fes)
    form += ngs.Variation(density(u) * ngs.dx)
    mu = ngs.Parameter(0.0)
    anchor = ngs.GridFunction(fes)
    shifted = ngs.BilinearForm(fes)
    shifted += ngs.Variation((density(u) + mu / 2 * (u - anchor) ** 2) * ngs.dx)
    free = np.array(fes.FreeDofs(), dtype=bool)

    def energy(vec):   # with the form's own quadrature: the residual is its exact gradient
        return float(form.Energy(vec))

    def factorize(f):
        return f.mat.Inverse(fes.FreeDofs(), inverse="umfpack")

    vectors = tuple(gfu.vec.CreateVector() for _ in range(5))
    timings = {k: 0.0 for k in ("residual", "assembly", "factorization", "solve", "line_search")}
    problem = dn.DisplacementProblem(
        form=form, u=gfu, free=free, fixed=~free, target=lambda load: np.zeros(fes.ndof),
        scale=lambda r, load: 1.0, energy=energy, admissible=lambda: True, factorize=factorize,
        shifted=lambda: (shifted, mu, anchor), mu0=lambda: mu0, ranks=Ranks(mesh), vectors=vectors,
        timings=timings)
    gfu.Set(1e-3 * ngs.x)   # off the maximum u = 0, zero on the left edge
    return problem, gfu, mesh


def _solve(expansion: int):
    problem, gfu, mesh = _problem()
    options = dn.NewtonOptions(max_iterations=200, atol=1e-12, levenberg_expansion=expansion)
    newton = dn.DisplacementNewton(options, rtol=1e-10, floor=None)
    return newton.solve(problem, 0.0), gfu, mesh


def test_the_expanded_levenberg_step_reaches_the_minimum_in_fewer_iterations():
    plain, gfu_plain, mesh = _solve(0)
    expanded, gfu, _ = _solve(dn.NewtonOptions().levenberg_expansion)   # the default
    assert plain.converged and expanded.converged
    assert plain.shifted > 0 and expanded.shifted > 0           # the tangent was indefinite
    # both reach the well u = +1 (u grows from 1e-3 x): away from the pinned edge |u - 1| is small
    for g in (gfu_plain, gfu):
        far = [g(mesh(x, y)) for x in (0.5, 0.75, 1.0) for y in (0.0, 0.5, 1.0)]
        np.testing.assert_allclose(far, 1.0, atol=1e-3)
    np.testing.assert_allclose(gfu.vec.FV().NumPy(), gfu_plain.vec.FV().NumPy(), atol=1e-8)
    # measured: 6 against 8 iterations here (shifts from 1e-2 to 1 alike); the test asks for fewer
    print(f"iterations: plain Levenberg {plain.iterations}, expanded {expanded.iterations}")
    assert expanded.iterations < plain.iterations


@pytest.mark.parametrize("bad", [-1, 1.5, True, "3", None])
def test_a_bad_levenberg_expansion_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match="levenberg_expansion"):
        dn.NewtonOptions(levenberg_expansion=bad)
