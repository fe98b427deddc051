"""Schedules land on every turning point; the step rule of Eq. 20 with halving and doubling."""
import math

import numpy as np
import pytest

import ngtmc
from ngtmc.stepping import AdaptiveStepControl, Schedule
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
    assert c.failed(1.0) == 0.5
    assert c.proposal(0.0) == 0.5
    assert c.failed(0.5) == 0.25
    assert c.failed(0.25) is None  # 0.125 < du_min
    c = AdaptiveStepControl(du_max=1.0, du_min=1e-3, n_s=3)
    c.failed(1.0)
    c.failed(0.5)
    assert c.scale == 0.25
    for _ in range(3):
        c.accepted()
    assert c.scale == 0.5
    for _ in range(3):
        c.accepted()
    assert c.scale == 1.0
    for _ in range(3):
        c.accepted()
    assert c.scale == 1.0


def test_simulation_lands_exactly_on_every_turning_point():
    sched = Schedule([0, 0.0123, 0.005, 0.02])
    res = ngtmc.simulate(tension_bar(fracture=False), sched, AdaptiveStepControl(du_max=0.004))
    loads = res.history["load"].to_numpy()
    for p in sched.points:
        assert np.any(loads == p), p
    assert loads[-1] == 0.02
    assert np.all(res.history["step_size"].to_numpy()[1:] <= 0.004 + 1e-15)
