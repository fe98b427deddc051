"""The bordered system of path following in one GMRES (ngtmc.coupled.bordered): GMRES and the
bordered solve against dense solves, and whole path-following runs with it against the two
solves it replaces, on every element type."""
import numpy as np
import ngsolve as ngs
import pytest
from netgen.meshing import MeshingParameters  # noqa: F401  (netgen loaded before ngsolve.meshes)
from ngsolve.meshes import MakeStructured2DMesh, MakeStructured3DMesh

import ngtmc
from ngtmc.coupled.bordered import bordered_gmres, gmres
from scenes import bar_mesh


def _system(n=40, seed=0):
    """A non-symmetric, well-conditioned n x n matrix, a perturbed inverse of it (the
    preconditioner), a load response t, a constraint row c and right-hand sides r, h."""
    rng = np.random.default_rng(seed)
    A = np.eye(n) * 4 + rng.standard_normal((n, n)) / np.sqrt(n)
    P = np.linalg.inv(A + 0.3 * np.diag(rng.random(n)))
    t, c, r = rng.standard_normal(n), rng.standard_normal(n), rng.standard_normal(n)
    return A, P, t, c, r, float(rng.standard_normal())


def test_gmres_solves_a_dense_system():
    """Left-preconditioned GMRES with a poor (Jacobi) preconditioner: the dense solution to 1e-9."""
    A, _, _, _, r, _ = _system()
    D = 1.0 / np.diag(A)
    x, its, converged = gmres(lambda v: D * (A @ v), D * r, 1e-12, 100)
    assert converged and its < 40
    assert np.allclose(x, np.linalg.solve(A, r), rtol=0, atol=1e-9 * np.abs(x).max())


def test_bordered_gmres_solves_the_bordered_system():
    """[A -t; c^T 0] [p; dlambda] = [r; h]: the dense solution to 1e-9 with an inexact
    preconditioner; with P = A^-1 GMRES needs one iteration (the block preconditioner is then the
    bordered matrix's inverse)."""
    A, P, t, c, r, h = _system()
    n = r.size
    M = np.block([[A, -t[:, None]], [c[None, :], np.zeros((1, 1))]])
    exact = np.linalg.solve(M, np.append(r, h))
    p, dlam, its = bordered_gmres(lambda x: A @ x, lambda v: P @ v, r, t, c, h, 1e-12, 100, 1e-4)
    assert np.allclose(p, exact[:n], rtol=0, atol=1e-9 * np.abs(exact).max())
    assert dlam == pytest.approx(exact[n], rel=1e-9)
    Ainv = np.linalg.inv(A)
    *_, its_exact = bordered_gmres(lambda x: A @ x, lambda v: Ainv @ v, r, t, c, h, 1e-12, 100, 1e-4)
    assert its_exact == 1 and its > its_exact


def test_bordered_gmres_declines_where_the_constraint_does_not_see_the_load():
    """c orthogonal to the preconditioned load response (s = 0): None, the caller's two solves
    decide; so also where GMRES cannot converge in its iterations."""
    A, P, t, c, r, h = _system()
    q = P @ t
    c0 = c - (c @ q) / (q @ q) * q
    assert bordered_gmres(lambda x: A @ x, lambda v: P @ v, r, t, c0, h, 1e-12, 100, 1e-4) is None
    assert bordered_gmres(lambda x: A @ x, lambda v: v, r, t, c, h, 1e-14, 2, 1e-4) is None


def _bar(kind):
    """Homogeneous tension of a bar 1 x 0.2 (x 0.2) mm on ``kind`` elements: x held on the left,
    the other directions on the bottom (and a side), x imposed on the right; AT-2 everywhere
    (l0 = 0.1 mm)."""
    if kind == "trig":
        mesh = bar_mesh(maxh=0.1)
    elif kind == "quad":
        mesh = MakeStructured2DMesh(quads=True, nx=10, ny=2, mapping=lambda x, y: (x, 0.2 * y))
    else:
        mesh = MakeStructured3DMesh(hexes=kind == "hex", nx=5, ny=1, nz=1,
                                    mapping=lambda x, y, z: (x, 0.2 * y, 0.2 * z))
    supports, pulled = [ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True)], "right"
    if mesh.dim == 3:   # NGSolve's structured 3D mesh: back x = 0, front x = 1, left y = 0, bottom z = 0
        supports = [ngtmc.Support("back", x=True), ngtmc.Support("left", y=True), ngtmc.Support("bottom", z=True)]
        pulled = "front"
    region = mesh.GetMaterials()[0]
    return ngtmc.Scene(mesh, {region: ngtmc.Material(1000.0, 0.3, 1e-3, 0.1)}, supports=supports,
                       load=ngtmc.DisplacementLoad(pulled, "x"), fracture_regions=region)


@pytest.mark.parametrize("kind", ["trig", "quad", "tet", "hex"])
def test_path_following_with_one_bordered_gmres_follows_the_two_solves(kind):
    """A path-following run through the softening of homogeneous tension to 0.01 mm (five times
    the peak's displacement), its dissipation steps (of 0.01 mm of crack) solved with one GMRES on
    the bordered system (the default) and with the two solves: the same steps and Newton
    iterations, every load and force the same to 1e-7 of the largest (the coupled tolerance is
    1e-6). The bordered solve made every direction of the dissipation steps. The u-u factor is made anew at every
    direction (``factor_reuse`` off): reuse decides on measured times, which differ between
    runs."""
    runs = {}
    for bordered in (True, False):
        sim = ngtmc.Simulation(_bar(kind), 0.01, ngtmc.AdaptiveStepControl(du_max=2e-3, du_min=1e-7),
                               scheme="path-following",
                               coupled={"bordered": bordered, "crack_advance": 0.01, "factor_reuse": False})
        runs[bordered] = (sim, sim.run().history)
    (one, h1), (two, h2) = runs[True], runs[False]
    lin = one.coupled.lin
    assert one._path.dissipation_steps >= 8
    assert lin.bordered_solves >= 3 * one._path.dissipation_steps and lin.bordered_fallbacks == 0
    assert two.coupled.lin.bordered_solves == 0
    assert len(h1) == len(h2)
    assert list(h1["newton_iterations"]) == list(h2["newton_iterations"])
    for col in ("load", "force"):
        a, b = h1[col].to_numpy(), h2[col].to_numpy()
        assert np.allclose(a, b, rtol=0, atol=1e-7 * np.abs(b).max()), col


def test_bordered_option_is_checked():
    with pytest.raises(ValueError, match="bordered"):
        ngtmc.Simulation(_bar("trig"), 0.01, scheme="path-following", coupled={"bordered": "yes"})


def test_a_bordered_solve_that_fails_with_an_older_factor_is_tried_again_with_a_new_one(monkeypatch):
    """FACTOR_REUSE with the bordered solve: where the bordered GMRES fails with a reused u-u
    factor, a new factor is made and the bordered solve tried again (not the two solves); where
    it fails with a new factor, the caller's two solves decide (counted in bordered_fallbacks)."""
    import ngtmc.coupled.linear as cl
    from test_monolithic import _damaged_state
    s, c = _damaged_state(seed=5)
    free = c._free_base.copy()
    free[:c.nu] &= ~s._dir_np
    rng = np.random.default_rng(3)
    r, t = (np.where(free, rng.standard_normal(free.size), 0.0) for _ in range(2))
    cvec = np.zeros(free.size)
    cvec[c.nu:] = np.where(free[c.nu:], rng.random(free.size - c.nu), 0.0)
    gm = cl.CoupledLinearSolver(c.form, c.nu, "block-gmres", gmres_rtol=1e-10, factor_reuse=True)
    c.form.AssembleLinearization(c.x.vec)
    p0, dl0 = gm.factorize(free).bordered(r, t, cvec, 0.1)
    gm._u_cost = 1e9                   # a factorization that never pays: keep the factor
    calls = []
    real = cl.bordered_gmres

    def failing_once(*a, **k):
        calls.append(1)
        return None if len(calls) == 1 else real(*a, **k)
    monkeypatch.setattr(cl, "bordered_gmres", failing_once)
    p1, dl1 = gm.factorize(free).bordered(r, t, cvec, 0.1)
    assert len(calls) == 2 and (gm.u_factorizations, gm.u_factor_reuses) == (2, 1)
    assert (gm.bordered_solves, gm.bordered_fallbacks) == (2, 0)
    assert dl1 == pytest.approx(dl0, rel=1e-7) and np.allclose(p1, p0, rtol=0, atol=1e-7 * np.abs(p0).max())
    monkeypatch.setattr(cl, "bordered_gmres", lambda *a, **k: None)
    assert gm.factorize(free).bordered(r, t, cvec, 0.1) is None   # a new factor (the last failed): no retry
    assert gm.bordered_fallbacks == 1
