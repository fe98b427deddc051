"""Benchmark of the per-iteration costs of the solver: assembly, factorization, residual, energy,
phase-field solve and history update, for a contact-and-fracture scene at several mesh sizes and
for the compile modes of the energy expressions.

Run:  python benchmarks/bench_solver.py [--sizes 0.1 0.05 0.025] [--real] [--threads 2]
Prints a table and writes reports/benchmarks/solver.csv. Timings depend on the machine and on
what else runs on it: they are never used in pass/fail tests.
"""
from __future__ import annotations

import argparse
import pathlib
import platform
import time

import numpy as np
import ngsolve as ngs
import pandas as pd
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, X, Y

import ngtmc


def scene(h):
    """Notched beam 2 x 0.4 under a pusher through a 0.05 mm void (the README scene), mesh size h (mm)."""
    beam = Rectangle(2.0, 0.4).Face() - MoveTo(0.99, 0.0).Rectangle(0.02, 0.1).Face()
    band = MoveTo(0.9, 0.0).Rectangle(0.2, 0.3).Face()
    lig, beam = beam * band, beam - band
    lig.faces.name, beam.faces.name = "ligament", "beam"
    void = MoveTo(0.0, 0.4).Rectangle(2.0, 0.05).Face()
    void.faces.name = "void"
    pusher = MoveTo(0.85, 0.45).Rectangle(0.3, 0.15).Face()
    pusher.faces.name = "pusher"
    shape = Glue([beam, lig, void, pusher])
    shape.edges.Max(Y).name = "top"
    shape.edges.Min(X).name = "left"
    shape.edges.Max(X).name = "right"
    mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=h))
    return ngtmc.Scene(mesh, {".*": ngtmc.Material(20.8e3, 0.3, 0.54, 0.04)}, density={"void": 0.0},
                       supports=[ngtmc.Support("left", x=True, y=True), ngtmc.Support("right", y=True)],
                       load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True), fracture_regions="ligament",
                       regulariser=ngtmc.Regulariser("void", length=2.0), gamma0=1e-4)


def timed(f, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def bench(h, compile_mode):
    import warnings
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    s = ngtmc.Solver(scene(h), compile=compile_mode)
    setup = time.perf_counter() - t0
    s.solve_phase_field()
    s.solve_displacement(0.03)
    u = s.u.vec
    r = u.CreateVector()
    row = {"h_mm": h, "compile": str(compile_mode), "elements": s.mesh.ne, "ndof_u": s.fes_u.ndof,
           "ndof_alpha": s.ndof["alpha"], "setup_s": setup}
    row["assemble_s"] = timed(lambda: s.a_u.AssembleLinearization(u))
    s.a_u.AssembleLinearization(u)
    row["factorize_fresh_s"] = timed(lambda: s.a_u.mat.Inverse(s.free, inverse="sparsecholesky"), 1)
    inv = s.a_u.mat.Inverse(s.free, inverse="sparsecholesky")
    row["factorize_update_s"] = timed(inv.Update)
    row["solve_s"] = timed(lambda: (inv * u).Evaluate())
    row["residual_s"] = timed(lambda: s.a_u.Apply(u, r))
    row["energy_s"] = timed(lambda: s.a_u.Energy(u))
    row["min_J_s"] = timed(s.min_J)
    row["alpha_solve_s"] = timed(s.solve_phase_field)
    row["history_update_s"] = timed(s.trial_history)
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.1, 0.05, 0.025])
    ap.add_argument("--real", action="store_true", help="also time compile='real' (C++ code generation)")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    ngs.SetNumThreads(args.threads)
    rows = []
    with ngs.TaskManager():
        for h in args.sizes:
            for mode in ([True, "real"] if args.real else [True]):
                rows.append(bench(h, mode))
                print({k: (round(v, 4) if isinstance(v, float) else v) for k, v in rows[-1].items()}, flush=True)
    df = pd.DataFrame(rows)
    out = pathlib.Path("reports/benchmarks")
    out.mkdir(parents=True, exist_ok=True)
    df.assign(machine=platform.processor() or platform.machine(), threads=args.threads).to_csv(out / "solver.csv", index=False)
    print(df.to_string(index=False))
    print(f"written {out / 'solver.csv'}")


if __name__ == "__main__":
    main()
