"""Accuracy of the cost-saving choices against the full model, on scenes users bring
(``python -m benchmarks.verification``; about 3 minutes on one core).

1. **Self-contact of one body on a quad-dominated mesh** (:func:`c_shape`): a C-shaped block whose
   upper arm is pushed down until it closes its slot, a void, onto the lower arm. At two
   resolutions (h = 0.1 and 0.05 mm) side by side:

   * ``exact``: the defaults (order 2 everywhere, the regulariser's rule exact on the
     quadrilaterals: :func:`ngtmc.discrete.spaces.term_rules`), steps of 0.0096 mm;
   * ``fine``: the same with steps of 0.0024 mm and the regulariser integrated with a rule of
     order 8, the reference;
   * ``one-point``: the regulariser's one-point rule on every element type (exact on straight
     triangles only; the rule before 0.2.0);
   * ``variable order``: order 1 in the body, 2 in the void (``Scene(variable_order=True)``).

   The corner where the arms meet and the force at the last load common to all variants are
   compared with ``fine``.
2. **Rigid rotation of a free body with a void** (tests/test_verification.py) by 90 degrees in 1, 5,
   10 and 90 steps: largest force (N/mm) and energy (N mm) over the run, and how far the strip held
   by the void alone ends from the rotation (mm).

Writes ``benchmarks/results/verification-<UTC stamp>.json`` and ``.md``. Units: mm, N, MPa; forces
per mm of thickness (N/mm).
"""
from __future__ import annotations

import json
import platform
import subprocess
import sys
import time
import warnings
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, X, Y

import ngtmc
import ngtmc.discrete.displacement_energy as _energy
from ngtmc.discrete.spaces import rules, term_rules

RESULTS = Path(__file__).resolve().parent / "results"
FINAL = 0.24            # mm: the slot (0.2 mm) closed and the arms pressed 0.04 mm further


def c_shape(maxh: float = 0.1, quad: bool = True, variable_order: bool = False) -> tuple:
    """A 1 x 1 mm block with a slot 0.7 x 0.2 mm cut from its right side at mid-height and filled
    with void (gamma0 1e-6, regulariser kbar_r 1e-5, L = 1 mm; E 1000 MPa, nu 0.3), clamped at the
    bottom and pushed down on its top (x held): the upper arm closes the slot onto the lower one.
    netgen's ``quad_dominated`` mesh (``quad``) at ``maxh`` (mm, half of it in the slot). Returns
    (scene, mesh)."""
    outer = Rectangle(1.0, 1.0).Face()
    outer.edges.Max(Y).name = "top"
    outer.edges.Min(Y).name = "bottom"
    slot = MoveTo(0.3, 0.4).Rectangle(0.7, 0.2).Face()
    body = outer - slot
    body.faces.name, slot.faces.name = "body", "void"
    slot.faces.maxh = maxh / 2
    mesh = ngs.Mesh(OCCGeometry(Glue([body, slot]), dim=2).GenerateMesh(maxh=maxh, quad_dominated=quad))
    scene = ngtmc.Scene(mesh, {".*": ngtmc.Material(1000.0, 0.3)}, density={"void": 0.0}, gamma0=1e-6,
                        supports=[ngtmc.Support("bottom", x=True, y=True)],
                        load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True),
                        regulariser=ngtmc.Regulariser("void", length=1.0, kbar_r=1e-5),
                        variable_order=variable_order)
    return scene, mesh


class _rule_override:
    """The regulariser's rule of :func:`ngtmc.discrete.spaces.term_rules` replaced for the block:
    ``"one-point"`` (order 2p - 4 on every element type, the rule before 0.2.0) or ``"order8"``
    (order 8 on every element type, the reference: exact on straight elements, converged to
    1e-6 or better elsewhere). The elastic terms keep their rules (the history and J-guard points)."""

    def __init__(self, kind: str):
        self.kind = kind

    def __enter__(self):
        self._saved = _energy.term_rules

        def patched(mesh, term, p):
            if term != "regularisation":
                return self._saved(mesh, term, p)
            return rules(mesh, 8 if self.kind == "order8" else max(2 * p - 4, 0))
        _energy.term_rules = patched
        return self

    def __exit__(self, *exc):
        _energy.term_rules = self._saved
        return False


def run_c_shape(maxh: float, variant: str) -> dict:
    """One variant of item 1 of the module docstring; its record (dict)."""
    scene, mesh = c_shape(maxh, variable_order=variant == "variable order")
    du = FINAL / (100 if variant == "fine" else 25)
    control = ngtmc.AdaptiveStepControl(du_max=du, du_min=1e-7, k_u=1e3)
    t0 = time.perf_counter()
    rec = {"maxh_mm": maxh, "variant": variant, "elements": mesh.ne, "du_max_mm": du}
    try:
        if variant in ("one-point", "fine"):
            with _rule_override("one-point" if variant == "one-point" else "order8"):
                res = ngtmc.simulate(scene, FINAL, control)
        else:
            res = ngtmc.simulate(scene, FINAL, control)
        h, solver = res.history, res.solver
        rec["finished"] = True
    except ngtmc.StepFailure as fail:
        h, solver = fail.history, None
        rec["finished"] = False
        rec["failure"] = str(fail).split(";")[0]
    rec.update(wall_time_s=time.perf_counter() - t0, steps=len(h) - 1,
               newton_iterations=int(h["newton_iterations"].sum()), last_load_mm=float(h["load"].iloc[-1]),
               ndof=None if solver is None else solver.fes_u.ndof)
    rec["curve"] = {"load_mm": h["load"].tolist(), "force_N_per_mm": h["force"].tolist()}
    if solver is not None:
        rec["corner_mm"] = [float(v) for v in solver.u(mesh(1.0, 0.6))]
    return rec


def run_rotation(steps: int) -> dict:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_verification import _free_body, _rotation
    mesh = _free_body()
    sc = ngtmc.Scene(mesh, {".*": ngtmc.Material(1000.0, 0.3, 1.0, 0.05)}, supports=[],
                     load=ngtmc.DisplacementField("left", _rotation), density={"void": 0.0}, gamma0=1e-4,
                     regulariser=ngtmc.Regulariser("void", length=1.0, kbar_r=1e-6), fracture_regions="strip")
    t0 = time.perf_counter()
    res = ngtmc.simulate(sc, 1.0, ngtmc.AdaptiveStepControl(du_max=1.0 / steps, du_min=1e-4 / steps, k_u=1e-9))
    h = res.history
    off = np.linalg.norm(np.asarray(res.solver.u(mesh(1.0, 0.4))) - np.asarray(_rotation(1.0, 0.4, 1.0)))
    return {"steps_asked": steps, "steps": len(h) - 1, "newton_iterations": int(h["newton_iterations"].sum()),
            "max_abs_force_N_per_mm": float(np.abs(h["force"]).max()),
            "max_energy_N_mm": float(np.abs(h["elastic_energy"]).max() + np.abs(h["regularisation_energy"]).max()),
            "strip_off_rotation_mm": float(off), "floor_accepts": int(h["floor_accepts"].sum()),
            "wall_time_s": time.perf_counter() - t0}


def _compare(records: list) -> list:
    """Each variant against ``fine`` at the same maxh: force at the last load both reached (by
    linear interpolation) and the corner displacement (where both finished), in %."""
    out = []
    for r in records:
        ref = next(q for q in records if q["maxh_mm"] == r["maxh_mm"] and q["variant"] == "fine")
        lam = min(r["last_load_mm"], ref["last_load_mm"])
        f = np.interp(lam, r["curve"]["load_mm"], r["curve"]["force_N_per_mm"])
        f_ref = np.interp(lam, ref["curve"]["load_mm"], ref["curve"]["force_N_per_mm"])
        row = {"maxh_mm": r["maxh_mm"], "variant": r["variant"], "finished": r["finished"],
               "compared_at_mm": lam, "force_N_per_mm": f, "force_diff_pct": 100 * (f / f_ref - 1),
               "steps": r["steps"], "newton_iterations": r["newton_iterations"], "ndof": r["ndof"],
               "wall_time_s": r["wall_time_s"]}
        if "corner_mm" in r and "corner_mm" in ref:
            row["corner_y_diff_pct"] = 100 * (r["corner_mm"][1] / ref["corner_mm"][1] - 1)
        out.append(row)
    return out


def main():
    warnings.simplefilter("ignore")
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    c_records = [run_c_shape(h, v) for h in (0.1, 0.05) for v in ("fine", "exact", "one-point", "variable order")]
    rot = [run_rotation(n) for n in (1, 5, 10, 90)]
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=Path(__file__).parent).stdout.strip()
    except OSError:
        commit = ""
    record = {"benchmark": "verification", "date_utc": stamp, "commit": commit, "machine": platform.node(),
              "python": platform.python_version(), "ngsolve": ngs.__version__,
              "c_shape": _compare(c_records), "c_shape_runs": c_records, "rigid_rotation": rot}
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"verification-{stamp}.json"
    path.write_text(json.dumps(record, indent=1, default=float))
    lines = [f"# verification ({stamp}, commit {commit})", "",
             "Self-contact of one body (C-shape), quad-dominated mesh, against the fine-step order-8 reference:", "",
             "| h (mm) | variant | finished | compared at (mm) | force (N/mm) | force diff (%) | corner y diff (%) "
             "| steps | Newton | u dofs | wall (s) |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in record["c_shape"]:
        cy = r.get("corner_y_diff_pct")
        lines.append(f"| {r['maxh_mm']} | {r['variant']} | {r['finished']} | {r['compared_at_mm']:.4f} | "
                     f"{r['force_N_per_mm']:.4f} | {r['force_diff_pct']:+.3f} | "
                     f"{'' if cy is None else f'{cy:+.3f}'} | {r['steps']} | {r['newton_iterations']} | "
                     f"{r['ndof']} | {r['wall_time_s']:.1f} |")
    lines += ["", "Rigid rotation by 90 degrees of a free body with a void:", "",
              "| steps asked | steps | Newton | max force (N/mm) | max energy (N mm) | strip off (mm) | floor accepts |",
              "|---|---|---|---|---|---|---|"]
    for r in rot:
        lines.append(f"| {r['steps_asked']} | {r['steps']} | {r['newton_iterations']} | {r['max_abs_force_N_per_mm']:.2e} "
                     f"| {r['max_energy_N_mm']:.2e} | {r['strip_off_rotation_mm']:.2e} | {r['floor_accepts']} |")
    path.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"record: {path}")


if __name__ == "__main__":
    main()
