"""CI test of the l_panel study at ``quick`` resolution: case ``main`` (load 0 -> 6.3 -> 6 -> 7 mm)
and case ``monotonic`` (0 -> 6.6 mm, past the first-loading peak; about 70 s more).

Thickness convention: ``Scene(thickness=100)``, the Winkler panel's, so every force is for the
whole panel in N and compares directly with the paper's 7.6 kN = 7600 N. k_u = 50 is in 1/N with
W_f per unit thickness (the history's fracture_energy is for the whole panel, 100 times that).

Measured at quick (8516 elements, h_band = 2 mm = 1.7 l0; see the study's records and EXPECTED):
the first loading does not reach its peak before the turning point (17.9 kN at 6.3 mm, diffuse
damage, max alpha 0.41);
the crack runs on reloading, from a peak of 23.6 kN at 6.46 mm. The published reload peak (7.6 kN)
and the "lower peak on reloading" are not met, and not at medium either (h_band = 1 mm: 18.2 kN
at the turning point, reload peak at least 20.8 kN at 6.35 mm, run stopped there): the first
loading is mesh-independent to 1.5 % between the two, so this is not a resolution effect (see the
study docstring). Those two checks are strict xfails with the measured values (the published reload
peak as a record of the study's EXPECTED, checked by test_expected); the irreversibility checks
(what the study is about) pass.

The monotonic case peaks at 22.96 kN at 6.451 mm, past the paper's turning point; Ambati et al.
2015 read about 16 kN (whole 100 mm panel): +43.5 %, a strict xfail record of EXPECTED. The l0
sweep of the study (L0_SWEEP, four quick runs) is not run here; its record is checked.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ngtmc.study import load_study, records
from ngtmc.study import study_parameters
from study_expected import expected_test

S = load_study("l_panel")
#: the measured runs of the study (studies/records/l_panel.json): record key -> figures
MEASURED = {key: rec["figures"] for key, rec in records("l_panel").items()}
L0_SWEEP = [MEASURED[key] for key in S.L0_SWEEP_KEYS]
WHOLE_WIDTH = [MEASURED[key] for key in S.WHOLE_WIDTH_KEYS]


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


def test_monotonic_case_passes_its_peak(run_dir):
    """Case ``monotonic`` (0 -> 6.6 mm) goes past the first-loading peak: the peak lies beyond the
    paper's turning point (6.3 mm: the paper's first loading ends before it at quick; measured 22.96 kN
    at 6.451 mm) and the force then drops by more than 10 % (measured 25 % by 6.6 mm, the crack runs,
    max alpha 1)."""
    import json

    res = json.loads((run_dir / "metadata.json").read_text())["results"]
    mono = res["monotonic"]
    assert mono["peak_passed"]
    assert mono["first_peak_load"] > S.PARAMETERS["schedule"][0][1]
    assert mono["drop_after_peak"] > 0.10
    assert mono["max_alpha_final"] == pytest.approx(1.0, abs=0.01)


def test_reload_rejoins_the_monotonic_peak(run_dir):
    """Unloading from 6.3 mm, before the peak, freezes the damage and leaves the strength alone: the
    reload peak of ``main`` is the monotonic peak within 5 % (measured +2.9 % at quick, 23.6 against
    22.96 kN; the single-pass lag shifts it slightly)."""
    import json

    res = json.loads((run_dir / "metadata.json").read_text())["results"]
    assert res["main"]["reload_peak_force"] == pytest.approx(res["monotonic"]["peak_force"], rel=0.05)


def test_load_cases_option():
    _, p = study_parameters(S, "quick")
    assert [c.name for c in S.cases(p)] == ["main", "monotonic"]
    _, p = study_parameters(S, "quick", {"load_cases": "monotonic"})
    (case,) = S.cases(p)
    assert case.name == "monotonic" and list(case.schedule.points) == pytest.approx([0.0, 6.6])
    assert [t["case"] for t in S.targets(p)] == ["monotonic"]
    _, p = study_parameters(S, "quick", {"load_cases": "cyclic", "load_introduction": "segment"})
    assert [c.name for c in S.cases(p)] == ["main"]
    _, p = study_parameters(S, "quick", {"load_cases": "monotonic", "load_introduction": "segment"})
    assert list(S.cases(p)[0].schedule.points) == pytest.approx([0.0, 0.6])  # the gap taken off
    with pytest.raises(ValueError, match="load_cases"):
        S.cases(study_parameters(S, "quick", {"load_cases": "reload"})[1])


def test_l0_sweep_record():
    """The recorded l0 sweep (L0_SWEEP, the study's records): its largest l0 is the one at
    which AT-2's homogeneous strength 3 sqrt(3)/16 sqrt(E Gc / l0) is concrete's 2.7 MPa, the quick
    band resolves every l0 but today's (h_band <= l0/2), the peak falls as l0 grows, and no l0
    reaches Winkler's 6.7-7.6 kN band (the study's conclusion). A record check: the sweep itself is
    not run here (four quick runs)."""
    E, Gc = S.PARAMETERS["E"][0], S.PARAMETERS["Gc"][0]
    l0_t = S.l0_for_strength(E, Gc, S.SIGMA_T)
    assert l0_t == pytest.approx(33.33, abs=0.01)
    assert S.at2_strength(E, Gc, l0_t) == pytest.approx(2.7, rel=1e-12)
    assert S.at2_strength(E, Gc, S.PARAMETERS["l0"][0]) == pytest.approx(14.3, abs=0.05)  # the docstring's
    rows = [r for r in L0_SWEEP if r["h_far"] == S.RESOLUTIONS["quick"]["h_far"]]
    l0s = [r["l0"] for r in rows]
    assert l0s[0] == S.PARAMETERS["l0"][0] and l0s[-1] == pytest.approx(l0_t, abs=0.01) and l0s == sorted(l0s)
    assert all(r["h_band"] == S.RESOLUTIONS["quick"]["h_band"] for r in L0_SWEEP)
    assert [r["h_band"] <= r["l0"] / 2 for r in rows] == [False] + [True] * (len(rows) - 1)
    peaks = [r["peak_force"] for r in rows]
    assert all(a > b for a, b in zip(peaks, peaks[1:]))
    assert min(peaks) > S.WINKLER_PEAK_BAND[1]
    # the monotonic regression record is the sweep's first row
    assert S.EXPECTED["monotonic_peak_force"]["value"] == rows[0]["peak_force"]
    assert S.EXPECTED["monotonic_peak_load"]["value"] == rows[0]["peak_load"]
    # the far-mesh check of the largest l0: within 2 %
    fine = [r for r in L0_SWEEP if r["h_far"] < S.RESOLUTIONS["quick"]["h_far"]]
    assert fine and fine[0]["peak_force"] == pytest.approx(rows[-1]["peak_force"], rel=0.02)
    fig = S.figures(study_parameters(S, "quick")[1])[0]
    curve = fig["series"][0]
    assert curve["x"] == l0s and curve["y"] == peaks


def test_reload_peak_record():
    """The recorded reload peaks of a cracked panel (MEASURED, the study's records and the
    report's second figure): the paper's single-pass scheme lets the damage grow while unloading,
    yet reloads higher than path following, so it does not explain the paper's lower 7.6 kN; nor
    does the mesh: with the paper's schedule medium and the paper's resolution agree; nor does the
    split (spectral against J-based vol-dev at medium), nor the load introduction (a held segment
    without indenter and void reloads higher; half the indenter's radius reloads the same); at
    the paper's resolution the reload peak lies 16.2 % above 7.6 kN."""
    turn = MEASURED["quick_turn_past_the_peak"]
    pf, sp = turn["path_following"], turn["single_pass"]
    assert pf["unload_wf_growth"] == 0.0 and sp["unload_wf_growth"] > 0.4 * sp["wf_at_turning_point"]
    assert sp["reload_peak_force"] > pf["reload_peak_force"] > 7600.0
    paper = MEASURED["paper_path_following_completed"]
    assert paper["reload_peak_force"] / 7600.0 - 1.0 == pytest.approx(0.162, abs=0.001)
    fig = S.figures(study_parameters(S, "quick")[1])[1]
    ys = [s["y"][0] for s in fig["series"] if s["kind"] == "points"]
    med = turn["path_following_medium"]
    med6 = MEASURED["medium_path_following_paper_schedule"]
    spectral = MEASURED["medium_path_following_paper_schedule_spectral"]
    assert ys == [pf["reload_peak_force"], sp["reload_peak_force"], med["reload_peak_force"],
                  med6["reload_peak_force"], spectral["reload_peak_force"], paper["reload_peak_force"]]
    # nor does the split: Miehe's spectral split reloads to the J-based vol-dev split's peak
    assert spectral["reload_peak_force"] == pytest.approx(med6["reload_peak_force"], rel=1e-3)
    # nor does the load introduction: without indenter and void (a held segment) the reload peak
    # at medium is higher, not lower
    segment = MEASURED["medium_path_following_segment"]
    assert segment["reload_peak_force"] > 1.05 * med6["reload_peak_force"]
    # nor the indenter's radius (ours, 20 mm): halved, the reload peak moves by 0.2 %
    r10 = MEASURED["medium_path_following_indenter_r10"]
    assert r10["reload_peak_force"] == pytest.approx(med6["reload_peak_force"], rel=0.01)
    # turning point 6.6 mm: quick is too coarse, the reload peak falls to medium by about the square
    # root of the toughness factors
    factor = [1 + h / (2 * S.PARAMETERS["l0"][0]) for h in (2.0, 1.0)]
    assert pf["reload_peak_force"] / med["reload_peak_force"] == pytest.approx((factor[0] / factor[1]) ** 0.5, rel=0.05)
    # the paper's turning point 6.3 mm: medium and the paper's resolution agree within 2 %, both
    # more than 14 % above 7.6 kN (the mesh does not explain the paper's value)
    assert med6["reload_peak_force"] == pytest.approx(paper["reload_peak_force"], rel=0.02)
    assert min(med6["reload_peak_force"], paper["reload_peak_force"]) > 1.14 * 7600.0
    # the first-loading peak without the damage lag at medium: 2-6 % above Ambati's 16 kN
    l0_fig = S.figures(study_parameters(S, "quick")[1])[0]
    (pf_medium,) = [s["y"] for s in l0_fig["series"] if "path following" in s["label"]]
    assert pf_medium == [med["first_loading_peak_force"], med6["first_loading_peak_force"]]
    assert all(0.0 < f / 16000.0 - 1.0 < 0.06 for f in pf_medium)


def test_reload_peak_against_l0_record():
    """The recorded medium runs with the paper's schedule at l0 = 1.1875, 2.375 and 4.75 mm (the
    paper's l0 is not legible in its text): the reload peak falls much faster with l0 than the
    first-loading peak (measured -26 % against -9 % from 1.1875 to 2.375 mm), and the paper's 7.6 kN
    lies between the two smaller l0; the cracks at the turning point have about the same length
    (their tips at x = 134-149 mm, near the band's end at 150 mm). The report's third figure shows
    the same numbers."""
    l0s = (1.1875, 2.375, 4.75)
    rec = [MEASURED[S.MEDIUM_PAPER_SCHEDULE_BY_L0[l0]] for l0 in l0s]
    assert rec[0] is MEASURED["medium_path_following_paper_schedule"]
    assert [r.get("l0", S.PARAMETERS["l0"][0]) for r in rec] == list(l0s)
    first = [r["first_loading_peak_force"] for r in rec]
    reload = [r["reload_peak_force"] for r in rec]
    assert first[0] > first[1] > first[2] and reload[0] > 7600.0 > reload[1] > reload[2]
    assert reload[1] / reload[0] < 0.8 < 0.85 < first[1] / first[0]
    # at 4 x l0 the crack grows again at the turning point's force: no reload peak above it
    assert reload[2] == pytest.approx(rec[2]["force_at_turning_point"], rel=0.01)
    fig = S.figures(study_parameters(S, "quick")[1])[2]
    series = {s["label"]: s for s in fig["series"]}
    assert series["reload peak (medium, path following)"]["y"] == reload
    assert series["first-loading peak (medium, path following)"]["y"] == first


def test_reload_peak_set_by_the_band_end_record():
    """The recorded medium run with the refined band from x = 100 instead of 150 mm (the paper's
    schedule, path following, l0 = 1.1875 mm): the same first loading, but the crack stops at the
    band's end by the turning point in both runs (x = 149 and 100 mm), so the wider band's crack is
    50 mm longer there and the reload peak halves, from above the paper's 7.6 kN to below it. The
    report's third figure shows the point."""
    band = MEASURED["medium_path_following_paper_schedule"]
    r10 = MEASURED["medium_path_following_indenter_r10"]  # reloads as band does, crack_x recorded
    wide = MEASURED["medium_path_following_band_left_100"]
    assert S.PARAMETERS["band_left"][0] == 150.0 and wide["band_left"] == 100.0
    assert r10["crack_x_at_turning_point"] == pytest.approx(150.0, abs=2.0)
    assert wide["crack_x_at_turning_point"] == pytest.approx(100.0, abs=2.0)
    assert wide["first_loading_peak_force"] == pytest.approx(band["first_loading_peak_force"], rel=1e-3)
    assert wide["dissipated_at_turning_point"] > 1.3 * r10["dissipated_at_turning_point"]
    assert wide["reload_peak_force"] < 0.55 * band["reload_peak_force"]
    assert wide["reload_peak_force"] < 7600.0 < band["reload_peak_force"]
    fig = S.figures(study_parameters(S, "quick")[1])[2]
    (point,) = [s for s in fig["series"] if "band from x = 100 mm" in s["label"]]
    assert point["x"] == [1.1875] and point["y"] == [wide["reload_peak_force"]]


def test_a_crack_free_to_run_breaks_the_panel_record():
    """The recorded medium run with the band over the whole width: the same first loading as the
    100 mm band's; before the turning point (6.3 mm) its crack passes both band ends (x = 150 and
    100 mm) while the load stays below 6.3 mm, and by the turning point it has run through the
    panel's 250 mm width (x = 250 -> 4.3 mm), so reloading finds no peak, only a force below 3 % of the 100 mm
    band's reload peak: a crack resolved wherever it runs does not stop at l0 = 1.1875 mm, so the
    study's reload peaks are bounds set by the band (records medium_path_following_band_left_*)."""
    wide = MEASURED["medium_path_following_band_left_100"]
    free = MEASURED["medium_path_following_band_left_0"]
    assert free["band_left"] == 0.0 and free["status"] == "finished"
    assert free["first_loading_peak_force"] == pytest.approx(wide["first_loading_peak_force"], rel=2e-3)
    track = free["crack_track"]
    steps, loads, forces, xs = ([r[i] for r in track] for i in (0, 1, 2, 4))
    assert steps == sorted(steps) and all(x1 <= x0 for x0, x1 in zip(xs, xs[1:]))   # the crack only grows
    before = [i for i, s in enumerate(steps) if s < 421]   # step 421: the turning point
    assert max(loads[i] for i in before) < 6.3 and xs[before[-1]] < wide["crack_x_at_turning_point"] - 50.0
    past_100 = [forces[i] for i in before if xs[i] < 100.0]
    assert past_100 and max(past_100) < wide["reload_peak_force"]
    assert free["crack_x_at_turning_point"] < 0.05 * 250.0   # through the 250 mm width, to within 5 %
    assert free["reload_peak_force"] is None
    assert free["reload_largest_force"] < 0.03 * wide["reload_peak_force"]
    assert free["unload_wf_growth"] == 0.0 and free["dissipated_at_turning_point"] > wide["dissipated_at_turning_point"]


def test_whole_width_runs_break_the_panel_at_every_l0_record():
    """The recorded runs with the band over the whole width (WHOLE_WIDTH): at every l0 measured the
    crack runs through the panel's width (to within 5 % of the 250 mm width) before the turning point, and the
    panel reloads to no peak, while the same quick run with the study's band (from x = 150 mm)
    arrests its crack near the band's end, reaches the same first-loading peak and reloads to a
    peak 70 times the whole width's force at 6.3 mm. The report's third figure shows the points."""
    free = [r for r in WHOLE_WIDTH if r["band_left"] == 0.0 and r["status"] == "finished"]
    assert {r["l0"] for r in free} >= {1.1875, 4.75}
    for r in free:
        assert r["crack_x_at_turning_point"] < 0.05 * 250.0 and r["reload_peak_force"] is None
        assert r["force_at_turning_point"] < 0.01 * r["first_loading_peak_force"]
        assert r["reload_largest_force"] < 1.1 * r["force_at_turning_point"]
        assert r["snap_back_lowest_load"] < 6.3
    (band,) = [r for r in WHOLE_WIDTH if r["band_left"] == 150.0]
    (twin,) = [r for r in free if r["l0"] == band["l0"] and r["resolution"] == band["resolution"]]
    assert band["first_loading_peak_force"] == pytest.approx(twin["first_loading_peak_force"], rel=0.01)
    assert band["crack_x_at_turning_point"] == pytest.approx(150.0, abs=15.0)
    assert band["reload_peak_force"] > 70.0 * twin["force_at_turning_point"]
    # the unfinished medium run at 4 x l0: its crack passes where the band's crack stood at the turning
    # point while the load is still below 6.3 mm, and runs on while the load snaps back
    (med,) = [r for r in WHOLE_WIDTH if r["resolution"] == "medium" and r["l0"] == 4.75]
    band475 = MEASURED["medium_path_following_l0_4.75"]
    assert med["first_loading_peak_force"] == pytest.approx(band475["first_loading_peak_force"], rel=0.01)
    track = med["crack_track"]
    assert all(t1[4] <= t0[4] for t0, t1 in zip(track, track[1:])) and max(t[1] for t in track) < 6.3
    assert track[-1][4] < band475["crack_x_at_turning_point"] - 50.0 and track[-1][1] < track[0][1]
    fig = S.figures(study_parameters(S, "quick")[1])[2]
    shown = {(x, y) for s in fig["series"] if "whole width" in s["label"] for x, y in zip(s["x"], s["y"])}
    assert shown == {(r["l0"], r["force_at_turning_point"]) for r in free}


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


def test_band_left_moves_the_refined_band_only():
    """``band_left`` (mm) moves the left end of the refined band (default 150 mm): the band is
    x in [band_left, 260] x y in [230, 320] mm cut to the panel, the panel's area is unchanged;
    a value outside [0, 250) is refused."""
    import ngsolve as ngs

    def areas(overrides):
        _, p = study_parameters(S, "quick", overrides)
        mesh = S.cases(p)[0].build_scene().mesh
        return (ngs.Integrate(1, mesh, definedon=mesh.Materials("band")),
                ngs.Integrate(1, mesh, definedon=mesh.Materials("band|contact_zone|clamp_strip|panel")), mesh.ne)

    band, panel, ne = areas({})
    # the band above the cut-out's corner (y > 250) spans x from band_left to 260, below it to 250
    assert band == pytest.approx(110 * 70 + 100 * 20, rel=1e-9)
    wide, panel_wide, ne_wide = areas({"band_left": 100})
    assert wide == pytest.approx(160 * 70 + 150 * 20, rel=1e-9)
    assert panel_wide == pytest.approx(panel, rel=1e-9) and panel == pytest.approx(500 ** 2 - 250 ** 2, rel=1e-9)
    assert ne_wide > ne
    with pytest.raises(ValueError, match="band_left"):
        S.cases(study_parameters(S, "quick", {"band_left": 250})[1])[0].build_scene()


def test_void_regulariser_option():
    """``kbar_r`` = 0 (default, paper): no regulariser and linear triangles; ``kbar_r`` > 0: the
    Hessian regulariser of Eq. 3 on the void only, with k_r = kbar_r L^2 K0 (L = ``reg_length``)
    and order-2 displacements there (order 1 elsewhere); a negative factor is refused."""
    _, p = study_parameters(S, "quick")
    scene = S.cases(p)[0].build_scene()
    assert scene.regulariser is None and scene.displacement_order == 1
    _, p = study_parameters(S, "quick", {"kbar_r": 1e-6, "reg_length": 250.0})
    scene = S.cases(p)[0].build_scene()
    reg = scene.regulariser
    assert (reg.regions, reg.kbar_r, reg.length, reg.damping) == ("void", 1e-6, 250.0, "none")
    assert scene.order is None and scene.variable_order and scene.displacement_order == 2
    with pytest.raises(ValueError, match="kbar_r"):
        S.cases(study_parameters(S, "quick", {"kbar_r": -1e-6})[1])[0].build_scene()
