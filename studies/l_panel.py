"""L-shaped panel, load - unload - reload through an indenter: irreversibility of the crack.

What this study shows
---------------------
The second validation of Ciceri et al. (2026), Sect. "L-shaped panel irreversibility": the
Winkler (2001) L-shaped concrete panel is loaded upward near the end of its horizontal arm by a
solid semicircular indenter that starts 6 mm (l_h) below it, across a third-medium void. The
imposed indenter displacement goes 0 -> 6.3 -> 6 -> 7 mm (load past the peak, unload back to the
contact point, reload). A crack starts at the re-entrant corner. What must be seen:

1. while the indenter crosses the gap the force stays small (the void, gamma0 = 1e-6, only
   stiffens as it is squeezed);
2. first loading: the panel is loaded through the squeezed void, a crack starts at the corner and
   the force peaks;
3. unloading to u = l_h: **no crack growth** (max alpha and W_f constant: the history variable
   H_n = max(H_{n-1}, Psi_plus) keeps alpha from healing), and the force returns to its
   first-loading value at u = l_h;
4. reloading: softer (the crack is there), up to a **lower peak**, 7.6 kN in the paper.

Two cases (``load_cases``): ``main``, the paper's schedule above, and ``monotonic``, 0 ->
``monotonic_to`` = 6.6 mm, past the first-loading peak, compared with Ambati et al. 2015 (Comput.
Mech. 55, Fig. 19: about 16 kN, read as the whole 100 mm panel: with the same parameters this model
carries 0.23 kN per mm of thickness, so 16 kN per mm is ruled out; Ambati's displacement has no gap,
only the force is compared). Run: ``ngtmc run l-panel [-r medium|paper] [--set load_cases=monotonic]``.

Geometry (mm; the paper's Fig. 12 is not available, sizes it does not give are our choices)
-------------------------------------------------------------------------------------------
* panel: 500 x 500 square without the lower-right 250 x 250 quadrant (Winkler); the bottom edge
  of the vertical leg (y = 0, x in [0, 250]) is clamped. Plane strain, thickness 100 mm (the
  Winkler specimen's): forces are for the whole panel, in N, as the paper's 7.6 kN;
* fracture everywhere in the panel except a strip ``clamp_strip`` = 25 mm high along the clamped
  edge (paper), the indenter and the contact zone x in [430, 500] x y in [250, 270] of the arm
  above the indenter (our addition: Winkler loaded the arm through a steel plate, so the load
  introduction is not part of the fracture problem; "What did not work"). No phase field in the void;
* indenter: solid half disc, radius ``indenter_radius`` = 20 mm (our choice), flat side down,
  centred under x = ``load_x`` = 470 mm (Winkler's load point), apex ``gap`` = 6 mm below the
  arm's lower face (y = 250); same material, no fracture. Its flat bottom edge is loaded (upward
  displacement imposed, tangential held); the recorded force is the vertical reaction there;
* void (rho = 0): the box x in [load_x - R - 10, 500] from the indenter's flat edge to the arm,
  minus the indenter; no regulariser (paper), so linear triangles throughout, as the paper
  (``kbar_r`` > 0 puts the Hessian regulariser of Eq. 3 on the void, k_r = kbar_r L^2 K0 with
  L = ``reg_length`` = 500 mm, and order-2 displacements there; an option, not the paper's scene);
* mesh: refined band x in [``band_left`` = 150, 260] x y in [230, 320] around the expected crack
  path (``h_band``), contact zone ``h_contact``, void and indenter ``h_void``, the rest ``h_far``.

Parameters and sources
----------------------
Table 2 of the paper: E0 = 2.58e4 MPa, nu = 0.18, Gc = 8.93e-5 kN/mm = 0.0893 N/mm,
gamma0 = 1e-6. l0 is not legible in the paper's text: l0 = 1.1875 mm (Ambati et al. 2015, who
also used h = 0.5 mm in the cracking region, as the paper). Schedule 0 -> 6.3 -> 6 -> 7 mm,
l_h = 6 mm, k_u = 50 (paper), **in 1/N with W_f per unit thickness** (N mm/mm,
:class:`ngtmc.AdaptiveStepControl`): W_f in the history (whole panel) is 100 times the W_f of
Eq. 20. Residual stiffness 1e-6 (at least gamma0, MODEL.md). Resolutions change mesh and step
sizes only: ``quick`` (CI; h_band = 2 mm = 1.7 l0, so the ResolutionWarning is expected: the
phase field overestimates the toughness by about 1 + h/(2 l0); du_min = 5e-3 mm), ``medium``
(h_band = 1 mm, du_min = 1e-8), ``paper`` (h_band = 0.5 mm as the paper, du_max = 0.01 mm; long).

Expected result (paper): force about zero until the void is squeezed near u = 6 mm; first peak,
crack started by 6.3 mm; unloading with alpha and W_f constant; reloading softer with a lower
peak, 7.6 kN. Winkler's experimental band (peak 6.7 - 7.6 kN at 0.2 mm) is shown shifted by the gap.

Results (forces for the whole panel; every run with its command, date and notes:
``studies/records/l_panel.json``, ``ngtmc.study.records("l_panel")``)
------------------------------------------------------------------------------------------
==============================  ==================  ===================  ==================================
case main, schedule 0-6.3-6-7   first loading       reload peak          record
==============================  ==================  ===================  ==================================
quick, single-pass              17.94 kN at 6.3 [1] 23.62 kN at 6.46     quick
quick, path following           18.08 kN at 6.3 [1] 18.60 kN at 6.311    quick_path_following_no_ceiling
medium, path following          16.84 kN at 6.274   8.68 kN at 6.492     medium_path_following_paper_sched...
paper, path following           16.01 kN at 6.248   8.83 kN at 6.640     paper_path_following_completed_...
paper, p.f., kbar_r = 1e-6 [2]  16.00 kN at 6.248   9.05 kN at 6.635     paper_path_following_cyclic_vo...
==============================  ==================  ===================  ==================================

[1] at the turning point, before the peak. [2] the void regulariser (``kbar_r``); without it the
same run on the current code stalls and fails at 6.209 mm in the first crack run
(``paper_path_following_cyclic_failed_step_242``; docs/performance.md).
Case monotonic: 22.96 kN at 6.451 mm at quick single-pass (+43.5 % against Ambati's 16 kN;
``quick_monotonic``), 18.62 kN with path following, 18.63 kN at medium, **15.72 kN at the paper's resolution (-1.7 %)** (``paper_path_following_partial``).

* Irreversibility holds: once unloading has settled, W_f and max alpha stay constant and the
  reloading curve retraces the unloading one. The single-pass scheme's damage lags one step
  (W_f +7.8 % in the first unloading steps at quick); path following and the monolithic scheme
  have no lag.
* At quick and medium the first loading stops before its peak, so their reload peak is the
  uncracked panel's; at the paper's resolution the panel reloads cracked: 8.83 kN, +16.2 %.
* That reload peak is set by where the refined band ends: the crack arrests there by 6.3 mm.
  With the band from x = 100 mm it reloads to 4.34 kN; with the band over the whole width the
  crack crosses the panel before 6.3 mm and there is no reload peak, at l0 = 1.1875 to 4.75 mm
  (``WHOLE_WIDTH_KEYS``). The paper's 7.6 kN, like ours, needs a crack arrested by its mesh.
* l0 sweep (case monotonic, quick, ``L0_SWEEP_KEYS``): the peak falls from 22.96 to 11.63 kN
  from l0 = 1.1875 to 33.33 mm (AT-2 strength 14.3 -> 2.7 MPa, concrete's): no l0 reaches
  Winkler's band. The report's figures show the recorded runs.

What did not work
-----------------
* Fracture in the contact zone: the contact pressure crushed the arm under the indenter (quick:
  17.8 -> 2.4 kN at u = 6.296 mm with 2.9 N mm/mm of crack energy; 5 kN reload peaks).
* The paper's du_min = 1e-8 mm at quick: more than 450 steps to 6.54 mm (``quick_with_du_min_1e-8``).
* Quick's du_min = 0.005 mm under path following without the growth ceiling: the cyclic case
  failed at 6.468 mm (hence ``PATH_FOLLOWING_DU_MIN``).
* Explaining the +16 % of the paper-resolution reload peak by the single-pass scheme (reloads 3 %
  higher), the element size (+1.7 % from medium), the split (the same to four digits), the
  indenter's radius (-0.2 %) or a held segment instead of the indenter (+10.6 %): records
  ``quick_turn_past_the_peak`` and ``medium_path_following_*``.
* A larger l0 to meet Winkler's band: none does; l0 = 4.75 mm meets Ambati's 16 kN, but Ambati
  used 1.1875 mm.
"""
from __future__ import annotations

from functools import partial

import numpy as np

import ngtmc
from ngtmc.study import Case
from ngtmc.study import SOLVER_PARAMETERS, simulation_options
from ngtmc.studies._l_panel_geometry import (_segment, build_mesh, effective_gap,  # noqa: F401 (interface)
                                            effective_schedule)
from ngtmc.studies._l_panel_figures import (L0_SWEEP_KEYS, MEDIUM_PAPER_SCHEDULE_BY_L0,  # noqa: F401 (interface)
                                           SIGMA_T, WHOLE_WIDTH_KEYS, WINKLER_PEAK_BAND, at2_strength, figures,
                                           l0_for_strength)
from ngtmc.studies._l_panel_results import monotonic_numbers, phases
from ngtmc.studies._l_panel_references import (AMBATI_SOURCE, WINKLER_A_SOURCE,  # noqa: F401 (interface)
                                              WINKLER_BAND_SOURCE, references)

NAME = "l_panel"
TITLE = "L-shaped panel: load, unload, reload through an indenter"
SUMMARY = (
    "Winkler's L-shaped panel (500 x 500 mm without a 250 x 250 quadrant, 100 mm thick, Table 2 of "
    "Ciceri et al. 2026) is pushed upward near the end of its arm by a semicircular indenter that starts "
    "6 mm away across a third-medium void (gamma0 = 1e-6, no regulariser, linear triangles). Schedule "
    "0 -> 6.3 -> 6 -> 7 mm: a crack starts at the re-entrant corner on first loading, does not grow while "
    "unloading (irreversibility), and the reloading is softer with a lower peak (paper: 7.6 kN). The Winkler "
    "experimental band is shown shifted by the gap."
)

#: Parameters added after runs of this study were recorded, at the default those runs had in
#: effect (``band_left``: the band from x = 150 mm): left out of the parameter hash at that default,
#: so that those runs still resume (:func:`ngtmc.study.parameters.added_at_default`).
ADDED_AT_DEFAULT = ("band_left", "kbar_r", "reg_length")

PARAMETERS = {
    "E": (2.58e4, "MPa", "Young's modulus E0 (Table 2)"),
    "nu": (0.18, "-", "Poisson's ratio (Table 2)"),
    "Gc": (0.0893, "N/mm", "critical energy release rate, 8.93e-5 kN/mm (Table 2)"),
    "l0": (1.1875, "mm", "phase-field length scale (Ambati et al. 2015; not legible in the paper)"),
    "gamma0": (1e-6, "-", "void stiffness ratio of Eq. 17 (Table 2)"),
    "residual_stiffness": (1e-6, "-", "added to g(alpha); at least about gamma0 (MODEL.md)"),
    "thickness": (100.0, "mm", "out-of-plane thickness: the Winkler panel (forces for the whole panel, N)"),
    "gap": (6.0, "mm", "gap l_h between indenter apex and the arm's lower face (paper)"),
    "schedule": ([0.0, 6.3, 6.0, 7.0], "mm", "imposed indenter displacement: load, unload to l_h, reload (paper)"),
    "load_x": (470.0, "mm", "x of the indenter axis, 30 mm from the arm's right end (Winkler)"),
    "indenter_radius": (20.0, "mm", "radius of the semicircular indenter (our choice)"),
    "void_margin": (10.0, "mm", "void box extends this far left of the indenter (our choice)"),
    "band_left": (150.0, "mm", "left end of the refined band (x from band_left to 260 mm, y from 230 to 320 mm; "
                  "our choice, around the expected crack path)"),
    "clamp_strip": (25.0, "mm", "height of the strip along the clamped edge without fracture (our choice)"),
    "k_u": (50.0, "1/N", "step-size sensitivity of Eq. 20, W_f per unit thickness (paper: 50)"),
    "kbar_r": (0.0, "-", "void regulariser factor of Eq. 3, k_r = kbar_r L^2 K0; 0: none and linear triangles "
               "(paper); > 0: the regulariser on the void, whose displacement is then of order 2"),
    "reg_length": (500.0, "mm", "characteristic length L of the regulariser (the panel's width)"),
    **SOLVER_PARAMETERS,
    "load_cases": ("both", "-", "'both' (the paper's load-unload-reload case 'main' and the monotonic case 'monotonic'), "
                   "'cyclic' (case 'main' only) or 'monotonic' (case 'monotonic' only, as in the l0 sweep)"),
    "monotonic_to": (6.6, "mm", "end of the monotonic case 'monotonic' (0 -> monotonic_to): past the first-loading "
                     "peak, which the paper's first loading (to 6.3 mm) does not reach at quick"),
    "load_introduction": ("indenter", "-", "'indenter' (paper: an indenter pushes the arm across a 6 mm void) or "
                          "'segment' (diagnostic: no indenter and no void; the schedule minus the gap is imposed on "
                          "the arm's lower face from load_x to its end)"),
    "split": ("vol-dev-J", "-", "tension/compression split (ngtmc.model.splits.SPLITS): 'vol-dev-J' (paper), "
              "'vol-dev-small', 'vol-dev-log', 'spectral' (Miehe 2010; Ambati's history) or 'none'"),
    "formulation": ("hybrid", "-", "where the split acts: 'hybrid' (history only; paper) or 'anisotropic'"),
}

RESOLUTIONS = {
    "quick": {"h_band": 2.0, "h_contact": 2.5, "h_void": 2.5, "h_far": 25.0, "du_max": 0.05, "du_min": 0.005},
    "medium": {"h_band": 1.0, "h_contact": 1.5, "h_void": 2.0, "h_far": 20.0, "du_max": 0.05, "du_min": 1e-8},
    "paper": {"h_band": 0.5, "h_contact": 1.0, "h_void": 1.0, "h_far": 15.0, "du_max": 0.01, "du_min": 1e-8},
}
RESOLUTION_PARAMETERS = {
    "h_band": ("mm", "element size in the refined band along the crack path"),
    "h_contact": ("mm", "element size in the arm above the indenter"),
    "h_void": ("mm", "element size in the void and the indenter"),
    "h_far": ("mm", "element size elsewhere in the panel"),
    "du_max": ("mm", "largest load increment (Eq. 20)"),
    "du_min": ("mm", "floor of Eq. 20 and smallest increment on cut-back (paper, three-point bending: 1e-8); under "
                      "path following at most 1e-6 (the floor of its cut-backs only)"),
}
DEFAULT_RESOLUTION = "quick"

REGIONS = "band|contact_zone|clamp_strip|panel|indenter|void"
FRACTURE_REGIONS = ["band", "panel"]


def build_scene(p: dict) -> ngtmc.Scene:
    mat = ngtmc.Material(E=float(p["E"]), nu=float(p["nu"]), Gc=float(p["Gc"]), l0=float(p["l0"]))
    if _segment(p):
        return ngtmc.Scene(
            mesh=build_mesh(p), materials={"band|contact_zone|clamp_strip|panel": mat},
            supports=[ngtmc.Support("clamp", x=True, y=True)],
            load=ngtmc.DisplacementLoad("load", direction="y"),
            fracture_regions=FRACTURE_REGIONS, regulariser=None,
            residual_stiffness=float(p["residual_stiffness"]), thickness=float(p["thickness"]), order=1,
            name="l_panel_segment", **_split(p))
    return ngtmc.Scene(
        mesh=build_mesh(p),
        materials={REGIONS: mat},
        supports=[ngtmc.Support("clamp", x=True, y=True)],
        load=ngtmc.DisplacementLoad("load", direction="y", hold_tangential=True),
        density={"void": 0.0},
        fracture_regions=FRACTURE_REGIONS,
        **_regulariser(p),
        gamma0=float(p["gamma0"]),
        residual_stiffness=float(p["residual_stiffness"]),
        thickness=float(p["thickness"]),
        name="l_panel",
        **_split(p),
    )


def _regulariser(p: dict) -> dict:
    """No regulariser and linear triangles (paper), or with ``kbar_r`` > 0 the Hessian regulariser
    of Eq. 3 on the void, whose displacement is then of order 2 (order 1 elsewhere); ``Regulariser``
    refuses a negative factor."""
    kbar_r = float(p.get("kbar_r", PARAMETERS["kbar_r"][0]))
    if kbar_r == 0:
        return dict(regulariser=None, order=1)
    length = float(p.get("reg_length", PARAMETERS["reg_length"][0]))
    return dict(regulariser=ngtmc.Regulariser("void", length=length, kbar_r=kbar_r), order=None, variable_order=True)


def _split(p: dict) -> dict:
    """The scene's energy split and formulation (``ngtmc.Scene`` checks them)."""
    return dict(split=str(p.get("split", PARAMETERS["split"][0])),
                formulation=str(p.get("formulation", PARAMETERS["formulation"][0])))


LOAD_CASES = {"both": ("main", "monotonic"), "cyclic": ("main",), "monotonic": ("monotonic",)}


def _load_cases(p: dict) -> tuple:
    mode = str(p.get("load_cases", "both"))
    if mode not in LOAD_CASES:
        raise ValueError(f"l_panel: load_cases = {mode!r} is not one of {', '.join(map(repr, LOAD_CASES))}")
    return LOAD_CASES[mode]


#: du_min under path following, mm, at most: there dissipation sets the steps of the crack run,
#: and du_min is only the floor of the cut-backs of a step. Quick's 0.005 mm (a floor for the
#: single-pass scheme's Eq. 20) allowed three halvings of a dissipation step, and the cyclic case
#: without the growth ceiling failed at 6.468 mm; with 1e-6 it completes (docs/performance.md).
PATH_FOLLOWING_DU_MIN = 1e-6


def _options(p: dict) -> dict:
    """Simulation options of both cases: the solver settings. Under path following the ceiling on
    the growth of the dissipation per step after a cut-back is ngtmc's default, ``"auto"``
    (:meth:`ngtmc.stepping.sizing.DissipationSizing.ceiling_applies`): off at quick, where the crack
    path's elements (a median longest edge of 2.6 mm, 2.2 l0) are larger than CEILING_MAX_H = 1.5 l0
    and a step of one l0 of crack is a fraction of an element; on at medium (1 mm band) and at the
    paper's resolution (0.5 mm, l0/2.4). Where a stall would still fail a step, its last attempt is a
    displacement step with staggered passes (path following's fallback). Measured step counts with
    and without the ceiling: records ``quick_path_following_no_ceiling`` and
    ``medium_monotonic_path_following_ceiling``."""
    return simulation_options(p, mesh_maxh=float(p["h_far"]))   # the global maxh of build_mesh


def cases(p: dict) -> list[Case]:
    """Case ``main``: the paper's schedule 0 -> 6.3 -> 6 -> 7 mm; case ``monotonic``: 0 ->
    ``monotonic_to`` (past the first-loading peak). ``load_cases`` selects them."""
    du_max = float(p["du_max"])
    shift = float(p["gap"]) - effective_gap(p)
    du_min = min(float(p["du_min"]), du_max)
    if p.get("scheme", SOLVER_PARAMETERS["scheme"][0]) == "path-following":   # the floor of its cut-backs only (see _options)
        du_min = min(du_min, PATH_FOLLOWING_DU_MIN)
    # (under path following the scale doubles after every successful step: ngtmc.stepping.path.N_S)
    control = ngtmc.AdaptiveStepControl(du_max=du_max, k_u=float(p["k_u"]), du_min=du_min)
    which = _load_cases(p)
    out = []
    if "main" in which:
        out.append(Case(
            name="main", label=f"this model (k_u = {float(p['k_u']):g} 1/N, du_max = {du_max:g} mm)",
            scene=partial(build_scene, dict(p)),
            schedule=ngtmc.Schedule(effective_schedule(p)),
            control=control,
            options=_options(p),
            snapshot_loads=[x - shift for x in (5.9, 6.1, 6.2, 6.3, 7.0) if x - shift >= 0],
            parameters={"k_u": float(p["k_u"]), "du_max": du_max},
        ))
    if "monotonic" in which:
        end = float(p["monotonic_to"]) - shift
        if not end > 0:
            raise ValueError(f"l_panel: monotonic_to = {p['monotonic_to']!r} mm does not go past the gap")
        out.append(Case(
            name="monotonic", label=f"monotonic to {float(p['monotonic_to']):g} mm (l0 = {float(p['l0']):g} mm)",
            scene=partial(build_scene, dict(p)),
            schedule=ngtmc.Schedule([0.0, end]),
            control=control,
            options=_options(p),
            snapshot_loads=[x - shift for x in (6.1, 6.3, 6.45) if 0 <= x - shift < end] + [end],
            parameters={"k_u": float(p["k_u"]), "du_max": du_max, "l0": float(p["l0"])},
        ))
    return out


def targets(p: dict) -> list[dict]:
    scale = float(p["thickness"]) / 100.0
    out = []
    if "main" in _load_cases(p):
        out.append({"case": "main", "quantity": "reload_peak_force", "value": 7600.0 * scale, "unit": "N",
                    "source": "Ciceri et al. 2026, L-panel text: reload peak 7.6 kN (whole 100 mm panel)",
                    "tolerance": 0.15})
    if "monotonic" in _load_cases(p):
        out.append({"case": "monotonic", "quantity": "peak_force", "value": 16000.0 * scale, "unit": "N",
                    "source": AMBATI_SOURCE, "tolerance": 0.15})
    return out


#: What the quick run (the CI run of tests/test_study_l_panel.py) is checked against, one record per
#: number (docs/study-interface.md): the quantity of metadata.json results (post_results: the
#: numbers of :func:`phases`), the value with its unit (N, whole 100 mm panel), tolerance (rel:
#: relative) and source. The published reload peak is not met (strict expected failure, with the
#: measured values); the measured quick values guard against regressions.
EXPECTED = {
    "reload_peak_force_published": {
        "case": "main", "quantity": "reload_peak_force", "value": 7600.0, "unit": "N", "rel": 0.15,
        "source": "Ciceri et al. 2026, L-panel text: reload peak 7.6 kN (whole 100 mm panel)",
        "xfail": "quick: reload peak measured 23.6 kN against the paper's 7.6 kN (+211 %); medium 20.8 kN "
                 "(+174 %): their first loading stops before the peak, so this is the uncracked panel's peak; "
                 "at the paper's resolution, where the crack runs before the turning point as in the paper, "
                 "8.83 kN at 6.640 mm (+16.2 %, path following, record paper_path_following_completed); not the paper's "
                 "single-pass scheme: at quick with the turning point past the peak it reloads to 10.16 kN "
                 "against path following's 9.86 kN (+3 %); the element size does not move it (the paper's schedule "
                 "at medium reloads to 8.68 kN, against 8.83 kN at the paper's resolution), the refined band's "
                 "extent does: the crack stops at the band's end (x = 150 mm) by the turning point, and with the "
                 "band from x = 100 mm it stops there and reloads to 4.34 kN (-43 %; record medium_path_following_band_left_100); with "
                 "the band over the whole width the crack runs through the panel's width (to x = 4.3 of 250 mm) "
                 "before 6.3 mm, with 98.8 N left, and reloading finds no peak (100.8 N at 7 mm; record medium_path_following_band_left_0), and so it "
                 "does at l0 = 2.375 and 4.75 mm (quick), where the study's band reloads to 5.48 kN (WHOLE_WIDTH): "
                 "the published reload peak needs a crack arrested by its mesh"},
    "first_peak_force": {"case": "main", "quantity": "first_peak_force", "value": 17935.0, "unit": "N", "rel": 0.05,
                         "source": "measured, quick (regression guard; the turning point, 6.3 mm)"},
    "reload_peak_force": {"case": "main", "quantity": "reload_peak_force", "value": 23621.0, "unit": "N", "rel": 0.05,
                          "source": "measured, quick (regression guard)"},
    "force_first_loading_at_gap": {"case": "main", "quantity": "force_first_loading_at_gap", "value": 4765.0,
                                   "unit": "N", "rel": 0.05, "source": "measured, quick (regression guard)"},
    "monotonic_peak_force_ambati": {
        "case": "monotonic", "quantity": "peak_force", "value": 16000.0, "unit": "N", "rel": 0.15,
        "source": AMBATI_SOURCE,
        "xfail": "quick: monotonic peak measured 22.96 kN at 6.451 mm against Ambati's about 16 kN (+43.5 %); "
                 "h_band = 2 mm = 1.7 l0 overestimates the toughness by 1 + h/(2 l0) = 1.84; medium (h_band = 1 mm) "
                 "18.63 kN (+16.4 %), extrapolated to h -> 0 about 14.3-15.6 kN; with path following (no damage lag) "
                 "16.27-16.84 kN at medium (+1.7 to +5.3 %) and 15.72 kN at the paper's resolution (-1.7 %, see the study)"},
    "monotonic_peak_force": {"case": "monotonic", "quantity": "peak_force", "value": 22962.0, "unit": "N", "rel": 0.05,
                             "source": "measured, quick (regression guard; l0 = 1.1875 mm)"},
    "monotonic_peak_load": {"case": "monotonic", "quantity": "peak_load", "value": 6.451, "unit": "mm", "abs": 0.03,
                            "source": "measured, quick (regression guard; past the paper's turning point 6.3 mm)"},
}


# ---------------------------------------------------------------------- post-processing
def post_results(p: dict, history, results: dict) -> dict:
    """Add to the results of case ``main`` the numbers of :func:`phases` (forces in N, loads in mm,
    W_f in N mm), once the history has reached the turning point of the schedule."""
    if history is None or not len(history):
        return results
    if "monotonic" in results and "case" in history:
        m = history[history["case"] == "monotonic"]
        if len(m):
            results["monotonic"].update(monotonic_numbers(m))
    if "main" not in results:
        return results
    h = history[history["case"] == "main"] if "case" in history else history
    if not len(h) or not np.isclose(h["load"].to_numpy(dtype=float), effective_schedule(p)[1], atol=1e-9).any():
        return results
    results["main"].update(phases(h, p))
    return results


if __name__ == "__main__":  # python studies/l_panel.py [options of `ngtmc run`], e.g. --resolution medium
    import sys

    from ngtmc.cli import run_script
    sys.exit(run_script(NAME))
