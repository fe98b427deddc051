"""The displacement Newton solver of :class:`ngtmc.discrete.solver.Solver`: Newton for u at an imposed load
with alpha fixed (step 2 of the paper's scheme), with an energy line search, a guard against
J <= 0, the Dirichlet increment carried by the Newton increment, and a shifted (Levenberg)
tangent where the tangent is indefinite (a squeezed void). The line search is
:mod:`ngtmc.discrete.energy_search`.

:class:`DisplacementNewton` is handed its problem (:class:`DisplacementProblem`: the energy form,
the unknown, its free and Dirichlet dofs, the boundary values at a load, the force scale of the
tolerance, the admissibility guard, the factorization and the Levenberg shift), as NGSolve's
``NewtonSolver(a, u, freedofs)`` or felupe's ``newtonraphson(x0, fun, jac)`` are; the
:class:`ngtmc.discrete.solver.Solver` builds that problem from its fields
(``Solver.displacement_problem``). The coupled Newton on (u, alpha) of the monolithic schemes is
:mod:`ngtmc.coupled.monolithic`.

Units: mm, N, MPa (residuals in N, for the scene thickness in 2D).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable
import math
import numbers
import time

import numpy as np

from ngtmc.discrete.energy_search import energy_line_search

__all__ = ["DisplacementNewton", "DisplacementProblem", "NewtonOptions", "NewtonResult", "DISPLACEMENT_RTOL", "FLOOR_RTOL", "residual_split",
           "meets", "lifted_direction"]

#: Relative residual of the displacement Newton where ``NewtonOptions.rtol`` is None (the default).
DISPLACEMENT_RTOL = 1e-8

#: Relative residual at which an iterate is accepted when the Newton direction no longer reduces
#: the residual (line search failed or the iteration stalled), instead of the solver's rtol
#: (1e-8): the default of ``NewtonOptions.floor_rtol`` (None refuses such iterates: the attempt
#: fails and the step is cut back). Relative to :meth:`ngtmc.Solver.equilibrium_scale`, the
#: reaction of the iterate itself, never a residual of the step, so that a large step cannot loosen it.
#: Why a floor at all: deep in the crack run of the paper three-point bending the correction is
#: dominated by a near-singular mode, the horizontal motion of a vertex of the void layer squeezed
#: under the indenter (the Hessian regulariser acts on the quadratic part of the order-2 field
#: only, so vertex motion is not penalised): a correction of 1.3e-3 mm for a residual of 5.6e-7 N,
#: and the residual along it is quadratic already at 1e-4 of the step, so no step length reduces
#: it; the floors met there were 2e-8 to 1.4e-6 of the reaction, hence 1e-5. On the paper L-panel,
#: 80 mm into the crack run, the u solve crept from 3.9e-5 N to 3.1e-5 N in 20 iterations against
#: a tolerance of 1.9e-5 N. Every acceptance is counted per step in the history column
#: ``floor_accepts`` and shown by the report.
FLOOR_RTOL = 1e-5


@dataclass
class NewtonOptions:
    """Options of the displacement Newton solver.

    max_iterations: iterations before the attempt counts as failed (the step is then halved);
    rtol: residual norm relative to the reaction-force scale (None: each Newton solver's own
    default, DISPLACEMENT_RTOL for the displacement Newton and ``ngtmc.coupled.settings.COUPLED_RTOL`` for
    the coupled Newton of the monolithic schemes); atol: absolute residual norm, N
    (None: 1e-12 E_max L^(d-1), L the diagonal of the mesh's bounding box); armijo: sufficient
    decrease constant; max_line_search: halvings of the step length before giving up;
    linear_solver: "sparsecholesky" (symmetric tangents, fastest) or "umfpack";
    floor_rtol: where the residual stops falling (the Newton direction no longer reduces it), the
    iterate is accepted if its residual is below floor_rtol times the reaction of that iterate
    (FLOOR_RTOL, 1e-5, the default; a round-off floor measured on the paper's studies) instead of
    rtol; None refuses such iterates (the attempt fails and the step is cut back). Each
    acceptance is counted in the history column ``floor_accepts`` of its step. Both Newton
    solvers (displacement and coupled) use it. levenberg_expansion: doublings of a Levenberg step
    of the displacement Newton accepted at full length while the energy keeps falling along it as
    fast as its slope predicts (the tangent is indefinite there;
    :func:`ngtmc.discrete.energy_search.expand`); 0: none.

    The tolerance an accepted state meets: residual norm on the free dofs (N) <= rtol x
    (the iterate's reaction norm, or the applied tractions' where larger:
    :meth:`ngtmc.Solver.equilibrium_scale`) + atol, with floor_rtol in place of rtol in the steps whose
    ``floor_accepts`` is not 0. The history column ``residual`` records it for every step.
    """

    max_iterations: int = 25
    rtol: float | None = None
    atol: float | None = None
    armijo: float = 1e-4
    max_line_search: int = 12
    linear_solver: str = "sparsecholesky"
    floor_rtol: float | None = FLOOR_RTOL
    levenberg_expansion: int = 10

    def __post_init__(self):
        if self.linear_solver not in ("sparsecholesky", "umfpack", "pardiso"):
            raise ValueError(f"linear_solver = {self.linear_solver!r} is not one of 'sparsecholesky', 'umfpack', 'pardiso'")
        if int(self.max_iterations) < 1:
            raise ValueError(f"max_iterations = {self.max_iterations!r} must be >= 1")
        if (isinstance(self.levenberg_expansion, bool) or not isinstance(self.levenberg_expansion, numbers.Integral)
                or self.levenberg_expansion < 0):
            raise ValueError(f"levenberg_expansion = {self.levenberg_expansion!r} must be an integer >= 0")
        for name in ("rtol", "floor_rtol"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not (0 < v < 1)):
                raise ValueError(f"NewtonOptions {name} = {v!r} must be a number in (0, 1) or None")
        if self.atol is not None and (isinstance(self.atol, bool) or not isinstance(self.atol, (int, float))
                                      or not self.atol >= 0):
            raise ValueError(f"NewtonOptions atol = {self.atol!r} must be a number >= 0 (N) or None")


@dataclass
class NewtonResult:
    """Outcome of one displacement solve."""

    converged: bool
    iterations: int
    residual: float
    solve_time: float
    assembly_time: float
    shifted: int = 0
    message: str = ""
    #: converged at the residual floor (``floor_rtol``), not at rtol
    floor: bool = False
    #: line searches whose energy could not resolve the step (round-off), so that the residual decided
    noise_switches: int = 0


def residual_split(r, u, target: np.ndarray, free: np.ndarray, dirichlet: np.ndarray, load: float, ranks=None):
    """Where a Newton iteration at the imposed displacement ``load`` (mm) stands, from the residual
    ``r`` (N) at ``u`` (NGSolve vectors) and the Dirichlet values ``target`` (mm, a dof array).

    Returns (rem, lifted, res, reac): the boundary values still to impose (dof array, mm, zero on
    the free dofs), whether any remain (the boundary values are then being lifted), the norm of
    the residual on the free dofs and on the Dirichlet dofs (N). ``ranks``: the reductions of a
    distributed mesh (:class:`ngtmc.scene.distributed.Ranks`; None for a serial one)."""
    rem = np.where(dirichlet, target - u.FV().NumPy(), 0.0)
    lifted = bool(np.any(np.abs(rem) > 1e-15 * max(1.0, abs(load))))
    if ranks is None:
        rN = r.FV().NumPy()
        return rem, lifted, float(np.linalg.norm(rN[free])), float(np.linalg.norm(rN[dirichlet]))
    return rem, ranks.any(lifted), ranks.masked_norm(r, free), ranks.masked_norm(r, dirichlet)


def meets(res: float, scale: float, rtol: float, atol: float) -> bool:
    """True where the residual norm ``res`` (N) meets ``rtol`` x ``scale`` + ``atol``. The scale is
    the iterate's own: the norm of its reaction on the dofs the displacement loads move, or of the
    applied tractions where that is larger (:meth:`ngtmc.Solver.equilibrium_scale`; the
    coupled Newton and the classical-contact solver take the same norm of their residual), never
    a residual of the step, which grows with the step (a rigid rotation by 90 degrees in one step
    was accepted with a force of 1.2e-7 N and a body 4e-7 mm off the rotation). The one owner of
    the test: the three Newton solvers use it."""
    return res <= rtol * scale + atol


def lifted_direction(mat, inv, r, rem: np.ndarray, dirichlet: np.ndarray, w, tmp, du):
    """The Newton increment ``du`` that carries the remaining boundary values: ``rem`` on the
    Dirichlet dofs, and on the free dofs -(K^-1 (r + K w)) with w = rem, so that the boundary
    values are never written into u directly (which would invert boundary elements). ``mat``: the
    tangent K; ``inv``: its inverse on the free dofs; ``w``, ``tmp``: work vectors."""
    w.FV().NumPy()[:] = rem
    tmp.data = r + mat * w
    du.data = inv * tmp
    duN = du.FV().NumPy()
    duN[:] = np.where(dirichlet, rem, -duN)


#: print the residuals of each Newton iteration (a debugging switch: ngtmc.discrete.newton._DEBUG = True)
_DEBUG = False

@dataclass
class DisplacementProblem:
    """What the displacement Newton is handed for one solve (units: mm, N).

    ``form``: the energy form of u (``Apply`` gives the residual, ``AssembleLinearization`` the
    tangent); ``u``: the unknown (a GridFunction, updated in place); ``free``, ``fixed``: its free
    and Dirichlet dofs (boolean arrays); ``target(load)``: the Dirichlet values at the imposed
    displacement ``load`` (a dof array, mm); ``scale(r, load)``: the force scale of the tolerance
    (:func:`meets`) of an iterate whose residual is ``r`` (N); ``energy(vec)``: the stored energy
    (N mm, summed over MPI ranks); ``admissible()``: the guard of a trial state besides a finite
    energy (J > 0 at the history points); ``factorize(form)``: a factorization of a form's matrix on
    the free dofs; ``shifted()``: the Levenberg form with its shift parameter and anchor
    (``(form, mu, anchor)``: the tangent plus mu M about the anchor); ``mu0()``: the first shift
    (MPa/mm^2); ``ranks``: the reductions over MPI ranks; ``vectors``: work vectors (r, du, w, tmp,
    u0), r holding the last residual; ``timings``: seconds per part, added to."""

    form: Any
    u: Any
    free: np.ndarray
    fixed: np.ndarray
    target: Callable[[float], np.ndarray]
    scale: Callable[[Any, float], float]
    energy: Callable[[Any], float]
    admissible: Callable[[], bool]
    factorize: Callable[[Any], Any]
    shifted: Callable[[], tuple]
    mu0: Callable[[], float]
    ranks: Any
    vectors: tuple
    timings: dict


class DisplacementNewton:
    """Newton for the displacement at a fixed phase field, with an energy line search (see
    :meth:`solve`). ``options``: :class:`NewtonOptions`; ``rtol``: the relative residual of
    convergence; ``floor``: the relative residual at which an iterate that no longer improves is
    accepted (``floor_rtol``; None: never)."""

    def __init__(self, options: NewtonOptions, rtol: float, floor: float | None):
        self.options = options
        self.rtol = rtol
        self.floor = floor

    def solve(self, p: DisplacementProblem, load: float) -> NewtonResult:
        """Newton solve of ``p`` for u at the imposed displacement ``load`` (mm) with alpha fixed.

        Converged where the residual on the free dofs meets rtol (``displacement_rtol``) times
        the iterate's own force scale (``p.scale``, :meth:`ngtmc.Solver.equilibrium_scale`: its reaction, or the applied
        tractions) plus atol (:func:`meets`); no residual of the step (a first iterate's, a predictor's) enters
        the tolerance, so that a large step cannot loosen it.

        The Dirichlet increment is carried by the Newton increment (never written into u
        directly, which would invert boundary elements). Steps are accepted only if the energy
        is finite (which fails as soon as J <= 0 at one quadrature point); once the boundary
        values are reached, steps must also decrease the energy (Armijo), or, where the energy's
        round-off hides the decrease (near convergence, :data:`ngtmc.discrete.energy_search.NOISE_FRACTION`), the residual norm. If the tangent is not
        a descent direction (indefinite tangent in a squeezed void), it is shifted by mu M with M
        the mass matrix, mu raised by tenfold until the direction descends. Where the residual
        stops falling (by less than half in an iteration, also the last one) or the line search
        fails, the iterate is accepted if its residual is below ``floor_rtol``
        (``NewtonOptions.floor_rtol``; None: never) of the same scale (the result's ``floor``).
        On failure u is left at the last iterate; the caller restores the state."""
        opt = self.options
        rtol = self.rtol
        u = p.u.vec
        r, du, w, tmp, u0 = p.vectors
        ranks = p.ranks if p.ranks.parallel else None
        target = p.target(load)
        solve_time = 0.0
        assembly_time = 0.0
        shifted = 0
        res = math.inf
        reac = 0.0
        res_prev = math.inf
        tm = p.timings
        floor = self.floor
        lifted = True
        noise_switches = 0

        def at_floor(it):
            """The residual no longer falls: the iterate accepted if it is below the floor, else None."""
            if not floor or lifted or not meets(res, p.scale(r, load), floor, opt.atol):
                return None
            return NewtonResult(True, it, res, solve_time, assembly_time, shifted, floor=True,
                                noise_switches=noise_switches)

        def settled(it):
            """After the residual of the iterate of ``it`` iterations: the result if it converged,
            or if the residual fell by less than half since the last one and sits at the floor;
            else None."""
            nonlocal res_prev
            if lifted:
                return None
            if meets(res, p.scale(r, load), rtol, opt.atol):
                return NewtonResult(True, it, res, solve_time, assembly_time, shifted, noise_switches=noise_switches)
            done = at_floor(it) if res > 0.5 * res_prev else None
            res_prev = res
            return done

        for it in range(1, opt.max_iterations + 1):
            t0 = time.perf_counter()
            p.form.Apply(u, r)
            tm["residual"] += time.perf_counter() - t0
            rem, lifted, res, reac = residual_split(r, u, target, p.free, p.fixed, load, ranks)
            if not np.isfinite(res):
                return NewtonResult(False, it, res, solve_time, assembly_time, shifted, "residual is not finite",
                                    noise_switches=noise_switches)
            if _DEBUG:
                print(f"  it {it} res {res:.3e} reac {reac:.3e} lifted {lifted} tol {rtol * p.scale(r, load) + opt.atol:.3e}")
            done = settled(it - 1)
            if done is not None:
                return done
            t0 = time.perf_counter()
            p.form.AssembleLinearization(u)
            assembly_time += time.perf_counter() - t0
            tm["assembly"] += time.perf_counter() - t0
            t0 = time.perf_counter()
            inv = p.factorize(p.form)
            t1 = time.perf_counter()
            lifted_direction(p.form.mat, inv, r, rem, p.fixed, w, tmp, du)
            t2 = time.perf_counter()
            solve_time += t2 - t0
            tm["factorization"] += t1 - t0
            tm["solve"] += t2 - t1
            t_ls = time.perf_counter()
            E0 = math.nan if lifted else p.energy(u)  # lifted steps only need a finite trial energy
            if not lifted and not math.isfinite(E0):
                return NewtonResult(False, it, res, solve_time, assembly_time, shifted,
                                    "energy of the current state is not finite", noise_switches=noise_switches)
            slope = p.ranks.dot(r, du)
            u0.data = u

            def line_search(slope, levenberg=False):
                """The energy line search (:func:`ngtmc.discrete.energy_search.energy_line_search`)
                along the direction du; a Levenberg step accepted at full length is lengthened."""
                nonlocal noise_switches
                accepted, switched = energy_line_search(p, opt, du, E0, slope, res, lifted, levenberg)
                noise_switches += switched
                return accepted

            accepted = (lifted or slope < 0.0) and line_search(slope)
            tm["line_search"] += time.perf_counter() - t_ls
            if not accepted:
                # the Newton direction ascends (indefinite tangent in a squeezed void), the energy
                # does not decrease along it, or no fraction of it keeps J > 0 (near-singular
                # tangent of broken elements after a large change of alpha): shift the tangent by
                # mu M (Levenberg), mu raised tenfold each time
                a_s, mu_par, anchor = p.shifted()
                anchor.vec.data = u
                mu = p.mu0()
                for _ in range(6):
                    shifted += 1
                    mu_par.Set(mu)
                    t0 = time.perf_counter()
                    a_s.AssembleLinearization(u)
                    assembly_time += time.perf_counter() - t0
                    tm["assembly"] += time.perf_counter() - t0
                    t0 = time.perf_counter()
                    inv_s = p.factorize(a_s)
                    tm["factorization"] += time.perf_counter() - t0
                    lifted_direction(a_s.mat, inv_s, r, rem, p.fixed, w, tmp, du)
                    solve_time += time.perf_counter() - t0
                    slope = p.ranks.dot(r, du)
                    t_ls = time.perf_counter()
                    ok = (lifted or slope < 0.0) and line_search(slope, levenberg=True)
                    tm["line_search"] += time.perf_counter() - t_ls
                    if ok:
                        accepted = True
                        break
                    mu *= 10.0
            if not accepted:
                done = at_floor(it - 1)
                if done is not None:
                    return done
                return NewtonResult(False, it, res, solve_time, assembly_time, shifted,
                                    "line search failed" if not lifted else "no admissible step towards the boundary values",
                                    noise_switches=noise_switches)
        # one last residual check after the final update
        p.form.Apply(u, r)
        _, lifted, res, reac = residual_split(r, u, target, p.free, p.fixed, load, ranks)
        done = settled(opt.max_iterations)
        if done is not None:
            return done
        return NewtonResult(False, opt.max_iterations, res, solve_time, assembly_time, shifted,
                            f"no convergence in {opt.max_iterations} iterations (residual {res:.3e} N)",
                            noise_switches=noise_switches)
