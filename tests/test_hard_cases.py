"""Hard cases that must run through to the end of their schedule without NaN."""
import numpy as np
import pytest

import ngtmc
from scenes import notched_plate, two_blocks


def _finite(h):
    cols = ["force", "elastic_energy", "regularisation_energy", "fracture_energy", "min_J"]
    return np.all(np.isfinite(h[cols].to_numpy()))


def test_two_bodies_pressed_through_a_thin_void():
    """Void layer 0.05 mm between two blocks, squeezed until min J < 0.05. The force is near zero
    while the void is open and rises steeply once it is squeezed."""
    sim = ngtmc.Simulation(two_blocks(gap=0.05, gamma0=1e-5), 0.0515, ngtmc.AdaptiveStepControl(du_max=0.005, du_min=1e-6))
    res = sim.run()
    h = res.history
    print(f"\nsqueeze: {len(h) - 1} steps, {int(h.newton_iterations.sum())} Newton iterations, "
          f"{int(h.cutbacks.sum())} cut-backs, min J {h.min_J.iloc[-1]:.4f}, force {h.force.iloc[-1]:.4g} N, "
          f"{res.wall_time:.1f} s")
    assert _finite(h)
    assert h["load"].iloc[-1] == pytest.approx(0.0515)
    assert h["min_J"].iloc[-1] < 0.05
    assert np.all(h["min_J"] > 0)
    f_half = np.interp(0.025, h["load"], h["force"])
    assert h["force"].iloc[-1] > 100 * f_half
    # parasitic void force at half the gap is of order gamma0 times the solid's stiffness
    assert f_half < 1e-3 * 1000.0 * 1.0 * 0.025 / 0.05


def test_void_closure_with_failed_steps_halved_and_regrown():
    """Large steps (0.02 mm on a 0.05 mm void) and a tight Newton budget (5 iterations): the steps
    that squeeze the void fail, are halved until they converge, and double again after n_s
    successes. The run reaches its end without NaN."""
    sim = ngtmc.Simulation(two_blocks(gap=0.05, gamma0=1e-5), 0.06,
                           ngtmc.AdaptiveStepControl(du_max=0.02, du_min=1e-6, n_s=2),
                           newton=ngtmc.NewtonOptions(max_iterations=5))
    h = sim.run().history
    print(f"\nclosure: {len(h) - 1} steps, {int(h.newton_iterations.sum())} Newton iterations, "
          f"{int(h.cutbacks.sum())} cut-backs")
    assert _finite(h)
    assert h["load"].iloc[-1] == pytest.approx(0.06)
    assert h["cutbacks"].sum() >= 2
    steps = h["step_size"].to_numpy()
    i_min = int(np.argmin(steps[1:])) + 1
    assert steps[i_min] <= 0.02 / 8
    assert steps[i_min:].max() >= 2 * steps[i_min]  # regrown after the failures
    assert h["min_J"].iloc[-1] < 0.01


def test_crack_running_unstably_with_cut_back_and_regrown_steps():
    """Single-edge-notched plate in tension: the crack runs unstably across the ligament at almost
    constant load. The step rule of Eq. 20 cuts the steps back by orders of magnitude while W_f
    jumps, and they regrow to du_max once the ligament is cut."""
    scene = notched_plate(maxh=0.1, h_band=0.025, l0=0.05)
    ctrl = ngtmc.AdaptiveStepControl(du_max=5e-4, k_u=100.0, du_min=1e-7)
    res = ngtmc.Simulation(scene, 0.009, ctrl).run()
    h = res.history
    print(f"\ncrack: {len(h) - 1} steps, {int(h.newton_iterations.sum())} Newton iterations, "
          f"{int(h.cutbacks.sum())} cut-backs, smallest step {h.step_size[1:].min():.2e} mm, "
          f"peak {h.force.max():.4g} N, {res.wall_time:.1f} s")
    assert _finite(h)
    assert h["load"].iloc[-1] == pytest.approx(0.009)
    assert h["max_alpha"].iloc[-1] > 0.99
    assert h["force"].iloc[-1] < 0.1 * h["force"].max()  # the ligament is cut
    i_small = int(h["step_size"][1:].idxmin())
    assert h["step_size"].iloc[i_small] < 1e-3 * 5e-4
    assert h["step_size"].iloc[i_small:].max() > 0.3 * 5e-4  # regrown after the crack ran
    assert np.all(np.diff(h["fracture_energy"]) >= -1e-12)
    assert np.all(np.diff(h["max_alpha"]) >= 0)


def test_load_reversal_after_cracking():
    """Crack partly, unload to zero, reload: no NaN, no damage growth while unloading, the force at
    zero load returns to about zero, and the reloading stiffness is lower than the initial one."""
    scene = notched_plate(maxh=0.1, h_band=0.025, l0=0.05)
    sched = ngtmc.Schedule([0, 0.0045, 0.0, 0.006])
    sim = ngtmc.Simulation(scene, sched, ngtmc.AdaptiveStepControl(du_max=5e-4, k_u=100.0, du_min=1e-7))
    h = sim.run().history
    assert _finite(h)
    load = h["load"].to_numpy()
    i_turn = int(np.argmax(load >= 0.0045))
    i_zero = int(np.argmax((np.arange(len(load)) > i_turn) & (load == 0.0)))
    assert load[i_turn] == 0.0045 and load[i_zero] == 0.0 and load[-1] == 0.006
    a = h["max_alpha"].to_numpy()
    assert a[i_turn] > 0.1  # damaged before unloading
    # single-pass scheme: alpha_n comes from H_{n-1}, so the first unloading step still takes the
    # damage driven by the turning point's history; from then on nothing grows while unloading
    assert np.all(np.abs(np.diff(a[i_turn + 1:i_zero + 1])) < 1e-9)
    wf = h["fracture_energy"].to_numpy()
    assert np.all(np.abs(np.diff(wf[i_turn + 1:i_zero + 1])) < 1e-9 * max(wf[i_turn], 1e-30))
    f = h["force"].to_numpy()
    assert abs(f[i_zero]) < 1e-6 * f.max()
    k0 = f[1] / load[1]
    k_reload = f[i_zero + 1] / load[i_zero + 1]
    assert k_reload < 0.98 * k0


@pytest.mark.parametrize("floor", [True, False])
def test_displacement_newton_accepts_at_its_residual_floor(floor):
    """A tolerance below round-off (rtol 1e-15, atol 1e-30 N): the residual stops falling at its
    floor. The displacement Newton accepts the iterate there (Solver.floor_rtol, FLOOR_RTOL of the
    reaction scale; the paper L-panel's crack run, 80 mm in, had a floor above its tolerance), and
    counts it; with floor_rtol None (the adjoint's recordings) it fails instead."""
    from ngtmc.discrete import FLOOR_RTOL
    s = ngtmc.Solver(two_blocks(gap=0.05, gamma0=1e-5), newton=ngtmc.NewtonOptions(rtol=1e-15, atol=1e-30))
    if not floor:
        s.floor_rtol = None
    res = s.solve_displacement(0.01)
    reaction = abs(s.reaction())
    if floor:
        assert res.converged and s.floor_accepts == 1
        assert 0 < res.residual <= FLOOR_RTOL * reaction
        assert res.iterations < s.newton.max_iterations      # stopped where the residual stalled
    else:
        assert not res.converged and s.floor_accepts == 0
        assert "no convergence" in res.message or "line search" in res.message
