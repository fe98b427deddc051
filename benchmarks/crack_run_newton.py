"""Changes to the path-following Newton's start and line search, tried on a study as a user runs
it: each variant patches one piece of the solver in its own process, then ``ngtmc run``; the
table gives steps, Newton iterations, cut-backs, the most in one step, the peak and the force at
the end. The variants are prototypes kept here as the evidence that they do not pay; none is an
option of the package.

    python -m benchmarks.crack_run_newton --study three-point-bending --resolution quick
    python -m benchmarks.crack_run_newton --variants base local-halve
    python -m benchmarks.crack_run_newton --study three-point-bending-3d --set parts=hemisphere --variants base chord

Variants (``base``: the package as it is):

* ``alpha-none``, ``alpha-half``, ``alpha-1.5``: the secant predictor's alpha extrapolated by 0,
  1/2 and 3/2 of the u fraction (:mod:`ngtmc.stepping.predictor`), not by the same fraction;
* ``alpha-quadratic``: alpha extrapolated through the last three accepted states, parametrised
  by their dissipation (Lagrange), u by the secant;
* ``u-relaxed``: after the predictor, u solved at the predicted alpha and load (the displacement
  Newton; its iterations are not in the history's count, they are reported apart);
* ``first-fixed-load``: the first direction of each dissipation solve at the predictor's load
  (the constraint left out of that one direction);
* ``local-halve``, ``local-freeze``: in the coupled line search, where a trial inverts elements
  (J <= 0), the u step on those elements' dofs is halved (up to 8 times), or set to zero (up to 4
  times), before the whole step is;
* ``active-set``: alpha dofs whose linear step crosses a bound are held on it and the direction
  solved again (up to twice per direction);
* ``rtol-1e-5``, ``rtol-1e-4``: the coupled Newton's relative tolerance (``COUPLED_RTOL``, 1e-6);
* ``chord``: rule 3's re-solve at a smaller dD from the chord to the long step's converged state
  (``coupled={"chord": True}`` on every case), not from the secant predictor; ``no-chord``: from
  the secant predictor on every case (``chord`` False), whatever the study sets.

Record: ``<study>-<resolution>-<UTC time>-crack-run-newton.json`` / ``.md`` in ``--out``.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .run import machine_info
from .study_process import RESULTS, git_state, git_text, run_study, stamp, summary_of, write_record

VARIANTS = ("base", "alpha-none", "alpha-half", "alpha-1.5", "alpha-quadratic", "u-relaxed", "first-fixed-load",
            "local-halve", "local-freeze", "active-set", "rtol-1e-5", "rtol-1e-4", "chord", "no-chord")

#: where a child process writes the counts its patch keeps (displacement relaxations, re-solves)
_COUNTS_ENV = "NGTMC_BENCH_COUNTS"


# ---------------------------------------------------------------------------- the patches
def _patch_alpha_fraction(scale: float):
    from ngtmc.stepping import predictor as P
    from ngtmc.stepping.secant import secant_displacement

    def set_(self, ratio, load=None):
        if self.x_prev is None:
            return None
        s = self.sim.solver
        u_n, a_n = self.x_n
        u_p, a_p = self.x_prev
        if load is None:
            load = self.load_n + ratio * (self.load_n - self.load_prev)
        f = secant_displacement(s, u_n, u_p, ratio, load)
        if f is None:
            return None
        s.alpha.vec.FV().NumPy()[:] = np.clip(a_n + scale * f * (a_n - a_p), a_n, 1.0)
        return load
    P.SecantPredictor.set = set_


def _patch_alpha_quadratic(counts):
    from ngtmc.stepping import predictor as P
    accepted, set_secant = P.SecantPredictor.accepted, P.SecantPredictor.set

    def dissipation(self):
        path = getattr(self.sim, "_path", None)
        return path.coupled.D.value() if path is not None and path.coupled is not None else None

    def accepted_(self):
        self.x_prev2, self.t_prev2 = getattr(self, "x_prev", None), getattr(self, "t_prev", None)
        self.t_prev = getattr(self, "t_n", None)
        accepted(self)
        self.t_n = dissipation(self)

    def set_(self, ratio, load=None):
        out = set_secant(self, ratio, load)
        x2 = getattr(self, "x_prev2", None)
        t0, t1, t2 = getattr(self, "t_prev2", None), getattr(self, "t_prev", None), getattr(self, "t_n", None)
        if out is None or x2 is None or None in (t0, t1, t2) or not (t0 < t1 < t2) \
                or x2[1].shape != self.x_n[1].shape:
            return out
        t = t2 + ratio * (t2 - t1)
        w0 = (t - t1) * (t - t2) / ((t0 - t1) * (t0 - t2))
        w1 = (t - t0) * (t - t2) / ((t1 - t0) * (t1 - t2))
        w2 = (t - t0) * (t - t1) / ((t2 - t0) * (t2 - t1))
        a = w0 * x2[1] + w1 * self.x_prev[1] + w2 * self.x_n[1]
        self.sim.solver.alpha.vec.FV().NumPy()[:] = np.clip(a, self.x_n[1], 1.0)
        counts["quadratic_predictions"] = counts.get("quadratic_predictions", 0) + 1
        return out
    P.SecantPredictor.accepted, P.SecantPredictor.set = accepted_, set_


def _patch_u_relaxed(counts):
    from ngtmc.stepping import predictor as P
    set_secant = P.SecantPredictor.set

    def set_(self, ratio, load=None):
        out = set_secant(self, ratio, load)
        if out is not None:
            s = self.sim.solver
            keep = s.get_state()
            res = s.solve_displacement(out)
            counts["displacement_iterations"] = counts.get("displacement_iterations", 0) + res.iterations
            if not res.converged:
                s.set_state(keep)
        return out
    P.SecantPredictor.set = set_


def _patch_first_fixed_load():
    from ngtmc.coupled import iteration as I
    direction = I.Iteration.direction

    def direction_(self, lin, free, fixed_step, a_cur, g):
        first = not getattr(self, "_directions", 0)
        self._directions = getattr(self, "_directions", 0) + 1
        if self.path and first:
            self.path = False
            try:
                return direction(self, lin, free, fixed_step, a_cur, g)
            finally:
                self.path = True
        return direction(self, lin, free, fixed_step, a_cur, g)
    I.Iteration.direction = direction_


def _element_dofs(s):
    """The u dofs of each element (rows, -1 padded), cached on the solver per mesh."""
    import ngsolve as ngs
    cache = getattr(s, "_bench_element_dofs", None)
    if cache is not None and cache[0] is s.mesh:
        return cache[1]
    rows = [list(s.fes_u.GetDofNrs(ngs.ElementId(ngs.VOL, e))) for e in range(s.mesh.ne)]
    tab = np.full((len(rows), max(len(r) for r in rows)), -1, dtype=np.int64)
    for i, r in enumerate(rows):
        tab[i, :len(r)] = r
    s._bench_element_dofs = (s.mesh, tab)
    return tab


def _patch_local(factor: float, rounds: int, counts):
    from ngtmc.coupled import iteration as I

    def search(self, dxN, dlam, merit0, scale_u, lam0):
        s, n, nu, xN, tmp = self.s, self.n, self.nu, self.xN, self.tmp
        t0 = time.perf_counter()
        x0 = self.x0.FV().NumPy()
        step = 1.0
        try:
            for _ in range(s.newton.max_line_search):
                damp = None
                for k in range(rounds + 1):
                    xN[:] = x0 + step * dxN
                    if damp is not None:
                        xN[:nu] = x0[:nu] + step * damp * dxN[:nu]
                    lam_t = lam0 + step * dlam
                    if self.path:
                        xN[:nu][self.dir_u] = s.dirichlet_target(lam_t)[self.dir_u]
                    s.u.vec.FV().NumPy()[:] = xN[:nu]
                    J = s.J_values()
                    admissible = s.ranks.min(J) > 0.0
                    if admissible or k == rounds:
                        break
                    bad = J.reshape(s.mesh.ne, -1).min(axis=1) <= 0.0
                    dofs = _element_dofs(s)[bad].ravel()
                    damp = np.ones(nu) if damp is None else damp
                    damp[dofs[dofs >= 0]] *= factor
                if damp is not None:
                    key = "local_admissible" if admissible else "local_not_admissible"
                    counts[key] = counts.get(key, 0) + 1
                if admissible:
                    n.form.Apply(self.x, tmp)
                    if self.ranks.all_finite(tmp.FV().NumPy()):
                        if self.lifted:
                            return True, lam_t, step, math.nan
                        rmu, rma, _ = self.split(xN, tmp)
                        m = self.merit_of(rmu, rma, self.constraint(xN), scale_u)
                        if m <= (1.0 - 1e-4 * step) * merit0:
                            return True, lam_t, step, m
                step *= 0.5
            return False, lam0, 0.0, math.inf
        finally:
            s.timings["line_search"] += time.perf_counter() - t0
    I.Iteration.search = search


def _patch_active_set(rounds: int, counts):
    from ngtmc.coupled import iteration as I
    timed = I.Iteration.timed_direction

    def timed_(self, factorize, free, fixed_step, a_cur, g):
        d = timed(self, factorize, free, fixed_step, a_cur, g)
        nu = self.nu
        for _ in range(rounds):
            if d is None:
                return d
            trial = a_cur + d[0][nu:]
            fa = free[nu:]
            low, up = fa & (trial < self.a_low - 1e-12), fa & (trial > self.a_up + 1e-12)
            if not (low.any() or up.any()):
                break
            counts["re_solves"] = counts.get("re_solves", 0) + 1
            fa[low | up] = False
            fixed_step[nu:][low] = (self.a_low - a_cur)[low]
            fixed_step[nu:][up] = (self.a_up - a_cur)[up]
            d = timed(self, factorize, free, fixed_step, a_cur, g)
        return d
    I.Iteration.timed_direction = timed_


def _patch_rtol(value: float):
    import ngtmc.coupled.monolithic as M
    M.COUPLED_RTOL = value


def apply(variant: str, counts: dict):
    """Patch the solver for ``variant`` (``base``: nothing)."""
    if variant == "base":
        return
    if variant.startswith("alpha-") and variant != "alpha-quadratic":
        _patch_alpha_fraction({"alpha-none": 0.0, "alpha-half": 0.5, "alpha-1.5": 1.5}[variant])
    elif variant == "alpha-quadratic":
        _patch_alpha_quadratic(counts)
    elif variant == "u-relaxed":
        _patch_u_relaxed(counts)
    elif variant == "first-fixed-load":
        _patch_first_fixed_load()
    elif variant == "local-halve":
        _patch_local(0.5, 8, counts)
    elif variant == "local-freeze":
        _patch_local(0.0, 4, counts)
    elif variant == "active-set":
        _patch_active_set(2, counts)
    elif variant.startswith("rtol-"):
        _patch_rtol(float(variant[5:]))
    elif variant in ("chord", "no-chord"):
        from ngtmc.stepping import path
        init = path.DissipationPath.__init__

        def init_(self, *args, **kw):
            init(self, *args, **kw)
            self.chord = variant == "chord"
        path.DissipationPath.__init__ = init_
    else:
        raise ValueError(f"unknown variant {variant!r}; known: {', '.join(VARIANTS)}")


def child(variant: str, argv: list[str]) -> int:
    """In a fresh process: patch for ``variant``, then ``ngtmc`` with ``argv``; the patch's counts
    go to the file named by NGTMC_BENCH_COUNTS."""
    counts: dict = {}
    apply(variant, counts)
    from ngtmc.cli import main as ngtmc_main
    try:
        return ngtmc_main(argv)
    finally:
        path = os.environ.get(_COUNTS_ENV)
        if path:
            Path(path).write_text(json.dumps(counts))


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["--child"]:
        return child(argv[1], argv[2:])
    ap = argparse.ArgumentParser(prog="python -m benchmarks.crack_run_newton", description=__doc__.split("\n\n")[0])
    ap.add_argument("--study", default="three-point-bending")
    ap.add_argument("--resolution", "-r", default="quick")
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                    help="a study setting for every variant (repeatable)")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    cmd = "python -m benchmarks.crack_run_newton " + shlex.join(argv)
    when = stamp()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for v in args.variants:
            folder, counts_file = Path(tmp) / v, Path(tmp) / f"{v}-counts.json"
            print(f"[crack_run_newton] {v}", flush=True)
            out = run_study(args.study, args.resolution, folder, args.threads, sets=args.sets,
                            env={_COUNTS_ENV: str(counts_file)},
                            launcher=(sys.executable, "-m", "benchmarks.crack_run_newton", "--child", v))
            row = {"variant": v, **out, **summary_of(folder)}
            if (folder / "history.csv").exists():
                import pandas as pd
                h = pd.read_csv(folder / "history.csv")
                h = h[h["step"] > 0]
                row["max_step_newton"] = int(h["newton_iterations"].max())
                row["final_force"] = float(h["force"].iloc[-1])
            row["counts"] = json.loads(counts_file.read_text()) if counts_file.exists() else {}
            rows.append(row)
            print(f"[crack_run_newton] {v}: {row.get('steps')} steps, {row.get('newton_iterations')} Newton, "
                  f"peak {row.get('peak_force')}", flush=True)
    record = {"command": cmd, "study": args.study, "resolution": args.resolution, "threads": args.threads, "sets": args.sets,
              "time": when, "git": git_state(), "machine": machine_info(), "rows": rows}
    lines = [f"### Path-following Newton variants, {args.study}, {args.resolution} ({when})", "", f"`{cmd}`", "",
             f"{git_text(record)}, {args.threads} thread(s), one run at a time; each variant patches the "
             "solver in its own process (`benchmarks/crack_run_newton.py`). Forces in N/mm (2D) or N.", "",
             "| variant | steps | Newton | cut-backs | most in a step | peak | at mm | force at the end | wall s | counts |",
             "|:---|---:|---:|---:|---:|---:|---:|---:|---:|:---|"]
    for r in rows:
        if "steps" not in r:
            lines.append(f"| {r['variant']} | failed | | | | | | | | |")
            continue
        counts = ", ".join(f"{k} {v}" for k, v in r["counts"].items()) or "-"
        lines.append(f"| {r['variant']} | {r['steps']} | {r['newton_iterations']} | {r['cutbacks']} | "
                     f"{r['max_step_newton']} | {r['peak_force']:.5f} | {r['peak_load_mm']:.6f} | "
                     f"{r['final_force']:.5f} | {r['wall_time_s']:.1f} | {counts} |")
    write_record(args.out, f"{args.study.replace('-', '_')}-{args.resolution}-{when}-crack-run-newton", record, lines)
    return 0 if all(r["returncode"] == 0 for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
