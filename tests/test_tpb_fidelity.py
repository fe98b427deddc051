"""Fidelity variants of the three-point bending (issue 15): the notch shape, fracture excluded
under the load and at the supports, and the linear-elastic reference of the unbroken beam.

No load steps: each test builds a mesh or scene at quick resolution, or does one linear solve
(a few seconds in all, one process).
"""
from __future__ import annotations

import warnings

import ngsolve as ngs
import numpy as np
import pytest

import ngtmc
from ngtmc.study import StudyError
from ngtmc.study import study_parameters
from ngtmc.studies import _tpb_elastic as elastic
from ngtmc.studies import three_point_bending as tpb
from tpb_runs import solve_quick


def _scene(overrides):
    _, p = study_parameters(tpb, "quick", overrides)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
        return p, tpb.cases(p)[0].build_scene().check()


def _region(mesh, x, y):
    mp = mesh(x, y)
    return mesh[ngs.ElementId(ngs.VOL, mp.nr)].mat if mp.nr >= 0 else None


def _area(mesh, region=".*"):
    return ngs.Integrate(ngs.CoefficientFunction(1.0), mesh, definedon=mesh.Materials(region))


def test_defaults_are_the_paper_scene():
    P = {k: v[0] for k, v in tpb.PARAMETERS.items()}
    assert (P["notch_shape"], P["indenter_exclusion"], P["support_exclusion"]) == ("flat", 0.0, True)
    p, scene = _scene({})
    assert "load_zone" not in scene.mesh.GetMaterials()
    assert scene.fracture_region_names == ["beam", "band"]
    assert _area(scene.mesh, "beam|band|support_zone") == pytest.approx(16.0 - 0.03 * 0.4, rel=1e-9)


@pytest.mark.parametrize("shape, width, area", [("flat", 0.03, 0.03 * 0.4), ("v", 0.03, 0.03 * 0.4 / 2),
                                                 ("slit", 0.015, 0.015 * 0.4)])
def test_notch_shapes(shape, width, area):
    """The notch is cut out of the band: its area, its width at mid-depth and its tip at 0.4 mm."""
    p, scene = _scene({"notch_shape": shape})
    mesh = scene.mesh
    assert scene.fracture_region_names == ["beam", "band"]
    assert _area(mesh, "beam|band|support_zone") == pytest.approx(16.0 - area, rel=1e-9)
    half = width / 2 * (0.5 if shape == "v" else 1.0)  # half width at y = 0.2 (mid-depth)
    assert mesh(4.0 + 0.9 * half, 0.2).nr == -1 and mesh(4.0 + 1.1 * half, 0.2).nr >= 0
    assert mesh(4.0, 0.399).nr == -1 and mesh(4.0, 0.401).nr >= 0
    if shape == "v":  # sharp tip: beside the axis just below the tip is material
        assert mesh(4.0 + 0.002, 0.399).nr >= 0


@pytest.mark.parametrize("loading, a", [("indenter", 0.1), ("window", 0.1), ("window", 0.03)])
def test_indenter_exclusion(loading, a):
    """A 2a x a rectangle under the load is region load_zone, same material, no fracture; the
    window stays one 0.1 mm load boundary when the zone is narrower or wider than it."""
    p, scene = _scene({"loading": loading, "indenter_exclusion": a})
    mesh = scene.mesh
    assert "load_zone" in mesh.GetMaterials()
    assert scene.fracture_region_names == ["beam", "band"]
    assert _area(mesh, "load_zone") == pytest.approx(2 * a * a, rel=1e-9)
    assert _region(mesh, 4.0 + 0.99 * a, 2.0 - 0.99 * a) == "load_zone"
    assert _region(mesh, 4.0, 2.0 - 1.01 * a) == "band"
    assert _area(mesh, "beam|band|support_zone|load_zone") == pytest.approx(16.0 - 0.03 * 0.4, rel=1e-9)
    if loading == "window":
        length = ngs.Integrate(ngs.CoefficientFunction(1.0), mesh, definedon=mesh.Boundaries("load"))
        assert length == pytest.approx(0.1)


def test_support_exclusion_off_same_mesh():
    _, p = study_parameters(tpb, "quick")
    _, q = study_parameters(tpb, "quick", {"support_exclusion": "false"})
    assert q["support_exclusion"] is False
    scene = tpb.build_scene(q)
    assert scene.fracture_region_names == ["beam", "band", "support_zone"]
    a, b = tpb.build_mesh(p), scene.mesh
    assert np.array_equal(np.asarray(a.ngmesh.Coordinates()), np.asarray(b.ngmesh.Coordinates()))


def test_support_zone_equal_to_support_length():
    """support_zone = support_length: only the 0.1 x 0.1 support squares are left without fracture."""
    p, scene = _scene({"support_zone": 0.1})
    assert _area(scene.mesh, "support_zone") == pytest.approx(2 * 0.1 * 0.1, rel=1e-9)
    assert _region(scene.mesh, 0.15, 0.05) == "beam" and _region(scene.mesh, 0.05, 0.05) == "support_zone"


def test_bad_fidelity_inputs():
    for overrides, match in (({"notch_shape": "u"}, r"notch_shape = 'u' is not one of 'flat', 'v', 'slit'"),
                             ({"indenter_exclusion": -0.1}, "indenter_exclusion"),
                             ({"indenter_exclusion": 1.6}, "indenter_exclusion"),  # reaches the notch tip
                             ({"notch_depth": 2.0}, "notch_depth")):
        _, p = study_parameters(tpb, "quick", overrides)
        with pytest.raises(StudyError, match=match):
            tpb.cases(p)
    with pytest.raises(StudyError, match="support_exclusion"):
        study_parameters(tpb, "quick", {"support_exclusion": "sometimes"})
    with pytest.raises(StudyError, match="indenter_exclusion expects a number"):
        study_parameters(tpb, "quick", {"indenter_exclusion": "wide"})


def test_linear_elastic_reference_against_beam_theory():
    """A slender unnotched beam (40 x 2 mm, S/H = 20) on 0.01 mm support segments against
    Euler-Bernoulli + Timoshenko shear (k = 5/6, span between the support centres, 39.99 mm): the
    mid-height deflection within 2 % (stated before the solve: shear is 0.9 % of the deflection,
    the 2D corrections of order (H/S)^2 = 0.25 %, the span uncertain by +-0.005 mm).

    With the study's 0.1 mm segments the same comparison failed (FE 4.0 % stiffer): a segment that
    holds u_y resists the end rotation (rough estimate, a rigid strip on a half-plane: rotational
    stiffness about pi E' s^2 / 8, here a 9 % smaller deflection); it scales with s^2, so 0.01 mm
    segments make it about 0.1 %. The test also checks that the 0.1 mm segments stiffen the beam."""
    _, p = study_parameters(tpb, "quick", {"notch_depth": 0.0, "beam_length": 40.0, "support_length": 0.01})
    beam = elastic.beam_theory_slope(p)
    S = 39.99
    assert beam == pytest.approx(1e-3 / (S ** 3 * 0.91 / (4 * 20.8e3 * 8) + S * 2.6 / (4 * 5 / 6 * 20.8e3 * 2)))
    r = tpb.linear_elastic_slope(p, order=2)
    assert r["slope_mid_height"] == pytest.approx(beam, rel=0.02)
    _, q = study_parameters(tpb, "quick", {"notch_depth": 0.0, "beam_length": 40.0})
    assert tpb.linear_elastic_slope(q, order=2)["slope_mid_height"] > 1.02 * r["slope_mid_height"]


def test_linear_elastic_reference_of_the_study_beam():
    """The study's 8 x 2 mm beam (S/H = 4): order 2 and 3 agree to 1 % on the quick mesh (measured
    0.6 %; the reference is compared with slopes 2-10 % apart); the notch
    and the window's local indentation make the beam softer. Beam theory is not a check here: at
    S/H = 4 it is 5.7-6.0 % softer than the 2D solution (measured: 1.216 against 1.286-1.290 N/mm per
    micrometre; a first version of this test with a 5 % tolerance failed), see docs/fidelity.md."""
    _, p = study_parameters(tpb, "quick", {"notch_depth": 0.0})
    assert elastic.beam_theory_slope(p) == pytest.approx(1.216, abs=1e-3)  # N/mm per micrometre, by hand
    r2, r3 = tpb.linear_elastic_slope(p, order=2), tpb.linear_elastic_slope(p, order=3)
    assert r2["slope"] == pytest.approx(r3["slope"], rel=0.01)
    assert r2["slope"] < r2["slope_mid_height"]
    _, q = study_parameters(tpb, "quick")
    notched = tpb.linear_elastic_slope(q, order=2)
    assert notched["slope"] < r2["slope"]


#: stopped once the force has fallen below half the peak (the crack has run; the tests need no
#: more of the curve)
WINDOW = {"loading": "window", "stop_load": 0.06, "stop_after_drop": 0.5}

#: the variants compared with it by their peaks: stopped below 0.8 of their peak, past it (measured
#: on the window variant, one thread: the peak after 20 s, below 0.8 of it after 35 s, below half
#: after 56 s)
PAST_THE_PEAK = {"stop_after_drop": 0.8}


@pytest.fixture(scope="module")
def window_run(tmp_path_factory):
    """The diagnostic variant ``--set loading=window`` (Ambati's set-up: the load on a 0.1 mm window
    of the beam top, no indenter, no void, order 1 everywhere) at quick with the study's default
    scheme, past its peak: (results of the case, history, parameters)."""
    return solve_quick(tmp_path_factory, "window", WINDOW)


@pytest.mark.slow
def test_ambatis_own_set_up_solves_past_its_peak(window_run):
    """Ambati's curve compares unshifted (no gap) with the window variant: its peak within the
    study's target (42 N/mm, 15 %), and its rising branch within 5 % of the linear-elastic slope
    of the same beam and element order, below it (the damage that AT-2 starts at once softens it,
    docs/fidelity.md); past the peak the crack has run."""
    r, h, p = window_run
    target = {t["quantity"]: t for t in tpb.targets(p)}["peak_force"]
    assert target["value"] == 42.0
    assert r["peak_force"] == pytest.approx(42.0, rel=target["tolerance"])
    slope = tpb.elastic_slope(h["load"], h["force"])
    reference = tpb.linear_elastic_slope(p, order=1)["slope"]
    print(f"slope {slope:.4f} against the linear-elastic {reference:.4f} N/mm per micrometre")
    assert slope == pytest.approx(reference, rel=0.05) and slope < reference
    assert h["force"].iloc[-1] < 0.5 * r["peak_force"]


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="measured 2026-11-25: the window variant peaks at 0.04113 mm (quick, path "
                   "following), 10.6 % before Ambati's 0.046 mm; its peak force is 11.5 % low (37.15 N/mm) on a "
                   "rising branch 2.3 % stiffer (order 1), so it reaches its peak early (docs/fidelity.md)")
def test_ambatis_own_set_up_peaks_where_ambati_does(window_run):
    r, _, p = window_run
    target = {t["quantity"]: t for t in tpb.targets(p)}["peak_load"]
    assert target["value"] == pytest.approx(0.046)
    assert r["peak_load"] == pytest.approx(0.046, rel=target["tolerance"])


@pytest.fixture(scope="module")
def v_window_run(tmp_path_factory):
    """The window variant with a V-notch of the same depth and mouth width (``--set loading=window
    --set notch_shape=v``) at quick, the study's default scheme, past its peak."""
    return solve_quick(tmp_path_factory, "v_window", {**WINDOW, **PAST_THE_PEAK, "notch_shape": "v"})[0]


@pytest.mark.slow
def test_the_v_notch_raises_the_peak_of_ambatis_set_up(window_run, v_window_run):
    """docs/fidelity.md: of the variants, the notch shape moves the peak most. A V-notch of the
    same depth and mouth width (sharp tip) raises the window variant's peak by more than 6 % at
    every resolution measured (single-pass: +9.8 % quick, +7.2 % medium, +6.3 % paper), while a
    split, the load introduction or fracture exclusions move it by at most 1.5 %."""
    flat, v = window_run[0]["peak_force"], v_window_run["peak_force"]
    print(f"V-notch {v:.3f} against flat {flat:.3f} N/mm: {100 * (v / flat - 1):+.2f} %")
    assert v > 1.06 * flat


#: Variants that move the window variant's peak by at most 0.7 % in docs/fidelity.md (single-pass and
#: path following, quick): the spectral split (Ambati's history split) and no fracture in a 0.2 x 0.1 mm
#: rectangle under the window. (Fracture allowed in the support zones, -0.38 %, is measured by a
#: benchmark record, not here: each of these runs costs about 85 s of the CI's 15 minutes.)
SMALL_MOVERS = {"spectral": {"split": "spectral"},
                "no_fracture_under_the_window": {"indenter_exclusion": 0.1}}


@pytest.fixture(scope="module", params=list(SMALL_MOVERS))
def small_mover_run(request, tmp_path_factory):
    """The window variant with one of SMALL_MOVERS, solved past its peak (stopped below 0.8 of it, or at
    0.05 mm)."""
    return request.param, solve_quick(tmp_path_factory, request.param, {**WINDOW, **PAST_THE_PEAK, "stop_load": 0.05,
                                                                    **SMALL_MOVERS[request.param]})


@pytest.mark.slow
def test_the_split_and_the_fracture_exclusions_do_not_close_the_gap(window_run, small_mover_run):
    """Issue 15's candidate (a), the split, and the exclusion under the load, each solved past its peak:
    none moves the window variant's peak by 3 % (the flat notch's peak scatters by 1.5 % between
    meshes, docs/fidelity.md), so none explains the 11.5 % between it and Ambati's 42 N/mm. The run
    is past its peak (the force has fallen below 0.8 of it)."""
    name, (r, h, _) = small_mover_run
    flat = window_run[0]["peak_force"]
    change = r["peak_force"] / flat - 1.0
    print(f"{name}: {r['peak_force']:.3f} against {flat:.3f} N/mm ({100 * change:+.2f} %)")
    assert abs(change) < 0.03
    assert r["peak_force"] < 0.92 * 42.0
    assert h["force"].iloc[-1] < PAST_THE_PEAK["stop_after_drop"] * r["peak_force"]
