"""Design for contact: place a little filler in a gap so that a notched beam absorbs more energy
(topology optimisation of a whole region, by :mod:`ngtmc.design`: the study ``c_shape_design``).

What this study shows
---------------------
How to use the exact gradients of :mod:`ngtmc.sensitivities` for a small design problem in which
contact and fracture both matter. A notched beam (4 x 1 mm, notch 0.2 mm deep at mid-span, plane
strain, supported on two 0.2 mm segments at its lower corners) is loaded by a rigid-ish indenter
(1.2 x 0.3 mm) pushed down on its top edge. Between indenter and beam lies a **pad**: a 1.2 x 0.1 mm
layer of third medium (rho = 0, gamma0 = 1e-4) that transmits almost no force until the indenter has
squeezed it (contact closes at about 0.08-0.1 mm), after which the beam bends and a crack runs from
the notch (peak force at about 0.18 mm in the initial design).

The design variables are the densities of the pad elements. A little filler (rho > 0) makes the pad
transmit load before the gap closes, and where it sits decides where the beam is loaded: under the
middle of the indenter it loads the notched section hardest, near the ends of the pad it spreads the
load. The problem

    maximise   W(rho) = sum_n (F_n + F_{n-1}) / 2 (lambda_n - lambda_{n-1})   (external work, N mm)
    subject to sum_e |e| rho_e <= v_f |pad|,   0 <= x_e <= 1,   rho = filter(x)

is solved by sequential linear programming with an adaptive move limit (scipy's ``linprog``) on the
design x, filtered by a density filter of radius ``filter_radius`` (linear hat weights). (SLSQP,
tried first, jumps to designs so far from the current one that their crack makes Newton fail; a
move limit that shrinks on rejection keeps every trial near an accepted design.) Every iteration
runs the forward path (adaptive control with k_u = 0, i.e. constant steps du unless Newton cuts
back) and one adjoint sweep for dW/drho. The external work is taken over the whole stroke (0 to
``final_load``), so it rewards both carrying load early (filler) and not breaking early (where the
filler sits).

Geometry and parameters are chosen for this demonstration (not from the paper): E = 1000 MPa,
nu = 0.3, Gc = 0.15 N/mm, l0 = 0.15 mm, gamma0 = 1e-4, residual stiffness 1e-4, Hessian
regulariser kbar_r = 1e-5 (L = 1 mm) in the pad, displacement order 2, fracture in the beam only.

Run
---
``run(out_dir, resolution)`` (``python studies/design_for_contact.py OUT [-r medium]``; code in
``studies/_design_optimisation.py``) runs the optimisation and writes, beside ``metadata.json`` and
``history.csv`` (cases ``initial`` and ``final``), ``optimisation.csv`` (iteration, W, volume, wall
time) and ``designs.npz`` (centroids, pad mask and rho of the pad at selected iterations).
``cases(p)`` returns the initial design only (a case is one forward load path, not a loop).

Gradient check: ``ngtmc run design-for-contact --set gradient_check=4 [--workers 2]`` runs the
initial design with its adjoint sweep and, per random direction d_j, the forward runs at x0 +- eps
d_j as cases of one run (docs/parallel.md); ``results.gradient_check`` of ``metadata.json``
compares dW/dx . d_j with central differences (4e-9 and 2e-8 on the coarse mesh of the tests).

Results (records: ``studies/records/design_for_contact.json``)
-------------------------------------------------------------
From a uniform filler density 0.0025 (half the volume bound) W rises from 0.621 to 0.730 N mm
(+17.7 %, 6 iterations) at quick, from 0.508 to 0.615 N mm (+21 %, 15 iterations; peak 4.36 ->
4.97 N/mm) at medium and from 0.412 to 0.513 N mm (+24.6 %, 30 iterations; peak 3.94 -> 4.44
N/mm) at paper. The optimiser takes the filler away from the middle of the pad, above the notch,
and piles it up at the ends of the pad: the indenter then loads the beam off-centre, the bending
moment at the notch is smaller for the same force, and the beam carries more before the crack runs.

Adaptive refinement (``--set h_crack=...``)
--------------------------------------------
The adjoint needs one mesh for the whole path (it refuses a run whose mesh changed,
:mod:`ngtmc.sensitivities`). So with ``h_crack`` > 0 the path is recorded on the final mesh of a
refining run: the beam is meshed at ``h`` without the band around the notch, the initial design is
run over the whole stroke with :class:`ngtmc.Adaptivity` (bisection to ``h_crack`` where alpha >
0.2 or H reaches Gc / (6 l0), :func:`refined_mesh`), and every case, the gradient check and the
optimisation then run on that mesh, fixed. The design variables are the pad elements of that mesh.
A design that moves the crack out of the refined zone meets coarser elements there. At quick with
``h_crack`` = l0/4 = 0.0375 mm the refining run ends with 11173 elements (561 with the band) and
refines almost the whole beam: this demonstration beam is damaged diffusely, not along one crack;
two iterations raise W by 15.9 % (record ``quick_h_crack``).
"""
from __future__ import annotations

import math
import sys

import numpy as np
import pandas as pd
import ngsolve as ngs

import ngtmc
from ngtmc.study import Case

NAME = "design_for_contact"
TITLE = "Design for contact: filler in a gap above a notched beam (gradient-based)"
SUMMARY = (
    "A notched beam is loaded through a 0.1 mm gap of third medium by an indenter. The densities of the "
    "gap elements are optimised (density filter, volume bound, sequential linear programming with a move "
    "limit, exact adjoint gradients through "
    "contact closure and crack growth) to maximise the external work over the stroke."
)

PARAMETERS = {
    "E": (1000.0, "MPa", "Young's modulus (beam, pad base material, indenter)"),
    "nu": (0.3, "-", "Poisson's ratio"),
    "Gc": (0.15, "N/mm", "critical energy release rate of the beam"),
    "l0": (0.15, "mm", "phase-field length scale"),
    "gamma0": (1e-4, "-", "void stiffness ratio of the pad (Eq. 17)"),
    "residual_stiffness": (1e-4, "-", "added to g(alpha)"),
    "kbar_r": (1e-5, "-", "regulariser factor (Eq. 3), L = 1 mm; 1e-6 let the squeezed pad invert at the history points"),
    "beam_length": (4.0, "mm", "beam length"),
    "beam_height": (1.0, "mm", "beam height"),
    "notch_depth": (0.2, "mm", "notch depth from the bottom at mid-span"),
    "notch_width": (0.04, "mm", "notch width"),
    "gap": (0.1, "mm", "pad (gap) thickness"),
    "pad_width": (1.2, "mm", "pad and indenter width"),
    "indenter_height": (0.3, "mm", "indenter height"),
    "support_length": (0.2, "mm", "length of each support segment"),
    "final_load": (0.2, "mm", "imposed downward displacement of the indenter top"),
    "volume_fraction": (0.005, "-", "bound on the filler volume as a fraction of the pad"),
    "initial_fill": (0.0025, "-", "uniform initial density of the pad"),
    "filter_radius": (0.15, "mm", "density filter radius"),
    "move_limit": (0.01, "-", "largest change of a design variable per iteration"),
    "thickness": (1.0, "mm", "out-of-plane thickness"),
    "gradient_check": (0, "-", "number of random design directions d along which ngtmc run checks the adjoint dW/dx . d "
                               "against central differences of forward runs (2 cases per direction; 0: no check)"),
    "gradient_check_eps": (1e-4, "-", "step of the central differences, times d (|d_i| <= initial_fill)"),
    "h_crack": (0.0, "mm", "adaptive refinement (ngtmc.Adaptivity, bisection) to this size where the crack is or is about "
                           "to be, for example l0/4; the beam is then meshed without the refined band (at h), and a "
                           "forward run of the initial design refines it; every case and the optimisation run on "
                           "that final mesh, fixed (the adjoint needs one mesh); 0: the band of h_band"),
}

RESOLUTIONS = {
    "quick": {"h_band": 0.1, "h_pad": 0.05, "h": 0.3, "du": 0.02, "iterations": 6},
    "medium": {"h_band": 0.06, "h_pad": 0.05, "h": 0.25, "du": 0.01, "iterations": 15},
    "paper": {"h_band": 0.04, "h_pad": 0.025, "h": 0.2, "du": 0.005, "iterations": 30},
}
DEFAULT_RESOLUTION = "quick"


def _params(resolution: str = DEFAULT_RESOLUTION, **overrides) -> dict:
    p = {k: v[0] for k, v in PARAMETERS.items()}
    p.update(RESOLUTIONS[resolution])
    p.update(overrides)
    return p


# ---------------------------------------------------------------------------- scene
def build_mesh(p: dict) -> ngs.Mesh:
    """Beam (region "beam", refined band around the notch), pad ("pad") and indenter ("indenter");
    boundaries "sup_left", "sup_right" (supports), "top" (loaded edge of the indenter).

    With ``h_crack`` > 0: no band; the mesh is the final mesh of a forward run of the initial
    design with adaptive refinement (:func:`refined_mesh`), the same object for the same
    parameters within a process."""
    if float(p.get("h_crack", 0.0)) > 0:
        return refined_mesh(p)
    return _generated_mesh(p, p["h_band"])


#: Final meshes of the refining runs, per parameter set (:func:`refined_mesh`).
_REFINED: dict = {}


def refined_mesh(p: dict) -> ngs.Mesh:
    """The mesh the optimisation runs on with ``h_crack`` > 0 (mm): the beam meshed at ``h``
    without the band, refined during a forward run of the initial design (uniform filler
    ``initial_fill``) by :class:`ngtmc.Adaptivity` (bisection, target ``h_crack`` where alpha >
    0.2 or H reaches Gc / (6 l0), one layer of neighbours, no corridor) over the whole stroke. The crack path of
    the initial design thus sets the fine zone; a design that moves the crack elsewhere meets
    coarser elements there. Computed once per parameter set and process (deterministic: the same
    marks on the same mesh give the same mesh in every process)."""
    key = tuple(sorted((k, repr(v)) for k, v in p.items()))
    if key not in _REFINED:
        # no corridor (the default "auto" is 4 l0): on this diffusely damaged beam it adds elements to
        # every later run and saves nothing (record quick_h_crack)
        adapt = ngtmc.Adaptivity(h_crack=float(p["h_crack"]), corridor=0.0)   # checks h_crack (finite, > 0)
        mesh = _generated_mesh(p, p["h"])
        sc = build_scene(p, mesh=mesh)
        rho = sc.element_density()
        rho[_pad_mask(mesh)] = p["initial_fill"]
        sc.density = rho
        sim = ngtmc.Simulation(sc, schedule(p), control(p), newton=newton_options(), adapt=adapt)
        print(f"[ngtmc design_for_contact] refining the mesh ({mesh.ne} elements) to h_crack = {adapt.h_crack:g} mm "
              "by a forward run of the initial design", file=sys.stderr, flush=True)
        try:
            res = sim.run()
        except ngtmc.StepFailure as e:
            raise RuntimeError(f"the refining run of the initial design (h_crack = {adapt.h_crack:g} mm) failed: {e}") from e
        _REFINED[key] = res.solver.mesh
        print(f"[ngtmc design_for_contact] refined mesh: {res.solver.mesh.ne} elements, {len(sim.refinements)} "
              f"refinements, {res.wall_time:.0f} s", file=sys.stderr, flush=True)
    return _REFINED[key]


def _generated_mesh(p: dict, h_band: float) -> ngs.Mesh:
    from netgen.occ import Glue, OCCGeometry, Rectangle, WorkPlane, Y

    L, Hb = p["beam_length"], p["beam_height"]
    nw, nd, ls = p["notch_width"], p["notch_depth"], p["support_length"]
    g, wpad, hi = p["gap"], p["pad_width"], p["indenter_height"]
    xm = L / 2
    wp = WorkPlane()
    wp.MoveTo(0, 0).LineTo(ls, 0, "sup_left").LineTo(xm - nw / 2, 0, "bottom").LineTo(xm - nw / 2, nd, "notch")
    wp.LineTo(xm + nw / 2, nd, "notch").LineTo(xm + nw / 2, 0, "notch").LineTo(L - ls, 0, "bottom")
    wp.LineTo(L, 0, "sup_right").LineTo(L, Hb, "right").LineTo(0, Hb, "beam_top").Close("left")
    beam = wp.Face()
    band = Rectangle(0.8, Hb).Face().Move((xm - 0.4, 0, 0))
    bb, br = beam * band, beam - band
    bb.faces.name = "beam"
    br.faces.name = "beam"
    bb.faces.maxh = h_band
    pad = Rectangle(wpad, g).Face().Move((xm - wpad / 2, Hb, 0))
    pad.faces.name = "pad"
    pad.faces.maxh = p["h_pad"]
    ind = Rectangle(wpad, hi).Face().Move((xm - wpad / 2, Hb + g, 0))
    ind.faces.name = "indenter"
    ind.edges.Max(Y).name = "top"
    return ngs.Mesh(OCCGeometry(Glue([bb, br, pad, ind]), dim=2).GenerateMesh(maxh=p["h"]))


def build_scene(p: dict, mesh: ngs.Mesh | None = None, rho: np.ndarray | None = None) -> ngtmc.Scene:
    """The scene for parameters ``p``; ``rho`` (per element) overrides the default density (pad 0)."""
    import warnings

    mesh = mesh or build_mesh(p)
    m = ngtmc.Material(E=p["E"], nu=p["nu"], Gc=p["Gc"], l0=p["l0"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
        sc = ngtmc.Scene(
            mesh, {"beam": m, "pad": m, "indenter": m},
            [ngtmc.Support("sup_left", x=True, y=True), ngtmc.Support("sup_right", y=True)],
            ngtmc.DisplacementLoad("top", "-y", hold_tangential=True),
            density={"pad": 0.0} if rho is None else np.asarray(rho, dtype=float),
            fracture_regions="beam", regulariser=ngtmc.Regulariser("pad", length=1.0, kbar_r=p["kbar_r"]),
            gamma0=p["gamma0"], residual_stiffness=p["residual_stiffness"], thickness=p["thickness"], order=2,
            name=NAME)
        sc.check()
    return sc


def schedule(p: dict) -> ngtmc.Schedule:
    return ngtmc.Schedule([0.0, p["final_load"]])


def control(p: dict) -> ngtmc.AdaptiveStepControl:
    """Constant steps du (k_u = 0); Newton failures halve a step (down to du/1024)."""
    return ngtmc.AdaptiveStepControl(du_max=p["du"], k_u=0.0, du_min=p["du"] / 1024)


def newton_options() -> ngtmc.NewtonOptions:
    return ngtmc.NewtonOptions(rtol=1e-12)


def cases(p: dict) -> list[Case]:
    """The initial design as a plain load path (the optimisation itself is :func:`run`). With
    ``gradient_check`` = k > 0, the check of the adjoint gradient instead (``ngtmc run
    design-for-contact --set gradient_check=4 [--workers 2]``; :func:`post_results` compares): the
    initial design with its adjoint sweep, and the 2 k forward runs of the central differences,
    independent cases that a Dask cluster runs side by side."""
    from functools import partial

    check_parameters(p)
    if int(p["gradient_check"]) > 0:
        k = int(p["gradient_check"])
        out = [Case("initial", "initial design, with the adjoint dW/dx . d of each direction", run=partial(_adjoint_case, p),
                    cost=2.0)]
        for j in range(k):
            for sign, name in ((1.0, "plus"), (-1.0, "minus")):
                out.append(Case(f"d{j}_{name}", f"x {'+' if sign > 0 else '-'} eps d{j}",
                                scene=partial(_design_scene, p, j, sign), schedule=schedule(p), control=control(p),
                                options={"newton": newton_options()}, parameters={"direction": j, "sign": sign}))
        return out
    return [Case("initial", "initial design (uniform filler)", scene=partial(_design_scene, p, None, 0.0),
                 schedule=schedule(p), control=control(p), options={"newton": newton_options()})]


def check_directions(p: dict, n: int) -> np.ndarray:
    """The ``gradient_check`` directions (k, n) over the n design variables: uniform in
    [-1, 1] times ``initial_fill`` (seeded, so every process draws the same)."""
    return np.random.default_rng(4).uniform(-1, 1, (int(p["gradient_check"]), n)) * p["initial_fill"]


def _design_scene(p: dict, direction: int | None, sign: float) -> ngtmc.Scene:
    """The scene of the initial design x0 (uniform ``initial_fill``), or of x0 + sign eps d_direction."""
    sc = build_scene(p)
    mask = _pad_mask(sc.mesh)
    if direction is None:
        rho = sc.element_density()
        rho[mask] = p["initial_fill"]
    else:
        prob = DesignProblem(p, mesh=sc.mesh)
        x = np.full(int(mask.sum()), float(p["initial_fill"]))
        x = x + sign * float(p["gradient_check_eps"]) * check_directions(p, x.size)[direction]
        rho = prob.rho(x)
    sc.density = rho
    return sc


def _adjoint_case(p: dict, case: Case, out_dir) -> pd.DataFrame:
    """The initial design's forward path and adjoint sweep (:meth:`DesignProblem.evaluate`): its
    history, with the adjoint directional derivatives dW/dx . d_j (N mm per unit x) in the
    columns ``adjoint_dW_d<j>`` of its last row."""
    prob = DesignProblem(p)
    x = np.full(int(prob.mask.sum()), float(p["initial_fill"]))
    W, dW, path = prob.evaluate(x)
    h = path.history.copy()
    for j, d in enumerate(check_directions(p, x.size)):
        h[f"adjoint_dW_d{j}"] = np.nan
        h.loc[h.index[-1], f"adjoint_dW_d{j}"] = float(dW @ d)
    h["wall_time"] = np.nan
    h.loc[h.index[-1], "wall_time"] = prob.evaluations[-1]["wall"]
    return h


def external_work(rows: pd.DataFrame) -> float:
    """The objective W of one case's history: the trapezoidal external work sum (F_n + F_{n-1})/2
    (u_n - u_{n-1}) (N mm per mm of thickness; :class:`ngtmc.sensitivities.ExternalWork`)."""
    u, F = rows["load"].to_numpy(dtype=float), rows["force"].to_numpy(dtype=float)
    return float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(u)))


def post_results(p: dict, history: pd.DataFrame, results: dict) -> dict:
    """With ``gradient_check``: ``results["gradient_check"]``, per direction j the central
    difference (W(x0 + eps d_j) - W(x0 - eps d_j)) / (2 eps) of the forward cases, the adjoint
    dW/dx . d_j of the initial case and their relative difference (None until the cases of a
    direction are done, or where the two forward runs took different load steps, which the
    difference would not survive)."""
    k = int(p["gradient_check"])
    if k <= 0 or "case" not in history:
        return results
    eps = float(p["gradient_check_eps"])
    rows = {c: g for c, g in history.groupby(history["case"].astype(str))}
    init = rows.get("initial")
    checks = []
    for j in range(k):
        plus, minus = rows.get(f"d{j}_plus"), rows.get(f"d{j}_minus")
        col = f"adjoint_dW_d{j}"
        adj = None
        if init is not None and col in init and init[col].notna().any():
            adj = float(init[col].dropna().iloc[-1])
        fd = None
        same_steps = (plus is not None and minus is not None and len(plus) == len(minus)
                      and np.allclose(plus["load"].to_numpy(float), minus["load"].to_numpy(float), rtol=0, atol=1e-14))
        if same_steps:
            fd = (external_work(plus) - external_work(minus)) / (2 * eps)
        rel = abs(fd - adj) / abs(adj) if fd is not None and adj not in (None, 0.0) else None
        checks.append({"direction": j, "finite_difference": fd, "adjoint": adj, "relative_difference": rel,
                       "same_load_steps": bool(same_steps)})
    results = dict(results)
    table = {"title": "Adjoint gradient against central differences",
             "caption": (f"Per random design direction d_j (|d_j,i| <= initial_fill): the adjoint dW/dx . d_j and the "
                         f"central difference (W(x0 + eps d_j) - W(x0 - eps d_j)) / (2 eps) of the forward cases "
                         f"d<j>_plus and d<j>_minus, eps = {eps:g}; W the external work over the stroke. A blank "
                         "difference: its two forward runs took different load steps, or are not done."),
             "columns": [{"name": "direction", "unit": ""}, {"name": "adjoint", "unit": "N mm"},
                         {"name": "central difference", "unit": "N mm"}, {"name": "relative difference", "unit": "-"}],
             "rows": [[c["direction"], c["adjoint"], c["finite_difference"], c["relative_difference"]] for c in checks]}
    results["gradient_check"] = {"eps": eps, "unit": "N mm per unit x", "directions": checks,
                                 "W_initial": external_work(init) if init is not None else None, "report_table": table}
    return results


def check_parameters(p: dict):
    """Raise StudyError naming the parameter for a negative or non-finite ``h_crack``."""
    from ngtmc.study import StudyError
    h = float(p.get("h_crack", 0.0))
    if not (math.isfinite(h) and h >= 0):
        raise StudyError(f"design_for_contact: h_crack = {p.get('h_crack')!r} mm must be >= 0 (0: the refined band)")


def references(p: dict) -> list[dict]:
    return []


def targets(p: dict) -> list[dict]:
    return []


EXPECTED: dict = {}   # an optimisation demo: no published or measured reference numbers


# ---------------------------------------------------------------------------- optimisation
# The optimisation (filter, objective and gradient, SLP, its run folder) is in the helper module;
# its names are re-exported here, where users of the study look for them.
from ngtmc.studies._design_optimisation import (  # noqa: E402,F401
    DesignProblem, _pad_mask, density_filter, optimise, run, run_metadata, write_optimisation_page, write_snapshots)


if __name__ == "__main__":  # pragma: no cover
    # python studies/design_for_contact.py [OUT_DIR] [--resolution R] [--set KEY=VALUE] [--no-report]:
    # the optimisation (`ngtmc run design-for-contact` runs only the initial design)
    import argparse

    from ngtmc.cli import parse_overrides
    from ngtmc.study import study_parameters
    ap = argparse.ArgumentParser(prog="python studies/design_for_contact.py", description=TITLE)
    ap.add_argument("out_dir", nargs="?", default="runs/design_for_contact-quick", help="run folder")
    ap.add_argument("--resolution", "-r", default=DEFAULT_RESOLUTION, help=", ".join(RESOLUTIONS))
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="override a parameter (repeatable)")
    ap.add_argument("--no-report", action="store_true", help="do not render report.html")
    args = ap.parse_args()
    given = parse_overrides(args.overrides)
    from ngtmc.study import StudyError
    try:
        _, values = study_parameters(sys.modules[__name__], args.resolution, given)  # typed, or StudyError
        check_parameters(values)
    except StudyError as e:
        ap.error(str(e))
    print(run(args.out_dir, args.resolution, {k: values[k] for k in given}, report=not args.no_report))
