"""CI test of the contact_gamma0 study at ``quick`` resolution (all four gamma0, about a minute).

Measured at quick (819 elements, 3400 dofs, du = 0.01 mm; classical reference eps = 2e5 N/mm^3 on
the same mesh with the void left out), parasitic force at u = 0.075 mm (TMC force minus the
classical one there, N/mm) and relative difference to the classical force at u = 0.3 mm:

    gamma0   parasitic   ratio to next   post-contact difference
    1e-4     0.02034     1.96            +35.0 %
    1e-5     0.01037     4.19            +12.3 %
    1e-6     0.002476    8.06            +1.67 %
    1e-7     0.000307    -               +0.26 %

Penalty convergence of the reference (force at 0.3 mm): 0.124348 / 0.124368 / 0.124370 N/mm for
eps = 2e4 / 2e5 / 2e6 N/mm^3.

Why the ratio is 10 only for small gamma0: the void is a spring in series with the lower beam.
With void stiffness kv = c gamma0 k (k the beam tip stiffness) the parasitic force is
F_ref c gamma0 / (1 + c gamma0), proportional to gamma0 only while c gamma0 << 1. One constant
c (fitted to gamma0 = 1e-7) reproduces all four values within about 15 %.
"""
from __future__ import annotations

import pandas as pd
import pytest

from ngtmc.study import load_study
from ngtmc.study import study_parameters
from study_expected import expected_test

S = load_study("contact_gamma0")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """The quick run folder, shared by this module's tests and test_expected."""
    from ngtmc.runner import run_study

    return run_study("contact_gamma0", resolution="quick", output=tmp_path_factory.mktemp("cg") / "run",
                     report=False, vtk=False, progress=False)


@pytest.fixture(scope="module")
def run(run_dir):
    hist = pd.read_csv(run_dir / "history.csv")
    _, p = study_parameters(S, "quick")
    hs = {c: g.sort_values("step") for c, g in hist.groupby("case")}
    return p, hs, S.compare(hs, p)


def test_all_cases_ran(run):
    p, hs, cmp = run
    for g0 in p["gamma0_values"]:
        h = hs[S.case_name(g0)]
        assert h["load"].iloc[-1] == pytest.approx(p["final_load"])
    assert hs["classical"]["load"].iloc[-1] == pytest.approx(p["final_load"])


# the classical reference against beam theory (at the probe load and the final load), and the
# smallest gamma0 against the classical reference (within 1 % at the final load and over the
# post-contact branch): the study's EXPECTED
test_expected = expected_test(S)


def test_classical_reference_is_converged_in_the_penalty(run):
    p, hs, cmp = run
    a = float(hs["classical"]["force"].iloc[-1])
    q = dict(p, penalty_factor=10 * p["penalty_factor"])
    b = float(S.run_classical(q, None)["force"].iloc[-1])
    assert abs(a - b) / abs(b) < 2e-3, (a, b)


def test_pre_contact_parasitic_force_scales_with_gamma0(run):
    p, hs, cmp = run
    g = sorted(float(x) for x in p["gamma0_values"])  # ascending
    par = {x: cmp[S.case_name(x)]["parasitic_force"] for x in g}
    f_ref = cmp["classical"]["pre_contact_force"]
    assert all(v > 0 for v in par.values()), par
    # decreasing with gamma0
    assert all(par[a] < par[b] for a, b in zip(g, g[1:])), par
    # proportional in the dilute regime: the two smallest gamma0 differ by about their ratio (10)
    r = par[g[1]] / par[g[0]]
    assert 7.0 < r < 12.0, (r, par)  # measured 8.06 (quick): slightly below 10 by the series effect
    # series-spring model with one constant fitted to the smallest gamma0 explains all of them
    c = par[g[0]] / (f_ref - par[g[0]]) / g[0]
    for x in g:
        model = f_ref * c * x / (1 + c * x)
        assert par[x] == pytest.approx(model, rel=0.2), (x, par[x], model)


def test_post_contact_converges_to_classical(run):
    p, hs, cmp = run
    g = sorted((float(x) for x in p["gamma0_values"]), reverse=True)  # descending
    d = [abs(cmp[S.case_name(x)]["post_contact_diff"]) for x in g]
    assert all(a > b for a, b in zip(d, d[1:])), d
    # smallest gamma0 within 1 % of the classical force at the final load and over the branch:
    # the study's EXPECTED (test_expected)
