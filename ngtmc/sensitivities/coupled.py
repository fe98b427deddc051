"""Exact gradients of a recorded path of the monolithic schemes: the discrete adjoint of
``scheme="monolithic"`` (load control) and ``scheme="path-following"`` (dissipation control where
the crack grows).

Use it through :mod:`ngtmc.sensitivities` (``record_path(..., scheme="monolithic")``, ``replay``,
``gradient``, ``directional_fd`` dispatch here for a :class:`CoupledPath`):

    path = S.record_path(scene, 0.012, AdaptiveStepControl(du_max=1e-3), scheme="path-following",
                         newton=NewtonOptions(rtol=1e-12), coupled={"alpha_tol": 1e-12})
    g = S.gradient(path, S.ExternalWork(), wrt=("rho", "E", "Gc", "l0", "gamma0"))

What is differentiated (derivation in ``docs/sensitivities.md``): at every recorded step n the
converged state of :meth:`ngtmc.coupled.monolithic.CoupledNewton.solve`,

1. R_u(u_n, alpha_n; p) = 0 on the free displacement dofs, u_n = u_D(lambda_n) on the Dirichlet
   dofs;
2. R_alpha(u_n, alpha_n; H_{n-1}, p) = 0 on the phase-field dofs that are free at the solution,
   alpha_n = alpha_{n-1} on the dofs held at the lower bound, alpha_n = 1 on those held at the upper
   bound; R_alpha contains g'(alpha) H_n(u) with H_n(u) = max(H_{n-1}, Psi_plus(u)) at the history
   points (the step's own history, inside the coupled tangent);
3. on a *dissipation step* (path following) the load lambda_n is an unknown too, closed by
   D(alpha_n; p) - D(alpha_{n-1}; p) = dD_n, D = 1/2 alpha^T M(Gc, l0, rho) alpha;
   on a *displacement step* lambda_n is given;
4. H_n = max(H_{n-1}, Psi_plus(u_n)) is committed for the next step.

**Held fixed:** the sequence of step types (displacement or dissipation step) and, per step, the
imposed load lambda_n of a displacement step or the dissipation target dD_n of a dissipation step
(the decisions of the step control and of :mod:`ngtmc.stepping.path` depend on Newton failures and on
predicted dissipations; they are not differentiable events); the active sets at the solution
(alpha dofs held at alpha_{n-1} or at 1, the branch of the max at every history point; one-sided
derivatives on ties); the Newton iterates (only the converged state enters). :func:`replay_coupled`
re-runs exactly this sequence: the same loads on displacement steps, the same dD_n on
dissipation steps (where the load comes out as a result).

The reverse sweep solves per step the transposed coupled tangent on the free set (UMFPACK; the
tangent is not symmetric), bordered on a dissipation step by the constraint and the load
column. The adjoint of a held alpha dof passes to alpha_{n-1} (through its bound), that of the
constraint to alpha_{n-1} through D(alpha_{n-1}); the history adjoint passes to u_n where the max
took Psi_plus and to H_{n-1} elsewhere.

Only steps solved by the coupled Newton can be differentiated: :func:`record_coupled_path`
refuses a path with a step accepted by a fallback of the monolithic scheme (staggered passes or a
single pass; use the path-following scheme or smaller steps), with Traction loads or with
displacement loads given by a callable (their reaction weight would depend on the load).
Objectives must give their derivative with respect to the loads on dissipation steps
(:meth:`ngtmc.sensitivities.Objective.load_seeds`); all built-in ones do.

Units: mm, N, MPa; forces and energies per scene thickness in 2D.
"""
from __future__ import annotations

from dataclasses import dataclass
import time

import numpy as np
import ngsolve as ngs

from ngtmc.sensitivities.adjoint import _Accumulator, _engine, _wrt_keys, history_adjoint
from ngtmc.sensitivities.objectives import Seeds
from ngtmc.sensitivities.path import Path, _capture, _reset, _set_parameters, _snapshot_parameters, replay_inputs
from ngtmc.discrete import history_pieces, phase_field_piece
from ngtmc.scene import Scene
from ngtmc.simulation import Simulation
from ngtmc.discrete import FLOOR_RTOL

__all__ = ["CoupledPath", "record_coupled_path", "replay_coupled", "coupled_gradient", "alpha_residual_pieces", "held_sets",
           "COUPLED_SCHEMES"]

#: schemes whose paths this module differentiates
COUPLED_SCHEMES = ("monolithic", "path-following")


@dataclass
class CoupledPath(Path):
    """A recorded path of a monolithic scheme (:class:`ngtmc.sensitivities.Path` plus the step types).

    Attributes (besides those of Path)
    ----------
    coupled : CoupledNewton
        The coupled solver of the run (reused by :func:`replay_coupled` and the sweep).
    scheme : str
        "monolithic" or "path-following".
    dissipation : ndarray (N + 1,)
        dD_n of step n, N mm (per thickness in 2D), on dissipation steps; NaN on displacement
        steps and at index 0.
    """

    coupled: object = None
    scheme: str = "monolithic"
    dissipation: np.ndarray = None

    @property
    def dissipation_steps(self) -> np.ndarray:
        """Boolean (N + 1,): True where step n was a dissipation step (the load an unknown)."""
        return np.isfinite(self.dissipation)

    def replay(self, rho=None, parameters=None) -> "CoupledPath":
        """:func:`ngtmc.sensitivities.replay` of this path: :func:`replay_coupled`."""
        return replay_coupled(self, rho, parameters)

    def gradient(self, objective, wrt=("rho", "E", "Gc", "l0", "gamma0")) -> dict:
        """:func:`ngtmc.sensitivities.gradient` of this path: :func:`coupled_gradient`."""
        return coupled_gradient(self, objective, wrt)


# ====================================================================== forward

class FallbackStep(ValueError, RuntimeError):
    """A step of a monolithic run was accepted by a fallback (staggered passes), not by the coupled
    Newton, so the path cannot be differentiated. A ValueError (the run cannot be recorded as
    asked) and a RuntimeError (it is an outcome of the run: smaller steps may avoid it)."""

def record_coupled_path(scene: Scene, schedule, control=None, newton=None, checkpoint_every=None,
                        **options) -> CoupledPath:
    """:func:`ngtmc.sensitivities.record_path` for ``scheme="monolithic"`` or ``"path-following"``
    (``options`` go to :class:`~ngtmc.simulation.loop.Simulation`). Records every accepted state and, per
    step, whether it was a dissipation step and its dD (from the converged coupled solve that gave
    the accepted state). The coupled Newton's residual-floor acceptance and its displacement
    relaxation (:mod:`ngtmc.coupled.monolithic`) are switched off for the recording and its replays: a state
    at the floor limits the gradient's accuracy, and a relaxation may reach another of two nearby
    equilibria (measured: FD and adjoint then differed by 8e-4 on the contact scene)."""
    if checkpoint_every is not None:
        raise ValueError("record_path: checkpointing is not available for the monolithic schemes so far")
    scheme = options.get("scheme")
    if scheme not in COUPLED_SCHEMES:
        raise ValueError(f"record_coupled_path: scheme = {scheme!r} is not one of {COUPLED_SCHEMES}")
    t0 = time.perf_counter()
    sim = Simulation(scene, schedule, control, newton=newton, **options)
    s = sim.solver
    c = sim.coupled
    if c is None:
        raise ValueError("record_path: the monolithic schemes need a scene with fracture regions")
    for rec in s._loads:
        if "mask" in rec and rec["unit"] is None:
            raise ValueError(f"record_path: the adjoint of the monolithic schemes does not handle displacement loads "
                             f"given by a callable ({rec['name']!r}) so far")
    s.floor_rtol = None  # (both Newton solvers) states at the residual floor would limit the gradient's accuracy
    c.relax = False      # a relaxation may reach another of two nearby equilibria (coupled.py)
    last = {}
    solve = c.solve

    def recording_solve(load, alpha_upper=None, dissipation=None, load_bounds=None):
        floors = c.floor_accepts
        res = solve(load, alpha_upper, dissipation, load_bounds)
        last.clear()
        if res.converged:
            last.update(u=s.u.vec.FV().NumPy().copy(), alpha=s.alpha.vec.FV().NumPy().copy(),
                        load=float(c.load_solved), dissipation=dissipation, floor=c.floor_accepts > floors)
        return res

    c.solve = recording_solve  # instance attribute: the simulation and its path rule call this one
    states = [_capture(s)]
    forces = [s.reaction()]
    loads = [0.0]
    targets = [np.nan]
    floor_steps = []

    def grab(sim_, row):
        n = len(states)
        if not (last and np.array_equal(last["u"], s.u.vec.FV().NumPy())
                and np.array_equal(last["alpha"], s.alpha.vec.FV().NumPy())):
            raise FallbackStep(f"record_path: step {n} (load {row['load']:.6g} mm) was not solved by the coupled Newton "
                             f"(a fallback of the monolithic scheme took it: staggered_iterations = "
                             f"{row.get('staggered_iterations')}); it cannot be differentiated. Use "
                             f"scheme='path-following' or smaller steps")
        states.append(_capture(s))
        forces.append(float(row["force"]))
        if last["floor"]:
            floor_steps.append(n)
        dD = last["dissipation"]
        targets.append(np.nan if dD is None else float(dD))
        loads.append(last["load"] if dD is not None else float(row["load"]))
        last.clear()

    try:
        result = sim.run(callbacks=[grab])
    finally:
        del c.solve
    if floor_steps:
        import warnings
        warnings.warn(f"record_path: {len(floor_steps)} step(s) ({floor_steps[:10]}) were accepted at the residual "
                      f"floor of the coupled Newton (relative residual up to {c.floor_worst:.2g}, FLOOR_RTOL = "
                      f"{FLOOR_RTOL:g}), not at the solver's rtol: the gradient is exact only to about that level there",
                      stacklevel=2)
    return CoupledPath(solver=s, loads=np.asarray(loads), states=states, forces=np.asarray(forces),
                       rho=s.rho.vec.FV().NumPy().copy(), parameters=_snapshot_parameters(s),
                       forward_time=time.perf_counter() - t0, history=result.history, coupled=c,
                       scheme=scheme, dissipation=np.asarray(targets))


def replay_coupled(path: CoupledPath, rho=None, parameters=None) -> CoupledPath:
    """:func:`ngtmc.sensitivities.replay` of a monolithic path: the same step types, the same loads
    on displacement steps and the same dD_n on dissipation steps (their loads are solved for).

    Each step starts from the recorded state of ``path`` (alpha kept in [alpha_{n-1}, 1]) and, if
    the coupled Newton fails from there, from the u solve with alpha_{n-1}. Raises RuntimeError
    if it fails at a step."""
    s, c = path.solver, path.coupled
    t0 = time.perf_counter()
    new_rho, pars = replay_inputs(path, rho, parameters)
    base = [path.state(n) for n in range(path.n_steps + 1)]  # before the solver's fields change
    base_loads = path.loads.copy()
    s.rho.vec.FV().NumPy()[:] = new_rho
    _set_parameters(s, pars)
    _reset(s)
    states = [_capture(s)]
    forces = [s.reaction()]
    loads = [0.0]
    for n in range(1, path.n_steps + 1):
        dD = path.dissipation[n]
        dD = None if not np.isfinite(dD) else float(dD)
        lam = float(base_loads[n])
        prev = s.get_state()
        s.u.vec.FV().NumPy()[:] = base[n]["u"]  # holds the boundary values of lam
        s.alpha.vec.FV().NumPy()[:] = np.clip(base[n]["alpha"], s.alpha_committed, 1.0)
        res = c.solve(lam, dissipation=dD)
        if not res.converged:
            s.set_state(prev)
            pre = s.solve_displacement(lam)
            res = c.solve(lam, dissipation=dD) if pre.converged else pre
        if not res.converged:
            raise RuntimeError(f"replay: coupled Newton failed at step {n} (load {lam:.6g} mm"
                               f"{'' if dD is None else f', dD {dD:.6g} N mm'}): {res.message}")
        H = s.trial_history()
        if not np.all(np.isfinite(H)):
            raise RuntimeError(f"replay: history not finite at step {n} (J <= 0 at a history point)")
        s.update_history(H)
        states.append(_capture(s))
        forces.append(s.reaction())
        loads.append(float(c.load_solved))
    return CoupledPath(solver=s, loads=np.asarray(loads), states=states, forces=np.asarray(forces), rho=new_rho,
                       parameters=pars, forward_time=time.perf_counter() - t0, coupled=c, scheme=path.scheme,
                       dissipation=path.dissipation.copy())


# ====================================================================== adjoint engine
def alpha_residual_pieces(s, w):
    """(CF, measure) pairs of <R_alpha(u, alpha; H, p), w>, the alpha rows of the coupled residual
    of :meth:`ngtmc.coupled.monolithic.CoupledNewton._build_form` contracted with ``w`` (a phase-field
    GridFunction, or the test function to assemble the rows themselves), at the solver's fields
    u, alpha and H (= H_{n-1} of the step)."""
    pieces = [(density.Diff(s.alpha, w), s.energy_measure(name, regions)) for name, density, regions in s.energy_terms(s.u)]
    pieces += history_pieces(s, s.u, s.alpha, w)
    pieces.append(phase_field_piece(s, s.alpha, w))
    return pieces


class _CoupledEngine:
    """Forms of the coupled sweep (on top of the single-pass engine's forms), built once per solver."""

    def __init__(self, eng, coupled):
        self.eng = eng
        s = self.s = eng.s
        self.c = coupled
        self.w_a = ngs.GridFunction(s.fes_a)      # alpha part of the step adjoint
        self.alpha_forms = eng._scalar_forms(alpha_residual_pieces(s, self.w_a), with_alpha=False)
        # derivative of <R_alpha, w_a> with respect to H_{n-1} (per unit weight) where the max kept it
        self.dH_cf = eng.frac_ind * (-2.0) * (1.0 - s.alpha) * self.w_a
        # D(a) = 1/2 int Gc (a^2 / l0 + l0 |grad a|^2): its partials in rho and the parameters
        self.a_D = ngs.GridFunction(s.fes_a)
        aD = self.a_D
        dens = 0.5 * phase_field_piece(s, aD, aD)[0]
        self.D_forms = eng._scalar_forms([(dens, eng.dx_af)], with_alpha=False)


def _coupled_engine(path: CoupledPath) -> _CoupledEngine:
    eng = _engine(path)
    ce = getattr(eng, "_coupled_engine", None)
    if ce is None or ce.c is not path.coupled:
        ce = eng._coupled_engine = _CoupledEngine(eng, path.coupled)
    return ce


def held_sets(path: CoupledPath, n: int):
    """(held at alpha_{n-1}, held at 1) of step n: boolean arrays over the phase-field dofs, from the
    recorded states (the converged solve puts held dofs exactly on their bound)."""
    c = path.coupled
    free_a = c._free_base[c.nu:]
    a, a_prev = path.state(n)["alpha"], path.state(n - 1)["alpha"]
    lo = free_a & (a <= a_prev)
    up = free_a & ~lo & (a >= 1.0)
    return lo, up


def coupled_gradient(path: CoupledPath, objective, wrt=("rho", "E", "Gc", "l0", "gamma0")) -> dict:
    """:func:`ngtmc.sensitivities.gradient` of a monolithic path (module docstring)."""
    t0 = time.perf_counter()
    wrt = tuple(wrt)
    s, c = path.solver, path.coupled
    path.activate()
    eng = _engine(path)
    ce = _coupled_engine(path)
    keys = _wrt_keys(s, wrt)
    acc = _Accumulator(s, wrt, keys)
    value = objective.value(path)
    N = path.n_steps
    t = s.thickness
    nu, na = c.nu, s.fes_a.ndof
    diss = path.dissipation_steps
    load_bar = objective.load_seeds(path) if np.any(diss) else np.zeros(N + 1)
    eta = np.zeros(s.irs.ndof)             # adjoint density of H_n (per unit quadrature weight)
    abar_carry = np.zeros(na)              # dJ/dalpha_n through the later steps
    A = c.form.mat
    vec = [A.CreateColVector() for _ in range(2)]

    def tmul(x, transpose=True):
        vec[0].FV().NumPy()[:] = x
        vec[1].data = (A.T if transpose else A) * vec[0]
        return vec[1].FV().NumPy().copy()

    for n in range(N, 0, -1):
        st_prev = path.state(n - 1)
        path.activate(n)
        seeds = objective.seeds(path, n) or Seeds()
        xbar = np.zeros(nu + na)
        xbar[nu:] = abar_carry
        abar = xbar[nu:]  # a view: the seeds' alpha partials land in xbar
        # ---- explicit partials of the objective's CF terms (with H = H_n in the solver)
        for cf, reg, w in seeds.cfs:
            forms = eng.cf_forms(cf, reg)
            forms["u"].Assemble()
            xbar[:nu] += w * t * forms["u"].vec.FV().NumPy()
            acc.add(forms, w * t, abar)
        # ---- history H_n = max(H_{n-1}, Psi_plus(u_n)): eta at the active points goes to u_n
        H_prev = st_prev["H"]
        eta, u_term, mask = history_adjoint(eng, H_prev, eta)
        if u_term is not None:
            xbar[:nu] += u_term
            acc.add(eng.hist_forms, 1.0)
        # ---- the coupled step: tangent at (u_n, alpha_n) with the step's H_{n-1}
        s.H.vec.FV().NumPy()[:] = H_prev
        c._gather()
        c.form.AssembleLinearization(c.x.vec)
        e = np.zeros(nu + na)
        e[:nu] = s.reaction_weight(lam=float(path.loads[n]))  # reaction weight of the force load
        fs = seeds.force * t
        if fs != 0.0:
            xbar += fs * tmul(e)  # F_n = t <R_u(x_n), e>: its derivative in x_n
        held_lo, held_up = held_sets(path, n)
        free = c._free_base.copy()
        free[nu:] &= ~(held_lo | held_up)
        inv = A.Inverse(ngs.BitArray(free.tolist()), inverse="umfpack")

        def solve_t(rhs):
            vec[0].FV().NumPy()[:] = np.where(free, rhs, 0.0)
            vec[1].data = inv.T * vec[0]
            return np.where(free, vec[1].FV().NumPy(), 0.0)

        w_f = solve_t(xbar)
        w_g = 0.0
        m = np.zeros(nu + na)
        if diss[n]:
            m[nu:] = c.D.gradient(path.state(n)["alpha"])  # d D / d alpha_n
            b = solve_t(m)
            e_load = np.zeros(nu + na)  # d u_D / d lambda of every Dirichlet dof (the loads are linear)
            e_load[:nu] = np.where(s._dir_np, s.dirichlet_target(1.0) - s.dirichlet_target(0.0), 0.0)
            r = np.where(free, tmul(e_load, transpose=False), 0.0)  # response of the free rows to the load
            w_g = (float(r @ w_f) - float(e_load @ xbar) - float(load_bar[n])) / float(r @ b)
            w_f = w_f - w_g * b
        # held alpha dofs: their equation alpha_n = bound carries w_c
        w_c = xbar[nu:] - tmul(w_f)[nu:] - w_g * m[nu:]
        abar_carry = np.where(held_lo, w_c, 0.0)
        # ---- partials of the step's equations in p, contracted with -w
        eng.z_u.vec.FV().NumPy()[:] = fs * e[:nu] - w_f[:nu]
        acc.add(eng.res_forms, 1.0)
        ce.w_a.vec.FV().NumPy()[:] = w_f[nu:]
        acc.add(ce.alpha_forms, -1.0)
        eng._irs_tmp.Interpolate(ce.dH_cf)
        eta = eta - np.where(mask, 0.0, eng._irs_tmp.vec.FV().NumPy())
        if diss[n]:
            a_prev = st_prev["alpha"]
            abar_carry = abar_carry + w_g * c.D.gradient(a_prev)
            ce.a_D.vec.FV().NumPy()[:] = path.state(n)["alpha"]
            acc.add(ce.D_forms, -w_g)
            ce.a_D.vec.FV().NumPy()[:] = a_prev
            acc.add(ce.D_forms, w_g)
    path.activate(N)
    return acc.result(value, t0, path.forward_time)
