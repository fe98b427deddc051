"""The check of a study's ``EXPECTED`` record against its quick run, shared by the study test modules.

Each study module defines one module-level ``EXPECTED`` dict (docs/study-interface.md): key ->
record with ``case``, ``quantity`` (a key of ``metadata.json["results"][case]``), ``value``,
``unit``, a tolerance (``rel``: relative, or ``abs``: absolute, in ``unit``), ``source`` and, for a
known disagreement, ``xfail`` (the reason, with the measured value: a strict expected failure).

The quick runs take minutes, so the check runs on the run folder that the study's own test module
computes (its module fixture ``run_dir``), never on a run of its own::

    from study_expected import expected_test
    test_expected = expected_test(three_point_bending)   # one test per EXPECTED record

tests/test_expected.py checks (cheaply, without runs) that the records are well formed and that
every study with records has its test module wired this way.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

__all__ = ["expected_test", "check_expected", "measured_value", "record_problems"]

TOLERANCES = ("rel", "abs")


def record_problems(key: str, rec) -> list[str]:
    """What is wrong with one EXPECTED record (empty if nothing)."""
    if not isinstance(rec, dict):
        return [f"{key}: not a dict"]
    out = []
    for field in ("case", "quantity", "unit", "source"):
        if not isinstance(rec.get(field), str) or not rec.get(field).strip():
            out.append(f"{key}: '{field}' must be a non-empty string")
    v = rec.get("value")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        out.append(f"{key}: 'value' must be a finite number, got {v!r}")
    tol = [t for t in TOLERANCES if t in rec]
    if len(tol) != 1:
        out.append(f"{key}: exactly one tolerance of {TOLERANCES} expected, got {tol}")
    else:
        t = rec[tol[0]]
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not t > 0:
            out.append(f"{key}: tolerance {tol[0]} must be a positive number, got {t!r}")
    if "xfail" in rec and (not isinstance(rec["xfail"], str) or not rec["xfail"].strip()):
        out.append(f"{key}: 'xfail' must give the reason")
    unknown = set(rec) - {"case", "quantity", "value", "unit", "source", "xfail", *TOLERANCES}
    if unknown:
        out.append(f"{key}: unknown fields {sorted(unknown)}")
    return out


def measured_value(run_dir, rec: dict) -> float:
    """The run's value of a record: ``metadata.json["results"][case][quantity]``."""
    meta = json.loads((Path(run_dir) / "metadata.json").read_text())
    results = meta.get("results") or {}
    case, q = rec["case"], rec["quantity"]
    assert case in results, f"case {case!r} not in the run's results ({sorted(results)})"
    assert q in results[case], f"{q!r} not in the results of case {case!r} ({sorted(results[case])})"
    return results[case][q]


def check_expected(study, key: str, run_dir):
    """Assert that the quick run in ``run_dir`` meets ``study.EXPECTED[key]``."""
    rec = study.EXPECTED[key]
    assert not record_problems(key, rec), record_problems(key, rec)
    meta = json.loads((Path(run_dir) / "metadata.json").read_text())
    assert meta.get("study") == study.NAME and meta.get("resolution") == "quick", (meta.get("study"), meta.get("resolution"))
    got = measured_value(run_dir, rec)
    assert got is not None and math.isfinite(float(got)), f"{key}: {got!r}"
    want, unit = float(rec["value"]), rec["unit"]
    what = f"{study.NAME} {key} ({rec['case']} {rec['quantity']}): {float(got):.6g} {unit}, expected {want:.6g} {unit}"
    if "rel" in rec:
        assert float(got) == pytest.approx(want, rel=rec["rel"], abs=0.0), \
            f"{what} +- {100 * rec['rel']:g} % ({rec['source']})"
    else:
        assert float(got) == pytest.approx(want, abs=rec["abs"], rel=0.0), \
            f"{what} +- {rec['abs']:g} {unit} ({rec['source']})"


def expected_test(study, fixture: str = "run_dir"):
    """A test function, parametrized over the records of ``study.EXPECTED``, that checks the run
    folder given by the fixture ``fixture`` of the calling test module (marked slow; records with
    ``xfail`` are strict expected failures with their reason)."""
    params = [pytest.param(key, id=key, marks=[pytest.mark.xfail(strict=True, reason=rec["xfail"])]
                           if isinstance(rec, dict) and rec.get("xfail") else [])
              for key, rec in study.EXPECTED.items()]

    @pytest.mark.slow
    @pytest.mark.parametrize("key", params)
    def test_expected(key, request):
        check_expected(study, key, request.getfixturevalue(fixture))

    test_expected.__doc__ = f"{study.NAME}: the quick run against each record of its EXPECTED (tests/study_expected.py)."
    return test_expected
