"""Every study keeps one EXPECTED record (docs/study-interface.md), checked against its quick run by
one shared parametrized test (tests/study_expected.py) in the study's own test module, on the run
that module computes anyway. These checks need no run: the records are well formed, agree with the
published targets the report shows, and every study with records has that test."""
from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

from ngtmc.study import STUDIES, load_study
from ngtmc.study import study_parameters
from study_expected import check_expected, record_problems

TESTS = Path(__file__).resolve().parent


def _test_module(name: str) -> Path:
    return TESTS / f"test_study_{name}.py"


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_expected_records_are_well_formed(name):
    mod = load_study(name)
    assert isinstance(getattr(mod, "EXPECTED", None), dict), f"{name} has no module-level EXPECTED dict"
    problems = [p for key, rec in mod.EXPECTED.items() for p in record_problems(key, rec)]
    assert not problems, problems
    _, p = study_parameters(mod, "quick")
    cases = {c.name for c in mod.cases(p)}
    for key, rec in mod.EXPECTED.items():
        assert rec["case"] in cases, f"{name} {key}: case {rec['case']!r} is not a case of the quick run {sorted(cases)}"


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_expected_agrees_with_the_published_targets(name):
    """A record of a number that targets(p) also gives (the report's key numbers) has its value and
    tolerance: one published number, not two."""
    mod = load_study(name)
    _, p = study_parameters(mod, "quick")
    targets = {(t["case"], t["quantity"]): t for t in (mod.targets(p) if hasattr(mod, "targets") else [])}
    for key, rec in mod.EXPECTED.items():
        t = targets.get((rec["case"], rec["quantity"]))
        if t is None or "measured" in rec["source"]:
            continue
        assert rec["value"] == pytest.approx(t["value"], rel=1e-12), (key, rec, t)
        assert rec.get("rel") == pytest.approx(t["tolerance"], rel=1e-12), (key, rec, t)
        assert rec["unit"] == t["unit"], (key, rec, t)


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_each_study_with_records_has_the_shared_check(name):
    """The study's test module binds ``test_expected = expected_test(<the study>)``, so its records
    are checked on the run folder of its module fixture ``run_dir`` (no second run)."""
    mod = load_study(name)
    if not mod.EXPECTED:
        return
    f = _test_module(name)
    assert f.is_file(), f"{name} has EXPECTED records but no test module {f.name}"
    tree = ast.parse(f.read_text())
    bound = [n for n in tree.body if isinstance(n, ast.Assign)
             and any(isinstance(t, ast.Name) and t.id == "test_expected" for t in n.targets)
             and isinstance(n.value, ast.Call) and getattr(n.value.func, "id", "") == "expected_test"]
    assert bound, f"{f.name} does not bind test_expected = expected_test(...)"
    fixtures = [n.name for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "run_dir"]
    assert fixtures, f"{f.name} has no module fixture run_dir"


def test_check_expected_compares_with_the_tolerance(tmp_path):
    """The shared check on a synthetic run folder: inside the tolerance passes, outside fails,
    a missing quantity or another resolution fails with a message."""
    import json
    import types

    study = types.SimpleNamespace(NAME="demo", EXPECTED={
        "f": {"case": "main", "quantity": "peak_force", "value": 10.0, "unit": "N", "rel": 0.1, "source": "paper"},
        "d": {"case": "main", "quantity": "diff", "value": 0.0, "unit": "-", "abs": 0.01, "source": "reference"},
        "m": {"case": "main", "quantity": "missing", "value": 1.0, "unit": "-", "rel": 0.1, "source": "x"}})

    def write(peak, diff, resolution="quick"):
        (tmp_path / "metadata.json").write_text(json.dumps({
            "study": "demo", "resolution": resolution, "results": {"main": {"peak_force": peak, "diff": diff}}}))

    write(10.9, -0.009)
    check_expected(study, "f", tmp_path)
    check_expected(study, "d", tmp_path)
    with pytest.raises(AssertionError, match="'missing' not in the results"):
        check_expected(study, "m", tmp_path)
    write(11.1, 0.011)
    with pytest.raises(AssertionError, match="peak_force.*11.1 N, expected 10 N"):
        check_expected(study, "f", tmp_path)
    with pytest.raises(AssertionError):
        check_expected(study, "d", tmp_path)
    write(10.0, 0.0, resolution="medium")
    with pytest.raises(AssertionError, match="medium"):
        check_expected(study, "f", tmp_path)
    write(math.nan, 0.0)
    with pytest.raises(AssertionError):
        check_expected(study, "f", tmp_path)
    assert record_problems("x", {"case": "main", "quantity": "q", "value": 1.0, "unit": "-", "source": "s"})
    assert record_problems("x", {"case": "main", "quantity": "q", "value": 1.0, "unit": "-", "source": "s",
                                 "rel": 0.1, "abs": 0.1})


def _synthetic_l_panel_history(p):
    import numpy as np
    import pandas as pd
    S = load_study("l_panel")
    u1, u2, u3 = S.effective_schedule(p)[1:4]
    loads = np.r_[np.linspace(0.0, u1, 20), np.linspace(u1, u2, 8)[1:], np.linspace(u2, u3, 10)[1:]]
    n = len(loads)
    main = pd.DataFrame({"case": "main", "step": np.arange(n), "load": loads, "force": 3000.0 * loads,
                         "fracture_energy": np.linspace(0.0, 1.0, n), "max_alpha": np.linspace(0.0, 1.0, n)})
    mono = np.linspace(0.0, S.cases(dict(p, load_cases="monotonic"))[0].schedule.points[-1], 30)
    m = len(mono)
    return pd.concat([main, pd.DataFrame({  # case monotonic: a rise, a peak two thirds along, a drop
        "case": "monotonic", "step": np.arange(m), "load": mono,
        "force": 3000.0 * np.minimum(mono, 2 * mono[-1] / 3) * np.where(mono > 2 * mono[-1] / 3, 0.5, 1.0),
        "fracture_energy": np.linspace(0.0, 1.0, m), "max_alpha": np.linspace(0.0, 1.0, m)})])


def _synthetic_contact_histories(p):
    import numpy as np
    import pandas as pd
    S = load_study("contact_gamma0")
    load = np.linspace(0.0, float(p["final_load"]), 31)
    names = [S.case_name(float(g)) for g in p["gamma0_values"]] + ["classical"]
    return pd.concat([pd.DataFrame({"case": c, "step": np.arange(len(load)), "load": load,
                                    "force": S.beam_theory(p, load)}) for c in names])


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_results_hold_every_expected_quantity(name):
    """Each quantity of EXPECTED reaches metadata.json results: the runner's case results, or the
    study's post_results (shown here on a synthetic history of the quick run's load path)."""
    from ngtmc.runner import case_results
    mod = load_study(name)
    if not mod.EXPECTED:
        return
    _, p = study_parameters(mod, "quick")
    history = {"l_panel": _synthetic_l_panel_history, "contact_gamma0": _synthetic_contact_histories}.get(name)
    if history is None:  # no post-processing: the runner's case results must hold them
        import pandas as pd
        h = pd.DataFrame({"step": [0, 1, 2], "load": [0.0, 0.1, 0.2], "force": [0.0, 2.0, 1.0]})
        results = {c.name: case_results(h) for c in mod.cases(p)}
        if hasattr(mod, "post_results"):
            results = mod.post_results(p, h.assign(case=mod.cases(p)[0].name), results) or results
    else:
        h = history(p)
        results = {c: case_results(g) for c, g in h.groupby("case")}
        results = mod.post_results(p, h, results) or results
    own = {c.name for c in mod.cases(p) if c.run is not None}   # their results come from their own run
    for key, rec in mod.EXPECTED.items():
        if rec["case"] in own:
            continue
        assert rec["quantity"] in results[rec["case"]], (key, sorted(results[rec["case"]]))
        assert math.isfinite(float(results[rec["case"]][rec["quantity"]])), key
