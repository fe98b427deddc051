"""One solve of the coupled Newton (:meth:`ngtmc.coupled.monolithic.CoupledNewton.solve`): the iteration on
(u, alpha), and with path following on the load, from the current state to a converged one.

What is solved, and how, is described in :mod:`ngtmc.coupled.monolithic`: a semi-smooth Newton method on the
median complementarity function of the bounds alpha_{n-1} <= alpha <= 1, a backtracking line search
on a scaled residual merit with the guard J > 0 and a finite residual, Levenberg steps where the
Newton direction does not reduce the merit, a displacement relaxation once per solve where the
iteration stalls, and acceptance at the residual floor (:data:`ngtmc.discrete.newton.FLOOR_RTOL`) where
the direction no longer helps. Under dissipation control (``dissipation``) each Newton step is the
bordered solution x = a + dlambda b of the linearised equations and the constraint.

An :class:`Iteration` holds the state of one solve (the iterate, the load, the residual norms,
the times); :class:`~ngtmc.coupled.monolithic.CoupledNewton` holds what outlives it (forms, linear solver,
scales, counters). Units: mm, N, MPa; residual norms of the displacement equation in N.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ngtmc.discrete import NewtonResult
from ngtmc.coupled import settings as C

__all__ = ["Iteration"]


class Iteration:
    """The state of one coupled solve and its steps; :meth:`run` returns the NewtonResult. See
    :meth:`ngtmc.coupled.monolithic.CoupledNewton.solve` for the arguments."""

    def __init__(self, newton, load: float, alpha_upper=None, dissipation=None, load_bounds=None):
        self.C = C   # the settings (STALL_*, LEVENBERG_SHIFTS, WEAK_STEP, DEBUG): ngtmc.coupled.settings
        self.n = n = newton
        self.t_start = time.perf_counter()
        self.s = s = n.s
        self.ranks = s.ranks
        self.nu = nu = n.nu
        s._r_valid = False
        s.H.vec.FV().NumPy()[:] = s.H_committed
        n._gather()
        self.x, self.r, self.dx, self.w, self.tmp, self.x0 = n.x.vec, n._r, n._dx, n._w, n._tmp, n._x0
        self.xN, self.rN = self.x.FV().NumPy(), self.r.FV().NumPy()
        self.a_low = a_low = s.alpha_committed
        self.a_up = (np.ones_like(a_low) if alpha_upper is None
                     else np.maximum(np.minimum(alpha_upper, 1.0), a_low))
        n.cap_binding = False
        n.load_out_of_bounds = None
        self.c = n._ncp_scale
        self.dir_u = dir_u = s._dir_np
        self.path = dissipation is not None
        self.lam = float(load)
        self.scale_g = None
        if self.path:
            if not dissipation > 0:
                raise ValueError(f"dissipation = {dissipation!r} N mm must be > 0")
            self.d_target = n.D.value(a_low) + float(dissipation)
            self.scale_g = float(dissipation)
            self.lam_lo, self.lam_hi = load_bounds if load_bounds is not None else (-math.inf, math.inf)
            self.xN[:nu][dir_u] = s.dirichlet_target(self.lam)[dir_u]
        self.target = s.dirichlet_target(self.lam)
        free_u = ~dir_u & n._free_base[:nu]
        # masks of the u dofs in the coupled vector (free ones; Dirichlet ones)
        self.free_ux = np.zeros(self.xN.size, dtype=bool)
        self.free_ux[:nu] = free_u
        self.dir_ux = np.zeros(self.xN.size, dtype=bool)
        self.dir_ux[:nu] = dir_u
        # the dofs the displacement loads move: their reaction is the equilibrium scale
        self.moved_ux = np.zeros(self.xN.size, dtype=bool)
        self.moved_ux[:nu] = s._moved_np
        self.solve_time = self.assembly_time = 0.0
        self.r_ref = 0.0
        self.tol_a = n.alpha_tol * n.alpha_residual_scale
        self.res_u = math.inf
        self.res_a = self.g = self.reac = self.scale = 0.0
        self.lifted = False
        self.merits = []
        self.relaxed = False
        self.relax_iterations = 0

    # ------------------------------------------------------------------ residuals
    def split(self, xv, rvec):
        """Residual norms of the residual vector ``rvec`` at the coupled iterate ``xv`` (u part
        on the free dofs; alpha part of the median NCP function, in units of the residual) and
        the bound each alpha dof is held at (0 none, -1 lower, +1 upper)."""
        nu, c, ranks = self.nu, self.c, self.ranks
        rvec = ranks.cumulated(rvec, self.n._rc)
        rv = rvec.FV().NumPy()
        a, ra = xv[nu:], rv[nu:]
        lo, up = a - self.a_low, a - self.a_up
        phi = np.median(np.stack([lo, up, c * ra]), axis=0)
        held = np.where(phi == lo, -1, np.where(phi == up, 1, 0))
        held[(held != 0) & (phi == c * ra)] = 0
        return ranks.masked_norm(rvec, self.free_ux), ranks.norm_of(phi / c, rvec, nu), held

    def constraint(self, xv) -> float:
        """Dissipation constraint D(alpha) - D_target, N mm (0 without path following)."""
        return self.n.D.value(xv[self.nu:]) - self.d_target if self.path else 0.0

    def merit_of(self, ru, ra, gv, scale_u) -> float:
        """The line search's merit: each residual relative to its natural scale (units differ:
        N and N mm): the reaction force of the step, the residual of a uniform unit alpha,
        the dissipation step."""
        return ((ru / scale_u) ** 2 + (ra / self.n.alpha_residual_scale) ** 2
                + ((gv / self.scale_g) ** 2 if self.path else 0.0))

    # ------------------------------------------------------------------ endings
    def failed(self, it, message):
        """The failure after ``it`` coupled iterations; the iterations of a displacement
        relaxation (:meth:`relax_u`) count as well, as in :meth:`accept`."""
        self.n._scatter()
        return NewtonResult(False, it + self.relax_iterations, self.res_u, self.solve_time, self.assembly_time, 0, message)

    def accept(self, iterations, held):
        n = self.n
        np.clip(self.xN[self.nu:], self.a_low, self.a_up, out=self.xN[self.nu:])  # held dofs sit on their bound to round-off
        n._scatter()
        self.s.load = self.lam
        n.load_solved = self.lam
        n.cap_binding = self.ranks.any(bool(np.any((held == 1) & (self.a_up < 1.0 - 1e-12))))
        return NewtonResult(True, iterations + self.relax_iterations, self.res_u, self.solve_time,
                            self.assembly_time, 0)

    def relax_u(self) -> bool:
        """Once per solve, where the coupled iteration stalls or its line search fails: solve R_u = 0
        at the current alpha and load by the displacement Newton, which descends the energy (so it
        leaves an unstable equilibrium of a squeezed void, where the residual merit of the coupled
        iteration cannot tell a saddle from a minimum); the iteration goes on from there. True if
        it converged. Under dissipation control only with ``relax_dissipation`` (RELAX_DISSIPATION)."""
        n = self.n
        if self.relaxed or self.lifted or not n.relax or (self.path and not n.relax_dissipation):
            return False
        self.relaxed = True
        n._scatter()
        res = self.s.solve_displacement(self.lam)
        self.relax_iterations += res.iterations
        n._gather()
        n.relaxations += 1
        if self.C.DEBUG:
            print(f"    u relaxation at fixed alpha: converged {res.converged} in {res.iterations} iterations", flush=True)
        return res.converged

    def at_floor(self, it, held):
        """The Newton direction no longer reduces the residual (line search failed, or the
        iteration stalled): accept the iterate if both residuals meet FLOOR_RTOL relative to
        their scales (:mod:`ngtmc.coupled.monolithic`)."""
        n = self.n
        fr = self.s.floor_rtol   # one setting for both Newton solvers (Solver.floor_rtol)
        if self.lifted or not fr or not n._converged(self.res_u, self.res_a, self.g, self.scale, fr,
                                                     fr / n.alpha_tol * self.tol_a, self.scale_g, g_rtol=fr):
            return None
        n.floor_accepts += 1
        n.floor_worst = max(n.floor_worst, self.res_u / max(self.scale, 1e-300))
        return self.accept(it, held)

    def stuck(self, it, held, message, done_iterations=None):
        """Where the iteration stalls or its line search fails: None after a displacement
        relaxation (the caller iterates on from there), else the iterate accepted at the
        residual floor, else the failure with ``message``. ``done_iterations``: the iterations
        that made the current iterate (default it - 1: iteration ``it`` did not move it)."""
        if self.relax_u():
            self.merits.clear()
            return None
        done = self.at_floor(it - 1 if done_iterations is None else done_iterations, held)
        return done if done is not None else self.failed(it, message)

    # ------------------------------------------------------------------ directions
    def direction(self, lin, free, fixed_step, a_cur, g):
        """Newton (or Levenberg) direction (dx, dlambda) from the factorization ``lin``; None
        when the damage does not respond to the load (path following). Under dissipation control
        the bordered system is solved in one GMRES where ``lin`` offers it (``lin.bordered``),
        else, or where that fails, as two systems."""
        n, s, nu = self.n, self.s, self.nu
        w, tmp, dx = self.w, self.tmp, self.dx
        wN = w.FV().NumPy()
        wN[:] = fixed_step
        tmp.data = self.r + n.form.mat * w
        if self.path:
            # response to a unit load change: the boundary values move by d target / d lambda
            lam = self.lam
            h = 1e-6 * max(abs(lam), 1e-3)
            dt_dl = (s.dirichlet_target(lam + h) - s.dirichlet_target(lam - h)) / (2 * h)
            unit = np.zeros_like(fixed_step)
            unit[:nu] = np.where(self.dir_u, dt_dl, 0.0)
            grad = n.D.gradient(a_cur)
            if getattr(lin, "bordered", None) is not None:
                tN = tmp.FV().NumPy()
                r = np.where(free, tN, 0.0)
                wN[:] = unit
                tmp.data = n.form.mat * w
                c = np.zeros_like(fixed_step)
                c[nu:] = np.where(free[nu:], grad, 0.0)
                if not c.any():   # every alpha dof with a gradient held: the two solves' slope is 0 too
                    return None
                out = lin.bordered(r, np.where(free, tN, 0.0), c,
                                   g + float(grad @ np.where(free[nu:], 0.0, fixed_step[nu:])))
                if out is not None:
                    return np.where(free, -out[0], fixed_step + out[1] * unit), out[1]
                tN[:] = r   # the two systems instead (their solve ignores the dofs that are not free)
        lin(tmp, dx)
        dxN = np.where(free, -dx.FV().NumPy(), fixed_step)
        dlam = 0.0
        if self.path:
            wN[:] = unit
            tmp.data = n.form.mat * w
            lin(tmp, w)
            bN = np.where(free, -w.FV().NumPy(), unit)
            slope = self.ranks.sum(float(grad @ bN[nu:]))
            if not abs(slope) > 0.0:
                return None
            dlam = -(g + self.ranks.sum(float(grad @ dxN[nu:]))) / slope
            dxN += dlam * bN
        return dxN, dlam

    def timed_direction(self, factorize, free, fixed_step, a_cur, g):
        """:meth:`direction` from the factorization ``factorize()`` returns, with the time of
        each part booked (factorization, solve)."""
        tm = self.s.timings
        t0 = time.perf_counter()
        lin = factorize()
        t1 = time.perf_counter()
        d = self.direction(lin, free, fixed_step, a_cur, g)
        t2 = time.perf_counter()
        tm["factorization"] += t1 - t0
        tm["solve"] += t2 - t1
        self.solve_time += t2 - t0
        return d

    def search(self, dxN, dlam, merit0, scale_u, lam0):
        """Backtracking from x0 along (dx, dlambda) on the merit function, guard J > 0 and a
        finite residual; returns (accepted, load, step, merit). The residual of an accepted
        iterate is left in tmp; a rejected search leaves the last trial in x (the caller restores
        x0)."""
        s, n, nu, xN, tmp = self.s, self.n, self.nu, self.xN, self.tmp
        debug = self.C.DEBUG
        t0 = time.perf_counter()
        step = 1.0
        try:
            for _ in range(s.newton.max_line_search):
                xN[:] = self.x0.FV().NumPy() + step * dxN
                lam_t = lam0 + step * dlam
                if self.path:
                    xN[:nu][self.dir_u] = s.dirichlet_target(lam_t)[self.dir_u]
                s.u.vec.FV().NumPy()[:] = xN[:nu]
                if s.min_J() > 0.0:
                    n.form.Apply(self.x, tmp)
                    if self.ranks.all_finite(tmp.FV().NumPy()):
                        if self.lifted:
                            return True, lam_t, step, math.nan
                        rmu, rma, _ = self.split(xN, tmp)
                        m = self.merit_of(rmu, rma, self.constraint(xN), scale_u)
                        if m <= (1.0 - 1e-4 * step) * merit0:
                            if debug:
                                print(f"    search: step {step:g} merit {m:.3e} from {merit0:.3e}", flush=True)
                            return True, lam_t, step, m
                    elif debug:
                        print(f"    search: step {step:g} residual not finite", flush=True)
                elif debug:
                    print(f"    search: step {step:g} J <= 0", flush=True)
                step *= 0.5
            if debug:
                print(f"    search: failed from {merit0:.3e}", flush=True)
            return False, lam0, 0.0, math.inf
        finally:
            s.timings["line_search"] += time.perf_counter() - t0

    def levenberg(self, accepted, step, merit, free, fixed_step, a_cur, merit0, scale_u, lam0):
        """The Newton direction does not reduce the merit function, or only along a small
        fraction of it (a near-singular or indefinite tangent): Levenberg steps, the tangent's
        free diagonal scaled by 1 + mu (LEVENBERG_SHIFTS); a weak Newton step is kept if no
        Levenberg step does better. Returns (accepted, merit, weak), weak: the weak Newton step
        was kept; the load is set."""
        n, xN, tmp = self.n, self.xN, self.tmp
        kept = (xN.copy(), tmp.FV().NumPy().copy(), self.lam, merit) if accepted else None
        for mu in self.C.LEVENBERG_SHIFTS:
            d = self.timed_direction(lambda: n.lin.shifted(free, mu), free, fixed_step, a_cur, self.g)
            if d is None:
                break
            ok, lam_l, step_l, merit_l = self.search(*d, merit0, scale_u, lam0)
            if self.C.DEBUG:
                print(f"    [{time.perf_counter() - self.t_start:7.1f}s] levenberg mu {mu:g}: accepted {ok} step {step_l:g} merit {merit_l:.3e} "
                      f"(newton step {step:g} merit {merit:.3e})", flush=True)
            if ok and merit_l < merit:
                accepted, self.lam, merit = True, lam_l, merit_l
                kept = None
                n.levenberg_steps += 1
                break
        weak = kept is not None
        if weak:
            xN[:], tmp.FV().NumPy()[:], self.lam, merit = kept
            self.s.u.vec.FV().NumPy()[:] = xN[:self.nu]
            accepted = True
        return accepted, merit, weak

    # ------------------------------------------------------------------ the iteration
    def run(self) -> NewtonResult:
        n, s, nu, ranks, C = self.n, self.s, self.nu, self.ranks, self.C
        tm = s.timings
        x, r, w, xN, rN = self.x, self.r, self.w, self.xN, self.rN
        dir_u = self.dir_u
        merits = self.merits
        have_r = False  # True when the line search left the residual of the accepted iterate in tmp
        for it in range(1, n.max_iterations + 1):
            t0 = time.perf_counter()
            if have_r:
                r.data = self.tmp
            else:
                n.form.Apply(x, r)
            tm["residual"] += time.perf_counter() - t0
            if not ranks.all_finite(rN):
                return self.failed(it, "residual is not finite")
            lam = self.lam
            rem = np.where(dir_u, self.target - xN[:nu], 0.0)
            self.lifted = lifted = (not self.path) and ranks.any(bool(np.any(np.abs(rem) > 1e-15 * max(1.0, abs(lam)))))
            rc = ranks.cumulated(r, n._rc)
            self.res_u, self.res_a, held = self.split(xN, rc)
            self.g = g = self.constraint(xN)
            self.reac = reac = ranks.masked_norm(rc, self.dir_ux)
            self.scale = ranks.masked_norm(rc, self.moved_ux)
            if C.DEBUG:
                # H_n = max(H_{n-1}, Psi_plus): points where Psi_plus wins, and changes since the last (benchmarks/history_branches.py)
                branch, last = s.psi_plus_values() > s.H_committed, getattr(self, "branch", None)
                changed, self.branch = (-1 if last is None else int(np.sum(branch != last))), branch
                print(f"    [{time.perf_counter() - self.t_start:7.1f}s] coupled it {it} lam {lam:.8g} res_u {self.res_u:.3e} (ref {max(reac, self.r_ref):.3e}) "
                      f"res_a {self.res_a:.3e} (tol {self.tol_a:.3e}) g {g:.3e} "
                      f"held {int(np.sum(held == -1))}/{int(np.sum(held == 1))} "
                      f"branch {int(branch.sum())} changed {changed} gmres {n.lin.gmres_iterations[-2:]}", flush=True)
            if not lifted:
                if self.r_ref == 0.0:
                    self.r_ref = self.res_u
                if n._converged(self.res_u, self.res_a, g, self.scale, n.rtol, self.tol_a, self.scale_g):
                    return self.accept(it - 1, held)
            scale_u = max(reac, self.r_ref, s.newton.atol)
            merit0 = self.merit_of(self.res_u, self.res_a, g, scale_u)
            merits.append(merit0)
            if not lifted and len(merits) > C.STALL_WINDOW + 2 and merit0 > C.STALL_FACTOR * merits[-1 - C.STALL_WINDOW]:
                # no nearby solution (a crack that wants to run at this load): stop early, the
                # caller cuts back or changes the control
                out = self.stuck(it, held, f"coupled Newton stalled (merit {merit0:.3g}, "
                                           f"{merits[-1 - C.STALL_WINDOW]:.3g} {C.STALL_WINDOW} iterations before)")
                if out is None:
                    have_r = False
                    continue
                return out
            # semi-smooth Newton step: held alpha dofs move onto their bound, the others and the
            # free u dofs solve the linearised equations; the Dirichlet remainder is carried
            t0 = time.perf_counter()
            n.form.AssembleLinearization(x)
            dt = time.perf_counter() - t0
            self.assembly_time += dt
            tm["assembly"] += dt
            # complementarity scale from the tangent's own diagonal: c R_alpha is then the Jacobi
            # estimate of the dof's Newton step (with c from the (Gc/l0) mass only, the notch tip,
            # where 2 H >> Gc/l0, was put on alpha = 1 and released again, step after step)
            self.c = n._ncp_scale = n.lin.diagonal_scale()
            self.res_u, self.res_a, held = self.split(xN, rc)
            merit0 = self.merit_of(self.res_u, self.res_a, g, scale_u)
            free = n._free_base.copy()
            free[nu:] &= held == 0
            a_cur = xN[nu:]
            wN = w.FV().NumPy()
            wN[:nu] = rem
            wN[nu:] = np.where(held == -1, self.a_low - a_cur, np.where(held == 1, self.a_up - a_cur, 0.0))
            fixed_step = wN.copy()
            d = self.timed_direction(lambda: n.lin.factorize(free), free, fixed_step, a_cur, g)
            if d is None:
                return self.failed(it, "dissipation control: the damage does not respond to the load here")
            self.x0.data = x
            lam0 = lam
            accepted, self.lam, step, merit = self.search(*d, merit0, scale_u, lam0)
            weak = False
            if not lifted and (not accepted or step < C.WEAK_STEP):
                accepted, merit, weak = self.levenberg(accepted, step, merit, free, fixed_step, a_cur, merit0, scale_u, lam0)
            have_r = accepted
            if weak and n.weak_stop:
                # the weak Newton step is kept, and the attempt is stalled (WEAK_STOP)
                out = self.stuck(it, held, f"coupled Newton: only a weak step of {step:g} reduces the merit "
                                           f"({merit0:.3g} -> {merit:.3g})", done_iterations=it)
                if out is None:
                    have_r = False
                    continue
                return out
            if not accepted:
                xN[:] = self.x0.FV().NumPy()
                self.lam = lam0
                out = self.stuck(it, held, "coupled line search failed" if not lifted
                                 else "no admissible step towards the boundary values")
                if out is None:
                    have_r = False
                    continue
                return out
            if self.path:
                self.target = s.dirichlet_target(self.lam)
                if not (self.lam_lo <= self.lam <= self.lam_hi):
                    n.load_out_of_bounds = self.lam
                    return self.failed(it, f"dissipation control: the load {self.lam:.6g} mm left "
                                           f"[{self.lam_lo:.6g}, {self.lam_hi:.6g}] mm")
        return self.failed(n.max_iterations, f"coupled Newton: no convergence in {n.max_iterations} iterations "
                                             f"(residual {self.res_u:.3e} N)")
