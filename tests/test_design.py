"""The pieces of topology optimisation (ngtmc.design): the Helmholtz filter against its exact
properties, the Heaviside projection against its limits and finite differences, and MMA (nlopt)
on a problem with a known optimum."""
import math

import numpy as np
import pytest
import ngsolve as ngs
from netgen.occ import OCCGeometry, Rectangle

from ngtmc.design import HelmholtzFilter, mma, project, project_derivative


def _mesh(maxh=0.1, quads=False):
    geo = OCCGeometry(Rectangle(1.0, 0.5).Face(), dim=2)
    return ngs.Mesh(geo.GenerateMesh(maxh=maxh, quad_dominated=quads))


@pytest.mark.parametrize("quads", [False, True])
def test_the_filter_keeps_constants_and_the_integral(quads):
    """-r^2 Laplace(u) + u = rho with Neumann conditions keeps the integral of rho, and the element
    means keep it too; a constant density is filtered to itself (both to round-off)."""
    mesh = _mesh(quads=quads)
    F = HelmholtzFilter(mesh, radius=0.15)
    assert np.allclose(F.filter(np.ones(mesh.ne)), 1.0, rtol=0, atol=1e-10)   # measured 4e-16 (trigs), 1.4e-12 (quads)
    assert F.areas.sum() == pytest.approx(0.5, rel=1e-12)            # mm^2
    x = np.random.default_rng(0).random(mesh.ne)
    assert (F.areas * F.filter(x)).sum() == pytest.approx((F.areas * x).sum(), rel=1e-12)


def test_the_transpose_is_the_adjoint_of_the_filter():
    mesh = _mesh()
    F = HelmholtzFilter(mesh, radius=0.2)
    rng = np.random.default_rng(1)
    x, y = rng.random(mesh.ne), rng.random(mesh.ne)
    assert F.filter(x) @ y == pytest.approx(x @ F.transpose(y), rel=1e-12)


def test_a_larger_radius_smooths_more():
    mesh = _mesh()
    x = np.random.default_rng(2).random(mesh.ne)
    spread = [np.std(HelmholtzFilter(mesh, radius=r).filter(x)) for r in (0.05, 0.2, 0.8)]
    assert np.std(x) > spread[0] > spread[1] > spread[2]


def test_the_filter_refuses_bad_input():
    mesh = _mesh(maxh=0.3)
    with pytest.raises(ValueError, match="radius"):
        HelmholtzFilter(mesh, radius=0.0)
    with pytest.raises(ValueError, match="one per element"):
        HelmholtzFilter(mesh, radius=0.1).filter(np.ones(mesh.ne + 1))


def test_the_projection_keeps_its_ends_and_its_derivative_is_exact():
    for beta in (1.0, 8.0, 64.0):
        assert project([0.0, 0.5, 1.0], beta) == pytest.approx([0.0, 0.5, 1.0], abs=1e-14)   # eta = 1/2: symmetric
        x = np.linspace(0.01, 0.99, 25)
        h = 1e-6
        fd = (project(x + h, beta) - project(x - h, beta)) / (2 * h)
        assert project_derivative(x, beta) == pytest.approx(fd, rel=1e-6, abs=1e-9)
    assert project([0.0, 1.0], 5.0, 0.4) == pytest.approx([0.0, 1.0], abs=1e-15)
    assert project(0.5, 1e-6) == pytest.approx(0.5)                   # beta -> 0: the identity
    assert project(0.6, 200.0) == pytest.approx(1.0, abs=1e-12)       # beta -> inf: a step
    with pytest.raises(ValueError, match="eta"):
        project(0.5, 1.0, eta=1.0)


def test_mma_finds_the_constrained_minimum():
    """min (x0 - 2)^2 + (x1 - 1)^2 subject to x0 + x1 <= 1 and 0 <= x <= 5: x = (1, 0), J = 2."""
    pytest.importorskip("nlopt")
    seen = []
    res = mma(lambda x: ((x[0] - 2) ** 2 + (x[1] - 1) ** 2, np.array([2 * (x[0] - 2), 2 * (x[1] - 1)])),
              [0.2, 0.2], 0.0, 5.0, [lambda x: (x[0] + x[1] - 1.0, np.array([1.0, 1.0]))],
              max_evaluations=200, callback=lambda x, v, rec: seen.append(v))
    assert res.x == pytest.approx([1.0, 0.0], abs=1e-4)
    assert res.objective == pytest.approx(2.0, rel=1e-5)
    assert res.evaluations == len(res.history) == len(seen) <= 200
    assert all(len(rec["constraints"]) == 1 for rec in res.history)


def test_mma_stops_on_a_failed_evaluation():
    pytest.importorskip("nlopt")
    calls = []

    def objective(x):
        calls.append(1)
        return (math.nan, np.zeros(2)) if len(calls) == 3 else (float(x @ x), 2 * x)

    with pytest.raises(RuntimeError, match="evaluation 3"):
        mma(objective, [0.5, 0.5], -1.0, 1.0, max_evaluations=50, xtol_rel=0.0)


def test_the_chain_of_filter_projection_and_adjoint_matches_finite_differences():
    """J(x) = end compliance of a bar whose densities are rho = project(F x): the gradient F^T
    (project'(F x) dJ/drho), dJ/drho from the adjoint, against central finite differences of J
    along a random direction (replays of the recorded path)."""
    import ngtmc
    from netgen.occ import X
    from ngtmc.sensitivities import ComplianceAtStep, differentiate, evaluate, replay
    face = Rectangle(1.0, 0.25).Face()
    face.faces.name = "bar"
    face.edges.Min(X).name, face.edges.Max(X).name = "left", "right"
    mesh = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.1))
    F = HelmholtzFilter(mesh, radius=0.2)
    rng = np.random.default_rng(3)
    x = 0.4 + 0.5 * rng.random(mesh.ne)
    beta = 4.0

    def rho(x):
        return project(F.filter(x), beta)

    scene = ngtmc.Scene(mesh, {"bar": ngtmc.Material(E=1000.0, nu=0.3)}, density=rho(x),
                        supports=[ngtmc.Support("left", x=True, y=True)], load=ngtmc.DisplacementLoad("right", "x"))
    objective = ComplianceAtStep()
    grads, path = differentiate(scene, ngtmc.Schedule([0.0, 0.01]), objective,
                                ngtmc.AdaptiveStepControl(du_max=0.005), wrt=("rho",))
    g = F.transpose(project_derivative(F.filter(x), beta) * grads["rho"])
    d = rng.standard_normal(mesh.ne)
    h = 1e-4
    fd = (evaluate(replay(path, rho(x + h * d)), objective) - evaluate(replay(path, rho(x - h * d)), objective)) / (2 * h)
    assert g @ d == pytest.approx(fd, rel=1e-5)          # measured: 7e-9 relative
