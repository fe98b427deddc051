"""Schedules land on every turning point; the step rule of Eq. 20 with halving and doubling."""
import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

import ngtmc
from ngtmc.stepping import AdaptiveStepControl, ControlState, Schedule
from scenes import tension_bar


def test_schedule_is_piecewise_linear_in_accumulated_load_change():
    s = Schedule([0, 6.3, 6.0, 7.0])
    assert s.total_time == pytest.approx(7.6)
    assert s.load(3.15) == pytest.approx(3.15)
    assert s.load(6.3) == 6.3
    assert s.load(6.45) == pytest.approx(6.15)
    assert s.load(6.6) == 6.0
    assert s.load(7.6) == 7.0
    assert s.next_turning_time(6.3) == pytest.approx(6.6)


def test_step_rule_of_eq_20():
    c = AdaptiveStepControl(du_max=0.5e-3, k_u=1000.0, du_min=1e-8)
    assert c.proposal(0.0) == pytest.approx(0.5e-3)
    assert c.proposal(1e-3) == pytest.approx(0.5e-3 * math.exp(-1.0))
    assert c.proposal(1.0) == 1e-8  # floored at du_min


def test_halving_on_failure_and_doubling_after_successes():
    c = AdaptiveStepControl(du_max=1.0, du_min=0.2, n_s=3)
    st = c.initial_state()
    st, du = c.failed(st, 1.0)
    assert du == 0.5
    assert c.proposal(0.0, st) == 0.5
    st, du = c.failed(st, 0.5)
    assert du == 0.25
    st, du = c.failed(st, 0.25)
    assert du is None  # 0.125 < du_min
    c = AdaptiveStepControl(du_max=1.0, du_min=1e-3, n_s=3)
    st = c.initial_state()
    st, _ = c.failed(st, 1.0)
    st, _ = c.failed(st, 0.5)
    assert st == ControlState(scale=0.25, successes=0)
    for _ in range(3):
        st = c.accepted(st)
    assert st.scale == 0.5
    for _ in range(3):
        st = c.accepted(st)
    assert st.scale == 1.0
    for _ in range(3):
        st = c.accepted(st)
    assert st.scale == 1.0


def test_control_is_a_settings_object_without_run_state():
    c = AdaptiveStepControl(du_max=1.0, du_min=1e-3, n_s=3)
    assert not hasattr(c, "scale") and not hasattr(c, "successes")
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.du_max = 2.0
    c.failed(c.initial_state(), 1.0)
    assert c.proposal(0.0) == 1.0  # a failure elsewhere does not halve this control
    assert c == AdaptiveStepControl(du_max=1.0, du_min=1e-3, n_s=3)


class _FailsLargeLateSteps(ngtmc.Simulation):
    """Fails every attempt longer than 3 µm from load 15 µm on, so the run ends with the scale
    of Eq. 20 halved (too few successes to double it again)."""

    def _attempt(self, t_new):
        if self.t >= 0.015 and t_new - self.t > 0.003:
            return False, {"newton_iterations": 0, "solve_time": 0.0, "assembly_time": 0.0, "message": "injected"}
        return super()._attempt(t_new)


def test_one_control_serves_two_simulations_alike():
    """The scale halved by a failure in one run stays in that run: a second simulation with the
    same control object takes the same steps and gives the same history."""
    ctrl = AdaptiveStepControl(du_max=0.004, du_min=1e-6, n_s=5)
    histories = []
    for _ in range(2):
        sim = _FailsLargeLateSteps(tension_bar(fracture=False), 0.02, ctrl)
        histories.append(sim.run().history)
        assert sim.control_state.scale == 0.5
    a, b = (h.drop(columns=["wall_time", "solve_time", "assembly_time"]) for h in histories)
    assert a["cutbacks"].sum() == 1
    assert a["step_size"].iloc[1] == 0.004
    steps = ["step", "load", "step_size", "cutbacks", "newton_iterations"]
    pd.testing.assert_frame_equal(a[steps], b[steps], check_exact=True)  # the same steps, exactly
    pd.testing.assert_frame_equal(a, b, rtol=1e-9, atol=1e-12)  # the direct solver's last bits vary between runs


def test_simulation_lands_exactly_on_every_turning_point():
    sched = Schedule([0, 0.0123, 0.005, 0.02])
    res = ngtmc.simulate(tension_bar(fracture=False), sched, AdaptiveStepControl(du_max=0.004))
    loads = res.history["load"].to_numpy()
    for p in sched.points:
        assert np.any(loads == p), p
    assert loads[-1] == 0.02
    assert np.all(res.history["step_size"].to_numpy()[1:] <= 0.004 + 1e-15)


def test_checkpointed_control_state_keeps_its_old_form():
    """A simulation's state holds the control's run state as the dict {"scale", "successes"} that
    checkpoints have always stored; a state of that form resumes at its scale."""
    ctrl = AdaptiveStepControl(du_max=0.004, du_min=1e-6, n_s=5)
    sim = ngtmc.Simulation(tension_bar(fracture=False), 0.02, ctrl)
    sim.advance()
    st = sim.get_state()
    assert st["control"] == {"scale": 1.0, "successes": 1}
    st["control"] = {"scale": 0.5, "successes": 4}  # as written by a run whose control was halved
    other = ngtmc.Simulation(tension_bar(fracture=False), 0.02, ctrl)
    other.set_state(st)
    assert other.control_state == ControlState(scale=0.5, successes=4)
    assert other.advance()["step_size"] == pytest.approx(0.002)
    assert other.control_state == ControlState(scale=1.0, successes=0)  # 5 successes: doubled back


@pytest.mark.parametrize("scheme, scale", [("single-pass", 0.5), ("path-following", 1.0)])
def test_path_following_doubles_the_scale_after_every_step(scheme, scale):
    """ngtmc.stepping.path.N_S: under path following the scale halved by a cut-back doubles after the next
    successful step, whatever the control's n_s; the other schemes keep n_s (here 5)."""
    ctrl = AdaptiveStepControl(du_max=0.004, du_min=1e-6, n_s=5)
    sim = ngtmc.Simulation(tension_bar(), 0.02, ctrl, scheme=scheme)
    sim.advance()
    st = sim.get_state()
    st["control"] = {"scale": 0.5, "successes": 0}
    sim.set_state(st)
    sim.advance()
    assert sim.control_state.scale == scale
    assert ctrl.accepted(ControlState(scale=0.25, successes=0), n_s=1) == ControlState(scale=0.5, successes=0)
