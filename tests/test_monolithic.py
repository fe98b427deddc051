"""The monolithic scheme (ngtmc.coupled.monolithic): its residual is the hybrid AT-2 system of Eq. 16 with
H_n = max(H_{n-1}, Psi_plus(u)) inside the step, its tangent is the derivative of that residual,
and it removes the one-step damage lag of the paper's single-pass scheme."""
import math

import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from ngtmc.coupled import CoupledNewton
from scenes import notched_plate, tension_bar, two_blocks


#: (split, formulation) pairs the coupled form is checked with: the default and two others
#: (the monolithic scheme follows Scene.split and Scene.formulation)
SPLIT_CASES = [("vol-dev-J", "hybrid"), ("vol-dev-small", "hybrid"), ("spectral", "anisotropic")]
#: ... and at displacement order 2, where the history points are the elastic terms' points and
#: the coupled form sums the H_n term and the removal of g'(alpha) Psi_d into one integrand
CASES = [(sp, fo, 1) for sp, fo in SPLIT_CASES] + [("vol-dev-J", "hybrid", 2), ("spectral", "anisotropic", 2)]


def _damaged_state(seed=0, split="vol-dev-J", formulation="hybrid", order=1):
    """Notched plate (order 1) with a random displacement, a random alpha in [0, 0.6] and a random
    committed history: some history points have Psi_plus above H_{n-1} (the max is active),
    others below."""
    s = ngtmc.Solver(notched_plate(maxh=0.2, h_band=0.05, l0=0.1, split=split, formulation=formulation, order=order))
    rng = np.random.default_rng(seed)
    s.u.Set(ngs.CF((2e-3 * ngs.x * ngs.y, 3e-3 * ngs.y + 1e-3 * ngs.x ** 2)))
    s.alpha.vec.FV().NumPy()[:] = rng.uniform(0.0, 0.6, s.fes_a.ndof)
    plus = s.psi_plus_values()
    s.H_committed = plus * rng.choice([0.5, 2.0], size=plus.size)
    s.H.vec.FV().NumPy()[:] = s.H_committed
    c = CoupledNewton(s)
    c._gather()
    return s, c


@pytest.mark.parametrize("split,formulation,order", CASES)
def test_coupled_residual_is_the_hybrid_system_with_the_current_history(split, formulation, order):
    s, c = _damaged_state(0, split, formulation, order)
    r = c.x.vec.CreateVector()
    c.form.Apply(c.x.vec, r)
    R = r.FV().NumPy()
    # displacement part: the residual of the displacement energy at this alpha
    ru = s.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, ru)
    np.testing.assert_allclose(R[:c.nu], ru.FV().NumPy(), rtol=0, atol=1e-10 * np.abs(ru.FV().NumPy()).max())
    # phase-field part: K(H_n) alpha - f(H_n) of the staggered solve, H_n = max(H_{n-1}, Psi_plus(u))
    H_n = s.trial_history()
    assert np.any(H_n > s.H_committed) and np.any(H_n == s.H_committed)
    s.H.vec.FV().NumPy()[:] = H_n
    s.a_alpha.Assemble()
    s.f_alpha.Assemble()
    ra = s.a_alpha.mat * s.alpha.vec - s.f_alpha.vec
    ra_vec = s.alpha.vec.CreateVector()
    ra_vec.data = ra
    np.testing.assert_allclose(R[c.nu:], ra_vec.FV().NumPy(), rtol=0, atol=1e-10 * np.abs(ra_vec.FV().NumPy()).max())


def _tangent_and_difference(c, rng, eps):
    """Along a random direction v (displacements of order 1e-3 mm, alpha of order 1): v, the
    assembled coupled tangent times v, and the central difference of the residual with step eps
    (numpy array), at the coupled Newton ``c``'s current iterate."""
    x = c.x.vec
    v = x.CreateVector()
    v.FV().NumPy()[:] = rng.standard_normal(x.size)
    v.FV().NumPy()[:c.nu] *= 1e-3
    c.form.AssembleLinearization(x)
    Kv = x.CreateVector()
    Kv.data = c.form.mat * v
    xp, xm, rp, rm = (x.CreateVector() for _ in range(4))
    xp.data = x + eps * v
    xm.data = x - eps * v
    c.form.Apply(xp, rp)
    c.form.Apply(xm, rm)
    return v, Kv, (rp.FV().NumPy() - rm.FV().NumPy()) / (2 * eps)


@pytest.mark.parametrize("split,formulation,order", CASES)
def test_coupled_tangent_is_the_derivative_of_the_residual(split, formulation, order):
    """Central finite differences of the residual along a random direction against the assembled
    (non-symmetric) tangent, constant part (phase-field operator, regulariser) included."""
    s, c = _damaged_state(1, split, formulation, order)
    x = c.x.vec
    rng = np.random.default_rng(3)
    v, Kv, fd = _tangent_and_difference(c, rng, 1e-7)
    K = Kv.FV().NumPy()
    err = np.linalg.norm(fd - K) / np.linalg.norm(K)
    print(f"relative FD error of the coupled tangent: {err:.2e}")
    assert err < 1e-6
    # and it is not symmetric (hybrid split): K_au differs from K_ua^T
    w = x.CreateVector()
    w.FV().NumPy()[:] = rng.standard_normal(x.size)
    Kw = x.CreateVector()
    Kw.data = c.form.mat * w
    asym = abs(ngs.InnerProduct(Kv, w) - ngs.InnerProduct(v, Kw)) / abs(ngs.InnerProduct(Kv, w))
    assert asym > 1e-6


@pytest.mark.parametrize("order", [1, 2])
def test_the_history_points_are_the_elastic_points_exactly_when_the_solver_says_so(order):
    """Solver.elastic_rule_is_history_rule decides whether the coupled form sums its history term
    and the removal of g'(alpha) Psi_d into one integrand: that is exact only if both rules are
    the same points, which an integrand no rule integrates exactly tells."""
    s = ngtmc.Solver(notched_plate(maxh=0.2, h_band=0.05, l0=0.1, order=order))
    frac = s.mesh.Materials(s.regions.fracture_regex)
    cf = ngs.exp(7 * ngs.x * ngs.y) * ngs.sin(13 * ngs.x + 5 * ngs.y)
    elastic = ngs.Integrate(cf * s.energy_measure("elastic_vol", s.regions.fracture_regex), s.mesh)
    history = ngs.Integrate(cf * ngs.dx(definedon=frac, intrules=s.irs.GetIntegrationRules()), s.mesh)
    same = abs(elastic - history) <= 1e-13 * abs(history)
    assert s.elastic_rule_is_history_rule() == same
    assert same == (order == 2)


def _peak(scheme, du, **kw):
    E, nu, Gc, l0 = 1000.0, 0.3, 1e-3, 1.0
    scene = tension_bar(E=E, nu=nu, Gc=Gc, l0=l0, maxh=0.1)
    res = ngtmc.simulate(scene, 1.2e-3, ngtmc.AdaptiveStepControl(du_max=du), scheme=scheme, staggered_tol=1e-8, **kw)
    sigma = res.history["force"].to_numpy() / (0.2 * scene.thickness)
    expected = 3 * math.sqrt(3) / 16 * math.sqrt(E / (1 - nu ** 2) * Gc / l0)
    return sigma.max(), expected, res


def test_monolithic_reaches_the_at2_peak_without_the_lag():
    """Homogeneous tension: the monolithic peak equals the converged staggered one (the same
    discrete solution), within 0.1 % of (3 sqrt 3 / 16) sqrt(E' Gc / l0), while the single-pass
    scheme with the same steps overshoots by several per cent."""
    mono, expected, res = _peak("monolithic", 4e-5)
    stag, _, _ = _peak("staggered", 4e-5)
    single, _, _ = _peak("single-pass", 4e-5)
    print(f"AT-2 {expected:.6g}; monolithic {mono:.6g}, staggered {stag:.6g}, single-pass {single:.6g} MPa")
    assert mono == pytest.approx(stag, rel=1e-5)
    assert mono == pytest.approx(expected, rel=2e-3)
    assert single > expected * 1.02
    a = res.solver.alpha.vec.FV().NumPy()
    assert a.max() - a.min() < 1e-6  # homogeneous damage


@pytest.mark.parametrize("linear_solver", ["block-gmres", "umfpack"])
def test_monolithic_linear_solvers_agree(linear_solver):
    peak, _, res = _peak("monolithic", 1e-4, coupled={"linear_solver": linear_solver})
    ref, _, _ = _peak("monolithic", 1e-4, coupled={"linear_solver": "umfpack"})
    assert peak == pytest.approx(ref, rel=1e-8)


def test_monolithic_passes_an_unstable_crack_and_keeps_alpha_monotone():
    """Notched plate (coarse): the crack runs across the ligament at almost constant load. The
    monolithic scheme takes it in a few steps (staggered passes carry the crack where the coupled
    Newton has no nearby solution); alpha and the history never decrease; its converged peak is
    below the lagged peak of the single-pass scheme with the same step control."""
    def run(scheme, callbacks=()):
        scene = notched_plate(maxh=0.2, h_band=0.05, l0=0.1)
        sim = ngtmc.Simulation(scene, 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                               scheme=scheme)
        return sim.run(callbacks=callbacks).history

    states = []
    h = run("monolithic", [lambda s, row: states.append((s.solver.H_committed.copy(),
                                                        s.solver.alpha.vec.FV().NumPy().copy()))])
    single = run("single-pass")
    print(f"\nmonolithic crack: {len(h) - 1} steps, {int(h.newton_iterations.sum())} iterations, peak "
          f"{h.force.max():.4g} N; single-pass: {len(single) - 1} steps, peak {single.force.max():.4g} N")
    assert h["load"].iloc[-1] == pytest.approx(0.012)
    assert h["max_alpha"].iloc[-1] > 0.99
    assert h["force"].iloc[-1] < 0.1 * h["force"].max()
    assert len(h) - 1 < 0.5 * (len(single) - 1)
    assert h.force.max() < 0.97 * single.force.max()
    for (H0, a0), (H1, a1) in zip(states, states[1:]):
        assert np.all(H1 >= H0) and np.all(a1 >= a0)


def test_coupled_newton_refuses_a_scene_without_phase_field_and_bad_solver():
    with pytest.raises(ValueError, match="fracture"):
        CoupledNewton(ngtmc.Solver(tension_bar(fracture=False)))
    with pytest.raises(ValueError, match="sparsecholesky"):
        CoupledNewton(ngtmc.Solver(tension_bar()), linear_solver="sparsecholesky")


@pytest.mark.parametrize("mu", [1e-4, 1.0])
def test_levenberg_solve_of_block_gmres_is_that_of_the_shifted_matrix(mu):
    """CoupledLinearSolver.shifted: the block-GMRES Levenberg solve (preconditioner factorized with
    the shifted diagonal, operator = restored matrix + shift) gives the UMFPACK solution of the
    matrix whose free diagonal is scaled by (1 + mu), to the GMRES tolerance; the assembled
    matrix is left unchanged, and a normal factorization after it solves the unshifted matrix."""
    from ngtmc.coupled import CoupledLinearSolver
    s, c = _damaged_state(seed=3)
    c.form.AssembleLinearization(c.x.vec)
    A = c.form.mat
    before = A.AsVector().FV().NumPy().copy()
    free = c._free_base.copy()
    free[:c.nu] &= ~s._dir_np
    free[c.nu::7] = False  # some alpha dofs held at a bound
    gm = CoupledLinearSolver(c.form, c.nu, "block-gmres", gmres_rtol=1e-12)
    um = CoupledLinearSolver(c.form, c.nu, "umfpack")
    rhs = c.x.vec.CreateVector()
    rhs.FV().NumPy()[:] = np.random.default_rng(5).standard_normal(rhs.size)
    rhs.FV().NumPy()[~free] = 0.0
    x_gm, x_um = rhs.CreateVector(), rhs.CreateVector()
    gm.shifted(free, mu)(rhs, x_gm)
    np.testing.assert_array_equal(A.AsVector().FV().NumPy(), before)
    um.shifted(free, mu)(rhs, x_um)
    np.testing.assert_array_equal(A.AsVector().FV().NumPy(), before)
    a, b = x_gm.FV().NumPy()[free], x_um.FV().NumPy()[free]
    assert np.linalg.norm(a - b) <= 1e-8 * np.linalg.norm(b)
    # the shifted solution is not the unshifted one (the shift acts), and a normal factorization
    # after a shifted one solves the unshifted matrix (the kept u-u factor is updated again)
    x_plain, x_plain_um = rhs.CreateVector(), rhs.CreateVector()
    gm.factorize(free)(rhs, x_plain)
    um.factorize(free)(rhs, x_plain_um)
    p, q = x_plain.FV().NumPy()[free], x_plain_um.FV().NumPy()[free]
    assert np.linalg.norm(p - q) <= 1e-8 * np.linalg.norm(q)
    assert np.linalg.norm(a - p) > 1e-6 * np.linalg.norm(p)


def test_block_gmres_solution_failing_its_true_residual_is_solved_by_umfpack(monkeypatch):
    """A block-GMRES solution is checked against the matrix (GMRES stops on its preconditioned
    residual): one whose true residual exceeds GMRES_TRUE_RTOL of the right-hand side is replaced
    by the UMFPACK solution, and counted. With the threshold at 0 every solve fails the check; at
    its value none does on this state."""
    import ngtmc.coupled.linear as cl
    s, c = _damaged_state(seed=3)
    c.form.AssembleLinearization(c.x.vec)
    free = c._free_base.copy()
    free[:c.nu] &= ~s._dir_np
    rhs = c.x.vec.CreateVector()
    rhs.FV().NumPy()[:] = np.random.default_rng(7).standard_normal(rhs.size)
    rhs.FV().NumPy()[~free] = 0.0
    x_um = rhs.CreateVector()
    cl.CoupledLinearSolver(c.form, c.nu, "umfpack").factorize(free)(rhs, x_um)
    b = x_um.FV().NumPy()[free]
    gm = cl.CoupledLinearSolver(c.form, c.nu, "block-gmres", gmres_rtol=1e-10)
    x = rhs.CreateVector()
    gm.factorize(free)(rhs, x)
    gmres_error = np.linalg.norm(x.FV().NumPy()[free] - b) / np.linalg.norm(b)
    assert gm.inexact_solves == 0 and 0 < gmres_error <= 1e-7
    monkeypatch.setattr(cl, "GMRES_TRUE_RTOL", 0.0)
    gm.factorize(free)(rhs, x)
    assert gm.inexact_solves == 1
    assert np.linalg.norm(x.FV().NumPy()[free] - b) <= 1e-12 * np.linalg.norm(b)
    # a GMRES stopped early (preconditioned residual down by 1e-2 only) fails the check at its value
    monkeypatch.setattr(cl, "GMRES_TRUE_RTOL", 1e-4)
    loose = cl.CoupledLinearSolver(c.form, c.nu, "block-gmres", gmres_rtol=1e-2)
    loose.factorize(free)(rhs, x)
    assert loose.inexact_solves == 1 and np.linalg.norm(x.FV().NumPy()[free] - b) <= 1e-12 * np.linalg.norm(b)


def test_block_gmres_reuses_its_u_factor_while_it_pays_and_solves_the_current_matrix(monkeypatch):
    """FACTOR_REUSE: with an older u-u factor GMRES still solves the current matrix (to UMFPACK's
    solution); a new factor is made once the extra GMRES time reaches the factorization's, for a
    shifted (Levenberg) direction and after it, and for a solve that failed with the older one."""
    import ngtmc.coupled.linear as cl
    s, c = _damaged_state(seed=5)
    free = c._free_base.copy()
    free[:c.nu] &= ~s._dir_np
    rhs = c.x.vec.CreateVector()
    rhs.FV().NumPy()[:] = np.random.default_rng(11).standard_normal(rhs.size)
    rhs.FV().NumPy()[~free] = 0.0
    x, x_um = rhs.CreateVector(), rhs.CreateVector()

    def umfpack():
        cl.CoupledLinearSolver(c.form, c.nu, "umfpack").factorize(free)(rhs, x_um)
        return x_um.FV().NumPy()[free].copy()

    def error():
        b = umfpack()
        return np.linalg.norm(x.FV().NumPy()[free] - b) / np.linalg.norm(b)

    gm = cl.CoupledLinearSolver(c.form, c.nu, "block-gmres", gmres_rtol=1e-10, factor_reuse=True)
    c.form.AssembleLinearization(c.x.vec)
    gm.factorize(free)(rhs, x)
    assert (gm.u_factorizations, gm.u_factor_reuses) == (1, 0) and error() <= 1e-7
    fresh_iterations = gm.gmres_iterations[-1]
    # another state, another tangent: the old factor preconditions, the solution is the new matrix's
    s.u.vec.FV().NumPy()[:] *= 1.3
    s.alpha.vec.FV().NumPy()[:] = np.minimum(1.2 * s.alpha.vec.FV().NumPy(), 0.9)
    c._gather()
    c.form.AssembleLinearization(c.x.vec)
    gm._u_cost = 1e9                   # a factorization that never pays: keep the factor
    gm.factorize(free)(rhs, x)
    assert (gm.u_factorizations, gm.u_factor_reuses) == (1, 1) and error() <= 1e-7
    assert gm.gmres_iterations[-1] > fresh_iterations   # the older factor is a poorer preconditioner
    # once the extra GMRES time reaches the factorization's, the next direction makes a new factor
    gm._u_cost, gm._u_extra = 1e-3, 1e-3
    gm.factorize(free)(rhs, x)
    assert (gm.u_factorizations, gm.u_factor_reuses) == (2, 1) and error() <= 1e-7
    # a shifted direction makes a new factor, and so does the direction after it
    gm._u_cost = 1e9
    y = rhs.CreateVector()
    gm.shifted(free, 0.1)(rhs, y)
    gm.factorize(free)(rhs, x)
    assert (gm.u_factorizations, gm.u_factor_reuses) == (4, 1) and error() <= 1e-7
    # a solve that fails with an older factor is repeated with a new one, then by UMFPACK (the
    # prices are set, not measured, so that the decisions do not depend on the machine's speed)
    gm._u_cost, gm._u_first = 1e9, 0.0
    gm.factorize(free)(rhs, x)
    assert (gm.u_factorizations, gm.u_factor_reuses) == (4, 2)
    monkeypatch.setattr(cl, "GMRES_TRUE_RTOL", 0.0)
    gm.factorize(free)(rhs, x)
    assert (gm.u_factorizations, gm.u_factor_reuses, gm.inexact_solves) == (5, 3, 1) and error() <= 1e-12
    # where the first reuse of a factor cost more GMRES time than a factorization (learned), the
    # factors that follow are not reused
    monkeypatch.setattr(cl, "GMRES_TRUE_RTOL", 1e-4)
    gm._u_first = 1e9
    made = gm.u_factorizations
    for _ in range(3):
        gm.factorize(free)(rhs, x)
    assert gm.u_factorizations == made + 3 and error() <= 1e-7
    # off (the default): a new factor for every direction
    off = cl.CoupledLinearSolver(c.form, c.nu, "block-gmres")
    off.factorize(free)(rhs, x)
    off.factorize(free)(rhs, x)
    assert (off.u_factorizations, off.u_factor_reuses) == (2, 0)
    assert c.factor_reuse is False        # FACTOR_REUSE "auto": off for 2D meshes
    with pytest.raises(ValueError, match="factor_reuse"):
        CoupledNewton(s, factor_reuse="yes")


def test_coupled_tangent_is_the_derivative_of_the_residual_in_3d_with_a_squeezed_void():
    """The same finite-difference check on a 3D scene (two blocks extruded into prisms, both
    fracture regions, a void between them squeezed to J of about 0.04, order 2 there with the
    Hessian regulariser) in a random damaged state away from the kinks of the history's max
    (H_{n-1} half or twice Psi_plus). At the quick 3D hemisphere's crack run the same check gave
    3e-7 on the u rows at eps = 1e-4 (a committed state, where the max sits on its kink for the
    alpha rows)."""
    sc2 = two_blocks(maxh=0.2, void_maxh=0.05)
    mat = ngtmc.Material(1000.0, 0.3, 1e-3, 0.25)
    scene = ngtmc.Scene(ngtmc.extrude(sc2.mesh, 0.2, layers=2),
                        {"lower": mat, "upper": mat, "void": ngtmc.Material(1000.0, 0.3)},
                        supports=[ngtmc.Support("bottom", x=True, y=True, z=True)],
                        load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True),
                        density={"void": 0.0}, gamma0=1e-5,
                        regulariser=ngtmc.Regulariser("void", length=1.0, kbar_r=1e-6),
                        fracture_regions="lower|upper")
    s = ngtmc.Solver(scene)
    assert s.mesh.dim == 3
    rng = np.random.default_rng(1)
    squeeze = -0.03 * ngs.IfPos(ngs.y - 0.42, 1.0, 0.0) * (ngs.y - 0.4) / 0.05
    s.u.Set(ngs.CF((2e-3 * ngs.x * ngs.y, squeeze + 1e-3 * ngs.x ** 2, 1e-3 * ngs.z * ngs.x)))
    assert 0.0 < s.min_J() < 0.1
    s.alpha.vec.FV().NumPy()[:] = rng.uniform(0.0, 0.6, s.fes_a.ndof)
    plus = s.psi_plus_values()
    s.H_committed = plus * rng.choice([0.5, 2.0], size=plus.size)
    s.H.vec.FV().NumPy()[:] = s.H_committed
    c = CoupledNewton(s)
    assert c.factor_reuse is True     # FACTOR_REUSE 'auto': on for 3D meshes
    c._gather()
    _, Kv, fd = _tangent_and_difference(c, rng, 1e-6)
    K = Kv.FV().NumPy()
    err_u = np.linalg.norm((fd - K)[:c.nu]) / np.linalg.norm(K[:c.nu])
    err_a = np.linalg.norm((fd - K)[c.nu:]) / np.linalg.norm(K[c.nu:])
    print(f"3D relative FD error of the coupled tangent: u rows {err_u:.2e}, alpha rows {err_a:.2e}")
    assert err_u < 1e-7 and err_a < 1e-7


def _line_search_failing(monkeypatch, **options):
    """A CoupledNewton (``options``) on the notched plate, solved at 1e-3 mm and then put off
    equilibrium, whose line search always fails and whose displacement relaxation fails after 7
    iterations; returns it and the list of the loads the relaxation was called at."""
    from ngtmc.coupled.iteration import Iteration
    from ngtmc.discrete import NewtonResult
    s = ngtmc.Solver(notched_plate(maxh=0.2, h_band=0.05, l0=0.1))
    c = CoupledNewton(s, **options)
    assert c.solve(1e-3).converged     # the boundary values in place: the next solve starts from them
    s.alpha.vec.FV().NumPy()[:] += 0.01   # off equilibrium, the boundary values kept
    monkeypatch.setattr(Iteration, "search", lambda self, dxN, dlam, merit0, scale_u, lam0: (False, lam0, 0.0, math.inf))
    calls = []

    def relaxation(load):
        calls.append(load)
        return NewtonResult(False, 7, 1.0, 0.0, 0.0, message="relaxation failed")

    monkeypatch.setattr(s, "solve_displacement", relaxation)
    return c, calls


def test_a_failed_solve_counts_the_iterations_of_its_displacement_relaxation(monkeypatch):
    """Where the line search fails the coupled Newton relaxes u at fixed alpha (a displacement
    Newton); the iterations it takes count in the solve's result whether the solve then converges
    or fails, so that a run's Newton iterations (the history, the benchmark records) hold all
    the work done."""
    c, calls = _line_search_failing(monkeypatch)
    r = c.solve(1e-3)
    assert calls == [1e-3] and c.relaxations == 1
    assert not r.converged
    assert r.iterations == 1 + 7   # the coupled iteration whose line search failed, and the relaxation's


@pytest.mark.parametrize("relax_dissipation", [None, False, True])
def test_a_dissipation_solve_relaxes_the_displacement_only_when_asked(monkeypatch, relax_dissipation):
    """``relax_dissipation`` (default True, RELAX_DISSIPATION; None here: not given): with it off a
    solve under dissipation control whose line search fails goes on to the residual floor or fails
    without the displacement relaxation; with it on it relaxes, as a solve at a fixed load always
    does. A value that is not a bool is an error."""
    from ngtmc.coupled.settings import RELAX_DISSIPATION
    assert RELAX_DISSIPATION is True
    options = {} if relax_dissipation is None else {"relax_dissipation": relax_dissipation}
    c, calls = _line_search_failing(monkeypatch, **options)
    relaxes = relax_dissipation is not False
    assert c.relax_dissipation is relaxes
    r = c.solve(1e-3, dissipation=1e-6)
    assert not r.converged
    assert calls == ([1e-3] if relaxes else []) and c.relaxations == int(relaxes)
    assert r.iterations == 1 + 7 * relaxes
    c.solve(1e-3)   # at a fixed load it relaxes either way
    assert len(calls) == 1 + relaxes
    with pytest.raises(ValueError, match="relax_dissipation"):
        CoupledNewton(c.s, relax_dissipation="no")
