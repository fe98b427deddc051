"""CI test of the l_panel study at ``quick`` resolution (load 0 -> 6.3 -> 6 -> 7 mm).

Thickness convention: ``Scene(thickness=100)``, the Winkler panel's, so every force is for the
whole panel in N and compares directly with the paper's 7.6 kN = 7600 N. k_u = 50 is in 1/N with
W_f per unit thickness (the history's fracture_energy is for the whole panel, 100 times that).

Measured at quick (8516 elements, h_band = 2 mm = 1.7 l0; see the study's MEASURED and EXPECTED):
the first loading does not reach its peak before the turning point (17.9 kN at 6.3 mm, diffuse
damage, max alpha 0.41);
the crack runs on reloading, from a peak of 23.6 kN at 6.46 mm. The published reload peak (7.6 kN)
and the "lower peak on reloading" are not met, and not at medium either (h_band = 1 mm: 18.2 kN
at the turning point, reload peak at least 20.8 kN at 6.35 mm, run stopped there): the first
loading is mesh-independent to 1.5 % between the two, so this is not a resolution effect (see the
study docstring). Those two checks are strict xfails with the measured values (the published reload
peak as a record of the study's EXPECTED, checked by test_expected); the irreversibility checks
(what the study is about) pass.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ngtmc.study import load_study, study_parameters
from study_expected import expected_test

S = load_study("l_panel")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """The quick run folder, shared by this module's tests and test_expected."""
    from ngtmc.runner import run_study

    return run_study("l_panel", resolution="quick", output=tmp_path_factory.mktemp("lp") / "run",
                     report=False, vtk=False, progress=False)


@pytest.fixture(scope="module")
def run(run_dir):
    hist = pd.read_csv(run_dir / "history.csv")
    _, p = study_parameters(S, "quick")
    h = hist[hist["case"] == "main"].sort_values("step").reset_index(drop=True)
    return p, h, S.phases(h, p)


def test_schedule_completed(run):
    p, h, ph = run
    assert ph["completed"]
    assert ph["unload_settled_steps"] >= 3


def test_no_damage_growth_while_unloading(run):
    p, h, ph = run
    # after the first 25 % of the unloading path (the single-pass scheme's lag, see phases())
    assert abs(ph["unload_max_alpha_change"]) <= 1e-9
    assert abs(ph["unload_wf_change"]) <= 1e-9 * ph["wf_at_turning_point"]
    # the lag itself: measured +7.8 % of W_f at quick, +21 % at medium (up to 0.06 mm below the turning point)
    assert ph["unload_wf_lag"] <= 0.3 * ph["wf_at_turning_point"]


def test_damage_is_irreversible(run):
    p, h, ph = run
    wf = h["fracture_energy"].to_numpy()
    ma = h["max_alpha"].to_numpy()
    assert (np.diff(wf) >= -1e-9 * wf.max()).all()
    assert (np.diff(ma) >= -1e-12).all()


def test_reload_retraces_unloading_branch(run):
    """Damage is frozen between 6 and 6.3 mm: reloading follows the unloading curve."""
    p, h, ph = run
    u1, u2 = p["schedule"][1], p["schedule"][2]
    load = h["load"].to_numpy()
    i1 = int(np.argmax(np.isclose(load, u1)))
    i2 = i1 + int(np.argmax(np.isclose(load[i1:], u2)))
    un = h.iloc[i1: i2 + 1]
    re = h.iloc[i2:]
    re = re[re["load"] <= u1 + 1e-12]
    un = un[un["load"] <= u1 - 0.1 * (u1 - u2)]
    f_un = np.interp(re["load"], un["load"][::-1], un["force"][::-1])
    sel = (re["load"] >= un["load"].min()) & (re["load"] <= un["load"].max())
    assert sel.sum() >= 3
    assert np.allclose(re["force"][sel], f_un[sel], rtol=0.02)


def test_force_returns_to_first_loading_value_at_gap(run):
    """At u = l_h the unloaded force equals the first-loading force there, within the stiffness lost
    to the (diffuse) damage. Not "about zero" as in the paper: the third medium already carries
    4.8 kN at u = l_h on first loading (the void between the curved indenter and the arm is squeezed
    over about 20 mm; effective contact begins near 5.8 mm)."""
    p, h, ph = run
    assert ph["force_unloaded_at_gap"] == pytest.approx(ph["force_first_loading_at_gap"], rel=0.10)
    assert ph["force_unloaded_at_gap"] <= ph["force_first_loading_at_gap"] * (1 + 1e-6)


@pytest.mark.xfail(strict=True, reason="quick (h_band = 1.7 l0): the first loading ends at 6.3 mm before its "
                   "peak (17.9 kN); the crack runs on reloading at 23.6 kN, so the reload peak is higher "
                   "(medium: 18.2 kN and 20.8 kN)")
def test_reload_peak_lower_than_first_peak(run):
    p, h, ph = run
    assert ph["reload_peak_force"] < ph["first_peak_force"]


# the published reload peak (strict xfail, with the measured values) and the measured quick values
# (regression guard, 5 %): the study's EXPECTED
test_expected = expected_test(S)


def test_segment_loading_variant_has_no_contact():
    """The diagnostic variant ``load_introduction = 'segment'`` (no indenter, no void, the schedule
    minus the gap imposed on the arm's lower face from x = 470 to 500 mm) isolates the fracture
    model from the contact: used to show that the panel's strength does not come from the contact."""
    import ngsolve as ngs

    _, p = study_parameters(S, "quick", {"load_introduction": "segment"})
    case = S.cases(p)[0]
    scene = case.build_scene()
    mesh = scene.mesh
    assert set(mesh.GetMaterials()) == {"band", "contact_zone", "clamp_strip", "panel"}
    assert ngs.Integrate(1, mesh, definedon=mesh.Boundaries("load")) == pytest.approx(30.0)
    assert scene.regulariser is None and scene.displacement_order == 1 and scene.density is None
    assert list(case.schedule.points) == pytest.approx([0.0, 0.3, 0.0, 1.0])
    band = S.references(p)[0]
    assert band["x"][0] == pytest.approx(0.0)  # the Winkler band is not shifted
    with pytest.raises(ValueError, match="load_introduction"):
        S.cases(study_parameters(S, "quick", {"load_introduction": "plate"})[1])[0].build_scene()
