"""studies/step_control.py: six three-point-bending runs (k_u in {0, 50, 1000} x two du_max) and
their speed-against-error numbers. The quick run (coarse mesh h_band = l0) is the CI run."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import ngtmc
from ngtmc.study import load_study
from ngtmc.study import study_parameters
from ngtmc.studies import step_control as sc
from ngtmc.studies import three_point_bending as tpb


def test_cases_and_physics_shared_with_three_point_bending():
    assert load_study("step-control") is sc
    assert {"quick", "medium", "paper"} <= set(sc.RESOLUTIONS)
    _, p = study_parameters(sc, "medium")
    cs = sc.cases(p)
    assert len(cs) == 6 and len({c.name for c in cs}) == 6
    kus = sorted({c.control.k_u for c in cs})
    assert kus == [0.0, 50.0, 1000.0]
    assert sorted({c.control.du_max for c in cs}) == [0.5e-3, 2e-3]
    assert sc.reference_case(p) == "ku1000_du5e-04"
    _, p = study_parameters(sc, "quick")  # CI subset: one du_max
    assert sorted((c.control.k_u, c.control.du_max) for c in sc.cases(p)) == [(0.0, 4e-3), (50.0, 4e-3), (1000.0, 4e-3)]
    assert sc.reference_case(p) == "ku1000_du4e-03"
    # same physics as three_point_bending: every physical parameter but k_u is shared, same values
    for k, v in tpb.PARAMETERS.items():
        if k not in ("k_u", "scheme"):
            assert sc.PARAMETERS[k] == v, k
    # but the scheme whose steps Eq. 20 sets, the paper's, not the three-point bending's default
    assert sc.PARAMETERS["scheme"][0] == "single-pass" != tpb.PARAMETERS["scheme"][0]
    assert {c.options["scheme"] for c in sc.cases(p)} == {"single-pass"}
    # overrides reach the cases
    _, p2 = study_parameters(sc, "quick", {"k_u_values": "0,50", "du_max_fine": "1e-3"})
    assert {(c.control.k_u, c.control.du_max) for c in sc.cases(p2)} == {(0.0, 4e-3), (50.0, 4e-3), (0.0, 1e-3),
                                                                        (50.0, 1e-3)}


def test_post_results_errors_against_reference():
    _, p = study_parameters(sc, "quick", {"du_max_fine": "2e-3"})
    res = {"ku1000_du2e-03": {"peak_force": 40.0, "peak_load": 0.1, "steps": 100, "wall_time_s": 100.0},
           "ku0_du4e-03": {"peak_force": 44.0, "peak_load": 0.11, "steps": 25, "wall_time_s": 20.0}}
    out = sc.post_results(p, pd.DataFrame(), res)
    assert out["ku0_du4e-03"]["peak_force_error"] == pytest.approx(0.1)
    assert out["ku0_du4e-03"]["peak_load_error"] == pytest.approx(0.1)
    assert out["ku0_du4e-03"]["steps_ratio"] == pytest.approx(0.25)
    assert out["ku1000_du2e-03"]["peak_force_error"] == 0.0


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("sc") / "quick"
    ngtmc.run_study("step_control", resolution="quick", output=out, report=False, progress=False)
    return out, json.loads((out / "metadata.json").read_text()), pd.read_csv(out / "history.csv")


@pytest.mark.slow
def test_quick_run(quick_run):
    out, meta, h = quick_run
    res = meta["results"]
    print("\nstep_control quick:")
    for name, r in res.items():
        print(f"  {name:16s} steps {r['steps']:4d}  Newton {r['newton_iterations']:5d}  "
              f"wall {r['wall_time_s']:7.1f} s  peak {r['peak_force']:.3f} N/mm at {r['peak_load']:.4f} mm  "
              f"error {100 * r['peak_force_error']:+.2f} %")
    # quick (CI): k_u in {0, 50, 1000} at one du_max; medium and paper add a second du_max
    _, p = study_parameters(sc, "quick")
    kus, dus = sc._grid(p)
    assert meta["status"] == "completed" and len(res) == len(kus) * len(dus) == 3
    assert sorted(h["case"].unique()) == sorted(res)
    ref = res[sc.reference_case(p)]
    assert ref["peak_force_error"] == 0.0
    for du in {f"{d:.0e}" for d in dus}:
        # k_u shrinks the steps while the crack runs: more steps for larger k_u at the same du_max
        assert res[f"ku0_du{du}"]["steps"] < res[f"ku50_du{du}"]["steps"] < res[f"ku1000_du{du}"]["steps"]
        assert res[f"ku1000_du{du}"]["min_step_size"] < 0.1 * res[f"ku0_du{du}"]["min_step_size"]
    for name, r in res.items():
        assert r["final_load"] == pytest.approx(sc.RESOLUTIONS["quick"]["stop_load"])
        assert np.isfinite(r["peak_force_error"]) and r["peak_load"] > 0.05
