"""The report's figures of the L-panel study (``studies/l_panel.py``): recorded runs, read from
``studies/records/l_panel.json`` (:func:`ngtmc.study.measured`), not computed in the run; and the
AT-2 strength of the l0 sweep. Forces in N for the whole 100 mm panel, loads and l0 in mm.

The file name starts with an underscore: it is a helper, not a study.
"""
from __future__ import annotations

import numpy as np

from ngtmc.study import records

#: The l0 sweep (case monotonic, quick; the first row is today's l0), record keys in sweep order.
L0_SWEEP_KEYS = ("quick_monotonic", "quick_monotonic_l0_4.75", "quick_monotonic_l0_12", "quick_monotonic_l0_33.33",
                 "quick_monotonic_l0_33.33_h_far_8")
#: The runs of the paper's schedule with the refined band over the whole width (band_left = 0) and
#: the same-resolution control with the study's band, record keys.
WHOLE_WIDTH_KEYS = ("medium_path_following_band_left_0",
                    "quick_path_following_band_left_0_l0_2.375",
                    "quick_path_following_band_left_0_l0_4.75",
                    "quick_path_following_band_left_150_l0_4.75",
                    "medium_path_following_band_left_0_l0_4.75",
                    "quick_path_following_band_left_0_l0_12")
#: the recorded medium runs with the paper's schedule and path following, by l0 (mm)
MEDIUM_PAPER_SCHEDULE_BY_L0 = {1.1875: "medium_path_following_paper_schedule",
                               2.375: "medium_path_following_l0_2.375",
                               4.75: "medium_path_following_l0_4.75"}


def measured() -> dict:
    """The figures of every recorded run of the study: record key -> figures."""
    return {key: rec["figures"] for key, rec in records("l_panel").items()}


#: Winkler's experimental peak band (whole 100 mm panel, N): the paper's 7.6 kN is its upper bound.
WINKLER_PEAK_BAND = (6700.0, 7600.0)
#: Concrete's tensile strength (Winkler), MPa: the strength l0_for_strength matches in the sweep.
SIGMA_T = 2.7


def at2_strength(E: float, Gc: float, l0: float) -> float:
    """Homogeneous (1D) strength of AT-2, MPa: 3 sqrt(3)/16 sqrt(E Gc / l0) (E in MPa, Gc in N/mm,
    l0 in mm)."""
    return 3.0 * np.sqrt(3.0) / 16.0 * np.sqrt(E * Gc / l0)


def l0_for_strength(E: float, Gc: float, sigma: float) -> float:
    """The l0 (mm) at which AT-2's homogeneous strength is ``sigma`` (MPa): 27 E Gc / (256 sigma^2)."""
    return 27.0 * E * Gc / (256.0 * sigma ** 2)


def figures(p: dict) -> list[dict]:
    """The report's figures of recorded runs: the l0 sweep (L0_SWEEP_KEYS, quick, far mesh of quick:
    peaks against l0, with Winkler's band and Ambati's first-loading peak), the reload peaks of a
    cracked panel (:func:`_reload_figure`) and the reload peak against l0 at medium
    (:func:`_reload_l0_figure`)."""
    runs = measured()
    rows = [r for r in (runs[k] for k in L0_SWEEP_KEYS) if r["h_far"] == 25.0]
    l0s = [r["l0"] for r in rows]
    x = [min(l0s) / 1.2, max(l0s) * 1.2]
    return [{
        "title": "First-loading peak against l0 (recorded l0 sweep, quick)",
        "x_title": "phase-field length l0 (mm)", "y_title": "peak force (N, whole 100 mm panel)", "x_log": True,
        "caption": ("Peak force of the monotonic case against l0, measured at quick (h_band = 2 mm, so l0 = "
                    "1.1875 mm is not resolved: h = 1.7 l0) with the commands of the study docstring; recorded "
                    "data of the study, not computed in this run. l0 = 33.33 mm gives AT-2 the strength 2.7 MPa "
                    "of concrete. At l0 = 1.1875 mm, also the medium mesh's peaks: the single-pass scheme's (its "
                    "damage lags one step) and path following's (two runs). Look for: whether any l0 reaches Winkler's "
                    "6.7-7.6 kN band (none does); path following at medium 2-5 % above Ambati's 16 kN."),
        "series": [
            {"label": "this model, monotonic peak (quick)", "kind": "curve", "x": l0s,
             "y": [r["peak_force"] for r in rows]},
            {"label": "Winkler experiments, peak band 6.7-7.6 kN", "kind": "band", "x": x,
             "y_lower": [WINKLER_PEAK_BAND[0]] * 2, "y_upper": [WINKLER_PEAK_BAND[1]] * 2},
            {"label": "Ambati et al. 2015, Fig. 19: about 16 kN at l0 = 1.1875 mm", "kind": "points",
             "x": [1.1875], "y": [16000.0]},
            {"label": "this model, monotonic peak at medium (h_band = 1 mm), single-pass", "kind": "points",
             "x": [1.1875], "y": [float(runs["medium_monotonic"]["peak_force"])]},
            {"label": "this model, first-loading peak at medium, path following (no damage lag)", "kind": "points",
             "x": [1.1875, 1.1875],
             "y": [float(runs["quick_turn_past_the_peak"]["path_following_medium"]
                         ["first_loading_peak_force"]),
                   float(runs["medium_path_following_paper_schedule"]["first_loading_peak_force"])]},
        ],
    }, _reload_figure(), _reload_l0_figure()]


def _whole_width_by_resolution(whole_width) -> dict:
    """The finished runs (WHOLE_WIDTH_KEYS) with the band over the whole width, by resolution (medium first)."""
    out: dict = {}
    for res in ("medium", "quick", "paper"):
        rows = sorted((r for r in whole_width if r["resolution"] == res and r["band_left"] == 0.0
                       and r["status"] == "finished"), key=lambda r: r["l0"])
        if rows:
            out[res] = rows
    return out


def _reload_l0_figure() -> dict:
    """The report's figure of the recorded first-loading and reload peaks against l0 at medium with
    the paper's schedule (path following), against the paper's 7.6 kN."""
    runs = measured()
    whole_width = [runs[k] for k in WHOLE_WIDTH_KEYS]
    l0s = sorted(MEDIUM_PAPER_SCHEDULE_BY_L0)
    rec = [runs[MEDIUM_PAPER_SCHEDULE_BY_L0[l0]] for l0 in l0s]
    wide = runs["medium_path_following_band_left_100"]
    quick_band = sorted((r for r in whole_width if r["band_left"] > 0 and r["status"] == "finished"),
                        key=lambda r: r["l0"])
    x = [l0s[0] / 1.2, l0s[-1] * 1.2]
    return {
        "title": "Reload peak against l0 (recorded runs, medium, the paper's schedule)",
        "x_title": "phase-field length l0 (mm)", "y_title": "force (N, whole 100 mm panel)", "x_log": True,
        "caption": ("First-loading and reload peaks of the case main (0 -> 6.3 -> 6 -> 7 mm) at medium (h_band = "
                    "1 mm) with path following, for the study's l0 = 1.1875 mm and twice and four times it "
                    "(--set l0=...; the paper's l0 is not legible in its text); recorded data of the study, not "
                    "computed in this run. Look for: the reload peak falls much faster with l0 than the first-loading "
                    "peak (-26 % against -9 % from 1.1875 to 2.375 mm), and the paper's 7.6 kN lies between the "
                    "two smaller l0; at 4.75 mm the crack grows again at the turning point's force, with no reload "
                    "peak above it. But every one of these cracks stops near the refined band's end (x = 150 mm) "
                    "by the turning point: with the band from x = 100 mm (--set band_left=100, l0 = 1.1875 mm) "
                    "the crack stops at x = 100 mm and the reload peak halves, 4.34 kN (the single point), so "
                    "these reload peaks are set by the band's extent, a choice of the mesh. With the band over the "
                    "whole width (--set band_left=0) the crack runs through the panel's width before the turning "
                    "point at every l0 whose run finished, and the panel reloads to no peak: those points are the "
                    "force left at 6.3 mm (below 0.1 kN); at quick the study's band reloads the same l0 to 5.48 kN "
                    "(the control)."),
        "series": [
            {"label": "first-loading peak (medium, path following)", "kind": "curve", "x": l0s,
             "y": [float(r["first_loading_peak_force"]) for r in rec]},
            {"label": "reload peak (medium, path following)", "kind": "curve", "x": l0s,
             "y": [float(r["reload_peak_force"]) for r in rec]},
            {"label": "force at the turning point, 6.3 mm", "kind": "points", "x": l0s,
             "y": [float(r["force_at_turning_point"]) for r in rec]},
            {"label": "reload peak with the band from x = 100 mm (medium, path following)", "kind": "points",
             "x": [l0s[0]], "y": [float(wide["reload_peak_force"])]},
            *[{"label": f"force at the turning point, band over the whole width ({res}): the crack through the "
                        "panel's width, no reload peak", "kind": "points", "x": [r["l0"] for r in rows],
               "y": [float(r["force_at_turning_point"]) for r in rows]}
              for res, rows in _whole_width_by_resolution(whole_width).items()],
            {"label": "reload peak with the study's band, quick (the same-resolution control)", "kind": "points",
             "x": [r["l0"] for r in quick_band], "y": [float(r["reload_peak_force"]) for r in quick_band]},
            {"label": "Ciceri et al. 2026: reload peak 7.6 kN", "kind": "curve", "x": x, "y": [7600.0, 7600.0]},
        ],
    }


def _reload_figure() -> dict:
    """The report's figure of the recorded reload peaks of a cracked panel (turning point past the
    first-loading peak): path following and the paper's single-pass scheme at quick, path following
    at the paper's resolution, against the paper's 7.6 kN."""
    runs = measured()
    turn = runs["quick_turn_past_the_peak"]
    paper = runs["paper_path_following_completed"]
    x = [6.55, 6.85]
    return {
        "title": "Reload peak of the cracked panel (recorded runs)",
        "x_title": "indenter displacement at the reload peak (mm)", "y_title": "reload peak (N, whole 100 mm panel)",
        "caption": ("Reload peaks of runs whose first loading passed its peak before the turning point, so that "
                    "the panel reloads with a crack: at quick with the turning point at 6.6 mm (--set "
                    "load_cases=cyclic --set schedule=0,6.6,6,7), path following and the paper's single-pass "
                    "scheme, at medium (path following), and with the paper's turning point 6.3 mm at medium and at "
                    "the paper's resolution (path following). Recorded data "
                    "of the study, not computed in this run. Look for: the single-pass scheme, whose damage keeps "
                    "growing while unloading (+45 % W_f at quick), reloads 3 % higher than path following, not "
                    "lower: the scheme does not explain the paper's 7.6 kN; nor does the mesh: with the paper's turning "
                    "point, medium and the paper's resolution agree within 2 %; nor does the split: the spectral split "
                    "reloads to the same 8.679 kN at medium as the J-based vol-dev split."),
        "series": [
            {"label": "path following, quick (turning point 6.6 mm)", "kind": "points",
             "x": [turn["path_following"]["reload_peak_load"]], "y": [float(turn["path_following"]["reload_peak_force"])]},
            {"label": "single-pass (paper's scheme), quick (turning point 6.6 mm)", "kind": "points",
             "x": [turn["single_pass"]["reload_peak_load"]], "y": [float(turn["single_pass"]["reload_peak_force"])]},
            {"label": "path following, medium (turning point 6.6 mm)", "kind": "points",
             "x": [turn["path_following_medium"]["reload_peak_load"]],
             "y": [float(turn["path_following_medium"]["reload_peak_force"])]},
            {"label": "path following, medium (turning point 6.3 mm)", "kind": "points",
             "x": [runs["medium_path_following_paper_schedule"]["reload_peak_load"]],
             "y": [float(runs["medium_path_following_paper_schedule"]["reload_peak_force"])]},
            {"label": "path following, medium, spectral split (turning point 6.3 mm)", "kind": "points",
             "x": [runs["medium_path_following_paper_schedule_spectral"]["reload_peak_load"]],
             "y": [float(runs["medium_path_following_paper_schedule_spectral"]["reload_peak_force"])]},
            {"label": "path following, paper resolution (turning point 6.3 mm)", "kind": "points",
             "x": [paper["reload_peak_load"]], "y": [float(paper["reload_peak_force"])]},
            {"label": "Ciceri et al. 2026: reload peak 7.6 kN (displacement not given)", "kind": "curve", "x": x,
             "y": [7600.0, 7600.0]},
        ],
    }

