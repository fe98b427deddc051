"""Discrete adjoint of the monolithic schemes (ngtmc.sensitivities.coupled) against finite differences.

Scenes (the small scenes of tests/test_sensitivities.py and tests/test_path_following.py):

* the design_for_contact geometry on the coarse mesh of test_sensitivities.py, monolithic (load
  control) to 0.125 mm in 5 steps: contact closes, the damage grows to 0.2 (the crack runs in the
  next step, where the monolithic scheme needs its staggered fallback, which is not
  differentiable); and path following over the whole path to 0.2 mm (contact, crack run with a
  snap-back, 14-18 steps);
* the coarse notched plate of test_path_following.py: monolithic with unloading (0 -> 0.005 ->
  0.003 mm, the phase field held at alpha_{n-1} on the unloading steps), and path following to
  0.0062 mm through the snap-back of its crack (8 dissipation steps; phase-field dofs held at
  alpha_{n-1} and at 1).

Every check compares the adjoint directional derivative with central differences of
:func:`~ngtmc.sensitivities.replay` runs (same step types, loads and dissipation targets), with
the tolerance of test_sensitivities.py (1e-4 relative). The finite-difference step is the
largest of EPS_LIST at which the +eps and -eps replays take the same active sets (a difference
across a switch of the max of the history is not a derivative: on the path-following run of the
contact scene the history points at the crack front are close to a tie, and 1 to 4 of them
switch at eps = 1e-4 .. 1e-5 relative).
"""
from __future__ import annotations

import numpy as np
import pytest

import ngtmc
from ngtmc import sensitivities as S
from ngtmc.sensitivities import coupled as SC
from ngtmc.studies import design_for_contact as D
from scenes import notched_plate, tension_bar

OVERRIDES = {"h_band": 0.2, "h_pad": 0.1, "h": 0.5, "du": 0.025, "l0": 0.3, "Gc": 0.1}
TOL = 1e-4
EPS_LIST = (1e-5, 1e-6)
NEWTON = ngtmc.NewtonOptions(rtol=1e-12)
COUPLED = {"alpha_tol": 1e-12, "linear_solver": "umfpack"}
WRT = ("rho", "E", "nu", "Gc", "l0", "gamma0")


def _contact(scheme, end=None):
    p = D._params("quick", **OVERRIDES)
    schedule = D.schedule(p) if end is None else ngtmc.Schedule([0.0, end])
    return S.record_path(D.build_scene(p), schedule, D.control(p), scheme=scheme, newton=NEWTON, coupled=COUPLED)


def _plate(schedule, scheme):
    control = ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7)
    return S.record_path(notched_plate(maxh=0.2, h_band=0.05, l0=0.1), schedule, control, scheme=scheme,
                         newton=NEWTON, coupled=COUPLED)


@pytest.fixture(scope="module")
def contact_monolithic():
    return _contact("monolithic", 0.125)


@pytest.fixture(scope="module")
def contact_path():
    return _contact("path-following")


@pytest.fixture(scope="module")
def plate_unloading():
    return _plate(ngtmc.Schedule([0.0, 0.005, 0.003]), "monolithic")


@pytest.fixture(scope="module")
def plate_path():
    return _plate(0.0062, "path-following")


def _objectives(path):
    return {
        "external_work": S.ExternalWork(),
        "reaction_last": S.ReactionAtStep(-1),
        "reaction_4": S.ReactionAtStep(4),
        "fracture_energy": S.FinalFractureEnergy(),
        "compliance": S.ComplianceAtStep(-2),
        "combination": S.ExternalWork() - 2.0 * S.FinalFractureEnergy(),
        # a monotone measured curve through the range of the path (the misfit depends on the loads)
        "curve_misfit": S.ForceCurveObjective.least_squares(
            [0.0, 0.5 * path.loads.max(), path.loads.max()], [0.0, 0.8 * path.forces.max(), 0.1 * path.forces.max()]),
    }


def _directions(path, with_pad=False):
    rng = np.random.default_rng(1)
    d = 0.1 * rng.standard_normal(path.rho.size)
    if with_pad:  # the void pad (rho = 0): keep rho +- eps d away from negative stiffness
        d = rng.standard_normal(path.rho.size)
        pad = S.design_mask(path, "pad")
        d[pad] = 5e-3 * rng.uniform(-1.0, 1.0, int(pad.sum()))
    out = {"rho": {"rho": d}}
    for k in ("E", "nu", "Gc", "l0") + (("gamma0",) if with_pad else ()):
        out[k] = {k: S.parameter_value(path, k)}  # relative steps
    return out


def _check(path, label, with_pad=False):
    objs = _objectives(path)
    names = list(objs)
    grads = {k: S.gradient(path, o, wrt=WRT) for k, o in objs.items()}
    worst = 0.0
    print(f"\n{label}: {path.n_steps} steps ({int(path.dissipation_steps.sum())} dissipation steps), "
          f"gradient {np.mean([g['time'] for g in grads.values()]):.2f} s per objective, forward {path.forward_time:.2f} s")
    for dname, d in _directions(path, with_pad).items():
        adj = np.array([S.directional_derivative(grads[k], d) for k in names])
        for eps in EPS_LIST:
            fd, paths = S.directional_fd(path, [objs[k] for k in names], d, eps, return_paths=True)
            switches = S.active_set_changes(*paths)["history"]
            if switches == 0:
                break
        assert switches == 0, f"{dname}: the history active set switches at every eps of {EPS_LIST}"
        rel = np.abs(fd - adj) / np.abs(adj)
        print(f"  {dname:6s} eps {eps:g}: " + " ".join(f"{k} {r:.1e}" for k, r in zip(names, rel)))
        for k, r, a, f in zip(names, rel, adj, fd):
            assert r <= TOL, f"{label}, d {k} / d {dname}: FD {f:.8e}, adjoint {a:.8e}"
        worst = max(worst, float(rel.max()))
    path.activate()
    return worst


# ---------------------------------------------------------------------- monolithic (load control)
def test_alpha_rows_reproduce_the_coupled_residual(plate_unloading):
    """The alpha rows of the coupled residual that the sweep differentiates
    (:func:`alpha_residual_pieces`) are those of CoupledNewton's form, at a damaged state."""
    import ngsolve as ngs
    path = plate_unloading
    s, c = path.solver, path.coupled
    n = 5
    path.activate(n)
    s.H.vec.FV().NumPy()[:] = path.state(n - 1)["H"]
    c._gather()
    r = c.x.vec.CreateVector()
    c.form.Apply(c.x.vec, r)
    lf = ngs.LinearForm(s.fes_a)
    for cf, meas in SC.alpha_residual_pieces(s, s.fes_a.TestFunction()):
        lf += cf * meas
    lf.Assemble()
    rows = r.FV().NumPy()[c.nu:]
    scale = np.abs(lf.vec.FV().NumPy()).max() + c.alpha_residual_scale
    assert np.abs(lf.vec.FV().NumPy() - rows).max() <= 1e-12 * scale
    path.activate()


def test_replay_reproduces_the_monolithic_path(plate_unloading):
    r = S.replay(plate_unloading)
    assert np.allclose(r.forces, plate_unloading.forces, rtol=1e-9, atol=1e-12)
    assert np.allclose(r.states[-1]["alpha"], plate_unloading.states[-1]["alpha"], atol=1e-10)
    plate_unloading.activate()


def test_monolithic_gradients_contact(contact_monolithic):
    path = contact_monolithic
    assert path.n_steps == 5 and not np.any(path.dissipation_steps)
    assert path.states[-1]["alpha"].max() > 0.1
    _check(path, "monolithic, contact scene", with_pad=True)


def test_monolithic_gradients_with_unloading(plate_unloading):
    """Unloading after damage: on the unloading steps every phase-field dof is held at alpha_{n-1}
    and no history point grows, so the adjoint passes through the held bound and the inactive max."""
    path = plate_unloading
    held = [int(SC.held_sets(path, n)[0].sum()) for n in range(1, path.n_steps + 1)]
    growing = [int(np.sum(path.state(n)["H"] > path.state(n - 1)["H"])) for n in range(1, path.n_steps + 1)]
    print(f"\nheld at alpha_(n-1) per step {held}, growing history points {growing}")
    assert held[-1] == path.solver.fes_a.ndof and growing[-1] == 0
    _check(path, "monolithic, plate with unloading")


# ---------------------------------------------------------------------- path following
def test_path_following_gradients_through_the_snap_back(plate_path):
    path = plate_path
    diss = path.dissipation_steps
    loads = path.loads
    assert diss.sum() >= 5
    assert np.any(np.diff(loads) < 0)  # the load falls back on a dissipation step (snap-back)
    held_lo = sum(int(SC.held_sets(path, n)[0].sum()) for n in range(1, path.n_steps + 1))
    held_up = sum(int(SC.held_sets(path, n)[1].sum()) for n in range(1, path.n_steps + 1))
    assert held_lo > 0 and held_up > 0
    # the dissipation constraint holds on the recorded dissipation steps
    c = path.coupled
    for n in np.flatnonzero(diss):
        dD = c.D.value(path.state(n)["alpha"]) - c.D.value(path.state(n - 1)["alpha"])
        assert dD == pytest.approx(path.dissipation[n], rel=1e-9)
    _check(path, "path following, notched plate")


def test_path_following_taylor_remainder_is_quadratic(plate_path):
    """|J(p + eps d) - J(p) - eps dJ.d| falls as eps^2 (external work, rho + Gc together), between
    consecutive eps at which no history point switches branch (a remainder across a switch is not
    that of a derivative); at least three such eps."""
    path = plate_path
    d = {"rho": 0.1 * np.random.default_rng(2).standard_normal(path.rho.size), "Gc": 0.02}
    g = S.gradient(path, S.ExternalWork(), wrt=("rho", "Gc"))
    t = S.taylor_test(path, S.ExternalWork(), d, g, eps_list=(4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4))
    print("\nTaylor test (path following, ExternalWork, rho + Gc): remainders",
          [f"{r:.2e}" for r in t["remainder"]], "orders", [f"{o:.2f}" for o in t["order"]],
          "history switches", t["switches"])
    clean = [o for o, a, b in zip(t["order"], t["switches"], t["switches"][1:]) if a == 0 and b == 0]
    assert len(clean) >= 2, t
    assert all(1.8 <= o <= 2.3 for o in clean)


def test_path_following_gradients_contact(contact_path):
    path = contact_path
    assert path.dissipation_steps.sum() >= 5 and path.loads[-1] == pytest.approx(0.2)
    _check(path, "path following, contact scene", with_pad=True)


def test_path_following_replay_holds_the_dissipation_targets(plate_path):
    """A replay with another Gc keeps the step types and dD_n; its loads move on dissipation steps only."""
    path = plate_path
    r = S.replay(path, parameters={"Gc": 1.01 * S.parameter_value(path, "Gc")})
    diss = path.dissipation_steps
    assert np.array_equal(np.isfinite(r.dissipation), diss)
    assert np.array_equal(r.loads[~diss], path.loads[~diss])
    assert np.all(r.loads[diss] != path.loads[diss])
    c = path.coupled
    for n in np.flatnonzero(diss):
        dD = c.D.value(r.state(n)["alpha"]) - c.D.value(r.state(n - 1)["alpha"])
        assert dD == pytest.approx(path.dissipation[n], rel=1e-9)
    path.activate()


# ---------------------------------------------------------------------- what is refused
def test_errors(plate_path):
    sc = tension_bar(maxh=0.2)
    sc.load = ngtmc.Traction("right", (1.0, 0.0))
    with pytest.raises(ValueError, match="Traction"):
        S.record_path(sc, 0.1, scheme="monolithic")
    with pytest.raises(ValueError, match="scheme"):
        S.record_path(tension_bar(maxh=0.2), 0.01, scheme="staggered")
    with pytest.raises(ValueError, match="checkpointing"):
        S.record_path(tension_bar(maxh=0.2), 0.01, scheme="monolithic", checkpoint_every=2)
    # a step taken by the single-pass fallback of the monolithic scheme (the crack runs at fixed load)
    with pytest.raises(ValueError, match="not solved by the coupled Newton"):
        S.record_path(notched_plate(maxh=0.2, h_band=0.05, l0=0.1), 0.007, ngtmc.AdaptiveStepControl(du_max=1e-3),
                      scheme="monolithic", newton=NEWTON, coupled=dict(COUPLED, fallback="single-pass"))

    class NoLoadSeeds(S.Objective):
        def value(self, path):
            return float(path.forces[-1])

        def seeds(self, path, n):
            return S.Seeds(force=1.0) if n == path.n_steps else None

    with pytest.raises(NotImplementedError, match="load_seeds"):
        S.gradient(plate_path, NoLoadSeeds())


def test_path_following_adjoint_follows_the_split():
    """The coupled adjoint differentiates the scene's split (history and alpha rows): the notched
    plate with the "vol-dev-small" hybrid pair, path following through its snap-back. (The
    "spectral" anisotropic pair agrees too, 8e-8 and 6e-7 relative at eps = 1e-5, but its gradient
    takes about 26 s here: the symbolic derivatives of the spectral split are slow to build.)"""
    sc = notched_plate(maxh=0.2, h_band=0.05, l0=0.1, split="vol-dev-small", formulation="hybrid")
    path = S.record_path(sc, 0.0062, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                         scheme="path-following", newton=NEWTON, coupled=COUPLED)
    assert path.dissipation_steps.sum() >= 5 and path.solver.max_alpha() > 0.99
    rng = np.random.default_rng(1)
    d = {"rho": 0.1 * rng.standard_normal(path.rho.size), "E": 2100.0, "Gc": 0.03}
    objs = [S.ExternalWork(), S.ReactionAtStep(-1)]
    adj = np.array([S.directional_derivative(S.gradient(path, o, wrt=("rho", "E", "Gc")), d) for o in objs])
    fd, paths = S.directional_fd(path, objs, d, EPS_LIST[0], return_paths=True)
    rel = np.abs(fd - adj) / np.abs(adj)
    print("\nvol-dev-small hybrid, path following: relative FD errors", [f"{r:.1e}" for r in rel],
          "history switches", S.active_set_changes(*paths)["history"])
    assert S.active_set_changes(*paths)["history"] == 0
    assert np.all(rel <= TOL)
