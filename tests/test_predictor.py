"""The secant predictor of the displacement Newton (ngtmc.stepping.schemes.StepSchemes._predict_displacement,
ngtmc.stepping.secant.secant_displacement): the same converged states as the start from the
last accepted step, fewer Newton iterations, no extrapolation across a load reversal, and a
checkpoint that keeps the secant's point (seconds)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import ngtmc
from ngtmc.stepping import StepSchemes
from ngtmc.stepping import AdaptiveStepControl, Schedule

from scenes import tension_bar, two_blocks


def _run(scene, schedule, control, monkeypatch=None, predictor=True, **kw):
    calls = []
    original = StepSchemes._predict_displacement

    def spy(self, load):
        taken = original(self, load) if predictor else False
        calls.append((self.solver.load, load, taken))
        return taken

    if monkeypatch is not None:
        monkeypatch.setattr(StepSchemes, "_predict_displacement", spy)
    res = ngtmc.simulate(scene, schedule, control, **kw)
    if monkeypatch is not None:
        monkeypatch.undo()
    return res.history, calls


@pytest.mark.parametrize("name, scene, schedule, control", [
    # a squeezed void between two blocks, loaded and partly unloaded (order 2, regulariser)
    ("contact", lambda: two_blocks(gap=0.05, maxh=0.1, void_maxh=0.025), Schedule([0, 0.04, 0.03]),
     AdaptiveStepControl(du_max=0.004)),
    # a bar in tension, damaged homogeneously past the AT-2 peak (at about 3.3e-4 mm), the paper's
    # single-pass scheme with Eq. 20
    ("damage", lambda: tension_bar(), Schedule([0, 1.2e-3]), AdaptiveStepControl(du_max=5e-5, k_u=1e4)),
])
def test_the_predictor_changes_the_iterations_not_the_states(monkeypatch, name, scene, schedule, control):
    """With and without the predictor: the same steps, forces and energies to the Newton
    tolerance (1e-8 of the reaction), fewer Newton iterations with it; across a load reversal
    it is not taken."""
    with_, calls = _run(scene(), schedule, control, monkeypatch, predictor=True)
    without, _ = _run(scene(), schedule, control, monkeypatch, predictor=False)
    assert len(with_) == len(without)
    pd.testing.assert_series_equal(with_["load"], without["load"], rtol=1e-12)
    scale = float(np.abs(without["force"]).max())
    assert np.abs(with_["force"] - without["force"]).max() <= 1e-6 * scale
    for col in ("elastic_energy", "fracture_energy"):
        assert np.abs(with_[col] - without[col]).max() <= 1e-6 * max(float(np.abs(without[col]).max()), 1e-300)
    n_with, n_without = int(with_["newton_iterations"].sum()), int(without["newton_iterations"].sum())
    print(f"{name}: {len(with_)} steps, Newton {n_without} -> {n_with}; predictor taken in "
          f"{sum(c[2] for c in calls)} of {len(calls)} attempts")
    assert n_with < n_without
    assert sum(c[2] for c in calls) >= len(with_) // 2
    if name == "damage":   # past the peak: the force has fallen by more than a third, alpha above 1/2
        assert without["force"].iloc[-1] < 0.65 * without["force"].max() and without["max_alpha"].iloc[-1] > 0.5
    if name == "contact":   # 0 -> 0.04 -> 0.03: the first step after the turning point extrapolates nothing
        turn = [c for c in calls if c[0] == pytest.approx(0.04) and c[1] < c[0]]
        assert turn and not any(c[2] for c in turn)


def test_a_resumed_simulation_keeps_the_secant_point():
    """get_state / set_state carry the predictor's previous point: the resumed simulation takes
    the same Newton iterations and reaches the same states as the uninterrupted one. A state
    without it (a checkpoint written before the predictor) resumes without a predictor for one
    step."""
    ctrl = AdaptiveStepControl(du_max=0.002)

    def sim():
        return ngtmc.Simulation(tension_bar(l0=0.5, Gc=1.0), 0.02, ctrl)

    a = sim()
    for _ in range(4):
        a.advance()
    st = a.get_state()
    assert st["arrays"]["u_before"].shape == (a.solver.fes_u.ndof,) and st["load_before"] == pytest.approx(0.006)
    b = sim()
    b.set_state(st)
    old = dict(st, arrays={})
    c = sim()
    c.set_state(old)
    rows = [(a.advance(), b.advance(), c.advance()) for _ in range(3)]
    for ra, rb, rc in rows:
        assert rb["newton_iterations"] == ra["newton_iterations"]
        assert rb["force"] == pytest.approx(ra["force"], rel=1e-12)
        assert rc["force"] == pytest.approx(ra["force"], rel=1e-7)
    assert rows[0][2]["newton_iterations"] > rows[0][0]["newton_iterations"]
    np.testing.assert_allclose(b.solver.u.vec.FV().NumPy(), a.solver.u.vec.FV().NumPy(), rtol=0, atol=1e-14)
