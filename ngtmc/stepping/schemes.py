"""How the equations of one load step are solved: the solution schemes of a run (``scheme=``).

* ``"single-pass"``: the paper's scheme of :mod:`ngtmc.discrete.solver`: alpha from H_{n-1}, Newton for u,
  history update, once per step; damage lags one step behind the displacement;
* ``"staggered"``: the same pass repeated at the same load until alpha changes by less than
  ``staggered_tol`` (alternate minimisation; converged damage, many passes while a crack runs);
* ``"monolithic"``: Newton on (u, alpha) together with the history of the step inside the
  iteration and alpha >= alpha_{n-1} as an active set (:mod:`ngtmc.coupled.monolithic`); converged damage.
* ``"path-following"``: the monolithic Newton with the load as an unknown where the crack grows
  (dissipation control, :mod:`ngtmc.stepping.path`): a crack that runs unstably is followed through its
  snap-back in steps of a prescribed crack advance; ``"monolithic"`` with
  ``coupled={"path": "dissipation"}``.

:class:`StepSchemes` holds the scheme's options and solves one step at a given load; the
load-stepping loop around it (step sizes, cut-backs, history, checkpoints) is
:class:`ngtmc.simulation.loop.Simulation`, which derives from it.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ngtmc.stepping.control import add_solve, attempt_info
from ngtmc.stepping.secant import secant_displacement
from ngtmc.coupled import CoupledLinearSolver
from ngtmc.coupled import CoupledNewton
from ngtmc.model import check_number
from ngtmc.stepping.path import DissipationPath

__all__ = ["SCHEMES", "PATH_STEPS", "StepSchemes", "alpha_u_passes"]

#: Solution schemes of a load step (see the module docstring).
SCHEMES = ("single-pass", "staggered", "monolithic", "path-following")

#: Under path following, displacement steps are at most 1/PATH_STEPS of the load path
#: (``Schedule.total_time``, mm) unless ``coupled={"du_max": ...}`` says otherwise.
PATH_STEPS = 50


def alpha_u_passes(s, load: float, max_passes: int = 1, info: dict | None = None, staggered_tol: float = 0.0,
                   newton_every: int = 0, coupled_newton=None):
    """alpha-u-H passes of solver ``s`` (:class:`ngtmc.discrete.solver.Solver`) at a fixed ``load`` (mm)
    (Sect. 4 of MODEL.md): alpha from the latest history, Newton for u, trial history. The one
    copy of the step's sequence: the runs' schemes and the adjoint's replays call it.

    One pass (``max_passes=1``) is the paper's scheme; several, until alpha changes by at most
    ``staggered_tol`` (max norm), the converged staggered scheme. ``newton_every`` > 0 calls
    ``coupled_newton(load, info)`` from the current iterate after that many passes, then after
    twice as many passes each time, and stops when it converges (the fallback of the monolithic
    scheme). u may hold a predictor (:meth:`StepSchemes._predict_displacement`) for the first
    pass's Newton. The history is not
    committed: ``info["H_trial"]`` holds the trial history for ``s.update_history``. Returns
    (ok, info dict)."""
    info = info if info is not None else {"newton_iterations": 0, "solve_time": 0.0, "assembly_time": 0.0}
    info.update(staggered_iterations=0, projected=0)
    H_trial = s.H_committed
    alpha_prev_pass = None
    passes = 0
    next_newton = newton_every

    def fail(message):
        info.update(message=message, staggered_iterations=passes)
        return False, info

    if max_passes < 1:
        return fail("no staggered passes allowed")
    for passes in range(1, max_passes + 1):
        info["projected"] = s.solve_phase_field(H_trial)
        if s.alpha is not None and alpha_prev_pass is not None:
            change = s.ranks.max(np.abs(s.alpha.vec.FV().NumPy() - alpha_prev_pass))
            if change <= staggered_tol:
                # alpha from the latest H agrees with the one u is in equilibrium with: keep u
                s.alpha.vec.FV().NumPy()[:] = alpha_prev_pass
                passes -= 1
                break
        res = s.solve_displacement(load)
        add_solve(info, res)
        if not res.converged:
            return fail(res.message)
        if s.alpha is None:
            break  # nothing may break: no history to keep
        H_trial = s.trial_history()
        if not s.ranks.all_finite(H_trial):
            return fail("history not finite (J <= 0 at a history point)")
        if max_passes == 1:
            break
        if newton_every and passes >= next_newton:
            next_newton = 2 * passes  # retries at 10, 20, 40, ... passes
            ok, _ = coupled_newton(load, info)
            if ok:
                info["staggered_iterations"] = passes
                return True, info
        alpha_prev_pass = s.alpha.vec.FV().NumPy().copy()
    else:
        if max_passes > 1 and s.alpha is not None:
            return fail(f"staggered passes did not converge in {max_passes}")
    info.update(staggered_iterations=max(passes, 1), H_trial=H_trial)
    return True, info


#: The keys of ``Simulation(coupled=...)`` that reach :class:`ngtmc.coupled.monolithic.CoupledNewton`.
_COUPLED_KEYS = ("alpha_tol", "max_iterations", "linear_solver", "gmres_rtol", "gmres_maxsteps", "weak_stop",
                 "factor_reuse", "bordered", "relax_dissipation")


class StepSchemes:
    """The solution scheme of a run's load steps (a base of :class:`ngtmc.simulation.loop.Simulation`,
    whose docstring lists the options). Needs ``self.solver`` (:class:`ngtmc.discrete.solver.Solver`) and
    ``self.schedule`` before :meth:`_init_scheme`."""


    @staticmethod
    def _check_scheme(scheme: str, staggered_tol: float):
        """Raise ValueError for an unknown ``scheme`` or a ``staggered_tol`` that is not > 0."""
        if scheme not in SCHEMES:
            raise ValueError(f"scheme = {scheme!r} is not one of {', '.join(map(repr, SCHEMES))}")
        check_number("staggered_tol", staggered_tol, "dimensionless")
        if not (staggered_tol > 0):
            raise ValueError(f"staggered_tol = {staggered_tol!r} must be > 0")

    def _init_scheme(self, scheme: str, staggered_tol: float, max_staggered: int, coupled: dict | None, control):
        """Parse the scheme's options, build the coupled Newton and the dissipation path it needs,
        and return the step control (under path following its du_max is the path's bound)."""
        schedule = self.schedule
        self.scheme = scheme
        self.staggered_tol = float(staggered_tol)
        if isinstance(max_staggered, bool) or not isinstance(max_staggered, int) or max_staggered < 1:
            raise ValueError(f"max_staggered = {max_staggered!r} must be an integer >= 1 (passes of the staggered scheme)")
        self.max_staggered = int(max_staggered)
        self.coupled = None
        if coupled is not None and not isinstance(coupled, dict):
            raise TypeError(f"coupled must be a dict of the monolithic scheme's options (e.g. "
                            f"{{'linear_solver': 'umfpack'}}) or None, got {type(coupled).__name__} {coupled!r}")
        copt = dict(coupled or {})
        if scheme == "path-following":
            copt.setdefault("path", "dissipation")
        self.fallback_passes = int(copt.pop("fallback_passes", 400))
        self.newton_every = int(copt.pop("newton_every", 10))
        self.fallback = str(copt.pop("fallback", "staggered"))
        if self.fallback not in ("single-pass", "staggered", "capped"):
            raise ValueError(f"coupled fallback = {self.fallback!r} is not one of 'single-pass', 'staggered', 'capped'")
        self.damage_cap = float(copt.pop("damage_cap", 0.25))
        self.max_substeps = int(copt.pop("max_substeps", 200))
        self.path = copt.pop("path", None)
        if self.path not in (None, "dissipation"):
            raise ValueError(f"coupled path = {self.path!r} is not one of None (load control), 'dissipation'")
        self.crack_advance = copt.pop("crack_advance", None)
        self.crack_front = copt.pop("crack_front", None)
        self.growth_ceiling = copt.pop("growth_ceiling", "auto")
        if not (isinstance(self.growth_ceiling, bool) or self.growth_ceiling == "auto"):
            raise ValueError(f"coupled growth_ceiling = {self.growth_ceiling!r} must be True, False or 'auto'")
        if self.crack_front is not None and not (float(self.crack_front) > 0 and self.solver.dim == 3):
            raise ValueError(f"coupled crack_front = {self.crack_front!r} mm must be > 0, and is for 3D scenes only "
                             "(in 2D the dissipation is per mm of thickness)")
        self.prescale, self.chord = copt.pop("prescale", False), copt.pop("chord", False)
        for key, value in (("prescale", self.prescale), ("chord", self.chord)):
            if not isinstance(value, bool):
                raise ValueError(f"coupled {key} = {value!r} must be True or False")
        path_du_max = copt.pop("du_max", None)
        if self.crack_advance is not None and not (float(self.crack_advance) > 0):
            raise ValueError(f"coupled crack_advance = {self.crack_advance!r} mm must be > 0")
        self._coupled_options = dict(copt)
        if "linear_solver" in copt or "gmres_rtol" in copt:   # checked whether the scheme uses them or not
            CoupledLinearSolver.check(copt.get("linear_solver", "block-gmres"), copt.get("gmres_rtol", 1e-8))
        unknown = sorted(set(copt) - set(_COUPLED_KEYS))
        if unknown:
            raise ValueError(f"coupled: unknown option(s) {unknown}; the coupled options are {', '.join(_COUPLED_KEYS)}")
        #: the displacement and load (mm) of the accepted state before the last one, and the
        #: mesh generation they belong to, for :meth:`_predict_displacement` (None: no such state)
        self._u_before = None
        #: whether the displacement Newton starts from the secant predictor
        #: (:meth:`_predict_displacement`); False: from the last accepted state, as the replays of
        #: the adjoint's recorded paths do (:func:`ngtmc.sensitivities.record_path`)
        self.secant_predictor = True
        if scheme in ("monolithic", "path-following") and self.solver.alpha is not None:
            self.coupled = CoupledNewton(self.solver, **copt)
        self._path = None
        if self.coupled is not None and self.path == "dissipation":
            self._path = DissipationPath(
                self, self.crack_advance, self.crack_front, self.growth_ceiling, prescale=self.prescale, chord=self.chord,
                coupled_step=lambda load, info: self._coupled_newton(load, info),
                fixed_step=lambda load, info, saved: self._coupled_or_fallback(load, info, saved))
            # a displacement step of the monolithic scheme carries no lag, so its size does not set
            # the accuracy: bound it by the curve's resolution (1/PATH_STEPS of the load path), not
            # by the du_max of the lagged schemes' Eq. 20
            if path_du_max is None:
                path_du_max = max(control.du_max, schedule.total_time / PATH_STEPS)
            check_number("coupled du_max (largest load increment under path following)", path_du_max, "mm")
            if not float(path_du_max) >= control.du_min:
                raise ValueError(f"coupled du_max = {path_du_max!r} mm must be >= du_min = {control.du_min} mm")
            control = dataclasses.replace(control, du_max=float(path_du_max))
        elif path_du_max is not None:
            raise ValueError("coupled du_max applies to path following only (scheme='path-following')")
        return control

    # ------------------------------------------------------------------ one step
    def _attempt(self, t_new: float):
        """Try the step to pseudo-time t_new. Returns (ok, info dict)."""
        load = self.schedule.load(t_new)
        if self._path is not None:
            return self._path.attempt(t_new)
        if self.coupled is not None:
            return self._attempt_monolithic(load)
        self._predict_displacement(load)
        return self._passes(load, 1 if self.scheme == "single-pass" else self.max_staggered)

    def _predict_displacement(self, load: float) -> bool:
        """Start the displacement Newton of the step to ``load`` (mm) from the secant through the
        last two accepted displacements (:func:`ngtmc.stepping.secant.secant_displacement`)
        instead of the last one. The Newton converges to the same state (its tolerance); where
        the path is smooth it starts close to it, so that the first iteration is no longer spent
        carrying the boundary increment (the quick L-panel's case monotonic: 434 -> 313 Newton
        iterations in the same 198 steps, docs/performance.md). Not after a reversal of the load
        (ratio <= 0), a mesh change, or where the secant would invert an element. Returns whether
        the predictor was taken."""
        prev = self._u_before
        s = self.solver
        if not self.secant_predictor or prev is None or prev[2] != s.mesh_generation or s.load == prev[1]:
            return False
        ratio = (load - s.load) / (s.load - prev[1])
        return secant_displacement(s, s.u.vec.FV().NumPy().copy(), prev[0], ratio, load) is not None

    def _remember_displacement(self, before: dict):
        """After an accepted step: ``before`` (a solver state on the current mesh, the state the
        step started from, whose arrays are the caller's own copies) becomes the secant's previous
        point (:meth:`_predict_displacement`)."""
        if self._path is None and self.secant_predictor:
            self._u_before = (np.asarray(before["u"], dtype=float), float(before["load"]), self.solver.mesh_generation)

    def _passes(self, load: float, max_passes: int, info: dict | None = None, newton_every: int = 0):
        """:func:`alpha_u_passes` with this run's ``staggered_tol`` and coupled Newton."""
        return alpha_u_passes(self.solver, load, max_passes, info, staggered_tol=self.staggered_tol,
                              newton_every=newton_every, coupled_newton=self._coupled_newton)

    def _coupled_newton(self, load: float, info: dict, alpha_upper=None):
        """Coupled Newton from the current (u, alpha); on failure the iterate is restored."""
        s = self.solver
        keep = s.get_state()
        res = self.coupled.solve(load, alpha_upper)
        add_solve(info, res)
        if res.converged:
            s._r_valid = False
            H_trial = s.trial_history()
            if s.ranks.all_finite(H_trial):
                info["H_trial"] = H_trial
                return True, info
            res.message = "history not finite (J <= 0 at a history point)"
        s.set_state(keep)
        info["message"] = res.message
        return False, info

    def _attempt_monolithic(self, load: float):
        """Monolithic step: a predictor (Newton for u with alpha_{n-1}, the robust energy-guarded
        solver of the contact problem), then the coupled Newton on (u, alpha).

        Where the coupled Newton fails (a crack that runs unstably at this load has no nearby
        solution, or the hybrid coupling of nearly broken elements defeats it), the step falls
        back according to ``coupled["fallback"]``:

        * "staggered" (default): staggered passes at the same load, the coupled Newton tried
          again after ``newton_every``, 2 ``newton_every``, 4 ``newton_every``, ... passes; the
          step stays converged (``staggered_iterations`` counts the passes, 0 for a step of the
          coupled Newton alone);
        * "single-pass": the paper's single pass from the state of the last step, so the crack
          runs through lagged steps as in the paper and the coupled Newton takes over again at the
          next step;
        * "capped": coupled sub-steps with a capped damage increase (``_capped_substeps``), then
          staggered passes.

        Measured on the notched plate (tests/test_monolithic.py) and the three-point bending:
        docs/performance.md."""
        s = self.solver
        saved = s.get_state() if self.fallback == "single-pass" else None
        info = attempt_info()
        self._predict_displacement(load)
        res = s.solve_displacement(load)
        add_solve(info, res)
        if not res.converged:
            info["message"] = res.message
            return False, info
        return self._coupled_or_fallback(load, info, saved)

    def _coupled_or_fallback(self, load: float, info: dict, saved: dict | None):
        """The coupled Newton at the fixed ``load`` from the current (predicted) state and, where
        it fails, the fallback of ``coupled["fallback"]`` (:meth:`_attempt_monolithic`); ``saved``: the
        state before the step, which the "single-pass" fallback starts from. The one owner of the
        fallback policy: the monolithic scheme's steps and path following's displacement steps
        (:meth:`ngtmc.stepping.path.DissipationPath._fixed`) both end here."""
        s = self.solver
        ok, info = self._coupled_newton(load, info)
        if ok:
            return True, info
        if self.fallback == "single-pass":
            s.set_state(saved)
            return self._passes(load, 1, info)
        if self.fallback == "capped":
            ok, info = self._capped_substeps(load, info)
            if ok:
                return True, info
        return self._passes(load, self.fallback_passes, info, newton_every=self.newton_every)

    def _capped_substeps(self, load: float, info: dict):
        """Carry a crack that runs at this load by coupled sub-steps whose damage increase is capped:
        sub-step k solves the coupled equations with alpha <= alpha^(k-1) + cap (still alpha >=
        alpha_{n-1}); the crack advances by at most ``cap`` per dof and sub-step, so each sub-step
        has a nearby solution. It ends when no cap binds (the state is then the equilibrium of the
        step, as for the uncapped Newton); a failing sub-step halves the cap down to cap / 16."""
        s = self.solver
        cap = self.damage_cap
        substeps = 0
        while substeps < self.max_substeps:
            upper = s.alpha.vec.FV().NumPy() + cap
            ok, info = self._coupled_newton(load, info, upper)
            if not ok:
                cap /= 2.0
                if cap < self.damage_cap / 16:
                    info["message"] = f"capped coupled sub-steps failed ({info.get('message', '')})"
                    return False, info
                continue
            substeps += 1
            info["substeps"] = substeps
            if not self.coupled.cap_binding:
                return True, info
        info["message"] = f"capped coupled sub-steps: no equilibrium in {self.max_substeps} sub-steps"
        return False, info
