"""The report entries of the C-shape topology optimisation (``studies/c_shape_design.py``): the
comparison of the two designs with fracture on, the gradient checks, the time split, and the
figures of the optimisation histories, force curves and designs (docs/study-interface.md:
``report_table`` and ``report_figure`` entries of ``results``).

The file name starts with an underscore: it is a helper, not a study. Units: mm, N, MPa."""
from __future__ import annotations

import math

LABELS = {"fracture": "designed with fracture", "contact_only": "designed with contact only"}


def _cases(results: dict) -> list:
    return [c for c in LABELS if isinstance(results.get(c), dict) and "objective_final" in results[c]]


def _gain(results: dict, cases: list) -> float | None:
    """With fracture on, the co-design's external work over the contact-only design's, minus 1."""
    if len(cases) < 2:
        return None
    a, b = results["fracture"]["W_fracture_on"], results["contact_only"]["W_fracture_on"]
    return a / b - 1.0 if b and math.isfinite(b) else None


def _comparison(results: dict, cases: list, gain: float | None) -> dict:
    rows = []
    for c in cases:
        r = results[c]
        rows.append([LABELS[c], r["W_as_designed"], r["W_fracture_on"], r.get("peak_force"), r["volume_final"],
                     r["alpha_max"], None if r["crack_x"] is None else f"({r['crack_x']:.3f}, {r['crack_y']:.3f})"])
    caption = ("Each final design run over the whole stroke as designed and with fracture on (the comparison). "
               "W: external work over the stroke; the peak force and the largest phase field (with its place, mm) "
               "of the run with fracture on.")
    if gain is not None:
        caption += f" With fracture on, the co-designed structure absorbs {100 * gain:+.1f} % of the energy of the contact-only one."
    return {"title": "The two designs, run with fracture on", "caption": caption,
            "columns": [{"name": "design", "unit": ""}, {"name": "W as designed", "unit": "N mm"},
                        {"name": "W with fracture on", "unit": "N mm"}, {"name": "peak force, fracture on", "unit": "N/mm"},
                        {"name": "volume fraction", "unit": "-"}, {"name": "largest alpha", "unit": "-"},
                        {"name": "at (x, y)", "unit": "mm"}], "rows": rows}


def _checks(results: dict, cases: list, p: dict) -> dict:
    rows = [[LABELS[c], ch["design"], ch["beta"], ch["direction"], ch["adjoint"], ch["finite_difference"],
             ch["relative_difference"], ch["switches"]] for c in cases for ch in results[c]["gradient_checks"]]
    return {"title": "Gradient checks", "caption": (
        f"Adjoint dJ/dx . d against the central difference (J(x + eps d) - J(x - eps d)) / (2 eps), eps = "
        f"{p['check_eps']:g}, d random with entries in [-1, 1], both runs on the load steps of the run at x; J the "
        "external work. Switches: history points whose branch of max(H, Psi+) differs between the two runs."),
            "columns": [{"name": "optimisation", "unit": ""}, {"name": "design", "unit": ""}, {"name": "beta", "unit": "-"},
                        {"name": "direction", "unit": ""}, {"name": "adjoint", "unit": "N mm"},
                        {"name": "central difference", "unit": "N mm"}, {"name": "relative difference", "unit": "-"},
                        {"name": "switches", "unit": ""}], "rows": rows}


def _times(results: dict, cases: list) -> dict:
    rows = []
    for c in cases:
        r = results[c]
        n = r["evaluations"]
        rows.append([LABELS[c], r["design_variables"], n, r["optimisation_s"], r["forward_s"] / n, r["adjoint_s"] / n,
                     r["adjoint_per_forward"], r["newton_iterations_total"], r["failed_attempts"], r["failed_designs"]])
    return {"title": "Optimisation size and cost", "caption": (
        "Per optimisation: design variables, evaluations (a forward run with its adjoint sweep each, the final "
        "design's included), wall time of the optimisation, mean forward and adjoint time per evaluation, the "
        "adjoint's cost in forward runs, Newton iterations of all forward runs, failed forward attempts that a "
        "retry recovered, and designs none of whose attempts ran (MMA restarted)."),
            "columns": [{"name": "optimisation", "unit": ""}, {"name": "variables", "unit": ""},
                        {"name": "evaluations", "unit": ""}, {"name": "wall", "unit": "s"},
                        {"name": "forward per evaluation", "unit": "s"}, {"name": "adjoint per evaluation", "unit": "s"},
                        {"name": "adjoint / forward", "unit": "-"}, {"name": "Newton iterations", "unit": ""},
                        {"name": "recovered failures", "unit": ""}, {"name": "failed designs", "unit": ""}],
            "rows": rows}


def _figures(results: dict, cases: list, p: dict) -> list:
    hist = {"title": "Objective against evaluation", "x_title": "evaluation", "y_title": "external work W (N mm)",
            "caption": "W of every design MMA evaluated; beta doubles at each stage (1, 2, 4, 8).",
            "series": [{"label": LABELS[c], "kind": "curve", "x": results[c]["optimisation"]["evaluation"],
                        "y": results[c]["optimisation"]["objective"]} for c in cases]}
    vol = {"title": "Volume against evaluation", "x_title": "evaluation", "y_title": "physical volume fraction (-)",
           "caption": f"The bound is {p['volume_fraction']:g}.",
           "series": [{"label": LABELS[c], "kind": "curve", "x": results[c]["optimisation"]["evaluation"],
                       "y": results[c]["optimisation"]["volume"]} for c in cases]}
    curves = {"title": "Force against displacement of the final designs", "x_title": "displacement (mm)",
              "y_title": "force (N/mm)", "caption": "As designed (fracture on for the co-design, off for the "
              "contact-only design); the contact-only design with fracture on is its case's curve in the force plot.",
              "series": [{"label": f"{LABELS[c]}, as designed", "kind": "curve", "x": results[c]["curve_as_designed"]["load"],
                          "y": results[c]["curve_as_designed"]["force"]} for c in cases]}
    out = [hist, vol, curves]
    for c in cases:
        d = results[c]["designs"]
        keys = sorted(d, key=int)
        L, H = p["length"], p["height"]
        out.append({"title": f"Designs, {LABELS[c]}", "x_title": "x (mm), one design per panel", "y_title": "y (mm)",
                    "caption": "Physical density (black: solid, white: third medium; the slot is third medium, the pad "
                               "solid) of the initial design and at the end of each stage of beta, after the "
                               "evaluations " + ", ".join(keys) + " (left to right, then the next row).",
                    "series": [{"label": f"evaluation {k}", "kind": "image", "z": d[k], "reverse": True,
                                "x0": (i % 3) * (L + 0.2), "dx": L / len(d[k][0]), "y0": -(i // 3) * (H + 0.3),
                                "dy": H / len(d[k])} for i, k in enumerate(keys)]})
    return out


def entries(p: dict, results: dict) -> dict:
    """``results`` with the study's tables and figures added (what the cases computed so far)."""
    cases = _cases(results)
    if not cases:
        return results
    out = dict(results)
    gain = _gain(results, cases)
    out["comparison"] = {"report_table": _comparison(results, cases, gain), "report_figure": _figures(results, cases, p),
                         "energy_gain": gain}
    out["gradient_checks"] = {"report_table": _checks(results, cases, p),
                              "worst": max(results[c]["worst_gradient_check"] for c in cases)}
    out["optimisation_cost"] = {"report_table": _times(results, cases)}
    return out
