"""The peak of a force-load curve has one definition (ngtmc.simulation.history.peak): the runner's results,
the report's key numbers and reference peaks, SimulationResult and the benchmark harness all give
the same peak of a hand-made history."""
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import ngtmc
from ngtmc.report.numbers import case_numbers, reference_peaks
from ngtmc.simulation import peak, peak_index
from ngtmc.runner import case_results

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks import harness as H  # noqa: E402

# a load-unload-reload history (mm, N/mm): a NaN force (a failed evaluation), an infinite one, and
# the largest finite force 5.0 reached twice, first at 0.3 mm (before the unloading), then at 0.4 mm
LOAD = [0.0, 0.1, 0.2, 0.3, 0.2, 0.25, 0.35, 0.4, 0.5]
FORCE = [0.0, 2.0, np.nan, 5.0, 3.0, np.inf, 4.0, 5.0, 1.0]


def _history():
    n = len(LOAD)
    return pd.DataFrame({"case": "main", "step": range(n), "load": LOAD, "force": FORCE,
                         "newton_iterations": [0] + [3] * (n - 1), "cutbacks": 0,
                         "step_size": [0.0] + list(np.abs(np.diff(LOAD))), "wall_time": np.linspace(0, 1, n),
                         "solve_time": 0.1, "fracture_energy": 0.0, "max_alpha": 0.0})


def test_peak_of_a_hand_made_history():
    assert peak_index(FORCE) == 3
    assert peak(FORCE, LOAD) == (5.0, 0.3)
    assert peak([np.nan, np.inf, -np.inf], [0, 1, 2]) == (None, None)
    assert peak([], []) == (None, None)
    assert peak([-3.0, -1.0, -2.0], [0.0, 1.0, 2.0]) == (-1.0, 1.0)  # compression: the largest value
    with pytest.raises(ValueError, match="3 forces but 2 loads"):
        peak([1, 2, 3], [0, 1])


def test_every_reader_of_a_history_takes_the_one_peak():
    h = _history()
    r = case_results(h)
    assert (r["peak_force"], r["peak_load"]) == (5.0, 0.3)
    nums = case_numbers({"results": {}}, h, "main")
    assert (nums["peak_force"], nums["peak_load"]) == (5.0, 0.3)
    res = ngtmc.SimulationResult(h.drop(columns="case"), {}, None, 1.0)
    assert (res.peak_force, res.peak_load) == (5.0, 0.3)
    s = H.summarise(h)
    assert (s["peak_force_N"], s["peak_load_mm"]) == (5.0, 0.3)
    refs = reference_peaks({"force_unit": "N/mm", "references": [
        {"label": "hand", "kind": "curve", "x": LOAD, "y": FORCE, "y_unit": "N/mm"}]})
    assert [(p["peak"], p["at"]) for p in refs] == [(5.0, 0.3)]
    c = H.compare(LOAD, FORCE, LOAD, FORCE)
    assert c["peak_force_error_pct"] == 0.0 and c["peak_load_error_pct"] == 0.0
    x, y = H.downsample(LOAD, FORCE, n=3)
    assert 0.3 in x and 5.0 in y  # the peak row is kept


def test_no_finite_force_has_no_peak():
    h = _history().assign(force=np.nan)
    r = case_results(h)
    assert math.isnan(r["peak_force"]) and math.isnan(r["peak_load"])
    assert case_numbers({"results": {"main": {"peak_force": 7.0, "peak_load": 0.2}}}, h, "main")["peak_force"] == 7.0
    res = ngtmc.SimulationResult(h.drop(columns="case"), {}, None, 1.0)
    assert math.isnan(res.peak_force) and math.isnan(res.peak_load)
    assert H.summarise(h)["peak_force_N"] is None
