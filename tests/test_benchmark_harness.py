"""The pure parts of benchmarks/harness.py (no simulation is run): reference comparison, curve
downsampling, summaries, option parsing and the table."""
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks import harness as H  # noqa: E402
from benchmarks.parallel import compare_histories  # noqa: E402
from benchmarks.run import parse_variants  # noqa: E402


def test_compare_peak_errors_and_interpolated_force_difference():
    # reference: F = 100 u on [0, 1] mm (peak 100 N at 1 mm); run: F = 90 u on [0, 0.5] mm, coarser
    ref_u = np.linspace(0.0, 1.0, 11)
    run_u = np.array([0.0, 0.25, 0.5])
    c = H.compare(run_u, 90.0 * run_u, ref_u, 100.0 * ref_u)
    assert c["peak_force_error_pct"] == pytest.approx(-55.0)       # 45 N against 100 N
    assert c["peak_load_error_pct"] == pytest.approx(-50.0)        # 0.5 mm against 1 mm
    assert c["common_range_mm"] == pytest.approx([0.0, 0.5])
    assert c["max_force_diff_N"] == pytest.approx(5.0)             # |90 - 100| * 0.5 at u = 0.5
    assert c["max_force_diff_load_mm"] == pytest.approx(0.5)
    assert c["max_force_diff_pct_of_peak"] == pytest.approx(5.0)


def test_compare_interpolates_the_run_onto_the_reference_loads():
    # run is piecewise linear through (0,0), (1,10): at the reference loads 0.3 and 0.7 it is 3 and 7
    c = H.compare([0.0, 1.0], [0.0, 10.0], [0.0, 0.3, 0.7, 1.0], [0.0, 3.5, 7.0, 12.0])
    assert c["max_force_diff_N"] == pytest.approx(2.0)              # at 1.0: 10 vs 12
    assert c["peak_force_error_pct"] == pytest.approx(100.0 * (10.0 - 12.0) / 12.0)
    assert c["peak_load_error_pct"] == pytest.approx(0.0)
    c = H.compare([0.0, 1.0], [0.0, 10.0], [0.0, 0.3, 0.7], [0.0, 3.5, 7.0])
    assert c["max_force_diff_N"] == pytest.approx(0.5)              # at 0.3: 3 vs 3.5


def test_compare_follows_unloading_in_pseudo_time():
    # load 0 -> 1 -> 0.5: the same load on both branches is told apart by the accumulated change
    ref_u, ref_f = [0.0, 1.0, 0.5], [0.0, 10.0, 2.0]
    c = H.compare([0.0, 1.0, 0.5], [0.0, 10.0, 4.0], ref_u, ref_f)
    assert c["max_force_diff_N"] == pytest.approx(2.0)
    assert c["max_force_diff_load_mm"] == pytest.approx(0.5)
    assert c["peak_force_error_pct"] == pytest.approx(0.0)


def test_compare_empty_run_gives_no_numbers():
    c = H.compare([], [], [0.0, 1.0], [0.0, 1.0])
    assert c["peak_force_error_pct"] is None and c["max_force_diff_N"] is None


def test_downsample_keeps_ends_peak_and_turning_points():
    u = np.concatenate([np.linspace(0, 1, 3001), np.linspace(1, 0.5, 2001)[1:]])
    f = np.sin(3 * u)
    f[1234] = 99.0
    x, y = H.downsample(u, f, n=200)
    assert len(x) <= 200 and len(x) == len(y)
    assert x[0] == 0.0 and x[-1] == 0.5 and 99.0 in y and 1.0 in x
    assert H.pseudo_time(x)[-1] == pytest.approx(1.5)
    assert H.downsample([0.0, 1.0], [0.0, 2.0]) == ([0.0, 1.0], [0.0, 2.0])


def test_summarise_history():
    h = pd.DataFrame({"step": [0, 1, 2, 3], "load": [0.0, 0.1, 0.2, 0.3], "force": [0.0, 5.0, 8.0, 2.0],
                      "newton_iterations": [0, 3, 4, 6], "cutbacks": [0, 0, 1, 2], "wall_time": [0, 1, 2, 3],
                      "assembly_time": [0.0, 0.5, 0.5, 1.0]})
    s = H.summarise(h)
    assert (s["steps"], s["newton_iterations"], s["cutbacks"]) == (3, 13, 3)
    assert (s["peak_force_N"], s["peak_load_mm"], s["final_load_mm"]) == (8.0, 0.2, 0.3)
    assert s["history_time_sums_s"] == {"assembly_time": 2.0}


def test_timing_split():
    t = H.timing_split({"assembly": 2.0, "factorization": 1.0}, wall_time_s=10.0, newton_iterations=100)
    assert t["assembly"] == {"s": 2.0, "ms_per_newton": 20.0, "pct_of_wall": 20.0}
    assert H.timing_split({"solve": 1.0}, 0.0, 0)["solve"]["ms_per_newton"] is None


def test_parse_options_and_variants():
    assert H.parse_assignments(["compile=False", "scheme=monolithic", "max_steps=10", "x= 1e-3 "]) == \
        {"compile": False, "scheme": "monolithic", "max_steps": 10, "x": 1e-3}
    with pytest.raises(ValueError):
        H.parse_assignments(["compile"])
    assert parse_variants(["monolithic"], ["a: ", "b: compile=False coupled={'alpha_tol': 1e-4}"]) == \
        [("monolithic", {"scheme": "monolithic"}), ("a", {}), ("b", {"compile": False, "coupled": {"alpha_tol": 1e-4}})]
    assert parse_variants([], []) == [("default", {})]
    with pytest.raises(ValueError):
        parse_variants([], ["a: ", "a: compile=False"])
    assert H.merge_options({"scheme": "single-pass", "compile": True}, {"scheme": "monolithic"}) == \
        {"compile": True, "scheme": "monolithic"}
    assert H.merge_options({"scheme": "single-pass"}, {"compile": False}) == {"scheme": "single-pass", "compile": False}


def _record(label, **kw):
    r = {"label": label, "ndof": {"u": 1000, "alpha": 200, "history_points": 5000}, "steps": 10,
         "newton_iterations": 40, "cutbacks": 1, "wall_time_s": 2.0, "time_pct_of_wall": {"assembly": 55.0},
         "peak_force_N": 38.1234, "peak_load_mm": 0.0979, "status": "completed",
         "errors": {"peak_force_error_pct": -1.5}}
    r.update(kw)
    return r


def test_table_formatting():
    recs = [_record("fast"), _record("reference", is_reference=True, errors=None),
            _record("broken", status="failed: step from load 0.1 mm failed", wall_time_s=None)]
    rows = H.table_rows(recs)
    assert rows[0] == ["fast", "1200", "10", "40", "1", "2.0", "50.0", "55", "-", "38.123", "0.09790", "-1.50", "ok"]
    assert rows[1][11] == "ref" and rows[2][5] == "-" and rows[2][6] == "-" and rows[2][12] == "failed"
    text = H.format_table(recs).splitlines()
    assert len(text) == 5 and text[0].startswith("label") and len({len(line) for line in text}) == 1
    md = H.format_table(recs, markdown=True).splitlines()
    assert md[0].startswith("| label | dofs |") and md[1].startswith("|:---|---:|") and len(md) == 5
    assert md[2] == "| " + " | ".join(rows[0]) + " |"


def test_jsonable():
    out = H.jsonable({"a": np.float64(np.nan), "b": np.arange(2), "c": (1, np.int64(2)), "d": np.bool_(True)})
    assert out == {"a": None, "b": [0, 1], "c": [1, 2], "d": True}


def test_benchmark_compares_histories_without_the_times():
    a = pd.DataFrame({"case": ["a", "a"], "step": [0, 1], "force": [0.0, 1.5], "wall_time": [0.0, 2.0]})
    b = a.assign(wall_time=[0.0, 7.0])
    assert compare_histories(a, b)["identical"] is True
    c = b.assign(force=[0.0, 1.5 + 1e-12])
    r = compare_histories(a, c)
    assert r["identical"] is False and 0 < r["max_abs_difference"] < 1e-11
    assert compare_histories(a, a.iloc[:1])["identical"] is False


def test_compare_histories_sees_a_changed_value_and_ignores_the_times():
    import pandas as pd
    from benchmarks.compare_histories import differing_columns
    a = pd.DataFrame({"step": [0, 1], "force": [0.0, float("nan")], "wall_time": [0.0, 1.0]})
    b = a.assign(wall_time=[0.0, 2.0])
    assert differing_columns(a, b) == []                    # NaN equals NaN, times ignored
    assert differing_columns(a, b.assign(force=[0.0, 1.0])) == ["force"]
    assert differing_columns(a, b.iloc[:1]) == ["(rows)"]
    assert differing_columns(a, b.drop(columns="force")) == ["force"]


def test_study_settings_variants_are_labelled_sets_of_study_settings():
    """benchmarks/study_settings.py: "label: key=value ..." -> (label, ["key=value", ...]); a
    variant without a label or with a word that is not key=value is refused."""
    from benchmarks.study_settings import parse_variant
    assert parse_variant("band:") == ("band", [])
    assert parse_variant("refined: h_band=0.06 h_crack=0.015") == ("refined", ["h_band=0.06", "h_crack=0.015"])
    for bad in (": h_crack=0.01", "refined: h_crack"):
        with pytest.raises(ValueError):
            parse_variant(bad)
