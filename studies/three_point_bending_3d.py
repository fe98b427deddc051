"""Three-point bending in 3D: a plane-strain slab checked against 2D, and a beam under a hemisphere.

What this study shows
---------------------
The paper's formulation, regulariser included, "can be extended to three dimensional problems
without requiring any conceptual modifications"; it shows only 2D. ngtmc's energies, split,
regulariser, phase field, history, reaction and path following are written once for both
dimensions. This study runs them in 3D in two ways:

(a) **slab**: the three-point bending of ``studies/three_point_bending.py`` (indenter, void,
    regulariser, crack) extruded into one layer of prisms (:func:`ngtmc.extrude`) of thickness
    ``slab_thickness``, with u_z held on both faces (plane strain). Case ``plane_strain_2d`` runs
    the same mesh in 2D (straight-sided, thickness ``slab_thickness``), so the two force curves
    compare directly, in N for that thickness.
(b) **hemisphere**: a notched beam indented by a hemisphere at mid-span and mid-width: the load
    is point-like, the contact patch is a disc and the crack front curves across the width.
    By default a quarter of the beam is modelled (``sphere_symmetry = "quarter"``: symmetry
    planes z = 0, u_z held, and x = L/2, u_x held; the left support a roller), so the crack plane
    is a face of the mesh; ``"half"`` models z >= 0 only (pin and roller supports). The recorded
    force is the reaction of the modelled part (N): the whole beam carries four (two) times it.

What the 3D slab must give, and why it is not exactly the 2D curve
-------------------------------------------------------------------
With order-1 elements and no void, the slab's space is the 2D space times linear functions of z,
and the slab reproduces its 2D twin to solver precision, through the peak and the crack
(``tests/test_extrude.py``, a notched plate: forces to 1e-7 of the peak). Two things make the
slab with the indenter differ from 2D, both measured on a coarse three-point bending
(h_band = 0.03 mm, 2613 elements, to 0.055-0.06 mm, single-pass, equal steps):

* **Eq. 3's regulariser subtracts |Lu|^2 / d**, d the dimension: for a field of x and y only,
  the 3D density is the 2D one plus k_r / 2 (1/2 - 1/3) |Lu|^2 (``tests/test_extrude.py``, a
  hand calculation). The model is therefore stiffer in 3D in a squeezed void.
* **The order-2 void elements have dofs that vary along z** (edge and face functions of the
  prisms' vertical edges and quadrilateral faces), which the 2D space does not have.

With both removed (a scratch patch: 1/2 in place of 1/d, order 1 along z) the slab matched 2D
to 7e-10 at 0.055 mm. With both in (the model as it is), the force at 0.06 mm differs by
+0.04 % with the 1/d term alone and by -0.14 % with both: below the stated tolerance of
**1 % on the peak** (the issue's target is 2 %). The measured peaks are in ``MEASURED``.

Geometry of (b), mm (our choices; no published 3D reference exists)
-------------------------------------------------------------------
* beam ``sphere_beam_length`` x ``sphere_beam_height`` x ``sphere_beam_width`` = 4 x 1 x 1 (half
  the 2D beam's length and height), notch across the whole width at mid-span from the bottom,
  ``sphere_notch_depth`` = 0.2 deep, ``sphere_notch_width`` = 0.04 wide, flat tip;
* supports: strips of the bottom face across the width, ``sphere_support_length`` = 0.1 long, pin
  (x, y held) on the left and roller (y held) on the right (the quarter model: a roller on the
  left, u_x held on the mid-span plane); no fracture in the
  ``sphere_support_zone`` = 0.15 mm blocks above them;
* no fracture either in the block of the beam top under the hemisphere, 0.3 long, 0.15 deep and
  0.15 wide (``sphere_load_zone``): without it, damage grew under the point-like contact
  (alpha 0.035 at 0.028 mm, 11-22 Newton iterations per step, measured) before the notch
  cracked, as the L-panel's arm was crushed under its indenter;
* indenter: hemisphere of radius ``sphere_radius`` = 0.25, flat face up, lowest point
  ``sphere_gap`` = 0.025 above the beam top at mid-span and mid-width; the flat face is the loaded
  boundary (u_y imposed, tangential held);
* void (rho = 0): the block x in [2 - 0.5, 2 + 0.5], from the beam top to the hemisphere's flat
  face, across the modelled width, minus the hemisphere; meshed to ``sphere_h_contact`` in a block
  of half side ``sphere_contact_box`` = 0.15 under the lowest point (the contact patch: its radius
  is about sqrt(R d) = 0.07 mm at d = 0.02 mm of indentation, one element of h_void = 0.06).
  Order-2 displacements and the regulariser only within ``sphere_regularised_radius`` = 0.25 mm
  of the hemisphere's axis (region ``void``); the rest of the block (``void_far``, J >= 0.65 there
  in the fully regularised run) has order 1 and no regulariser: a third fewer displacement dofs,
  30-50 % less time per Newton iteration, the peak within 0.23 % (2026-12-04, docs/three-d.md);
* material: Table 1 (E = 20.8e3 MPa, nu = 0.3, Gc = 0.54 N/mm) with **l0 = ``sphere_l0`` =
  0.08 mm** (not 0.03: at l0 = 0.03 the quick mesh would need about 1e6 tetrahedra), gamma0 = 5e-6,
  kbar_r = 1e-6 with L = 4 mm;
* the recorded force is the reaction on the modelled half (N); the whole beam carries twice it.

Resolutions
-----------
Mesh and step sizes only. ``quick``: the slab at h_band = 0.03 mm (2613 elements in the plane)
and the hemisphere at h_band = l0/2 = 0.04 mm (10767 tetrahedra in the quarter model, the void 0.02 mm under the contact); ``medium``: the slab at
the 2D study's quick sizes (h_band = 0.015 mm, 8632 prisms), the hemisphere at l0/3; ``paper``:
the slab at the 2D study's paper sizes (h_band = 0.0075 mm), the hemisphere at l0/4.

Measured (``MEASURED``, docs/three-d.md)
---------------------------------------
(a) quick, the void regularised within 0.5 mm of the axis as in the 2D study (2639 elements in the
plane; 2026-12-04, ``ngtmc run three-point-bending-3d``, all three cases in 535 s): the slab peaks
at 1.18677 N at 0.096790 mm, its 2D twin at 1.18672 N at 0.096786 mm: **+0.004 % and +0.003 %**
(100 and 98 steps, 405 and 382 Newton iterations, 170 and 75 s). Before the split (2026-12-02,
whole void): the slab peaks at 1.18292 N at 0.096625 mm, its 2D twin at 1.18315 N at 0.096620 mm:
**-0.020 % in the peak force and +0.006 % in its displacement** (78 and 71 steps, 345 and 342
Newton iterations). The 3D run cost 5.6x the CPU time of the 2D one (566 against 101 s) and
368 MB at its peak. medium (8632 prisms, 54294 u dofs; 2026-12-02): the slab peaks at 0.561981 N
at 0.095113 mm, its 2D twin at 0.559748 N at 0.095171 mm: **+0.40 % and -0.06 %** (115 and 77
steps, 494 and 411 Newton iterations), 1572 s of CPU against 308 s, 972 MB at its peak.

(b) quick, quarter model, the void regularised within 0.25 mm of the axis (10767 tetrahedra,
12675 u and 2428 alpha dofs; 2026-12-04, two threads, alone): peak **6.1871 N (quarter) at 0.0700
mm**, 65 steps, 310 Newton iterations, 2 cut-backs; **245 s for the case, 255.5 s (4 min 16 s) for
the command** (set-up, report and ParaView series included; compiled code cached), 311 MB at its
peak. The case sizes its dissipation steps before their solve (``coupled={"prescale": True}``,
:mod:`ngtmc.stepping.path`, rule 3): without it, the same day, 57 steps, 400 iterations, 307 s for the
case and 317 s for the command, the same peak. With the whole void regularised
(10896 tetrahedra, 19536 u dofs): 6.2013 N at 0.0700 mm, 64 steps, 345 iterations, 363 s on the
same day (300 s on 2026-12-03), 510 MB. Until 2026-12-02 the crack run after the peak took 13 Newton iterations per step (59 steps,
463 iterations, 400 s): dissipation steps of half the base failed in cycles, and a factor that
fails twice now holds the growth ceiling below it (``ngtmc.stepping.sizing.CEILING_REPEAT``;
docs/three-d.md, docs/performance.md).
The half model at the same sizes peaked at 12.911 N at 0.07314 mm (twice the quarter's: 12.403
N, **-3.9 %**) in 70 steps and 518 iterations, 3013 s of CPU beside other jobs. On a coarse mesh
(h = l0 above the notch) the half model is 4.6 % above the quarter; half of that difference goes
when the half model's mesh has a face at x = L/2 too (the crack on a mesh plane instead of
across tetrahedra), so the two models differ by the discretisation of the crack, which the
quarter model resolves better (docs/three-d.md).

Medium with it (2026-12-04, alone, two threads): the same peak 6.0307 N at 0.0700 mm, 67 steps,
410 Newton iterations, 3 cut-backs, **932 s** for the case (944 s for the command), 921 MB. The
rest of this paragraph was run before the prescale option; paper was not run again with it. Medium, quarter (31179 tetrahedra, 32667 u dofs,
two threads, alone; 2026-12-04): peak **6.0307 N
at 0.0700 mm** (-2.5 % against quick), the whole curve to 0.1 mm in 75 steps, 519 Newton
iterations, 3 cut-backs and **1130 s** (19 min), 1186 MB at its peak. With the whole void
regularised (31272 tetrahedra, 47139 u dofs; 2026-12-03): 6.0325 N at 0.0700 mm, 65 steps, 495
iterations, 4 cut-backs, 2221 s (beside a one-thread job for its first 18 minutes), 1692 MB
(docs/three-d.md). Paper, quarter (59879 tetrahedra, 64710 u dofs, two threads, alone; 2026-12-04):
peak **5.9282 N at 0.0700 mm** (-1.7 % against medium), the whole curve in 79 steps, 464 Newton
iterations, 4 cut-backs and **2794 s** (47 min; 2813 s for the command), **1272 MB** at its peak.
Paper, the whole void regularised (60049 tetrahedra, 103485 u dofs; 2026-12-03 and 2026-12-04, two
threads, mostly beside other jobs, resumed once): peak **5.9325 N at 0.0700 mm** (-1.7 % against
medium, -4.3 % against quick), after 35 steps and 144 Newton iterations in 2565 s; stopped in the
crack run at 0.0669 mm and 3.88 N after 41 steps, 238 iterations and 4757 s, 2504 MB at its peak
(docs/three-d.md). The rest of the crack run is not measured.

Adaptive refinement (``--set h_crack``, measured 2026-12-05)
----------------------------------------------------------
With ``h_crack`` the cases refine by bisection during the run (:class:`ngtmc.Adaptivity`,
docs/adaptivity.md); refinement by remeshing (2D only) is refused.

(a) The slab's prisms are bisected across their triangles only (the slab keeps its one layer),
and its 2D twin's triangles the same way: ``slab_thickness`` must then be at most ``h_crack`` (and
``amr_h_void``, if set) times ``amr_size_tolerance`` (checked before any case runs). On the
notched plate of ``tests/test_adapt_prisms.py`` the refined slab follows its refined 2D twin
element for element, its forces to solver precision. This study's slab
(``MEASURED["quick_slab_amr_2026_12_05"]``; ``--set parts=slab --set h_band=0.06 --set
slab_thickness=0.015 --set h_crack=0.015 --set amr_size_tolerance=1.41 --set
stop_after_drop=0.5``, two threads, alone): from 1466 elements in the plane, both refine to 1965
by the peak; the slab peaks at 0.561684 N at 0.09376 mm, its 2D twin at 0.561662 N at 0.093759
mm (**+0.004 %**; the twin -0.15 % against the 2D study's quick band, 37.499 N/mm times 0.015
mm). To half the peak: 136 and 122 steps, 785 and 772 Newton iterations, 5939 and 5851
elements, 654 and 155 s.

(b) ``--set parts=hemisphere --set h_crack=H`` refines the hemisphere's tetrahedra. Quick, from a
coarse band (``sphere_h_band=0.08``, l0; 6638 tetrahedra) to ``h_crack=0.04`` (l0/2) with
``amr_size_tolerance=1.41``, one thread beside two other runs (``MEASURED["quick_hemisphere_quarter_amr_2026_12_05"]``): peak **6.0642 N at 0.0700
mm**, -2.0 % against the quick band's 6.1871 N and +0.6 % against medium's 6.0307 N, after 35
steps and 186 Newton iterations in 694 s; but with **45220 tetrahedra at the peak**, against
10767 (quick band, l0/2) and 31179 (medium band, l0/3): the AT-2 damage before the peak is broad,
the indicator (H at the level where AT-2 peaks, alpha > 0.2, one layer of vertex neighbours) and
the bisection's closure spread over it, and a tetrahedron's longest edge halves only every few
bisections. With the strict size bound (``amr_size_tolerance=1``) it reached 99079 tetrahedra by
0.070 mm (6.0303 N). Without the layer of neighbours (``--set amr_buffer=0``, beside one other
run; ``MEASURED["quick_hemisphere_quarter_amr_buffer_0_2026_12_05"]``): **6.0834 N at 0.0700 mm**
(-1.7 % against the quick band, +0.9 % against medium) with **25005 tetrahedra at the peak** (2.3
times the quick band's), 35 steps, 185 Newton iterations, 312 s. The runs were stopped in the
crack run after the peak. So in 3D the refinement works (tests/test_adapt_3d.py), but on this
scene it does not yet pay: the hand-placed band is smaller.

The run's peak memory is in ``metadata.json`` (``results.<case>.peak_memory_mb``) and the
report.
"""
from __future__ import annotations

import dataclasses
from functools import partial

import numpy as np

import ngtmc
from ngtmc.study import StudyError
from ngtmc.study import Case
from ngtmc.study import SOLVER_PARAMETERS, simulation_options
from ngtmc.studies import _beam3d_geometry as _geometry
from ngtmc.studies import three_point_bending as _tpb

NAME = "three_point_bending_3d"
TITLE = "Three-point bending in 3D: a plane-strain slab against 2D, and a beam under a hemisphere"
SUMMARY = (
    "(a) The three-point bending of the 2D study (indenter, third-medium void, crack) extruded into one "
    "layer of prisms with u_z held on both faces (plane strain), against the same mesh in 2D: the 3D "
    "energy, regulariser, split and reaction against the 2D ones. (b) A notched 4 x 1 x 1 mm beam "
    "indented by a hemisphere across a 0.025 mm void gap (a quarter of the beam modelled by default, "
    "symmetry at z = 0 and at mid-span; the force is the modelled part's): "
    "a point-like load, a disc-shaped contact patch and a crack front that curves across the width."
)

_SLAB_KEYS = [k for k in _tpb.PARAMETERS if k not in SOLVER_PARAMETERS and k != "thickness"]

PARAMETERS = {
    **{k: _tpb.PARAMETERS[k] for k in _SLAB_KEYS},
    "parts": ("all", "-", "which cases run: 'all', 'slab' (the slab and its 2D twin) or 'hemisphere'"),
    # (b) the hemisphere
    "sphere_symmetry": ("quarter", "-", "part of the beam modelled: 'half' (z >= 0, symmetry plane z = 0) or "
                                        "'quarter' (also x <= mid-span, symmetry plane x = L/2); the recorded "
                                        "force is that of the modelled part"),
    "sphere_beam_length": (4.0, "mm", "beam length (half the 2D beam's)"),
    "sphere_beam_height": (1.0, "mm", "beam height"),
    "sphere_beam_width": (1.0, "mm", "beam width (z in [0, width/2] is modelled)"),
    "sphere_notch_depth": (0.2, "mm", "notch depth at mid-span, across the whole width"),
    "sphere_notch_width": (0.04, "mm", "notch width (flat tip)"),
    "sphere_radius": (0.25, "mm", "hemisphere radius"),
    "sphere_gap": (0.025, "mm", "gap between the hemisphere and the beam top"),
    "sphere_void_half_width": (0.5, "mm", "half length (x) of the void block around the hemisphere"),
    "sphere_band_half_width": (0.1, "mm", "half width of the refined block above the notch"),
    "sphere_support_length": (0.1, "mm", "length of the support strips across the width"),
    "sphere_support_zone": (0.15, "mm", "side of the blocks above the supports without fracture"),
    "sphere_contact_box": (0.15, "mm", "half side of the block of void under the hemisphere's lowest point meshed to "
                                      "sphere_h_contact (the contact patch); 0: none"),
    "sphere_load_zone": (0.15, "mm", "half length, depth and half width of the block of the beam top under the "
                                    "hemisphere without fracture (region 'load_zone'); 0: none"),
    "sphere_regularised_radius": (0.25, "mm", "the void within this distance of the hemisphere's axis (region 'void') "
                                             "carries the regulariser and order-2 displacements; the rest of the void "
                                             "block (region 'void_far', never squeezed) has order 1 and no "
                                             "regulariser; at least sqrt(2) sphere_contact_box; from "
                                             "sqrt(sphere_void_half_width^2 + sphere_beam_width^2/4) on: the whole void"),
    "sphere_l0": (0.08, "mm", "phase-field length scale of the hemisphere case (cost: see the docstring)"),
    "sphere_reg_length": (4.0, "mm", "length L of the regulariser, k_r = kbar_r L^2 K0 (the beam length)"),
    "sphere_final_load": (0.1, "mm", "final imposed displacement of the hemisphere"),
    **SOLVER_PARAMETERS,
    "scheme": ("path-following", "-", SOLVER_PARAMETERS["scheme"][2] + "; default here 'path-following'"),
}

RESOLUTIONS = {
    "quick": {"h_band": 0.03, "h_void": 0.06, "h_indenter": 0.16, "h_beam": 0.5, "slab_thickness": 0.03,
              "du_max": 1e-3, "stop_load": 0.12,
              "sphere_h_contact": 0.02, "sphere_h_band": 0.04, "sphere_h_void": 0.06, "sphere_h_indenter": 0.08, "sphere_h_beam": 0.25,
              "sphere_du_max": 2e-3, "sphere_stop_load": 0.1},
    "medium": {"h_band": 0.015, "h_void": 0.03, "h_indenter": 0.08, "h_beam": 0.25, "slab_thickness": 0.015,
               "du_max": 1e-3, "stop_load": 0.12,
               "sphere_h_contact": 0.015, "sphere_h_band": 0.0267, "sphere_h_void": 0.04, "sphere_h_indenter": 0.06, "sphere_h_beam": 0.2,
               "sphere_du_max": 1e-3, "sphere_stop_load": 0.1},
    "paper": {"h_band": 0.0075, "h_void": 0.015, "h_indenter": 0.04, "h_beam": 0.15, "slab_thickness": 0.0075,
              "du_max": 0.5e-3, "stop_load": 0.12,
              "sphere_h_contact": 0.01, "sphere_h_band": 0.02, "sphere_h_void": 0.03, "sphere_h_indenter": 0.05, "sphere_h_beam": 0.15,
              "sphere_du_max": 1e-3, "sphere_stop_load": 0.1},
}
#: the slab's sizes: those of the 2D study
_SLAB_RESOLUTION_KEYS = ("h_band", "h_void", "h_indenter", "h_beam", "du_max", "stop_load")
RESOLUTION_PARAMETERS = {
    **{k: (_tpb.RESOLUTION_PARAMETERS[k][0], "slab: " + _tpb.RESOLUTION_PARAMETERS[k][1])
       for k in _SLAB_RESOLUTION_KEYS if k != "stop_load"},
    "slab_thickness": ("mm", "slab: thickness of the one layer of prisms (about h_band)"),
    "stop_load": ("mm", "slab: load at which the slab and its 2D twin stop (after the drop)"),
    "sphere_h_band": ("mm", "hemisphere: element size in the block above the notch"),
    "sphere_h_void": ("mm", "hemisphere: element size in the void"),
    "sphere_h_contact": ("mm", "hemisphere: element size in the void under the lowest point (sphere_contact_box)"),
    "sphere_h_indenter": ("mm", "hemisphere: element size in the hemisphere"),
    "sphere_h_beam": ("mm", "hemisphere: element size in the rest of the beam"),
    "sphere_du_max": ("mm", "hemisphere: largest displacement step of the single-pass, staggered and monolithic "
                             "schemes; under path following (the default) the bound is the larger of this and "
                             "1/50 of the load path (ngtmc.stepping.schemes.PATH_STEPS), so a smaller value has no effect"),
    "sphere_stop_load": ("mm", "hemisphere: load at which the case stops"),
}
DEFAULT_RESOLUTION = "quick"

PARTS = ("all", "slab", "hemisphere")

#: Measured runs (one NGSolve thread per case, 3-4 jobs on the 2-core machine, 2026-12-02;
#: docs/three-d.md). Forces in N (the slab and its twin: for 0.03 mm of thickness).
MEASURED: dict = {
    "quick_plane_strain_2d": {"n_elements": 2613, "ndof_u": 4152, "ndof_alpha": 1376, "peak_force": 1.183155,
                              "peak_load": 0.096620, "steps": 71, "newton_iterations": 342, "cutbacks": 3,
                              "cpu_time_s": 101, "wall_time_s": 261, "peak_memory_mb": 206},
    "quick_slab": {"n_elements": 2613, "ndof_u": 15357, "ndof_alpha": 2752, "peak_force": 1.182921,
                   "peak_load": 0.096625, "steps": 78, "newton_iterations": 345, "cutbacks": 3, "cpu_time_s": 566,
                   "wall_time_s": 911, "peak_memory_mb": 368, "peak_force_vs_2d": -0.000197,
                   "peak_load_vs_2d": 0.0000567},
    "quick_plane_strain_2d_split_void": {"n_elements": 2639, "ndof_u": 3170, "ndof_alpha": 1390, "peak_force": 1.186717,
                              "peak_load": 0.096786, "steps": 98, "newton_iterations": 382, "cutbacks": 5,
                              "wall_time_s": 75.1, "peak_memory_mb": 203,
                              "note": "void regularised within regularised_half_width = 0.5 mm; the default command "
                                      "(all cases, serial, two threads for 3D), alone, 2026-12-04 13:33; 535 s for "
                                      "the command"},
    "quick_slab_split_void": {"n_elements": 2639, "ndof_u": 10359, "ndof_alpha": 2780, "peak_force": 1.186770,
                   "peak_load": 0.096790, "steps": 100, "newton_iterations": 405, "cutbacks": 5, "wall_time_s": 170.3,
                   "peak_memory_mb": 258, "peak_force_vs_2d": 0.0000446, "peak_load_vs_2d": 0.0000345,
                   "note": "the same run"},
    "quick_hemisphere_quarter": {"n_elements": 10767, "ndof_u": 12675, "ndof_alpha": 2428, "peak_force": 6.1871,
                                 "peak_load": 0.0700, "steps": 65, "newton_iterations": 310, "cutbacks": 2,
                                 "threads": 2, "wall_time_s": 245.4, "cpu_time_s": 487.7, "peak_memory_mb": 311,
                                 "note": "void regularised within sphere_regularised_radius = 0.25 mm; dissipation "
                                         "steps sized before their solve (coupled prescale); alone, 2026-12-04 "
                                         "12:54; command 255.5 s (docs/three-d.md)"},
    "quick_slab_amr_2026_12_05": {
        "n_elements_start": 1466, "h_band": 0.06, "slab_thickness": 0.015, "h_crack": 0.015,
        "amr_size_tolerance": 1.41, "peak_force": 0.561684, "peak_load": 0.09376, "n_elements_at_peak": 1965,
        "dofs_at_peak": 10208, "steps": 136, "newton_iterations": 785, "cutbacks": 5,
        "n_elements_end": 5939, "wall_time_s": 654, "threads": 2,
        "twin_2d": {"peak_force": 0.561662, "peak_load": 0.093759, "n_elements_at_peak": 1965, "steps": 122,
                    "newton_iterations": 772, "cutbacks": 5, "n_elements_end": 5851, "wall_time_s": 155},
        "peak_force_vs_2d": 0.0000392,
        "status": "stopped at half the peak (stop_after_drop = 0.5)",
        "note": "ngtmc run three-point-bending-3d --set parts=slab --set h_band=0.06 --set slab_thickness=0.015 "
                "--set h_crack=0.015 --set amr_size_tolerance=1.41 --set stop_after_drop=0.5 --threads 2; alone; "
                "forces in N for 0.015 mm of thickness"},
    "quick_hemisphere_quarter_amr_2026_12_05": {
        "n_elements_start": 6638, "sphere_h_band": 0.08, "h_crack": 0.04, "amr_size_tolerance": 1.41,
        "peak_force": 6.0642, "peak_load": 0.0700, "n_elements_at_peak": 45220, "ndof_u_at_peak": 42436,
        "steps_to_peak": 35, "newton_iterations_to_peak": 186, "cutbacks_to_peak": 0, "wall_time_to_peak_s": 694,
        "threads": 1, "status": "stopped at step 36 (0.0697 mm, 5.75 N, 55998 tetrahedra) in the crack run",
        "note": "ngtmc run three-point-bending-3d -r quick --set parts=hemisphere --set sphere_h_band=0.08 --set "
                "h_crack=0.04 --set amr_size_tolerance=1.41 --threads 1 --no-vtk; beside two other runs on the "
                "2 cores; with amr_size_tolerance=1: 99079 tetrahedra and 6.0303 N at 0.070 mm"},
    "quick_hemisphere_quarter_amr_buffer_0_2026_12_05": {
        "n_elements_start": 6638, "sphere_h_band": 0.08, "h_crack": 0.04, "amr_size_tolerance": 1.41, "amr_buffer": 0,
        "peak_force": 6.0834, "peak_load": 0.0700, "n_elements_at_peak": 25005, "ndof_u_at_peak": 26743,
        "steps_to_peak": 35, "newton_iterations_to_peak": 185, "cutbacks_to_peak": 0, "wall_time_to_peak_s": 312,
        "threads": 1, "status": "crack run after the peak not finished (step 36: 0.0699 mm, 5.79 N, 34742 tetrahedra)",
        "note": "the command of quick_hemisphere_quarter_amr_2026_12_05 with --set amr_buffer=0 --no-report, beside "
                "one other run"},
    "quick_hemisphere_quarter_no_prescale": {"n_elements": 10767, "ndof_u": 12675, "ndof_alpha": 2428,
                                 "peak_force": 6.1871, "peak_load": 0.0700, "steps": 57, "newton_iterations": 400,
                                 "cutbacks": 3, "threads": 2, "wall_time_s": 306.6, "peak_memory_mb": 427,
                                 "note": "the same before the prescale option, alone, 2026-12-04 11:41; command "
                                         "317 s (296.4 s for the case at 08:27)"},
    "medium_hemisphere_quarter": {"n_elements": 31179, "ndof_u": 32667, "ndof_alpha": 6476, "peak_force": 6.0307,
                                  "peak_load": 0.0700, "steps": 75, "newton_iterations": 519, "cutbacks": 3,
                                  "threads": 2, "wall_time_s": 1130, "cpu_time_s": 2200, "peak_memory_mb": 1186,
                                  "note": "void regularised within 0.25 mm; whole curve to 0.1 mm, alone, 2026-12-04 "
                                          "(before the prescale option; docs/three-d.md)"},
    "medium_hemisphere_quarter_prescale": {"n_elements": 31179, "ndof_u": 32667, "ndof_alpha": 6476,
                                  "peak_force": 6.0307, "peak_load": 0.0700, "steps": 67, "newton_iterations": 410,
                                  "cutbacks": 3, "threads": 2, "wall_time_s": 932.2, "cpu_time_s": 1843.5,
                                  "peak_memory_mb": 921,
                                  "note": "with the prescale option (the study's setting since 2026-12-04); whole "
                                          "curve to 0.1 mm, alone, 2026-12-04 13:45, 944 s for the command "
                                          "(--no-vtk)"},
    "paper_hemisphere_quarter": {"n_elements": 59879, "ndof_u": 64710, "ndof_alpha": 12144, "peak_force": 5.9282,
                                 "peak_load": 0.0700, "steps": 79, "newton_iterations": 464, "cutbacks": 4,
                                 "threads": 2, "wall_time_s": 2794, "cpu_time_s": 5352, "peak_memory_mb": 1272,
                                 "note": "void regularised within 0.25 mm; whole curve to 0.1 mm, alone, 2026-12-04 "
                                         "(before the prescale option); peak after 35 steps, 211 iterations, 1019 s "
                                         "(docs/three-d.md)"},
    "quick_hemisphere_quarter_whole_void": {"n_elements": 10896, "ndof_u": 19536, "ndof_alpha": 2450, "peak_force": 6.2013,
                                 "peak_load": 0.0700, "steps": 64, "newton_iterations": 345, "cutbacks": 3,
                                 "threads": 2, "wall_time_s": 300.2, "cpu_time_s": 580.6, "peak_memory_mb": 496,
                                 "note": "force of the modelled quarter; alone, 2026-12-03; before CEILING_REPEAT "
                                         "(2026-12-02): 59 steps, 463 iterations, 399.7 s (docs/three-d.md)"},
    "medium_hemisphere_quarter_whole_void": {"n_elements": 31272, "ndof_u": 47139, "ndof_alpha": 6475, "peak_force": 6.0325,
                                  "peak_load": 0.0700, "steps": 65, "newton_iterations": 495, "cutbacks": 4,
                                  "threads": 2, "wall_time_s": 2221, "cpu_time_s": 3267, "peak_memory_mb": 1692,
                                  "note": "whole curve to 0.1 mm, 2026-12-03 (CEILING_REPEAT); beside a one-thread "
                                          "job for its first 18 minutes (docs/three-d.md)"},
    "paper_hemisphere_quarter_whole_void": {"n_elements": 60049, "ndof_u": 103485, "ndof_alpha": 12201, "peak_force": 5.932502,
                                 "peak_load": 0.0700, "steps": 41, "newton_iterations": 238, "cutbacks": 2,
                                 "threads": 2, "wall_time_s": 4757, "cpu_time_s": 7193, "peak_memory_mb": 2504,
                                 "note": "peak after 35 steps, 144 iterations, 2565 s; stopped (SIGTERM) in the crack "
                                         "run at 0.0669 mm and 3.88 N; 2026-12-03/04, mostly beside other jobs, "
                                         "resumed once; u-u factors reused from step 36 (docs/three-d.md)"},
    "quick_hemisphere_half_whole_void": {"n_elements": 22098, "ndof_u": 36369, "ndof_alpha": 4603, "peak_force": 12.911,
                         "peak_load": 0.07314, "steps": 70, "newton_iterations": 518, "cutbacks": 2,
                         "cpu_time_s": 3013, "wall_time_s": 3422, "peak_memory_mb": 662,
                         "note": "force of the modelled half; interrupted at step 65 and resumed; 7-11 Newton "
                                 "iterations per step while the contact patch grows (docs/three-d.md)"},
    "medium_plane_strain_2d": {"n_elements": 8632, "ndof_u": 14372, "ndof_alpha": 4441, "peak_force": 0.559748,
                               "peak_load": 0.095171, "steps": 77, "newton_iterations": 411, "cutbacks": 1,
                               "cpu_time_s": 308, "peak_memory_mb": 296},
    "medium_slab": {"n_elements": 8632, "ndof_u": 54294, "ndof_alpha": 8882, "peak_force": 0.561981,
                    "peak_load": 0.095113, "steps": 115, "newton_iterations": 494, "cutbacks": 2,
                    "cpu_time_s": 1572, "wall_time_s": 2732, "peak_memory_mb": 972, "peak_force_vs_2d": 0.00399,
                    "peak_load_vs_2d": -0.00061,
                    "note": "--resolution medium --set parts=slab (2026-12-02), beside other jobs and stopped "
                            "for about 14 minutes (its wall time counts the pause)"},
}

#: What the quick run is checked against (docs/study-interface.md): the slab's peak against its
#: 2D twin's is checked by tests/test_study_three_point_bending_3d.py (a ratio of two cases).
EXPECTED: dict = {}


def check_parameters(p: dict):
    """Raise StudyError naming the parameter for an unknown ``parts`` or impossible sizes."""
    if p.get("parts", "all") not in PARTS:
        raise StudyError(f"three_point_bending_3d: parts = {p.get('parts')!r} is not one of "
                         f"{', '.join(map(repr, PARTS))}")
    if p.get("sphere_symmetry", "quarter") not in ("half", "quarter"):
        raise StudyError(f"three_point_bending_3d: sphere_symmetry = {p.get('sphere_symmetry')!r} is not 'half' "
                         "or 'quarter'")
    adapt = simulation_options(p).get("adapt")
    if adapt is not None and p.get("parts", "all") != "hemisphere":
        # refused before any case runs (the 2D twin would run first): NGSolve bisects the slab's
        # prisms across their triangles only (ngtmc.adapt.check_solver)
        smallest = adapt.smallest_size()
        if float(p["slab_thickness"]) > smallest * (1.0 + 1e-9):
            raise StudyError(f"three_point_bending_3d: slab_thickness = {p['slab_thickness']!r} mm is more than the "
                             f"size the slab is refined to (h_crack or amr_h_void times amr_size_tolerance = "
                             f"{smallest:g} mm); its one layer of prisms is bisected across its triangles only: "
                             "set slab_thickness to at most that")
    if float(p.get("amr_remesh_maxh", 0.0) or 0.0) > 0:
        raise StudyError("three_point_bending_3d: amr_remesh_maxh > 0 asks for refinement by remeshing, which is "
                         "2D only; the hemisphere is refined by bisection (amr_remesh_maxh = 0)")
    if not float(p["slab_thickness"]) > 0:
        raise StudyError(f"three_point_bending_3d: slab_thickness = {p['slab_thickness']!r} mm must be > 0")
    try:
        _tpb.check_parameters(_slab_parameters(p))
        _geometry.check_hemisphere(p)
    except ValueError as e:
        raise StudyError(str(e)) from None


def _slab_parameters(p: dict) -> dict:
    """The 2D study's parameter dict for the slab (its physics, the slab's sizes)."""
    return {**{k: p[k] for k in _SLAB_KEYS if k in p}, **{k: p[k] for k in SOLVER_PARAMETERS if k in p},
            **{k: p[k] for k in _SLAB_RESOLUTION_KEYS},
            "thickness": float(p["slab_thickness"])}


def build_plane_strain_scene(p: dict) -> ngtmc.Scene:
    """The 2D three-point-bending scene on its straight-sided mesh, thickness ``slab_thickness``."""
    scene = _tpb.build_scene(_slab_parameters(p))
    scene.mesh.Curve(1)
    return dataclasses.replace(scene, name="plane_strain_2d")


def build_slab_scene(p: dict) -> ngtmc.Scene:
    """The 2D scene's mesh extruded into one layer of prisms, u_z held on ``front`` and ``back``."""
    from ngtmc.scene.extrude import plane_strain_slab
    return plane_strain_slab(build_plane_strain_scene(p), float(p["slab_thickness"]), name="slab")


def _hemisphere_supports(p: dict) -> list:
    """Half model: pin left, roller right, u_z held on z = 0. Quarter model (``sphere_symmetry``):
    u_x held on the mid-span plane instead of the right support, and the left support a roller
    (the span may lengthen, as under the half model's roller)."""
    if p["sphere_symmetry"] == "quarter":
        return [ngtmc.Support("support_left", y=True), ngtmc.Support("sym", z=True), ngtmc.Support("sym_x", x=True)]
    return [ngtmc.Support("support_left", x=True, y=True), ngtmc.Support("support_right", y=True),
            ngtmc.Support("sym", z=True)]


def build_hemisphere_scene(p: dict) -> ngtmc.Scene:
    """The notched beam under a hemisphere (half or quarter, ``sphere_symmetry``; module docstring)."""
    mesh = _geometry.hemisphere_mesh(p)
    mat = ngtmc.Material(E=float(p["E"]), nu=float(p["nu"]), Gc=float(p["Gc"]), l0=float(p["sphere_l0"]))
    return ngtmc.Scene(
        mesh, {"beam|band|support_zone|load_zone|void|void_far|indenter": mat},
        supports=_hemisphere_supports(p),
        fracture_regions=["beam", "band"], gamma0=float(p["gamma0"]),
        residual_stiffness=float(p["residual_stiffness"]),
        load=ngtmc.DisplacementLoad("load", direction="-y", hold_tangential=True),
        density={"void|void_far": 0.0},
        regulariser=ngtmc.Regulariser("void", length=float(p["sphere_reg_length"]), kbar_r=float(p["kbar_r"])),
        variable_order=True,   # order 2 in the regularised void only, as the 2D study (its EXPECTED was measured so)
        split=p.get("split", PARAMETERS["split"][0]), formulation=p.get("formulation", PARAMETERS["formulation"][0]),
        name="hemisphere")


def cases(p: dict) -> list[Case]:
    check_parameters(p)
    parts = p.get("parts", "all")
    out = []
    opts = simulation_options(p)
    if parts in ("all", "slab"):
        stop = min(float(p["stop_load"]), float(p["final_load"]))
        control = ngtmc.AdaptiveStepControl(du_max=float(p["du_max"]), k_u=float(p["k_u"]),
                                            du_min=min(float(p["du_min"]), float(p["du_max"])))
        snaps = [x for x in _tpb.SNAPSHOT_LOADS if x <= stop + 1e-12]   # and the last step, as every case
        twin = dict(opts)
        if opts.get("adapt") is not None and opts["adapt"].corridor == "auto":
            # the slab (3D) resolves the default corridor to none; its 2D twin refines as it does
            twin["adapt"] = dataclasses.replace(opts["adapt"], corridor=0.0)
        out.append(Case(name="plane_strain_2d", label="2D, plane strain, same mesh in the plane",
                        scene=partial(build_plane_strain_scene, dict(p)), schedule=ngtmc.Schedule.monotonic(stop),
                        control=control, options=twin, snapshot_loads=snaps, cost=1.0))
        out.append(Case(name="slab", label="3D slab, one layer of prisms, u_z held on both faces",
                        scene=partial(build_slab_scene, dict(p)), schedule=ngtmc.Schedule.monotonic(stop),
                        control=control, options=dict(opts), snapshot_loads=snaps, cost=3.0))
    if parts in ("all", "hemisphere"):
        stop = min(float(p["sphere_stop_load"]), float(p["sphere_final_load"]))
        du = float(p["sphere_du_max"])
        out.append(Case(name="hemisphere", label=f"3D beam under a hemisphere ({p['sphere_symmetry']} modelled)",
                        scene=partial(build_hemisphere_scene, dict(p)), schedule=ngtmc.Schedule.monotonic(stop),
                        control=ngtmc.AdaptiveStepControl(du_max=du, k_u=float(p["k_u"]),
                                                          du_min=min(float(p["du_min"]), du)),
                        options={**opts, "coupled": {"prescale": True}},
                        snapshot_loads=[float(x) for x in np.linspace(0.0, stop, 7)[1:]],
                        section=("x", float(p["sphere_beam_length"]) / 2), cost=4.0))
    return out


def references(p: dict) -> list[dict]:
    return []


def targets(p: dict) -> list[dict]:
    return []


def post_results(p: dict, history, results: dict) -> dict:
    """Add to the slab's results its peak against the 2D twin's (``peak_force_vs_2d``, relative)
    when both ran."""
    a, b = results.get("slab"), results.get("plane_strain_2d")
    if a and b and a.get("peak_force") and b.get("peak_force"):
        a["peak_force_vs_2d"] = float(a["peak_force"]) / float(b["peak_force"]) - 1.0
        a["peak_load_vs_2d"] = float(a["peak_load"]) / float(b["peak_load"]) - 1.0
    return results


if __name__ == "__main__":
    import sys
    from ngtmc.cli import run_script
    sys.exit(run_script(NAME))
