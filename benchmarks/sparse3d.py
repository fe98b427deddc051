"""Sparse direct solvers on 3D tangents: NGSolve's sparsecholesky against UMFPACK and MKL Pardiso.

Run:  python -m benchmarks.sparse3d [--resolutions quick medium] [--threads 1] [--python PATH]
                                   [--symmetry half|quarter] [--matrices u coupled]

The matrices are those of the 3D study's hemisphere case (``studies/three_point_bending_3d.py``):
the displacement tangent (symmetric; order 2 in the void, 1 elsewhere) and the coupled (u, alpha)
tangent (non-symmetric) of its first loaded state, of the half model (the default here, as in the
first recorded table) or the quarter model (``--symmetry quarter``, the study's default). Each
factorization is timed fresh (symbolic and numeric) and, where the solver has one, by
``Update()`` after a change of the matrix's values, which is what a Newton iteration costs (the
values are scaled by 1.001 between the updates). Each (resolution, solver) pair runs in its own
process, so its peak resident memory is its own. Pardiso needs the ``mkl`` package in the
interpreter that runs the benchmark: ``--python`` names another interpreter (for example a venv
with ``pip install mkl``; NGSolve then also makes Pardiso its *default* inverse, silently, which
is why ngtmc always passes ``inverse=``). Times are best of 3 on a shared machine: compare the
ratios of one run. Writes ``benchmarks/results/sparse3d-<UTC>.json`` and ``.md``.
Units: s, MB.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

SOLVERS = {"u": ("sparsecholesky", "umfpack", "pardiso"), "coupled": ("umfpack", "pardiso")}


def measure(resolution: str, matrix: str, solver: str, threads: int, symmetry: str = "half") -> dict:
    """Factorize and solve one matrix of the hemisphere case; returns times (s), sizes and the
    process's peak memory (MB)."""
    import numpy as np
    import ngsolve as ngs

    import ngtmc
    from ngtmc.coupled import CoupledNewton
    from ngtmc.runner.cases import peak_memory_mb
    from ngtmc.study import load_study
    from ngtmc.study import study_parameters

    ngs.SetNumThreads(threads)
    mod = load_study("three_point_bending_3d")
    # the half model by default, as in the first recorded table (docs/three-d.md); the study's is the quarter
    _, p = study_parameters(mod, resolution, {"parts": "hemisphere", "sphere_symmetry": symmetry})
    scene = mod.build_hemisphere_scene(p)
    s = ngtmc.Solver(scene)
    rss0 = peak_memory_mb()
    if matrix == "u":
        s.solve_displacement(float(p["sphere_gap"]) * 1.2)   # past contact: a squeezed void
        s.a_u.AssembleLinearization(s.u.vec)
        A, free = s.a_u.mat, s.free
    else:
        c = CoupledNewton(s)
        c.solve(float(p["sphere_gap"]) * 1.2)
        c.form.AssembleLinearization(c.x.vec)
        A, free = c.form.mat, ngs.BitArray(c._free_base.tolist())
    rhs = A.CreateColVector()
    rhs.FV().NumPy()[:] = np.random.default_rng(0).standard_normal(A.height)
    out = A.CreateColVector()
    t_fact, t_solve = float("inf"), float("inf")
    with ngs.TaskManager():
        for _ in range(3):
            t0 = time.perf_counter()
            inv = A.Inverse(free, inverse=solver)
            t_fact = min(t_fact, time.perf_counter() - t0)
            t0 = time.perf_counter()
            out.data = inv * rhs
            t_solve = min(t_solve, time.perf_counter() - t0)
        t_update = float("inf")
        vals = A.AsVector()
        for _ in range(3):
            vals.data *= 1.001            # new values, the same pattern: a Newton iteration's refactorization
            t0 = time.perf_counter()
            try:
                inv.Update()
            except Exception:             # the solver has no Update
                t_update = None
                break
            t_update = min(t_update, time.perf_counter() - t0)
        out.data = inv * rhs
    res = A.CreateColVector()
    res.data = A * out - rhs
    fr = np.array(list(free), dtype=bool)
    rel = float(np.linalg.norm(res.FV().NumPy()[fr]) / np.linalg.norm(rhs.FV().NumPy()[fr]))
    return {"resolution": resolution, "matrix": matrix, "solver": solver, "threads": threads,
            "elements": scene.mesh.ne, "n": int(A.height), "free": int(fr.sum()), "nnz": int(A.nze),
            "factorize_s": t_fact, "update_s": t_update, "solve_s": t_solve, "residual": rel, "symmetry": symmetry,
            "memory_before_mb": rss0, "peak_memory_mb": peak_memory_mb()}


def _s(x) -> str:
    return "-" if x is None else f"{x:.3f}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolutions", nargs="+", default=["quick", "medium"])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--python", default=sys.executable, help="interpreter for the runs (one with mkl for pardiso)")
    ap.add_argument("--symmetry", choices=("half", "quarter"), default="half", help="hemisphere model (default half)")
    ap.add_argument("--matrices", nargs="+", choices=tuple(SOLVERS), default=list(SOLVERS), help="matrices to factorize")
    ap.add_argument("--one", nargs=3, metavar=("RESOLUTION", "MATRIX", "SOLVER"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.one:
        print(json.dumps(measure(*a.one, a.threads, a.symmetry)))
        return 0
    rows = []
    for r in a.resolutions:
        for matrix in a.matrices:
            for solver in SOLVERS[matrix]:
                cmd = [a.python, "-m", "benchmarks.sparse3d", "--threads", str(a.threads), "--symmetry", a.symmetry,
                       "--one", r, matrix, solver]
                proc = subprocess.run(cmd, capture_output=True, text=True, cwd=Path(__file__).resolve().parents[1])
                line = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else ""
                try:
                    row = json.loads(line)
                except json.JSONDecodeError:
                    row = {"resolution": r, "matrix": matrix, "solver": solver,
                           "error": (proc.stderr.strip().splitlines() or ["?"])[-1][:160]}
                rows.append(row)
                print(json.dumps(row), flush=True)
    head = ("| resolution | matrix | solver | n | nnz | factorize s | update s | solve s | residual | peak MB |\n"
            "|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    lines = [head]
    for row in rows:
        if "error" in row:
            lines.append(f"| {row['resolution']} | {row['matrix']} | {row['solver']} | failed: {row['error']} ||||||")
        else:
            lines.append(f"| {row['resolution']} | {row['matrix']} | {row['solver']} | {row['n']} | {row['nnz']} | "
                         f"{row['factorize_s']:.3f} | {_s(row.get('update_s'))} | {row['solve_s']:.4f} | {row['residual']:.1e} | "
                         f"{row['peak_memory_mb']:.0f} |")
    table = f"`python -m benchmarks.sparse3d {' '.join(argv if argv is not None else sys.argv[1:])}`\n\n" + "\n".join(lines)
    print(table)
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    outdir = Path(__file__).resolve().parent / "results"
    outdir.mkdir(exist_ok=True)
    (outdir / f"sparse3d-{stamp}.json").write_text(json.dumps(rows, indent=1))
    (outdir / f"sparse3d-{stamp}.md").write_text(table + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
