"""Contact benchmark: how the void stiffness gamma0 biases third-medium contact.

What this study shows
---------------------
Ciceri et al. (2026), Sect. "Material interpolation", Fig. 3-4: two structural members initially
0.15 mm apart are pressed into contact through a third medium (the void, rho = 0) whose stiffness is
gamma0 times the solid's. gamma0 must be small to avoid parasitic forces and large enough for the
solver. This study sweeps gamma0 = 1e-4, 1e-5, 1e-6, 1e-7 on one geometry and compares every curve
with a **classical contact solution of the same bodies** (no void at all; frictionless penalty
contact with NGSolve's ``ContactBoundary``, :mod:`ngtmc.classical.penalty_contact`):

1. before contact the void transmits a parasitic force, the difference between the TMC force and
   the classical (contact-free) force. The void acts as a spring of stiffness c gamma0 k (k the
   tip stiffness of a beam) in series with the lower beam, so the parasitic force is
   F_ref c gamma0 / (1 + c gamma0): proportional to gamma0 while c gamma0 << 1 (measured ratio 8.1
   between gamma0 = 1e-6 and 1e-7 at quick), saturating at F_ref when the void is as stiff as the
   beam (c = 1.2e5 here, so gamma0 = 1e-5 and 1e-4 drag the lower beam along: ratios 4.2 and 2.0);
2. after contact the TMC curves converge to the classical one as gamma0 falls.

Geometry (mm; the paper's Fig. 3 is not available, this one is our design)
-------------------------------------------------------------------------
* two parallel cantilevers ``beam_length`` x ``beam_thickness`` = 10 x 1, both clamped (x and y)
  on their left edge x = 0: the lower one occupies y in [0, 1], the upper one y in [1.15, 2.15]
  (``gap`` = 0.15 mm, the paper's);
* void (rho = 0): the whole gap between them, x in [0, 10], y in [1, 1.15] (its left edge is free;
  it sits between the two clamped ends there). Nothing else is meshed: the space around the beam
  tips is empty (the tips never leave the gap's footprint, so no void is needed there);
* load: the whole right end edge of the upper beam (x = 10) is displaced downwards (direction -y),
  its x-motion left free (``hold_tangential=False``); the recorded force is the vertical reaction
  there, N per mm of thickness (plane strain, thickness 1 mm). Final displacement 0.3 mm (twice the
  gap), so that about half of the curve is post-contact;
* classical reference: the same two beams without the void (the same mesh, with the void's
  elements left out, so that both share the beams' discretisation exactly); frictionless penalty
  contact between the upper beam's bottom face (master: the contact term is integrated there) and
  the lower beam's top face (minion). With the roles the other way round the medium mesh failed at
  u = 0.222 mm: the upper beam's tip corner, where contact is carried, was then a minion point
  next to the end of the master face, and the pairs flipped between iterations;
  penalty stiffness
  eps = ``penalty_factor`` E / h_beam (N/mm^3). Its penalty convergence is measured in the tests
  (the force at 0.3 mm changes by less than 1e-3 relative between 10x and 100x that value).

Parameters and sources
----------------------
Our choices (the paper does not give them): E = 1000 MPa, nu = 0.3 (any E scales all forces
alike); same Neo-Hookean energy (Eq. 2) for beams and void. The void regulariser (Eq. 3) with the
literature value kbar_r = 1e-6 and L = 10 mm (the beam length), displacement order 2 (MODEL.md).
Gap 0.15 mm (paper). gamma0 sweep 1e-4 ... 1e-7 (issue 3; the paper's Fig. 3 uses 1e-5). No
fracture in this study.

Resolutions change mesh and step sizes only: ``quick`` (CI: 2 quadratic elements through the beam
thickness, one across the gap; du = 0.01 mm), ``medium`` (h halved, du = 0.005 mm), ``paper``
(h quartered, du = 0.0025 mm; the paper gives no mesh for this benchmark).

Expected result
---------------
Euler-Bernoulli beam theory (plane strain, E' = E/(1 - nu^2)): each cantilever has tip stiffness
k = E' t^3 / (4 L^3) = 0.2747 N/mm per mm. Before contact F = k u; after the tips touch the two
beams act in parallel, F = k (2 u - gap) (0.1236 N/mm at u = 0.3). The classical FE solution
follows this within about 1 %. The TMC curve with gamma0 = 1e-4 is dominated by the void (the
lower beam is dragged along long before contact).

Results (records: ``studies/records/contact_gamma0.json``, ``ngtmc.study.records("contact_gamma0")``)
-----------------------------------------------------------------------------------------------------
TMC force at 0.3 mm relative to the classical one, and parasitic force at half the gap (N/mm):

==========  ===========  ===========  ===========  ===========  =====================
resolution  1e-4         1e-5         1e-6         1e-7         classical (N/mm)
==========  ===========  ===========  ===========  ===========  =====================
quick       +34.7 %      +12.1 %      +1.46 %      +0.06 %      0.12463 (+0.8 % [1])
paper       +34.5 %      +11.8 %      +1.28 %      -0.10 %      0.124467 (+0.68 % [1])
parasitic   0.0203       0.0103       0.00245      0.00030      (paper)
==========  ===========  ===========  ===========  ===========  =====================

[1] against beam theory. The numbers are mesh-converged at quick to a few tenths of a per cent
(medium: record ``medium``); the penalty convergence is checked by the tests' penalty sweep.
"""
from __future__ import annotations

from functools import partial

import numpy as np

import ngtmc
from ngtmc.study import Case

NAME = "contact_gamma0"
TITLE = "Contact benchmark: influence of the void stiffness gamma0"
#: What the report shows besides its sections: the force on a log scale too (the parasitic force
#: before contact spans decades of gamma0), the rules gamma(rho) and Gc(rho), and no speed
#: against error (the cases differ in physics, not in settings).
REPORT = {"force_log_scale": True, "interpolation": True, "speed_against_error": False}
SUMMARY = (
    "Two parallel 10 x 1 mm cantilevers, 0.15 mm apart, the upper one pushed down at its tip to 0.3 mm "
    "through a third-medium void (rho = 0) filling the gap, for gamma0 = 1e-4 ... 1e-7. Before contact "
    "the void transmits a parasitic force proportional to gamma0; after contact the curves converge to "
    "the classical frictionless penalty-contact solution of the same two beams (NGSolve ContactBoundary, "
    "no void) as gamma0 falls. Euler-Bernoulli beam theory is shown as a sanity check."
)

# physics: never changed by the resolution. name -> (value, unit, description)
PARAMETERS = {
    "E": (1000.0, "MPa", "Young's modulus of both beams (our choice)"),
    "nu": (0.3, "-", "Poisson's ratio (our choice)"),
    "beam_length": (10.0, "mm", "length of each cantilever (our design)"),
    "beam_thickness": (1.0, "mm", "height of each cantilever (our design)"),
    "gap": (0.15, "mm", "initial gap between the beams (paper)"),
    "final_load": (0.3, "mm", "final downward displacement of the upper beam's tip edge (twice the gap)"),
    "gamma0_values": ([1e-4, 1e-5, 1e-6, 1e-7], "-", "void stiffness ratios swept (issue 3; paper Fig. 3 uses 1e-5)"),
    "kbar_r": (1e-6, "-", "void regulariser factor, k_r = kbar_r L^2 K0 (literature value)"),
    "reg_length": (10.0, "mm", "characteristic length L of the regulariser (beam length)"),
    "thickness": (1.0, "mm", "out-of-plane thickness (forces in N per mm of thickness)"),
    "penalty_factor": (100.0, "-", "classical reference: penalty eps = penalty_factor * E / h_beam (N/mm^3)"),
    "classical": (True, "-", "also run the classical penalty-contact reference case"),
    "probe_load": (0.075, "mm", "displacement at which the pre-contact (parasitic) force is compared (half the gap)"),
}

# mesh and step sizes only
RESOLUTIONS = {
    "quick": {"h_beam": 0.5, "h_void": 0.15, "du_max": 0.01},
    "medium": {"h_beam": 0.25, "h_void": 0.075, "du_max": 0.005},
    "paper": {"h_beam": 0.125, "h_void": 0.0375, "du_max": 0.0025},
}
RESOLUTION_PARAMETERS = {
    "h_beam": ("mm", "element size in the beams"),
    "h_void": ("mm", "element size in the void (gap)"),
    "du_max": ("mm", "load increment (constant: no fracture, k_u = 0)"),
}
DEFAULT_RESOLUTION = "quick"

SNAPSHOT_LOADS = [0.075, 0.15, 0.2, 0.3]


def case_name(gamma0: float) -> str:
    """Case name of one gamma0, e.g. ``gamma0_1e-06``."""
    return f"gamma0_{gamma0:.0e}"


def build_mesh(p: dict, void: bool = True):
    """Mesh of the two beams (regions ``lower``, ``upper``) and, if ``void``, the gap (``void``).

    Boundaries: ``clamp`` (x = 0 of both beams), ``load`` (x = L of the upper beam), ``lower_top``
    and ``upper_bottom`` (the faces that come into contact), ``void_left`` (x = 0 of the void)."""
    from netgen.occ import Glue, MoveTo, OCCGeometry, X, Y
    import ngsolve as ngs

    L, T, g = float(p["beam_length"]), float(p["beam_thickness"]), float(p["gap"])
    hb, hv = float(p["h_beam"]), float(p["h_void"])
    lower = MoveTo(0, 0).Rectangle(L, T).Face()
    upper = MoveTo(0, T + g).Rectangle(L, T).Face()
    lower.faces.name, upper.faces.name = "lower", "upper"
    lower.faces.maxh = hb
    upper.faces.maxh = hb
    lower.edges.Min(X).name = "clamp"
    upper.edges.Min(X).name = "clamp"
    upper.edges.Max(X).name = "load"
    lower.edges.Max(Y).name = "lower_top"
    upper.edges.Min(Y).name = "upper_bottom"
    parts = [lower, upper]
    if void:
        gap = MoveTo(0, T).Rectangle(L, g).Face()
        gap.faces.name = "void"
        gap.faces.maxh = hv
        gap.edges.Min(X).name = "void_left"
        parts.append(gap)
    return ngs.Mesh(OCCGeometry(Glue(parts), dim=2).GenerateMesh(maxh=hb))


def material(p: dict) -> ngtmc.Material:
    return ngtmc.Material(E=float(p["E"]), nu=float(p["nu"]))


def build_scene(p: dict, gamma0: float) -> ngtmc.Scene:
    """The third-medium scene for one gamma0."""
    return ngtmc.Scene(
        mesh=build_mesh(p, void=True),
        materials={"lower|upper|void": material(p)},
        supports=[ngtmc.Support("clamp", x=True, y=True)],
        load=ngtmc.DisplacementLoad("load", direction="-y", hold_tangential=False),
        density={"void": 0.0},
        regulariser=ngtmc.Regulariser("void", length=float(p["reg_length"]), kbar_r=float(p["kbar_r"])),
        gamma0=float(gamma0),
        thickness=float(p["thickness"]),
        order=2,
        name=f"contact_gamma0 (gamma0 = {gamma0:g})",
    )


def penalty(p: dict) -> float:
    """Penalty stiffness of the classical reference, N/mm^3."""
    return float(p["penalty_factor"]) * float(p["E"]) / float(p["h_beam"])


def build_classical(p: dict, penalty_value: float | None = None):
    """The classical reference: :class:`ngtmc.classical.penalty_contact.PenaltyContact` on the beams only.

    It uses the very mesh of the third-medium scene with the void left out (``regions``), so that
    reference and TMC solutions share the beams' discretisation and differ only by the void."""
    from ngtmc.classical import PenaltyContact

    return PenaltyContact(
        build_mesh(p, void=True), {"lower|upper": material(p)},
        supports=[ngtmc.Support("clamp", x=True, y=True)],
        load=ngtmc.DisplacementLoad("load", direction="-y", hold_tangential=False),
        master="upper_bottom", minion="lower_top",
        penalty=penalty(p) if penalty_value is None else float(penalty_value),
        order=2, thickness=float(p["thickness"]), maxdist=10 * float(p["gap"]), regions="lower|upper")


def run_classical(p: dict, case: Case, out_dir=None):
    """``Case.run`` of the classical reference: a DataFrame with step, load, force, energy (elastic +
    penalty, N mm), newton_iterations, cutbacks, step_size, wall_time (the history columns that have
    no meaning here, such as max_alpha, are absent)."""
    ref = build_classical(p)
    hist = ref.run(ngtmc.Schedule.monotonic(float(p["final_load"])), du=float(p["du_max"]))
    return hist


def cases(p: dict) -> list[Case]:
    out = []
    final = float(p["final_load"])
    for g0 in p["gamma0_values"]:
        g0 = float(g0)
        out.append(Case(
            name=case_name(g0), label=f"third medium, gamma0 = {g0:g}",
            scene=partial(build_scene, dict(p), g0),
            schedule=ngtmc.Schedule.monotonic(final),
            control=ngtmc.AdaptiveStepControl(du_max=float(p["du_max"]), k_u=0.0, du_min=float(p["du_max"]) / 1024),
            snapshot_loads=[x for x in SNAPSHOT_LOADS if x <= final + 1e-12],
            parameters={"gamma0": g0},
        ))
    if p.get("classical", True):
        out.append(Case(
            name="classical", label=f"classical penalty contact (no void, eps = {penalty(p):g} N/mm^3)",
            run=partial(_run_case, dict(p)),
            parameters={"penalty": penalty(p), "method": "NGSolve ContactBoundary, frictionless penalty"},
        ))
    return out


def _run_case(p, case, out_dir):
    return run_classical(p, case, out_dir)


def beam_theory(p: dict, loads) -> np.ndarray:
    """Euler-Bernoulli force (N per mm of thickness) of the two cantilevers touching at their tips:
    F = k u before contact, k (2 u - gap) after, k = E' t^3 / (4 L^3), E' = E/(1 - nu^2)."""
    E = float(p["E"]) / (1 - float(p["nu"]) ** 2)
    t, L, g = float(p["beam_thickness"]), float(p["beam_length"]), float(p["gap"])
    k = E * t**3 / (4 * L**3) * float(p["thickness"])
    u = np.asarray(loads, dtype=float)
    return np.where(u <= g, k * u, k * (2 * u - g))


def references(p: dict) -> list[dict]:
    x = np.linspace(0.0, float(p["final_load"]), 61)
    return [{"label": "Euler-Bernoulli beam theory (tips in contact after the gap closes)",
             "source": "small-strain cantilever formula k = E' t^3 / (4 L^3), E' = E/(1 - nu^2); not a published curve",
             "kind": "curve", "x": x.tolist(), "y": beam_theory(p, x).tolist(), "x_unit": "mm", "y_unit": "N/mm"}]


def targets(p: dict) -> list[dict]:
    """No published numbers exist for this geometry (the paper's is not available); the beam-theory
    force at the final load is given as a sanity target for the classical case and the smallest gamma0."""
    final = float(p["final_load"])
    f = float(beam_theory(p, [final])[0])
    out = []
    if p.get("classical", True):
        out.append({"case": "classical", "quantity": "peak_force", "value": f, "unit": "N/mm",
                    "source": "Euler-Bernoulli beam theory (not published)", "tolerance": 0.05})
    g_min = min(float(g) for g in p["gamma0_values"])
    out.append({"case": case_name(g_min), "quantity": "peak_force", "value": f, "unit": "N/mm",
                "source": "Euler-Bernoulli beam theory (not published)", "tolerance": 0.05})
    return out


# ---------------------------------------------------------------------- post-processing
def post_results(p: dict, history, results: dict) -> dict:
    """Add to each case's results the numbers of :func:`compare` (forces in N/mm, differences
    relative to the classical force), when the history holds the classical reference."""
    if history is None or "case" not in history or "classical" not in set(history["case"]):
        return results
    histories = {c: g.sort_values("step") for c, g in history.groupby("case")}
    for name, numbers in compare(histories, p).items():
        if name in results:
            results[name].update(numbers)
    return results


def compare(histories: dict, p: dict) -> dict:
    """Key numbers from the histories ({case name: DataFrame with load, force}).

    Returns per gamma0: ``pre_contact_force`` (N/mm at ``probe_load``), ``parasitic_force`` (that
    minus the classical force there), ``post_contact_diff`` (TMC minus classical at the final load,
    relative to the classical force) and ``post_contact_max_diff`` (largest |difference| over the
    post-contact loads from gap + 0.05 mm to the final load, relative to the classical force at the
    final load)."""
    ref = histories["classical"]
    probe, final, g = float(p["probe_load"]), float(p["final_load"]), float(p["gap"])
    f_ref_probe = float(np.interp(probe, ref["load"], ref["force"]))
    f_ref_final = float(np.interp(final, ref["load"], ref["force"]))
    xs = np.linspace(min(g + 0.05, final), final, 21)
    out = {"classical": {"pre_contact_force": f_ref_probe, "final_force": f_ref_final}}
    for g0 in p["gamma0_values"]:
        name = case_name(float(g0))
        if name not in histories:
            continue
        h = histories[name]
        f_probe = float(np.interp(probe, h["load"], h["force"]))
        f_final = float(np.interp(final, h["load"], h["force"]))
        diff = np.interp(xs, h["load"], h["force"]) - np.interp(xs, ref["load"], ref["force"])
        out[name] = {"gamma0": float(g0), "pre_contact_force": f_probe, "parasitic_force": f_probe - f_ref_probe,
                     "final_force": f_final, "post_contact_diff": (f_final - f_ref_final) / f_ref_final,
                     "post_contact_max_diff": float(np.max(np.abs(diff))) / f_ref_final}
    return out


_DEFAULTS = {k: v[0] for k, v in PARAMETERS.items()}
#: What the quick run (the CI run of tests/test_study_contact_gamma0.py) is checked against, one
#: record per number (docs/study-interface.md): the quantity of metadata.json results
#: (post_results: the numbers of :func:`compare`), the value with its unit, tolerance (rel:
#: relative, abs: absolute) and source. No published numbers exist for this geometry.
EXPECTED = {
    "classical_force_at_probe": {
        "case": "classical", "quantity": "pre_contact_force", "unit": "N/mm", "rel": 0.02,
        "value": float(beam_theory(_DEFAULTS, [_DEFAULTS["probe_load"]])[0]),
        "source": "Euler-Bernoulli beam theory at probe_load = 0.075 mm (beam_theory; small strain, slender: ~1 %)"},
    "classical_final_force": {
        "case": "classical", "quantity": "final_force", "unit": "N/mm", "rel": 0.03,
        "value": float(beam_theory(_DEFAULTS, [_DEFAULTS["final_load"]])[0]),
        "source": "Euler-Bernoulli beam theory at the final load 0.3 mm (beam_theory, tips in contact)"},
    "smallest_gamma0_final_force": {
        "case": case_name(min(_DEFAULTS["gamma0_values"])), "quantity": "post_contact_diff", "value": 0.0,
        "unit": "-", "abs": 0.01,
        "source": "the classical penalty-contact case of the same run (relative difference at the final load; "
                  "measured +0.06 %)"},
    "smallest_gamma0_post_contact_branch": {
        "case": case_name(min(_DEFAULTS["gamma0_values"])), "quantity": "post_contact_max_diff", "value": 0.0,
        "unit": "-", "abs": 0.01,
        "source": "the classical penalty-contact case of the same run (largest difference from gap + 0.05 mm "
                  "to the final load, relative to its final force)"},
}


if __name__ == "__main__":  # python studies/contact_gamma0.py [options of `ngtmc run`], e.g. --resolution medium
    import sys

    from ngtmc.cli import run_script
    sys.exit(run_script(NAME))
