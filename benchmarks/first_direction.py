"""The first Newton direction of path-following steps against the step's converged state: how far
the bordered direction x = a + dlambda b (a the correction at fixed load, b the response to a
unit load change) moves the load and the fields, and how many iterations the coupled Newton
needs from the secant predictor and from predictors made consistent with the phase field.

    python -m benchmarks.first_direction --study three_point_bending --resolution quick --start 42 --steps 5

The study's case runs to step ``--start``; each of the next ``--steps`` steps is taken as the
run takes it (its first converged dissipation solve is captured), then, from the captured
starting state: the full, half and quarter bordered step and the linearised family
x0 + a + mu b for mu from dlambda down to 0 (load error against the converged load, mm; the
merit of the coupled line search; the u error relative to the step's own u change; the largest
alpha error), and the coupled solve again from the secant predictor and from three variants
(``pf``: alpha solved at the predictor's u with its trial history; ``pfmax``: the larger of that
and the secant's alpha; ``pf+u``: ``pf`` then the displacement solved at that alpha). Record:
``<study>-<resolution>-<UTC time>-first-direction.json`` / ``.md`` in ``--out``.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

from ngtmc.coupled import monolithic as M
from ngtmc.coupled.iteration import Iteration
from ngtmc.simulation import Simulation
from ngtmc.study import load_study, study_parameters

from .run import machine_info
from .study_process import RESULTS, git_state, git_text, stamp, write_record


class _Probe(Iteration):
    """An Iteration that stops at its first line search, keeping the direction and the response
    b to a unit load change."""

    def direction(self, lin, free, fixed_step, a_cur, g):
        out = super().direction(lin, free, fixed_step, a_cur, g)
        n, s, nu = self.n, self.s, self.nu
        w, tmp = self.w, self.tmp
        wN = w.FV().NumPy()
        h = 1e-6 * max(abs(self.lam), 1e-3)
        dt_dl = (s.dirichlet_target(self.lam + h) - s.dirichlet_target(self.lam - h)) / (2 * h)
        wN[:] = 0.0
        wN[:nu] = np.where(self.dir_u, dt_dl, 0.0)
        unit = wN.copy()
        tmp.data = n.form.mat * w
        lin(tmp, w)
        self.bN = np.where(free, -w.FV().NumPy(), unit)
        return out

    def search(self, dxN, dlam, merit0, scale_u, lam0):
        self.found = (dxN.copy(), dlam, self.x0.FV().NumPy().copy(), lam0, merit0, scale_u)
        raise StopIteration


def _start(newton, c):
    st, u0, a0, _ = c["start"]
    s = newton.s
    s.set_state(st)
    s.u.vec.FV().NumPy()[:] = u0
    s.alpha.vec.FV().NumPy()[:] = a0


def probe(newton, c) -> list[dict]:
    """The bordered direction from the captured start, evaluated along its family."""
    _start(newton, c)
    s, nu = newton.s, newton.nu
    st, u0, a0, load = c["start"]
    it = _Probe(newton, load, None, c["dissipation"], c["bounds"])
    try:
        it.run()
    except StopIteration:
        pass
    dxN, dlam, x0, lam0, merit0, scale_u = it.found
    aN = dxN - dlam * it.bN
    rows = []
    trials = [("bordered x t", t, x0 + t * dxN, lam0 + t * dlam) for t in (1.0, 0.5, 0.25)]
    trials += [("a + mu b, mu/dlambda", f, x0 + aN + f * dlam * it.bN, lam0 + f * dlam)
               for f in (1.0, 0.5, 0.25, 1 / 16, 1 / 64, 0.0)]
    for kind, f, x, lam in trials:
        x = x.copy()
        x[:nu][it.dir_u] = s.dirichlet_target(lam)[it.dir_u]
        s.u.vec.FV().NumPy()[:] = x[:nu]
        J = s.min_J()
        newton.x.vec.FV().NumPy()[:] = x
        newton.form.Apply(newton.x.vec, it.tmp)
        ru, ra, _ = it.split(x, it.tmp)
        rows.append({"kind": kind, "factor": f, "load_error_mm": lam - c["lam"], "min_J": J,
                     "merit": it.merit_of(ru, ra, it.constraint(x), scale_u), "merit_start": merit0,
                     "u_error_rel": float(np.linalg.norm(x[:nu] - c["u"]) / np.linalg.norm(c["u"] - u0)),
                     "alpha_error_max": float(np.abs(x[nu:] - c["a"]).max())})
    return rows


def variant(newton, c, name, solve) -> dict:
    """The coupled solve again from the captured start, its alpha (and u) changed per ``name``."""
    _start(newton, c)
    s = newton.s
    a0 = c["start"][2]
    extra = 0
    if name != "secant":
        s.solve_phase_field(s.trial_history())
        if name == "pfmax":
            s.alpha.vec.FV().NumPy()[:] = np.maximum(s.alpha.vec.FV().NumPy(), a0)
        s.H.vec.FV().NumPy()[:] = s.H_committed
    if name == "pf+u":
        extra = s.solve_displacement(c["start"][3]).iterations
    r = solve(newton, c["start"][3], None, c["dissipation"], c["bounds"])
    return {"predictor": name, "converged": bool(r.converged), "iterations": int(r.iterations),
            "displacement_iterations": int(extra),
            "alpha_difference": float(np.abs(s.alpha.vec.FV().NumPy() - c["a"]).max())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.first_direction", description=__doc__.split("\n\n")[0])
    ap.add_argument("--study", default="three_point_bending")
    ap.add_argument("--resolution", "-r", default="quick")
    ap.add_argument("--start", type=int, default=42, help="steps taken before the first one probed")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    mod = load_study(args.study)
    _, p = study_parameters(mod, args.resolution, {})
    case = mod.cases(p)[0]
    sim = Simulation(case.build_scene(), case.schedule, case.control, progress=False, **(case.options or {}))
    if sim.coupled is None or sim._path is None:
        ap.error(f"{args.study}: its first case does not run path following")
    while sim.step < args.start:
        sim.advance()
    captured = []
    solve = M.CoupledNewton.solve

    def capturing(self, load, alpha_upper=None, dissipation=None, load_bounds=None):
        st = self.s.get_state()
        start = (st, self.s.u.vec.FV().NumPy().copy(), self.s.alpha.vec.FV().NumPy().copy(), load)
        r = solve(self, load, alpha_upper, dissipation, load_bounds)
        if dissipation is not None and r.converged:
            captured.append(dict(start=start, dissipation=dissipation, bounds=load_bounds, its=r.iterations,
                                 u=self.s.u.vec.FV().NumPy().copy(), a=self.s.alpha.vec.FV().NumPy().copy(),
                                 lam=self.load_solved))
        return r

    M.CoupledNewton.solve = capturing
    steps = []
    try:
        for _ in range(args.steps):
            captured.clear()
            row = sim.advance()
            entry = {"step": sim.step, "load_mm": row["load"], "newton": int(row["newton_iterations"])}
            if captured:
                c = captured[0]
                save = sim.solver.get_state()
                entry.update(converged_load_mm=c["lam"], predictor_load_mm=c["start"][3], iterations=c["its"],
                             family=probe(sim.coupled, c),
                             predictors=[variant(sim.coupled, c, v, solve) for v in ("secant", "pf", "pfmax", "pf+u")])
                sim.solver.set_state(save)
            steps.append(entry)
            print(f"[first-direction] step {entry['step']}: {entry.get('iterations', '-')} iterations", flush=True)
    finally:
        M.CoupledNewton.solve = solve
    when = stamp()
    cmd = "python -m benchmarks.first_direction " + " ".join(sys.argv[1:] if argv is None else argv)
    record = {"command": cmd, "time": when, "git": git_state(), "machine": machine_info(), "steps": steps}
    lines = [f"### First Newton directions of path-following steps ({when})", "", f"`{cmd}`", "",
             f"{git_text(record)}. Load errors in mm "
             "against the step's converged load; u error relative to the step's own u change.", ""]
    for e in steps:
        if "family" not in e:
            continue
        lines += [f"**Step {e['step']}**: predictor load {e['predictor_load_mm']:.6g} mm, converged "
                  f"{e['converged_load_mm']:.6g} mm in {e['iterations']} iterations.", "",
                  "| trial | factor | load error mm | min J | merit (start) | u error | alpha error |",
                  "|:---|---:|---:|---:|---:|---:|---:|"]
        for r in e["family"]:
            lines.append(f"| {r['kind']} | {r['factor']:.4g} | {r['load_error_mm']:+.2e} | {r['min_J']:.3g} | "
                         f"{r['merit']:.2e} ({r['merit_start']:.2e}) | {r['u_error_rel']:.2f} | {r['alpha_error_max']:.3f} |")
        lines += ["", "| predictor | converged | iterations | + displacement iterations | alpha difference |",
                  "|:---|:---|---:|---:|---:|"]
        for v in e["predictors"]:
            lines.append(f"| {v['predictor']} | {v['converged']} | {v['iterations']} | {v['displacement_iterations']} | "
                         f"{v['alpha_difference']:.1e} |")
        lines.append("")
    write_record(args.out, f"{args.study}-{args.resolution}-{when}-first-direction", record, lines, shown=None,
                 default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
