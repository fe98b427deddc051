"""One scene on MPI ranks against the same scene in one process, and how iterative solvers cope
with the third medium, in one command.

    python -m benchmarks.mpi                 # serial, 2 and 3 ranks, and the solver probe
    python -m benchmarks.mpi --ranks 3 --no-solvers

The scene is ``benchmarks/mpi_scene.py`` (a punch through a void gap onto a block that cracks;
24 steps of the single-pass scheme). Part 1 runs it in this process and under ``mpiexec -n N
python -m mpi4py`` for each N of ``--ranks`` (NGSolve gives rank 0 no elements: N ranks compute on
N - 1; the Newton systems are gathered and factorized on rank 0), and prints wall time, steps,
Newton iterations, the largest difference of the force history from the serial one, and each
rank's time split. Part 2 (``--solvers``) takes the tangent of the displacement problem at four
states of the serial run and solves it with a random right-hand side (tolerance 1e-8) by CG and
GMRES, preconditioned by NGSolve's BDDC and by Jacobi, next to the direct factorization; and the
unloaded tangent at three void stiffnesses gamma0. Writes ``<out>/mpi-<UTC time>.json`` and
``.md``. Needs ``pip install ngtmc[mpi]``. Units: s, N (per mm of thickness), mm.
"""
from __future__ import annotations

import argparse
import dataclasses
import datetime as _dt
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from .run import ROOT, machine_info
from . import mpi_scene


def _launcher() -> str:
    for name in ("mpiexec", "mpirun"):
        exe = Path(sys.executable).parent / name
        if exe.exists():
            return str(exe)
        if shutil.which(name):
            return shutil.which(name)
    sys.exit("no mpiexec or mpirun found: pip install ngtmc[mpi]")


def ranks_table(ranks: list[int]) -> tuple[list[dict], str]:
    """Part 1: the serial run and one run per number of ranks."""
    import ngtmc
    warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
    t0 = time.perf_counter()
    sim = mpi_scene.run(mpi_scene.scene())
    serial = {"ranks": 1, "wall_time_s": time.perf_counter() - t0, "history": sim.history.to_dict(orient="list"),
              "timings": [dict(sim.solver.timings)]}
    rows = [serial]
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    for n in ranks:
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "h.json"
            t0 = time.perf_counter()
            proc = subprocess.run([_launcher(), "-n", str(n), sys.executable, "-m", "mpi4py",
                                   str(ROOT / "benchmarks" / "mpi_scene.py"), str(out)],
                                  capture_output=True, text=True, env=env)
            total = time.perf_counter() - t0
            if proc.returncode != 0:
                sys.exit(f"mpiexec -n {n} failed:\n{proc.stderr[-2000:]}")
            rec = json.loads(out.read_text())
        rows.append({"ranks": n, "wall_time_s": rec["wall_time_s"], "launch_total_s": total, "history": rec["history"],
                     "timings": [r["timings_s"] for r in rec["ranks_local"]],
                     "elements": [r["elements"] for r in rec["ranks_local"]]})
    f_ref = np.asarray(serial["history"]["force"])
    lines = ["| ranks | elements per rank | wall s (the run) | steps | Newton its | cut-backs | max force difference from serial (N) | "
             "per rank: assembly + residual / factorization + solve / line search s |", "|---:|:---|---:|---:|---:|---:|---:|:---|"]
    for r in rows:
        h = r["history"]
        f = np.asarray(h["force"])
        diff = float(np.max(np.abs(f - f_ref))) if f.shape == f_ref.shape else float("nan")
        split = "; ".join(f"{t['assembly'] + t['residual']:.2f} / {t['factorization'] + t['solve']:.2f} / {t['line_search']:.2f}"
                          for t in r["timings"])
        els = "/".join(map(str, r.get("elements", ["all"])))
        lines.append(f"| {r['ranks']} | {els} | {r['wall_time_s']:.2f} | {len(h['step']) - 1} | {sum(h['newton_iterations'])} | "
                     f"{sum(h['cutbacks'])} | {diff:.1e} | {split} |")
    return rows, "\n".join(lines)


def _tangent(solver):
    """The displacement tangent as one plain NGSolve form, with a BDDC preconditioner registered."""
    import ngsolve as ngs
    from ngtmc.discrete import merged_terms
    trial = solver.fes_u.TrialFunction()
    a = ngs.BilinearForm(solver.fes_u, symmetric=True)
    for name, density, regions in merged_terms(solver.energy_terms(trial)):
        a += ngs.Variation(density * solver.energy_measure(name, regions))
    pre = ngs.Preconditioner(a, "bddc")
    a.AssembleLinearization(solver.u.vec)
    return a, pre


def probe(solver, label: str) -> dict:
    """Iterations and relative error (against the direct solve) of CG and GMRES with BDDC and
    Jacobi on the displacement tangent at the solver's state, random right-hand side."""
    from ngsolve.krylovspace import CGSolver, GMResSolver
    a, pre = _tangent(solver)
    rhs = solver.u.vec.CreateVector()
    rhs.FV().NumPy()[:] = np.where(solver._free_np, np.random.default_rng(0).standard_normal(len(rhs)), 0.0)
    t0 = time.perf_counter()
    direct = a.mat.Inverse(solver.free, inverse="sparsecholesky")
    xd = rhs.CreateVector()
    xd.data = direct * rhs
    out = {"state": label, "min_J": solver.min_J(), "ndof": solver.fes_u.ndof, "direct_s": time.perf_counter() - t0}
    x = rhs.CreateVector()
    for kind, P in (("BDDC", pre.mat), ("Jacobi", a.mat.CreateSmoother(solver.free))):
        for name, cls in (("CG", CGSolver), ("GMRES", GMResSolver)):
            sol = cls(a.mat, P, tol=1e-8, maxiter=3000, printrates=False)
            t0 = time.perf_counter()
            x.data = sol * rhs
            out[f"{kind} {name}"] = (sol.iterations, float((x - xd).Norm() / xd.Norm()), time.perf_counter() - t0)
    return out


def solvers_table() -> tuple[list[dict], str]:
    """Part 2: iterative solvers on the tangent along the serial run and at three gamma0."""
    import ngtmc
    warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
    sim = ngtmc.Simulation(mpi_scene.scene(), mpi_scene.LOAD, ngtmc.AdaptiveStepControl(du_max=0.004, du_min=1e-7))
    rows = [probe(sim.solver, "unloaded")]
    marks = [0.04, 0.052, 0.0551]
    for row in sim.steps():
        if marks and row["load"] >= marks[0] - 1e-12:
            marks.pop(0)
            rows.append(probe(sim.solver, f"{row['load']:.5f} mm, max alpha {row['max_alpha']:.2f}"))
        if not marks or row["step"] >= mpi_scene.STEPS:
            break
    for g0 in (0.999, 1e-2, 1e-5):
        rows.append(probe(ngtmc.Solver(dataclasses.replace(mpi_scene.scene(), gamma0=g0)), f"unloaded, gamma0 = {g0:g}"))
    keys = ["BDDC CG", "BDDC GMRES", "Jacobi CG", "Jacobi GMRES"]
    lines = ["| state | min J | u dofs | direct (factorization + solve) s | " + " | ".join(f"{k}: its (error)" for k in keys) + " |",
             "|:---|---:|---:|---:|" + "---:|" * len(keys)]
    for r in rows:
        lines.append(f"| {r['state']} | {r['min_J']:.3g} | {r['ndof']} | {r['direct_s']:.3f} | "
                     + " | ".join(f"{r[k][0]} ({r[k][1]:.0e})" for k in keys) + " |")
    return rows, "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.mpi", description=__doc__.splitlines()[0])
    ap.add_argument("--ranks", type=int, nargs="+", default=[2, 3], help="numbers of MPI ranks (default 2 3)")
    ap.add_argument("--no-solvers", action="store_true", help="skip part 2 (iterative solvers)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"), help="folder of the record")
    args = ap.parse_args(argv)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    record = {"command": "python -m benchmarks.mpi " + " ".join(argv if argv is not None else sys.argv[1:]),
              "machine": machine_info(), "utc": stamp}
    runs, t1 = ranks_table(args.ranks)
    record["runs"] = runs
    text = "## One scene on MPI ranks\n\n" + t1 + "\n"
    print(text, flush=True)
    if not args.no_solvers:
        probes, t2 = solvers_table()
        record["solvers"] = probes
        part2 = "\n## Iterative solvers on the displacement tangent (serial)\n\n" + t2 + "\n"
        print(part2, flush=True)
        text += part2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"mpi-{stamp}.json").write_text(json.dumps(record, indent=1, default=float))
    (out / f"mpi-{stamp}.md").write_text(f"`{record['command']}`, {stamp}\n\n" + text)
    print(f"record: {out / f'mpi-{stamp}.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
