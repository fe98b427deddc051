"""Step control: the three-point bending run repeated for several k_u and du_max.

What this study shows
---------------------
The adaptive displacement control of Ciceri et al. (2026), Eq. 20,

    du = du_max * exp(-k_u (W_f^i - W_f^{i-1}))      (floored at du_min, halved on failure),

shrinks the load step while the fracture energy W_f (Eq. 19, per mm of thickness, in N) grows,
i.e. while a crack runs. ``k_u = 0`` gives constant steps du_max; the larger k_u, the smaller the
steps during crack growth. Because the paper's single-pass staggered scheme lags the damage by one
step, large steps while the crack runs overshoot the peak and delay the drop (the influence of k_u
shown in the paper's Fig. 6). This study runs the three-point-bending scene of
``studies/three_point_bending.py`` (same geometry, same physics, same mesh at a given
resolution) once per (k_u, du_max) pair and records, per case: accepted steps, Newton
iterations, wall time, and the peak force with its error relative to the **reference case**, the
finest one (largest k_u with the smallest du_max). It is the speed-against-error trade-off of the
step rule.

Cases
-----
k_u in {0, 50, 1000} 1/N (``k_u_values``) times du_max in {``du_max_coarse``, ``du_max_fine``}
(resolution keys: they are step sizes). Case names ``ku<k_u>_du<du_max>``, e.g. ``ku1000_du5e-04``.

Resolutions (mesh and step sizes only; the physics is that of three_point_bending)
----------------------------------------------------------------------------------
* ``quick`` (CI, about 5 minutes): a **coarse mesh**, h_band = l0 = 0.03 mm, which does not resolve
  the phase field (the solver warns; the peak is higher than at the finer resolutions: compare the
  cases with each other only, not with Ambati), k_u in {0, 50, 1000} at du_max = 4e-3 mm only,
  stopping just after the peak at 0.105 mm.
* ``medium``: the three_point_bending quick mesh (h_band = l0/2), du_max in {2e-3, 0.5e-3} mm,
  full load 0.15 mm.
* ``paper``: the three_point_bending medium mesh (h_band = l0/3), du_max in {2e-3, 0.5e-3} mm
  (0.5e-3 is the paper's), full load.

Expected result
---------------
Constant steps (k_u = 0) take the fewest steps but overshoot the peak (the crack lags by a step);
k_u = 1000 spends most of its steps in the crack-growth tail (MODEL.md: steps fall to
1e-7..1e-5 mm).

Results (single-pass; every case in ``studies/records/step_control.json``)
--------------------------------------------------------------------------
Peak force error against the finest case of the same resolution, and steps:

==================  ===============  ===============  ===============  ===============
k_u, du_max         quick (4e-3)     medium           paper            steps (paper)
==================  ===============  ===============  ===============  ===============
0, 2e-3 mm          +8.2 % [1]       +27.0 %          +29.0 %          75
50, 2e-3 mm         +7.9 % [1]       +15.0 %          +16.1 %          137
1000, 2e-3 mm       reference [1]    +1.5 %           +1.6 %           574
0, 5e-4 mm          -                +6.8 %           +7.6 %           300
50, 5e-4 mm         -                +5.0 %           +5.4 %           377
1000, 5e-4 mm       -                reference        reference        950
==================  ===============  ===============  ===============  ===============

[1] quick has one du_max, 4e-3 mm, and stops at 0.105 mm. k_u matters: with constant steps the
single-pass scheme overshoots the peak (the crack lags the load), k_u = 1000 comes within 1.5 %
at 60 % of the reference's steps, most of them in the crack tail after the peak. Even the finest
case stays +3.2 % above the converged peak of the same mesh (path following, three_point_bending
record ``medium_path_following``): the lag that Eq. 20 bounds does not vanish at du_max = 5e-4 mm.
"""
from __future__ import annotations

from ngtmc.study import SOLVER_PARAMETERS
from ngtmc.studies import three_point_bending as tpb

NAME = "step_control"
TITLE = "Step control: influence of k_u and du_max (three-point bending)"
SUMMARY = (
    "The three-point bending run (same scene and physics) repeated for k_u = 0, 50, 1000 per N and two "
    "maximum load steps du_max. Per run: accepted steps, Newton iterations, wall time, and the peak "
    "force with its error against the finest run (largest k_u, smallest du_max): the influence of k_u "
    "(paper Fig. 6) and the speed-against-error trade-off of the adaptive displacement control (Eq. 20)."
)

PARAMETERS = {k: v for k, v in tpb.PARAMETERS.items() if k != "k_u"}
PARAMETERS["k_u_values"] = ([0.0, 50.0, 1000.0], "1/N", "values of k_u in Eq. 20 (one run per value and du_max)")
# Eq. 20 sets the steps of the paper's single-pass scheme, which this study measures; the
# three-point bending's own default, path following, sizes its steps by dissipation instead
PARAMETERS["scheme"] = SOLVER_PARAMETERS["scheme"]

RESOLUTIONS = {
    "quick": {"h_band": 0.03, "h_void": 0.04, "h_indenter": 0.1, "h_beam": 0.3,
              "du_max_coarse": 4e-3, "du_max_fine": 4e-3, "stop_load": 0.105},
    "medium": {**{k: v for k, v in tpb.RESOLUTIONS["quick"].items() if k != "du_max"},
               "du_max_coarse": 2e-3, "du_max_fine": 0.5e-3, "stop_load": 0.15},
    "paper": {**{k: v for k, v in tpb.RESOLUTIONS["medium"].items() if k != "du_max"},
              "du_max_coarse": 2e-3, "du_max_fine": 0.5e-3, "stop_load": 0.15},
}
DEFAULT_RESOLUTION = "quick"

RESOLUTION_PARAMETERS = {
    "h_band": ("mm", "element size in the band above the notch"),
    "h_void": ("mm", "element size in the void"),
    "h_indenter": ("mm", "element size in the indenter"),
    "h_beam": ("mm", "element size in the rest of the beam"),
    "du_max_coarse": ("mm", "larger of the two du_max values"),
    "du_max_fine": ("mm", "smaller of the two du_max values"),
    "stop_load": ("mm", "load at which the runs stop (<= final_load; the full 0.15 mm at every resolution)"),
}


def case_name(k_u: float, du_max: float) -> str:
    return f"ku{k_u:g}_du{du_max:.0e}"


def _grid(p):
    kus = [float(k) for k in p["k_u_values"]]
    dus = sorted({float(p["du_max_coarse"]), float(p["du_max_fine"])}, reverse=True)
    return kus, dus


def reference_case(p) -> str:
    """The finest case: largest k_u with the smallest du_max."""
    kus, dus = _grid(p)
    return case_name(max(kus), min(dus))


def cases(p: dict) -> list:
    kus, dus = _grid(p)
    tpb.check_stop_load(p, study="step_control")
    stop = min(float(p["stop_load"]), float(p["final_load"]))
    q = dict(p)
    out = []
    for du in dus:
        for ku in kus:
            case = tpb.make_case(q, name=case_name(ku, du), label=f"k_u = {ku:g} 1/N, du_max = {du:g} mm",
                                 k_u=ku, du_max=du, final_load=stop, snapshot_loads=[0.1, stop])
            # a rough model of the recorded step counts (studies/records/step_control.json), for the
            # order in which a cluster starts the cases: steps ~ stop / du_max, k_u = 1000 about ten times more
            case.cost = stop / du * (1.0 + ku / 100.0)
            out.append(case)
    return out


def references(p: dict) -> list[dict]:
    return tpb.references(p)


def targets(p: dict) -> list[dict]:
    return []


#: Numbers the quick run is checked against (docs/study-interface.md): none, no published numbers for these runs; the tests compare the cases with each other.
EXPECTED: dict = {}


def post_results(p: dict, history, results: dict) -> dict:
    """Add per case: peak-force error and peak-load error against the reference case, step and
    time ratios. Called by the runner with the history DataFrame and its per-case results."""
    ref = reference_case(p)
    r0 = results.get(ref)
    if not r0 or r0.get("peak_force") in (None, 0):
        return results
    for name, r in results.items():
        r["reference_case"] = ref
        if r.get("peak_force") is None:
            continue
        r["peak_force_error"] = (r["peak_force"] - r0["peak_force"]) / r0["peak_force"]
        r["peak_load_error"] = (r["peak_load"] - r0["peak_load"]) / r0["peak_load"]
        if r0.get("steps"):
            r["steps_ratio"] = r["steps"] / r0["steps"]
        if r0.get("wall_time_s") and r.get("wall_time_s"):
            r["wall_time_ratio"] = r["wall_time_s"] / r0["wall_time_s"]
    return results


if __name__ == "__main__":  # python studies/step_control.py [options of `ngtmc run`], e.g. --resolution medium
    import sys

    from ngtmc.cli import run_script
    sys.exit(run_script(NAME))
