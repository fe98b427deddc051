"""The linear solves of one coupled (u, alpha) Newton iteration of a named study's scene, side by
side for the coupled linear solvers (``ngtmc.coupled.linear.LINEAR_SOLVERS``, and a preconditioner
tried and not kept, ``symmetric-part``): factorization of
the assembled tangent, and the two solves of the bordered system of path following (the Newton
correction and the response to a unit load change). Best of 3, ms; GMRES iterations per solve.

The state is made, not run to: the displacement solve at ``--load`` (mm) with alpha = 0, then a
straight smeared crack alpha = exp(-d / l0) (d the distance to the segment ``--crack`` x0,y0,x1,y1,
mm) and the history H = Psi_plus of that displacement, so that the coupling blocks are those of a
cracked state. The tangent's size and sparsity are those of the run; its conditioning is that of
this state, not of a particular step of a run.

    python -m benchmarks.coupled_linear --study l_panel --resolution quick --load 6.2 \\
        --crack 250,250,200,255

Timings depend on the machine and on what else runs on it; they are never pass/fail tests.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
import ngsolve as ngs

import ngtmc
from ngtmc.coupled import LINEAR_SOLVERS
from ngtmc.study import load_study
from ngtmc.study import simulation_options, study_parameters


def best(f, n=3):
    """(smallest wall time of n calls of f in s, the last call's result)."""
    t, out = [], None
    for _ in range(n):
        t0 = time.perf_counter()
        out = f()
        t.append(time.perf_counter() - t0)
    return min(t), out


def cracked_state(sim, load: float, crack: tuple[float, float, float, float]):
    """Set the solver of ``sim`` to the made state of the module docstring."""
    s = sim.solver
    res = s.solve_displacement(load)
    if not res.converged:
        raise RuntimeError(f"the displacement solve at {load} mm did not converge: {res.message}")
    x0, y0, x1, y1 = crack
    px, py = ngs.x - x0, ngs.y - y0
    dx, dy = x1 - x0, y1 - y0
    t = ngs.IfPos(px * dx + py * dy, ngs.IfPos(px * dx + py * dy - (dx * dx + dy * dy), 1.0,
                                               (px * dx + py * dy) / (dx * dx + dy * dy)), 0.0)
    d = ngs.sqrt((px - t * dx) ** 2 + (py - t * dy) ** 2)
    s.alpha.Set(ngs.exp(-d / s.l0))
    s.H_committed[:] = s.psi_plus_values()
    s.H.vec.FV().NumPy()[:] = s.H_committed


def measure(sim, solver_name: str, threads: int) -> dict:
    """ms of the factorization and of each of the two solves, and GMRES iterations per solve."""
    c = sim.coupled
    c.linear_solver = solver_name
    c._mesh_data()  # a fresh CoupledLinearSolver for this linear solver
    s = sim.solver
    c._gather()
    out = {}
    with ngs.TaskManager(pajetrace=0) if threads > 1 else _nothing():
        c.form.AssembleLinearization(c.x.vec)
        free = c._free_base.copy()
        free[:c.nu] &= ~s._dir_np
        c.lin.factorize(free)  # the first factorization (symbolic steps) is not timed
        out["factorization"], solve = best(lambda: c.lin.factorize(free))
        rhs = c.x.vec.CreateVector()
        rng = np.random.default_rng(1)
        rhs.FV().NumPy()[:] = rng.standard_normal(rhs.size)
        res = rhs.CreateVector()
        n0 = len(c.lin.gmres_iterations)
        out["one solve"], _ = best(lambda: solve(rhs, res))
        its = c.lin.gmres_iterations[n0:]
        out["GMRES its"] = float(np.mean(its)) if its else float("nan")
        resid = rhs.CreateVector()
        resid.data = c.form.mat * res
        rN, bN = resid.FV().NumPy(), rhs.FV().NumPy()
        out["rel. residual"] = float(np.linalg.norm((rN - bN)[free]) / np.linalg.norm(bN[free]))
    return out


def measure_symmetric_part(sim) -> dict:
    """The same for a preconditioner tried and not kept: one sparse Cholesky factorization of the
    symmetric part (A + A^T) / 2 of the whole coupled tangent, in GMRES on the tangent."""
    from ngsolve.krylovspace import GMResSolver
    from ngtmc.coupled.linear import Masked, SquareOperator
    c, s = sim.coupled, sim.solver
    c._gather()
    c.form.AssembleLinearization(c.x.vec)
    A = c.form.mat
    free = c._free_base.copy()
    free[:c.nu] &= ~s._dir_np
    vals, cols, rowptr = A.CSR()
    vals = np.asarray(vals)
    cols = np.asarray(cols).astype(np.int64)
    rowptr = np.asarray(rowptr).astype(np.int64)
    rows = np.repeat(np.arange(rowptr.size - 1), np.diff(rowptr))
    n = A.height
    key, tkey = rows * n + cols, cols * n + rows
    order = np.argsort(key)
    transposed = order[np.searchsorted(key[order], tkey)]
    M = A.CreateMatrix()
    M.AsVector().FV().NumPy()[:] = 0.5 * (vals + vals[transposed])
    inv = M.Inverse(ngs.BitArray(free.tolist()), inverse="sparsecholesky")
    out = {"factorization": best(inv.Update)[0]}

    class Pre(SquareOperator):
        def Mult(self, x, y):
            y.data = inv * x
            y.FV().NumPy()[~free] = x.FV().NumPy()[~free]

    op, pre = Masked(A, free), Pre(A)
    rhs = c.x.vec.CreateVector()
    rhs.FV().NumPy()[:] = np.random.default_rng(1).standard_normal(rhs.size)
    rhs.FV().NumPy()[~free] = 0.0
    its = []

    def solve():
        gm = GMResSolver(mat=op, pre=pre, tol=1e-8, atol=1e-300, maxiter=100, printrates=False)
        sol = gm.Solve(rhs=rhs)
        its.append(gm.iterations)
        return sol
    out["one solve"], sol = best(solve)
    out["GMRES its"] = float(np.mean(its))
    resid = rhs.CreateVector()
    resid.data = A * sol
    rN, bN = resid.FV().NumPy(), rhs.FV().NumPy()
    out["rel. residual"] = float(np.linalg.norm((rN - bN)[free]) / np.linalg.norm(bN[free]))
    return out


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *a):
        return False


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--study", default="l_panel")
    ap.add_argument("--resolution", default="quick")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--load", type=float, required=True, help="imposed displacement of the state, mm")
    ap.add_argument("--crack", required=True, help="x0,y0,x1,y1 of the straight crack, mm")
    ap.add_argument("--solvers", nargs="+", default=list(LINEAR_SOLVERS) + ["symmetric-part"],
                    help="linear solvers of the coupled tangent, and 'symmetric-part' (a preconditioner "
                         "tried and not kept, measure_symmetric_part)")
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args(argv)
    mod = load_study(a.study)
    _, p = study_parameters(mod, a.resolution, dict(kv.split("=", 1) for kv in a.set))
    case = mod.cases(p)[0]
    t0 = time.perf_counter()
    opts = {**simulation_options(p), **case.options, "scheme": "path-following"}
    sim = ngtmc.Simulation(case.build_scene(), case.schedule, case.control, **opts)
    print(f"{a.study} {a.resolution}: {sim.solver.ndof['u']} u dofs, {sim.solver.ndof['alpha']} alpha dofs, "
          f"set-up {time.perf_counter() - t0:.1f} s", flush=True)
    cracked_state(sim, a.load, tuple(float(v) for v in a.crack.split(",")))
    print(f"{'linear solver':14s} {'factorization ms':>17s} {'one solve ms':>13s} {'GMRES its':>10s} "
          f"{'rel. residual':>14s}")
    for name in a.solvers:
        try:
            m = measure_symmetric_part(sim) if name == "symmetric-part" else measure(sim, name, a.threads)
        except Exception as e:  # a solver that NGSolve does not have here (pardiso without MKL)
            print(f"{name:14s} not available: {type(e).__name__}: {e}")
            continue
        print(f"{name:14s} {1e3 * m['factorization']:17.1f} {1e3 * m['one solve']:13.1f} {m['GMRES its']:10.1f} "
              f"{m['rel. residual']:14.2e}", flush=True)


if __name__ == "__main__":
    main()
