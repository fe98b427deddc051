"""Topology optimisation of a C-shape that must touch itself to carry load, with and without fracture.

What this study shows
---------------------
A structure designed by gradient for the most energy absorbed over a stroke, with a volume bound,
when its members must touch through the third medium to carry load **and** may break: the
optimisation that neither contact-only topology optimisation (Bluhm et al. 2021; Frederiksen,
Sigmund and Ferrari 2025) nor fracture-resistance optimisation without contact (Xia, Da and
Yvonnet 2018) can do. Two designs come out of one run, side by side:

* ``fracture``: designed with fracture on (the model of the paper: AT-2, hybrid, history);
* ``contact_only``: the same problem designed with fracture off (contact only, the state of the
  art), then run again with fracture on.

Both are compared with fracture on: the co-designed structure should absorb more energy, and the
report shows where the contact-only design cracks.

Geometry (mm, plane strain, thickness 1 mm; our design after the C-shape of the literature)
---------------------------------------------------------------------------------------------
A box ``length`` x ``height`` = 2 x 1, clamped on its left edge. A slot of third medium
(``gap`` = 0.1 high) runs from x = ``spine`` = 0.3 to the right edge at mid-height: it is not
designed (rho = 0), so the upper arm carries the load to the lower arm only through contact once
the slot has closed at its tip, or through the spine. A solid pad (0.2 x 0.1, rho = 1, not designed)
at the top right corner carries the load: its top edge moves down by ``stroke`` = 0.3 mm (x free).
Everything else is the design region: one design variable per element.

Design
------
x -> Helmholtz filter of radius ``filter_radius`` -> Heaviside projection (eta = 0.5, beta
continuation 1, 2, 4, 8 over equal shares of the evaluations) -> SIMP (p = 3) -> the model's rho;
the physical density is bounded by ``volume_fraction`` of the design region; MMA (nlopt) from a
uniform design at the bound; the objective is the external work W = int F du over the stroke
(N mm per mm of thickness), maximised, by the exact adjoint of the single-pass scheme
(:mod:`ngtmc.sensitivities`) on constant steps of ``stroke``/``steps``. The library's
:class:`ngtmc.design.TopologyOptimisation` does all this: the study is its scene and its report.

Gradient checks: central differences in ``check_directions`` random directions at the initial
design, at the gray design after the first stage (beta = 1) and at the final one, each against
the adjoint (study table "Gradient checks").

Parameters are our choices (not the paper's): E = 1000 MPa, nu = 0.3, Gc = 0.15 N/mm, l0 = 0.1 mm,
gamma0 = 1e-4, residual stiffness 1e-4, regulariser kbar_r = 1e-5 with L = 1 mm over the design
region and the slot (it acts where rho < 1, through the factor 1 - rho), displacement order 2.

Results
-------
At quick the co-designed structure absorbs more energy with fracture on than the contact-only
optimum, which loses about a third of its own objective when it may break and cracks at the
corner of the loaded pad, where the co-design keeps its phase field lower; every gradient check
agrees to better than 1e-4 and no forward run fails. The measured figures are the records of
``studies/records/c_shape_design.json``; the report of a run gives them all.
"""
from __future__ import annotations

from functools import partial
import warnings

import numpy as np
import ngsolve as ngs

import ngtmc
from ngtmc.study import Case

NAME = "c_shape_design"
TITLE = "Topology optimisation of a C-shape that touches itself and may break"
SUMMARY = (
    "A C-shaped design region, clamped on the left, its upper arm pushed down onto the lower arm through a slot "
    "of third medium, is designed by MMA with exact adjoint gradients for the most energy absorbed over the "
    "stroke at a volume bound: once with fracture on, once with contact only (then run with fracture on)."
)

PARAMETERS = {
    "E": (1000.0, "MPa", "Young's modulus"),
    "nu": (0.3, "-", "Poisson's ratio"),
    "Gc": (0.15, "N/mm", "critical energy release rate"),
    "l0": (0.1, "mm", "phase-field length scale"),
    "gamma0": (1e-4, "-", "void stiffness ratio (Eq. 17)"),
    "residual_stiffness": (1e-4, "-", "added to g(alpha)"),
    "kbar_r": (1e-5, "-", "regulariser factor (Eq. 3), L = 1 mm"),
    "length": (2.0, "mm", "length of the box"),
    "height": (1.0, "mm", "height of the box"),
    "gap": (0.1, "mm", "height of the slot of third medium"),
    "spine": (0.3, "mm", "distance of the slot from the clamped edge"),
    "pad": (0.2, "mm", "width of the loaded solid pad (its height is half of it)"),
    "stroke": (0.3, "mm", "imposed downward displacement of the pad's top edge"),
    "volume_fraction": (0.5, "-", "bound on the physical volume of the design region"),
    "filter_radius": (0.1, "mm", "Helmholtz filter radius"),
    "simp_p": (3.0, "-", "SIMP exponent"),
    "check_directions": (2, "-", "random directions of each gradient check"),
    "check_eps": (1e-4, "-", "step of the central differences (times a direction with entries in [-1, 1])"),
}

RESOLUTIONS = {
    "quick": {"h": 0.035, "steps": 8, "evaluations": 100},
    "medium": {"h": 0.02, "steps": 10, "evaluations": 100},
    "paper": {"h": 0.014, "steps": 20, "evaluations": 200},
}
DEFAULT_RESOLUTION = "quick"
#: unit and meaning of the resolution keys (``ngtmc show c-shape-design``)
RESOLUTION_PARAMETERS = {"h": ("mm", "element size (3282 design variables at 0.035 mm, 10374 at 0.02 mm)"),
                         "steps": ("-", "constant load steps over the stroke"),
                         "evaluations": ("-", "forward runs with their adjoint per optimisation (and the final design's)")}
REPORT = {"speed_against_error": False}


def build_mesh(p: dict) -> ngs.Mesh:
    """Regions "design", "slot" (third medium) and "pad" (solid); boundaries "clamp" (x = 0) and
    "load" (top edge of the pad)."""
    from netgen.occ import Glue, OCCGeometry, Rectangle, X

    L, H, g, xs, w = p["length"], p["height"], p["gap"], p["spine"], p["pad"]
    box = Rectangle(L, H).Face()
    slot = Rectangle(L - xs, g).Face().Move((xs, H / 2 - g / 2, 0))
    pad = Rectangle(w, w / 2).Face().Move((L - w, H - w / 2, 0))
    design = box - slot - pad
    design.faces.name, slot.faces.name, pad.faces.name = "design", "slot", "pad"
    shape = Glue([design, slot, pad])
    for e in shape.edges:
        if abs(e.center.y - H) < 1e-9 and e.center.x > L - w:
            e.name = "load"
    shape.edges.Min(X).name = "clamp"
    return ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=p["h"]))


def build_scene(p: dict, fracture: bool, mesh: ngs.Mesh | None = None) -> ngtmc.Scene:
    """The C-shape with the initial design (uniform ``volume_fraction``); ``fracture``: the design
    region may break."""
    mesh = mesh or build_mesh(p)
    m = ngtmc.Material(E=p["E"], nu=p["nu"], Gc=p["Gc"], l0=p["l0"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
        sc = ngtmc.Scene(mesh, {"design|slot|pad": m}, [ngtmc.Support("clamp", x=True, y=True)],
                         ngtmc.DisplacementLoad("load", "-y"),
                         density={"design": p["volume_fraction"], "slot": 0.0, "pad": 1.0},
                         fracture_regions="design" if fracture else (),
                         regulariser=ngtmc.Regulariser("design|slot", length=1.0, kbar_r=p["kbar_r"]),
                         gamma0=p["gamma0"], residual_stiffness=p["residual_stiffness"], order=2, name=NAME)
        sc.check()
    return sc


def optimisation(p: dict, fracture: bool, progress: bool = True):
    """The :class:`ngtmc.design.TopologyOptimisation` of the study, designed with or without fracture."""
    from ngtmc.design import Interpolation, TopologyOptimisation
    stroke = float(p["stroke"])
    control = ngtmc.AdaptiveStepControl(du_max=stroke / int(p["steps"]), k_u=0.0,
                                        du_min=stroke / int(p["steps"]) / 64)
    return TopologyOptimisation(build_scene(p, fracture), "design", stroke, volume_fraction=p["volume_fraction"],
                                filter_radius=p["filter_radius"], interpolation=Interpolation("simp", p["simp_p"]),
                                control=control, progress=progress)


def cases(p: dict) -> list[Case]:
    """Two optimisations: designed with fracture on, and with contact only (then run with fracture on)."""
    from ngtmc.studies._c_shape_run import optimise_case
    return [Case("fracture", "designed with fracture on", run=partial(optimise_case, p, True), cost=2.0),
            Case("contact_only", "designed with contact only, run with fracture on",
                 run=partial(optimise_case, p, False), cost=1.0)]


def post_results(p: dict, history, results: dict) -> dict:
    """The comparison, gradient checks, optimisation histories and designs as report tables and
    figures (:mod:`ngtmc.studies._c_shape_run`)."""
    from ngtmc.studies._c_shape_run import report_entries
    return report_entries(p, results)


def references(p: dict) -> list[dict]:
    return []


def targets(p: dict) -> list[dict]:
    return []


#: The contract of a run: the gradient checks agree to 1e-4 and no design fails to run. It holds at
#: every size; the test suite checks it on a coarse run (tests/test_study_c_shape_design.py), the quick
#: run's figures are in the record.
EXPECTED: dict = {
    "fracture_gradient": {"case": "fracture", "quantity": "worst_gradient_check", "value": 0.0, "abs": 1e-4,
                          "unit": "-", "source": "central differences against the adjoint (relative difference)"},
    "contact_gradient": {"case": "contact_only", "quantity": "worst_gradient_check", "value": 0.0, "abs": 1e-4,
                         "unit": "-", "source": "central differences against the adjoint (relative difference)"},
    "fracture_failures": {"case": "fracture", "quantity": "failed_designs", "value": 0, "abs": 0.5, "unit": "-",
                          "source": "no design whose forward run failed (a count: 0.5 admits none)"},
    "contact_failures": {"case": "contact_only", "quantity": "failed_designs", "value": 0, "abs": 0.5, "unit": "-",
                         "source": "no design whose forward run failed (a count: 0.5 admits none)"},
}


if __name__ == "__main__":  # pragma: no cover
    import sys
    from ngtmc.cli import run_script
    sys.exit(run_script(NAME))
