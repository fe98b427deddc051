"""Path following of the monolithic scheme (ngtmc.stepping.path, CoupledNewton.solve with ``dissipation``):
the dissipation it controls is that of the recorded history, a dissipation step ends in an
equilibrium of the fixed-load problem at the load it found, and a crack that snaps back is
followed through the snap-back in a few steps."""
import numpy as np
import pytest

import ngtmc
from ngtmc.coupled import CoupledNewton
from ngtmc.stepping.control import attempt_info
from scenes import notched_plate


def _plate():
    return notched_plate(maxh=0.2, h_band=0.05, l0=0.1)


def _loaded(load=0.005):
    """Notched plate loaded by the monolithic scheme to ``load`` mm (before the crack runs)."""
    sim = ngtmc.Simulation(_plate(), load, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7), scheme="monolithic")
    sim.run()
    return sim


def test_dissipation_is_the_recorded_dissipated_energy():
    """D = 1/2 alpha^T M alpha of the path equals W_f / c_w of the history (per mm of thickness),
    and the reference toughness is the plate's Gc (2.7 N/mm)."""
    sim = _loaded(0.004)
    c = sim.coupled
    en = sim.solver.energies()
    assert en["dissipated_energy"] > 0
    assert c.D.value() == pytest.approx(en["dissipated_energy"] / sim.solver.thickness, rel=1e-10)
    assert c.D.reference_toughness() == pytest.approx(2.7, rel=1e-12)


def test_dissipation_step_ends_in_the_equilibrium_of_its_load():
    """A dissipation step from an accepted state dissipates the prescribed energy (to 1e-6 of
    it), keeps alpha >= alpha_{n-1}, and its state is an equilibrium of the fixed-load coupled
    problem at the load it found: the load-controlled Newton started there takes no iteration."""
    sim = _loaded(0.005)
    s, c = sim.solver, sim.coupled
    d0 = c.D.value()
    a0 = s.alpha_committed.copy()
    dD = 0.05  # N mm per mm, about 0.02 mm of crack at Gc = 2.7 N/mm
    res = s.solve_displacement(0.0051)
    assert res.converged
    res = c.solve(0.0051, dissipation=dD, load_bounds=(0.0, 0.012))
    assert res.converged, res.message
    lam = c.load_solved
    print(f"\ndissipation step: load {lam:.6g} mm after {res.iterations} iterations")
    assert c.D.value() - d0 == pytest.approx(dD, rel=1e-6)
    assert np.all(s.alpha.vec.FV().NumPy() >= a0)
    again = c.solve(lam)
    assert again.converged and again.iterations == 0


def test_path_following_passes_the_snap_back_in_few_steps():
    """The crack of the notched plate runs unstably: under dissipation control the load falls
    back along the snap-back (the load decreases over accepted steps while the force drops) and
    the whole curve to 0.012 mm takes a few tens of steps. alpha and the history never decrease,
    and the final state (a broken plate) carries the force of the load-controlled monolithic run
    (both converged at 0.012 mm)."""
    states = []

    def run(coupled):
        sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                               scheme="monolithic", coupled=coupled)
        cb = [lambda s, row: states.append((s.solver.H_committed.copy(), s.solver.alpha.vec.FV().NumPy().copy()))]
        return sim, sim.run(callbacks=cb if coupled else ()).history

    sim, h = run({"path": "dissipation"})
    _, ref = run(None)
    load, force = h["load"].to_numpy(), h["force"].to_numpy()
    back = np.diff(load) < 0
    print(f"\npath following: {len(h) - 1} steps ({sim._path.dissipation_steps} under dissipation control), "
          f"{int(h.newton_iterations.sum())} iterations, peak {force.max():.5g} N; load control: {len(ref) - 1} steps, "
          f"{int(ref.newton_iterations.sum())} iterations, peak {ref.force.max():.5g} N; final force {force[-1]:.5g} "
          f"against {ref.force.iloc[-1]:.5g} N")
    assert back.sum() >= 2 and np.all(np.diff(force)[back] < 0)
    assert load[-1] == pytest.approx(0.012)
    assert len(h) - 1 < 40
    assert sim._path.dissipation_steps >= 5
    assert force[-1] < 0.01 * force.max() and ref.force.iloc[-1] < 0.01 * ref.force.max()
    assert force.max() == pytest.approx(ref.force.max(), rel=0.01)  # both peaks sampled at du_max steps
    assert h["max_alpha"].iloc[-1] > 0.99
    for (H0, a0), (H1, a1) in zip(states, states[1:]):
        assert np.all(H1 >= H0) and np.all(a1 >= a0)


def _growth_stepper(**coupled):
    """A path-following Simulation of the plate and ``step(iterations, cutbacks, converged_at,
    forward)``, which feeds DissipationPath.accepted a dissipation step with those numbers (the
    factor of the attempt that converged: halved per cut-back by the step control's scale) and
    returns the growth factor after it."""
    sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7),
                           scheme="path-following", coupled=coupled)
    path, s = sim._path, sim.solver

    def step(iterations, cutbacks=0, converged_at=None, forward=True):
        path._last_kind = "dissipation"
        path._factor_tried = converged_at if converged_at is not None else path.factor
        s.load = path.predictor.load_n + (1e-5 if forward else -1e-5)
        path.accepted(1e-5, iterations=iterations, cutbacks=cutbacks)
        return path.sizing.growth

    return path, step


def test_without_the_growth_ceiling_a_cut_back_sets_none():
    """coupled={"growth_ceiling": False}: a cut-back sets no ceiling; the growth factor is kept (the
    step control's halved scale alone shrinks the next steps until it recovers) and easy steps
    double it as before (the L-panel's long crack run, docs/performance.md)."""
    from ngtmc.stepping.sizing import GROWTH_MAX
    path, step = _growth_stepper(growth_ceiling=False)
    assert path.sizing.option is False

    path.sizing.growth = 1.0
    assert step(20, cutbacks=1, converged_at=0.5) == 1.0        # not lowered to 0.5, no ceiling
    assert path.sizing.ceiling == GROWTH_MAX
    assert [step(4) for _ in range(4)] == [2.0, 4.0, 8.0, GROWTH_MAX]


def test_a_dissipation_step_predicted_past_du_max_is_scaled_before_it_is_solved():
    """Rule 3 of ngtmc.stepping.path before the solve (``prescale``, off by default): after a
    dissipation step, where the secant through the last two states moves the load by more than
    du_max, dD (and the growth factor) is scaled down at once. Both runs follow the same curve
    (the peaks, sampled by different steps, within 0.5 %) and break the plate; no accepted
    dissipation step moves the load by more than du_max in either run."""
    runs = {}
    for prescale in (True, False):
        sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                               scheme="path-following", coupled={"prescale": prescale})
        count = [0]
        sim.run(callbacks=[lambda s, row: count.append(s._path.dissipation_steps)])
        h = sim.history
        runs[prescale] = (sim, h)
        dl = np.abs(np.diff(h["load"].to_numpy()))
        dissipation = np.diff(count) > 0   # the steps under dissipation control
        assert len(dissipation) == len(dl) and dissipation.sum() >= 5
        assert np.all(dl[dissipation] <= sim.control.du_max * (1 + 1e-9))
    (on, h_on), (off, h_off) = runs[True], runs[False]
    c_on, c_off = on.counters()["coupled"], off.counters()["coupled"]
    print(f"\nprescaled: {c_on['dissipation_prescaled']} scaled before, {c_on['dissipation_resolved']} solved again, "
          f"{int(h_on.newton_iterations.sum())} iterations, peak {h_on.force.max():.6g} N; only after: "
          f"{c_off['dissipation_resolved']} solved again, {int(h_off.newton_iterations.sum())} iterations, "
          f"peak {h_off.force.max():.6g} N")
    assert c_on["dissipation_prescaled"] >= 1 and c_off["dissipation_prescaled"] == 0
    assert c_off["dissipation_resolved"] >= 1
    assert h_on.force.max() == pytest.approx(h_off.force.max(), rel=5e-3)
    assert h_on.force.iloc[-1] < 0.01 * h_on.force.max() and h_off.force.iloc[-1] < 0.01 * h_off.force.max()


def test_path_options_are_checked():
    with pytest.raises(ValueError, match="growth_ceiling"):
        ngtmc.Simulation(_plate(), 0.01, scheme="path-following", coupled={"growth_ceiling": "no"})
    with pytest.raises(ValueError, match="prescale"):
        ngtmc.Simulation(_plate(), 0.01, scheme="path-following", coupled={"prescale": "yes"})
    with pytest.raises(ValueError, match="chord"):
        ngtmc.Simulation(_plate(), 0.01, scheme="path-following", coupled={"chord": 1})
    with pytest.raises(ValueError, match="weak_stop"):
        ngtmc.Simulation(_plate(), 0.01, scheme="path-following", coupled={"weak_stop": 1})
    with pytest.raises(ValueError, match="path"):
        ngtmc.Simulation(_plate(), 0.01, scheme="monolithic", coupled={"path": "arc-length"})
    with pytest.raises(ValueError, match="crack_advance"):
        ngtmc.Simulation(_plate(), 0.01, scheme="monolithic", coupled={"path": "dissipation", "crack_advance": -1})
    with pytest.raises(ValueError, match="dissipation"):
        CoupledNewton(ngtmc.Solver(_plate())).solve(0.001, dissipation=0.0)


def test_resumed_path_following_continues_the_same_path():
    """A run stopped after 8 steps and resumed from Simulation.get_state (the rule's scalars and
    the two states of its secant predictor) takes the same steps as the uninterrupted run.
    Both use UMFPACK (bitwise reproducible; sparsecholesky is not, tests/test_traps.py): with
    sparsecholesky, a step that only just converges in one run may be cut back in the other, and
    the two runs then take different sequences of steps (seen in CI: 32 against 29 steps)."""
    def sim():
        return ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                                scheme="path-following", coupled={"linear_solver": "umfpack"},
                                newton=ngtmc.NewtonOptions(linear_solver="umfpack"))
    whole = sim().run().history
    first = sim()
    for _ in range(8):
        first.advance()
    state = first.get_state()
    assert set(state["arrays"]) == {"path_u_n", "path_alpha_n", "path_u_prev", "path_alpha_prev"}
    second = sim()
    second.set_state(state)
    resumed = second.run().history
    assert len(resumed) == len(whole)
    assert np.allclose(resumed["load"], whole["load"], rtol=1e-6, atol=1e-12)
    assert np.allclose(resumed["force"], whole["force"], rtol=1e-5, atol=1e-6)


def test_displacement_steps_of_path_following_are_bounded_by_the_curve_resolution():
    """Under path following a displacement step carries no lag, so its bound is 1/PATH_STEPS of
    the load path (or ``coupled["du_max"]``), not the lagged schemes' du_max: the first step of
    the plate (elastic, nothing dissipates yet) is 0.012/50 mm with du_max = 1e-4 mm."""
    from ngtmc.simulation.loop import PATH_STEPS
    control = ngtmc.AdaptiveStepControl(du_max=1e-4, du_min=1e-7)
    sim = ngtmc.Simulation(_plate(), 0.012, control, scheme="path-following")
    assert sim.control.du_max == pytest.approx(0.012 / PATH_STEPS)
    row = sim.advance()
    assert row["step_size"] == pytest.approx(0.012 / PATH_STEPS, rel=1e-9)
    own = ngtmc.Simulation(_plate(), 0.012, control, scheme="path-following", coupled={"du_max": 5e-4})
    assert own.control.du_max == 5e-4
    with pytest.raises(ValueError, match="du_min"):
        ngtmc.Simulation(_plate(), 0.012, control, scheme="path-following", coupled={"du_max": 1e-9})
    with pytest.raises(ValueError, match="path following only"):
        ngtmc.Simulation(_plate(), 0.012, control, scheme="monolithic", coupled={"du_max": 5e-4})


def test_turning_point_starts_the_rule_afresh():
    """Load to 0.007 mm (damage grows under dissipation control near the peak), unload to
    0.005 mm and reload to 0.012 mm: the unloading segment dissipates nothing and takes
    displacement steps (the rule's rate and hysteresis of the loading segment are dropped at the
    turning point), and the run completes through the crack run on reloading."""
    sched = ngtmc.Schedule([0.0, 0.007, 0.005, 0.012])
    sim = ngtmc.Simulation(_plate(), sched, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                           scheme="path-following")
    h = sim.run().history
    load = h["load"].to_numpy()
    i_turn = int(np.argmax(load >= 0.007 - 1e-12))
    j_back = i_turn + int(np.argmax(load[i_turn:] <= 0.005 + 1e-12))
    unload = h.iloc[i_turn:j_back + 1]
    print(f"\ncycle: {len(h) - 1} steps, unloading {len(unload) - 1} steps, dissipated while unloading "
          f"{unload.dissipated_energy.iloc[-1] - unload.dissipated_energy.iloc[0]:.3e} N mm")
    assert load[-1] == pytest.approx(0.012)
    assert np.all(np.diff(unload["load"]) < 0)
    assert unload.dissipated_energy.iloc[-1] - unload.dissipated_energy.iloc[0] <= 1e-9 * h.dissipated_energy.max()
    assert h["max_alpha"].iloc[-1] > 0.99


def test_a_cut_back_sets_a_ceiling_on_the_growth_of_the_dissipation_step():
    """The growth factor of dD doubles after easy steps of stable growth; a cut-back sets a ceiling
    at the factor (scale times growth) at which the step converged, at least CEILING_MIN, that holds
    until GROWTH_CEILING_STEPS easy steps at it double it (so a tail that failed at 16x runs at 8x,
    not in cycles of 1, 2, 4, 8, 16, and a crack run that failed at the base runs at half of it
    also after the step control's scale has recovered)."""
    from ngtmc.stepping.sizing import CEILING_MIN, GROWTH_CEILING_STEPS, GROWTH_MAX
    path, step = _growth_stepper()

    path.sizing.growth = 1.0
    assert [step(4) for _ in range(5)] == [2.0, 4.0, 8.0, GROWTH_MAX, GROWTH_MAX]
    assert step(20, cutbacks=1, converged_at=GROWTH_MAX / 2) == GROWTH_MAX / 2   # failed at 16: ceiling 8
    assert [step(4) for _ in range(GROWTH_CEILING_STEPS - 1)] == [GROWTH_MAX / 2] * (GROWTH_CEILING_STEPS - 1)
    assert step(4) == GROWTH_MAX                                    # the ceiling doubles again
    assert step(9) == GROWTH_MAX                                    # a hard step keeps the factor
    assert step(20, cutbacks=2, converged_at=GROWTH_MAX / 4) == GROWTH_MAX / 4
    # a crack run: failed at the base (factor 1), converged at half of it; snap-back steps (the load
    # goes back) double the growth up to 1, but not past the ceiling
    path.sizing.growth, path.sizing.ceiling = 1.0, GROWTH_MAX
    assert step(20, cutbacks=1, converged_at=0.5) == 0.5
    assert path.sizing.ceiling == 0.5
    assert [step(6, forward=False) for _ in range(3)] == [0.5] * 3
    path.sizing.growth = 1.0
    assert step(20, cutbacks=3, converged_at=0.125) == 0.125        # the next step starts where this one converged,
    assert path.sizing.ceiling == CEILING_MIN                              # below a ceiling of at least CEILING_MIN
    assert [step(4) for _ in range(3)] == [0.25, 0.5, 0.5]
    state = path.get_state()
    assert state["ceiling"] == CEILING_MIN and state["at_ceiling"] == 1   # one step taken at it
    # snap-back steps at the ceiling count towards GROWTH_CEILING_STEPS too
    assert [step(6, forward=False) for _ in range(GROWTH_CEILING_STEPS - 2)] == [0.5] * (GROWTH_CEILING_STEPS - 2)
    assert path.sizing.ceiling == CEILING_MIN
    assert step(6, forward=False) == 1.0 and path.sizing.ceiling == 2 * CEILING_MIN and path.sizing.at_ceiling == 0
    assert step(6, forward=False) == 1.0                            # a snap-back step: not past the base


def test_the_growth_ceiling_is_on_by_default_where_the_crack_is_meshed_finer_than_l0():
    """growth_ceiling="auto" (the default): a cut-back sets a ceiling where the median element
    holding alpha >= CRACK_ALPHA is no larger than CEILING_MAX_H = 1.5 l0 (or nothing is cracked
    yet), none where the crack crosses larger elements (a step of one l0 of crack is then a
    fraction of an element); True and False force it."""
    import warnings

    def applies(l0, alpha_band, **coupled):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
            sim = ngtmc.Simulation(notched_plate(maxh=0.2, h_band=0.05, l0=l0), 0.01,
                                   scheme="path-following", coupled=coupled)
        s = sim.solver
        pts = np.array([v.point for v in s.mesh.vertices])
        a = s.alpha.vec.FV().NumPy()
        a[:] = 0.0
        a[:len(pts)][(np.abs(pts[:, 1] - 0.5) < alpha_band) & (pts[:, 0] > 0.3)] = 1.0   # the ligament
        return sim._path.sizing.ceiling_applies()

    assert applies(0.1, 0.0) is True          # nothing cracked: a ceiling
    assert applies(0.1, 0.03) is True         # elements of 0.05 mm, l0 = 0.1 mm
    assert applies(0.02, 0.03) is False       # the same elements, l0 = 0.02 mm
    assert applies(0.045, 0.03) is True       # the same elements, about 1.2 l0 (CEILING_MAX_H = 1.5)
    assert applies(0.02, 0.03, growth_ceiling=True) is True
    assert applies(0.1, 0.03, growth_ceiling=False) is False


def test_a_very_easy_step_at_the_ceiling_doubles_it_at_once():
    """A step at the ceiling that took at most CEILING_EASY_ITERATIONS Newton iterations doubles the
    ceiling at once, forward or snap-back (the quick L-panel's crack run, where steps at half the base
    take 2-3 iterations, would otherwise run at half the base for 16 steps after each cut-back)."""
    from ngtmc.stepping.sizing import CEILING_EASY_ITERATIONS, GROWTH_MAX
    path, step = _growth_stepper()

    path.sizing.growth = 1.0
    assert step(20, cutbacks=1, converged_at=0.5) == 0.5 and path.sizing.ceiling == 0.5
    assert step(CEILING_EASY_ITERATIONS + 1, forward=False) == 0.5 and path.sizing.ceiling == 0.5
    assert step(CEILING_EASY_ITERATIONS, forward=False) == 1.0 and path.sizing.ceiling == 1.0
    assert step(CEILING_EASY_ITERATIONS) == 2.0 and path.sizing.ceiling == 2.0      # stable growth beyond the base
    assert step(CEILING_EASY_ITERATIONS + 4) == 2.0 and path.sizing.ceiling == 2.0  # a hard step: neither moves
    while path.sizing.ceiling < GROWTH_MAX:
        step(CEILING_EASY_ITERATIONS)
    assert step(CEILING_EASY_ITERATIONS) == GROWTH_MAX and path.sizing.ceiling == GROWTH_MAX


def test_the_step_controls_scale_halves_the_dissipation_step_only_within_a_step():
    """dD is the base times the growth factor, halved with each failed attempt of the step (the step
    control's scale against its value when the step began); the step control's recovery of its
    scale over the next steps does not move dD: the growth factor and its ceiling hold that memory."""
    sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7),
                           scheme="path-following")
    path = sim._path
    base = path.gc_ref * path.crack_advance
    path.sizing.growth = 1.0
    assert path.target == pytest.approx(base)
    sim.control_state, _ = sim.control.failed(sim.control_state, 1e-4)   # a failed attempt: half
    assert path.target == pytest.approx(base / 2)
    path._last_kind, path._factor_tried = "dissipation", path.factor
    sim.solver.load = path.predictor.load_n + 1e-5
    path.accepted(1e-5, iterations=20, cutbacks=1)
    assert path.target == pytest.approx(base / 2)                       # the next step: where it converged
    sim.control_state = sim.control.initial_state()                      # the step control's scale recovers
    path._scale_ref = sim.control_state.scale * 0.5                      # (its value when that step began)
    assert path.target == pytest.approx(base)                           # only within a step would that count
    path._scale_ref = sim.control_state.scale
    assert path.target == pytest.approx(base / 2)
    assert path.get_state()["scale_ref"] == 1.0


def test_a_secant_predictor_that_inverts_an_element_is_damped(monkeypatch):
    """Where the full secant through the last two states would invert an element (min J <= 0:
    a squeezed void), the predictor takes the first fraction of it in SECANT_DAMPING that keeps
    J > 0: here the full secant is refused once, so the predictor is u_n + 0.5 (u_n - u_{n-1}) on
    the free dofs, the boundary values those of the step's load, and alpha as extrapolated by
    half, kept in [alpha_n, 1]. If every fraction inverts, the state is left as it was."""
    from ngtmc.stepping.secant import SECANT_DAMPING
    assert SECANT_DAMPING[0] == 1.0 and SECANT_DAMPING[1] == 0.5
    sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7),
                           scheme="path-following")
    sim.advance()
    sim.advance()
    path, s = sim._path, sim.solver
    (u_n, a_n), (u_p, a_p) = path.predictor.x_n, path.predictor.x_prev
    load = path.predictor.load_n + (path.predictor.load_n - path.predictor.load_prev)
    real_min_J = s.min_J
    calls = []

    def min_J_refusing_the_full_secant():
        calls.append(1)
        return -1.0 if len(calls) == 1 else real_min_J()

    monkeypatch.setattr(s, "min_J", min_J_refusing_the_full_secant)
    assert path.predictor.set(1.0, load) == load
    assert len(calls) == 2
    uN = s.u.vec.FV().NumPy()
    free = s._free_np
    np.testing.assert_allclose(uN[free], (u_n + 0.5 * (u_n - u_p))[free], rtol=0, atol=1e-15)
    np.testing.assert_allclose(uN[~free], s.dirichlet_target(load)[~free], rtol=0, atol=1e-15)
    np.testing.assert_allclose(s.alpha.vec.FV().NumPy(), np.clip(a_n + 0.5 * (a_n - a_p), a_n, 1.0), atol=1e-15)

    before = uN.copy()
    monkeypatch.setattr(s, "min_J", lambda: -1.0)
    assert path.predictor.set(1.0, load) is None
    np.testing.assert_array_equal(s.u.vec.FV().NumPy(), before)


def _failing_dissipation(sim):
    """Make every dissipation solve of ``sim`` fail."""
    from ngtmc.discrete import NewtonResult
    c = sim.coupled
    solve = c.solve

    def failing(load, alpha_upper=None, dissipation=None, load_bounds=None):
        if dissipation is None:
            return solve(load, alpha_upper, dissipation, load_bounds)
        c.load_out_of_bounds = None
        return NewtonResult(False, 1, 1.0, 0.0, 0.0, 0, "made to fail")
    c.solve = failing


def test_path_following_takes_a_displacement_step_where_the_damage_does_not_respond():
    """Where the last attempt of a step (du < 2 du_min) fails as a dissipation step (the crack has
    arrested, or the solve stalled at every dD), the step becomes a displacement step of du
    (rule 3 of ngtmc.stepping.path): with every dissipation solve failing, the run goes on by displacement
    steps alone (to 0.0055 mm, before the snap-back, which fixed-load steps cannot pass); where
    that displacement step fails too, the run fails at du_min with both messages."""
    def sim():
        return ngtmc.Simulation(_plate(), 0.0055, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=0.6e-3),
                                scheme="path-following")
    ref = sim()
    ref.run()
    assert ref._path.dissipation_steps > 0
    a = sim()
    _failing_dissipation(a)
    h = a.run().history
    assert a._path.dissipation_steps == 0
    assert h["load"].iloc[-1] == pytest.approx(0.0055)
    assert np.all(np.diff(h["load"].to_numpy()) > 0)
    # where that displacement step fails too, the run fails at du_min and says both
    c = sim()
    _failing_dissipation(c)
    last_flags = []

    def no_displacement_step(saved, t_new, info, last):
        last_flags.append(last)
        info["message"] = "displacement step made to fail"
        return False, info
    c._path._displacement_step = no_displacement_step
    with pytest.raises(ngtmc.StepFailure, match="made to fail; then a displacement step: displacement step made to fail"):
        c.run()
    assert last_flags and all(last_flags)   # only the last attempt, and flagged as the last


def test_a_displacement_step_that_the_coupled_newton_cannot_close_falls_back_to_staggered_passes(monkeypatch):
    """Path following's displacement steps taken instead of a dissipation step end, where the
    coupled Newton fails, in the monolithic scheme's fallback (coupled["fallback"], default
    converged staggered passes at that load): the step is closed, in equilibrium, with
    staggered_iterations > 0 (which the adjoint refuses). The probing displacement step before a
    dissipation step has no fallback: there the dissipation step follows. Here the coupled Newton
    is made to fail on the notched plate before its crack runs, where the staggered passes
    converge in a few passes."""
    sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7),
                           scheme="path-following")
    for _ in range(3):
        sim.advance()
    path, s = sim._path, sim.solver
    saved = s.get_state()
    load = path.predictor.load_n + 1e-3

    def fail(load, info, alpha_upper=None):
        info["message"] = "made to fail"
        return False, info

    monkeypatch.setattr(sim, "_coupled_newton", fail)
    ok, out = path._fixed(load, attempt_info())
    assert not ok and out["message"] == "made to fail"
    s.set_state(saved)
    ok, out = path._fixed(load, attempt_info(), fallback=True)
    assert ok and out["staggered_iterations"] >= 1
    assert s.load == pytest.approx(load)
    again = s.solve_displacement(load)                  # u is in equilibrium at that load and alpha
    assert again.converged and again.iterations == 0


def test_the_last_attempts_displacement_step_starts_from_the_accepted_state(monkeypatch):
    """A displacement step taken on a step's last attempt (du < 2 du_min, ``fallback``) starts
    from the last accepted state, not from the secant predictor: the secant scales the last step's
    change by the ratio of the load changes, and after a dissipation step at an almost constant
    load (a snap-back) that ratio asks for a whole crack advance per 1e-8 mm. The paper L-panel
    failed so at 6.2093 mm (docs/performance.md): from the secant its last attempt began 60 times
    further from equilibrium than the accepted state and stalled; from that state it closed. Here
    the secant is made wrong (the state before the last one moved): the step must not use it, and
    closes at once next to the accepted state."""
    sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7),
                           scheme="path-following")
    for _ in range(3):
        sim.advance()
    path, s = sim._path, sim.solver
    u_prev, a_prev = path.predictor.x_prev
    path.predictor.x_prev = (u_prev - 50.0 * (path.predictor.x_n[0] - u_prev), a_prev)   # a wrong secant
    accepted = s.get_state()
    used = []
    set_secant = path.predictor.set
    monkeypatch.setattr(path.predictor, "set", lambda *a, **k: used.append(a) or set_secant(*a, **k))
    load = path.predictor.load_n + 1e-8
    ok, out = path._fixed(load, attempt_info(), fallback=True)
    assert ok and not used and out["staggered_iterations"] == 0
    assert out["newton_iterations"] <= 2
    assert s.load == pytest.approx(load, abs=1e-15)
    du = s.u.vec.FV().NumPy() - accepted["u"]
    assert np.abs(du).max() < 5 * 1e-8   # u moved by the order of the load change (1e-8 mm)
    # the probing displacement step (no fallback) still starts from the secant
    s.set_state(accepted)
    path._fixed(load, attempt_info())
    assert used


def test_a_factor_that_fails_again_holds_the_ceiling_below_it():
    """CEILING_REPEAT: a cut-back whose first attempt's factor is no larger than that of the last
    cut-back (the factor failed again) sets the ceiling at half of it, below CEILING_MIN if need be,
    and one very easy step no longer doubles it: only GROWTH_CEILING_STEPS easy steps do (the quick
    3D hemisphere's crack run, where steps at a quarter of the base take 3 Newton iterations and
    steps at half of it failed in cycles). The rule's state is part of the checkpoint."""
    from ngtmc.stepping.sizing import CEILING_EASY_ITERATIONS, CEILING_MIN, GROWTH_CEILING_STEPS
    path, step = _growth_stepper()

    # the first failure, at CEILING_MIN: the ceiling stays at CEILING_MIN, and an easy step
    # doubles the growth back to it
    path.sizing.growth = CEILING_MIN
    assert step(20, cutbacks=1, converged_at=CEILING_MIN / 2) == CEILING_MIN / 2
    assert path.sizing.ceiling == CEILING_MIN and not path.sizing.ceiling_held
    assert step(CEILING_EASY_ITERATIONS) == CEILING_MIN
    # the same factor fails again: the ceiling goes to half of it and holds
    assert step(20, cutbacks=1, converged_at=CEILING_MIN / 2) == CEILING_MIN / 2
    assert path.sizing.ceiling == CEILING_MIN / 2 and path.sizing.ceiling_held
    state = path.get_state()
    assert state["failed_factor"] == CEILING_MIN and state["ceiling_held"] is True
    easy = [step(CEILING_EASY_ITERATIONS) for _ in range(GROWTH_CEILING_STEPS - 1)]
    assert easy == [CEILING_MIN / 2] * (GROWTH_CEILING_STEPS - 1) and path.sizing.ceiling == CEILING_MIN / 2
    assert step(CEILING_EASY_ITERATIONS) == CEILING_MIN and path.sizing.ceiling == CEILING_MIN   # the 16th doubles it
    assert not path.sizing.ceiling_held
    # a failure at a larger factor than the last one is no repeat: the ceiling is at least CEILING_MIN
    path.sizing.growth, path.sizing.ceiling = 4.0, 16.0
    assert step(20, cutbacks=2, converged_at=1.0) == 1.0 and path.sizing.ceiling == 1.0 and not path.sizing.ceiling_held
    # restored from the checkpoint state
    path.set_state(state)
    assert path.sizing.failed_factor == CEILING_MIN and path.sizing.ceiling_held is True


def test_stop_after_drop_ends_the_run_once_the_force_has_fallen():
    """``stop_after_drop``: the run follows the same path as the whole schedule's and stops at the
    first step after the peak whose force is below the fraction of it; the steps before are those
    of the full run. Bad fractions are refused."""
    sc = notched_plate(maxh=0.2, h_band=0.05, l0=0.1)
    runs = {}
    for drop in (None, 0.5):
        # UMFPACK solves bitwise alike from run to run, so the two runs take the same steps
        sim = ngtmc.Simulation(sc, 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=20.0), scheme="path-following",
                               newton=ngtmc.NewtonOptions(linear_solver="umfpack"),
                               coupled={"linear_solver": "umfpack"}, stop_after_drop=drop)
        runs[drop] = sim.run().history
        assert sim.finished
    full, short = runs[None], runs[0.5]
    F = full["force"].max()
    assert short["force"].max() == F
    assert 0 < len(short) < len(full) and short["load"].iloc[-1] < 0.012
    assert short["force"].iloc[-1] < 0.5 * F <= short["force"].iloc[-2]
    n = len(short)
    np.testing.assert_array_equal(short["force"], full["force"][:n])
    for bad in (0.0, 1.0, -0.1, float("nan")):
        with pytest.raises(ValueError, match="stop_after_drop"):
            ngtmc.Simulation(sc, 0.012, stop_after_drop=bad)
    with pytest.raises(TypeError, match="stop_after_drop"):
        ngtmc.Simulation(sc, 0.012, stop_after_drop="half")
    with pytest.raises(ValueError, match="monotonic schedule.*turns at 0.01 mm"):
        ngtmc.Simulation(sc, ngtmc.Schedule([0.0, 0.01, 0.0]), stop_after_drop=0.5)


def test_a_failed_re_solve_on_a_refined_mesh_cuts_back_but_sets_no_ceiling(monkeypatch):
    """A step whose re-solve on a refined mesh failed (Simulation._refine_and_resolve) is cut back,
    and the history counts the cut-back, but the path's sizing hears of none (no ceiling on dD:
    the failure is the mesh's doing), nor of a failed attempt after it (from the state carried to
    the refined mesh); a failure of the step's own solve before any refinement is heard as
    before."""
    from ngtmc.adapt import Adaptivity
    sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7),
                           scheme="path-following", adapt=Adaptivity(h_crack=0.05))
    heard = []
    accepted = sim._path.accepted

    def hear(step_size, iterations=0, cutbacks=0):
        heard.append(cutbacks)
        return accepted(step_size, iterations, cutbacks)

    monkeypatch.setattr(sim._path, "accepted", hear)
    fail_resolve, fail_attempt = [True], []

    def refine_and_resolve(t_new, info, saved, totals):
        if fail_resolve:   # a re-solve follows a refinement, recorded before it
            fail_resolve.pop()
            sim.refinements.append((sim.step + 1, None))
            info["message"] = "re-solve on the refined mesh failed (made to fail)"
            return False, info, saved
        return True, info, saved

    attempt = sim._attempt

    def own_attempt(t_new):
        ok, info = attempt(t_new)
        if fail_attempt and fail_attempt.pop(0):
            return False, info
        return ok, info

    monkeypatch.setattr(sim, "_refine_and_resolve", refine_and_resolve)
    monkeypatch.setattr(sim, "_attempt", own_attempt)
    row = sim.advance()
    assert row["cutbacks"] == 1 and heard == [0]
    fail_attempt.append(True)
    row = sim.advance()
    assert row["cutbacks"] == 1 and heard == [0, 1]
    row = sim.advance()
    assert row["cutbacks"] == 0 and heard == [0, 1, 0]
    fail_resolve.append(True)           # the re-solve fails, then the attempt after it
    fail_attempt.extend([False, True])
    row = sim.advance()
    assert row["cutbacks"] == 2 and heard == [0, 1, 0, 0]
    fail_attempt.extend([True])         # the step's own solve fails, then the re-solve
    fail_resolve.append(True)
    row = sim.advance()
    assert row["cutbacks"] == 2 and heard == [0, 1, 0, 0, 1]


def test_the_chord_to_a_long_step_starts_its_re_solve(monkeypatch):
    """Rule 3 of ngtmc.stepping.path: a dissipation step whose load moved past du_max is solved
    again at a smaller dD from the chord x_n + f (x_long - x_n) to the state it converged to
    (SecantPredictor.chord; f = the ratio of the dDs): u on the free dofs on the chord, the
    boundary values those of the chord's load, alpha on the chord kept in [alpha_n, 1]; a
    fraction outside (0, 1) or a chord that inverts an element leaves the state as it was. With
    ``coupled={"chord": True}`` and without it (the secant predictor, the default) the plate breaks along the same
    curve (peaks within 0.5 %), no dissipation step moves the load past du_max, and the re-solves
    take fewer Newton iterations from the chord."""
    from ngtmc.coupled import monolithic

    # the chord itself, on a state two steps into the run
    sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7),
                           scheme="path-following")
    sim.advance()
    sim.advance()
    pr, s = sim._path.predictor, sim.solver
    u_n, a_n = pr.x_n
    rng = np.random.default_rng(0)
    end = {"u": u_n + 1e-4 * rng.standard_normal(u_n.size), "alpha": np.clip(a_n + rng.uniform(-0.2, 0.6, a_n.size), 0, 1)}
    end_load = pr.load_n + 2e-3
    assert pr.chord(end, end_load, 0.25) == pytest.approx(pr.load_n + 0.5e-3, rel=1e-12)
    free, uN = s._free_np, s.u.vec.FV().NumPy()
    np.testing.assert_allclose(uN[free], (u_n + 0.25 * (end["u"] - u_n))[free], rtol=0, atol=1e-15)
    np.testing.assert_allclose(uN[~free], s.dirichlet_target(pr.load_n + 0.5e-3)[~free], rtol=0, atol=1e-15)
    np.testing.assert_allclose(s.alpha.vec.FV().NumPy(), np.clip(a_n + 0.25 * (end["alpha"] - a_n), a_n, 1.0), atol=1e-15)
    before = uN.copy()
    for fraction in (0.0, 1.0, 1.5):
        assert pr.chord(end, end_load, fraction) is None
    assert pr.chord({"u": u_n + 1e3 * rng.standard_normal(u_n.size), "alpha": a_n}, end_load, 0.5) is None
    np.testing.assert_array_equal(s.u.vec.FV().NumPy(), before)

    # the rule: the re-solves' iterations with and without the chord
    runs = {}
    for chord in (True, False):
        sim = ngtmc.Simulation(_plate(), 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                               scheme="path-following", coupled={"chord": chord})
        re_solves, seen = [], [0]
        solve = monolithic.CoupledNewton.solve

        def spy(self, *args, **kw):
            res = solve(self, *args, **kw)
            if sim._path is not None and sim._path.rescaled_steps > seen[0]:
                seen[0] = sim._path.rescaled_steps
                re_solves.append(res.iterations)
            return res
        monkeypatch.setattr(monolithic.CoupledNewton, "solve", spy)
        count = [0]
        sim.run(callbacks=[lambda s, row: count.append(s._path.dissipation_steps)])
        monkeypatch.setattr(monolithic.CoupledNewton, "solve", solve)
        h = sim.history
        dl = np.abs(np.diff(h["load"].to_numpy()))
        assert np.all(dl[np.diff(count) > 0] <= sim.control.du_max * (1 + 1e-9))
        runs[chord] = (h, re_solves)
    (h_on, r_on), (h_off, r_off) = runs[True], runs[False]
    print(f"\nre-solves from the chord: {r_on} ({int(h_on.newton_iterations.sum())} iterations in all, peak "
          f"{h_on.force.max():.6g} N); from the predictor: {r_off} ({int(h_off.newton_iterations.sum())}, "
          f"{h_off.force.max():.6g} N)")
    assert r_on and r_off
    assert np.mean(r_on) < np.mean(r_off)
    assert h_on.force.max() == pytest.approx(h_off.force.max(), rel=5e-3)
    assert h_on.force.iloc[-1] < 0.01 * h_on.force.max() and h_off.force.iloc[-1] < 0.01 * h_off.force.max()
