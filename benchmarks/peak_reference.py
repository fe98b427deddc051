"""Tiny-step reference of the three-point bending's peak on one mesh: the study's default scheme
(path following: converged monolithic steps, no lag) with displacement steps of at most
``--du-coarse`` up to ``--fine-from`` and at most ``--du-fine`` from there, until the force has
fallen below ``--drop`` times its maximum (the crack runs) or the load reaches ``--stop``. Before
the peak the loading is monotone at every history point, so converged steps of any size reach
the same states; the fine steps sample the flat top of the curve (``--crack-advance``: finer
dissipation steps too, where path following switches to them). ``--scheme monolithic`` uses
fixed-load steps only (at the paper's resolution they stall at 0.0903 mm: the squeezed-void
mode of ``ngtmc.coupled.monolithic.FLOOR_RTOL``, which path following accepts at its residual floor).
Prints and writes a JSON record with the peak (N/mm), its load (mm), steps, Newton iterations
and wall time.

    python -m benchmarks.peak_reference --resolution paper --fine-from 0.088 --du-fine 5e-5

Timings depend on the machine and on what else runs on it; never pass/fail tests.
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import ngsolve as ngs

import ngtmc
from ngtmc.simulation import StepFailure
from ngtmc.study import load_study
from ngtmc.study import study_parameters


def reference_peak(resolution: str, fine_from: float, du_fine: float, du_coarse: float = 2e-3, stop: float = 0.0946,
                   du_min: float = 1e-6, threads: int = 1, overrides: dict | None = None,
                   scheme: str = "path-following", drop: float = 0.9, crack_advance: float | None = None) -> dict:
    """Run the reference (module docstring) and return its record: loads in mm, forces in N/mm."""
    ngs.SetNumThreads(threads)
    mod = load_study("three_point_bending")
    _, p = study_parameters(mod, resolution, overrides or {})
    scene = mod.cases(p)[0].build_scene()
    t0 = time.perf_counter()
    rows, status = [], "completed"
    with ngs.TaskManager():
        first = ngtmc.Simulation(scene, ngtmc.Schedule.monotonic(fine_from),
                                 ngtmc.AdaptiveStepControl(du_max=du_coarse, k_u=0.0, du_min=du_min), scheme=scheme)
        first.run()
        state = first.get_state()
        fine = {"coupled": {"crack_advance": crack_advance}} if crack_advance and scheme == "path-following" else {}
        second = ngtmc.Simulation(scene, ngtmc.Schedule.monotonic(stop),
                                  ngtmc.AdaptiveStepControl(du_max=du_fine, k_u=0.0, du_min=du_min), scheme=scheme,
                                  **fine)
        second.set_state(state)
        second.control_state = type(second.control_state)()  # full fine steps from here
        top = 0.0
        try:
            for row in second.steps():
                top = max(top, float(row["force"]))
                if float(row["force"]) < drop * top:
                    status = f"stopped after the drop (force below {drop:g} of its maximum)"
                    break
        except StepFailure as e:  # the crack runs: no equilibrium near the last one at fixed load
            status = f"stopped: {e}"
        rows = second.rows
    wall = time.perf_counter() - t0
    force = [float(r["force"]) for r in rows]
    i = max(range(len(force)), key=force.__getitem__)
    return {"resolution": resolution, "scheme": scheme, "crack_advance_mm": crack_advance, "fine_from_mm": fine_from, "du_fine_mm": du_fine, "du_coarse_mm": du_coarse,
            "peak_force_N_per_mm": force[i], "peak_load_mm": float(rows[i]["load"]), "steps": len(rows),
            "newton_iterations": int(sum(int(r.get("newton_iterations", 0)) for r in rows)),
            "last_load_mm": float(rows[-1]["load"]), "status": status, "wall_time_s": wall, "threads": threads,
            "ndof": first.solver.ndof, "cpu_count": os.cpu_count(), "load_average": os.getloadavg()[0]}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m benchmarks.peak_reference", description=__doc__.split("\n")[0])
    ap.add_argument("--resolution", default="paper")
    ap.add_argument("--fine-from", type=float, default=0.088, help="load (mm) from which the steps are fine")
    ap.add_argument("--du-fine", type=float, default=5e-5, help="fine step (mm)")
    ap.add_argument("--du-coarse", type=float, default=2e-3, help="step before --fine-from (mm)")
    ap.add_argument("--stop", type=float, default=0.0946, help="last load (mm)")
    ap.add_argument("--scheme", default="path-following", help="path-following (default) or monolithic")
    ap.add_argument("--drop", type=float, default=0.9, help="stop when the force falls below this fraction of its maximum")
    ap.add_argument("--crack-advance", type=float, default=None,
                    help="path following: crack advance per dissipation step from --fine-from (mm; default l0)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", default="benchmarks/results")
    args = ap.parse_args(argv)
    rec = reference_peak(args.resolution, args.fine_from, args.du_fine, args.du_coarse, args.stop, threads=args.threads,
                         scheme=args.scheme, drop=args.drop, crack_advance=args.crack_advance)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    path = Path(args.out) / f"three_point_bending-{args.resolution}-{stamp}-peak-reference.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(rec, indent=1))
    print(json.dumps(rec, indent=1))
    print(f"written {path}")


if __name__ == "__main__":
    main()
