"""From a scene and a load schedule to a recorded history: the load-stepping loop.

    sim = Simulation(scene, Schedule([0, 0.15]), AdaptiveStepControl(du_max=5e-4, k_u=1000))
    result = sim.run()
    result.history          # pandas DataFrame, one row per accepted step
    result.units            # column -> unit

Each accepted step solves the equations of the step by one of four schemes (``scheme=``:
``"single-pass"``, the paper's, ``"staggered"``, ``"monolithic"`` and ``"path-following"``), described
and implemented in :mod:`ngtmc.stepping.schemes`, the base of :class:`Simulation`.

A step that fails (Newton does not converge) is retried with half the increment; a run that fails
at the minimum increment raises :class:`StepFailure`, which carries the history recorded so far.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
import math
import time
from typing import Callable, Iterator, Sequence

import numpy as np
import pandas as pd

from ngtmc.stepping import N_S as PATH_N_S
from ngtmc.simulation.history import HISTORY_UNITS as _HISTORY_UNITS, peak, peak_index
from ngtmc.scene import Scene
from ngtmc.stepping import PATH_STEPS, SCHEMES, StepSchemes
from ngtmc.discrete import NewtonOptions, Solver, blas_limited
from ngtmc.simulation.records import RunRecords
from ngtmc.simulation.refine import RunRefinement
from ngtmc.simulation.state import RunState
from ngtmc.stepping import AdaptiveStepControl, ControlState, Schedule
from ngtmc.simulation.options import check_options, simulation_keywords
from ngtmc.adapt import Adaptivity, check_solver, private_scene
from ngtmc.adapt import Remesher
from ngtmc.model import check_number
from ngtmc.scene import check_supported
from ngtmc.scene import check_load_scale
from ngtmc.simulation.history import force_unit
from ngtmc.simulation.plugins import Progress

__all__ = ["Simulation", "SimulationResult", "StepFailure", "HISTORY_UNITS", "SCHEMES", "PATH_STEPS", "check_stop_after_drop"]

#: Units of the history columns (force and energies are for the scene thickness in 2D); defined
#: once, in :mod:`ngtmc.study.run_files`.
HISTORY_UNITS = _HISTORY_UNITS


class StepFailure(RuntimeError):
    """A load step failed at the minimum increment. ``history`` holds every accepted step so far,
    ``state`` the solver state of the last accepted step."""

    def __init__(self, message: str, history: pd.DataFrame, state: dict | None = None):
        super().__init__(message)
        self.history = history
        self.state = state


@dataclass
class SimulationResult:
    """Outcome of :meth:`Simulation.run`: the history (DataFrame), its units, and the solver in its
    final state (fields ``u``, ``alpha``, ``rho`` for plotting or post-processing)."""

    history: pd.DataFrame
    units: dict
    solver: Solver
    wall_time: float
    #: the run folder, for ``simulate(..., out_dir=...)``; None for a run kept in memory
    run_dir: Path | None = None

    @property
    def peak_force(self) -> float:
        """Largest recorded force (:func:`ngtmc.simulation.history.peak`), in ``units["force"]`` (N, or N/mm in
        2D with thickness 1 mm); NaN when no force is finite."""
        f, _ = peak(self.history["force"], self.history["load"])
        return math.nan if f is None else f

    def reaction_vector(self):
        """The nodal reactions of the final state (N, per unit thickness times the scene's thickness
        in 2D), one entry per displacement dof, zero on the free dofs:
        :meth:`ngtmc.discrete.solver.Solver.reaction_vector`."""
        return self.solver.reaction_vector()

    @property
    def peak_load(self) -> float:
        """Applied displacement at the largest force (:func:`ngtmc.simulation.history.peak`), mm; NaN when no
        force is finite."""
        _, x = peak(self.history["force"], self.history["load"])
        return math.nan if x is None else x


def check_stop_after_drop(value, schedule: Schedule | None = None):
    """Raise TypeError or ValueError (naming ``stop_after_drop``) unless ``value`` is a fraction of
    the peak force in (0, 1), and, with ``schedule``, unless that schedule is monotonic (one
    segment: unloading would drop the force and stop the run)."""
    check_number("stop_after_drop", value, "dimensionless")
    if not (0.0 < value < 1.0):
        raise ValueError(f"stop_after_drop = {value!r} is outside the allowed range (0, 1) "
                         "(a fraction of the peak force; None: the whole schedule)")
    if schedule is not None and len(schedule.points) > 2:
        raise ValueError(f"stop_after_drop needs a monotonic schedule (one segment); this one turns at "
                         f"{', '.join(f'{x:g}' for x in schedule.points[1:-1])} mm, where unloading would "
                         "drop the force and stop the run")


class Simulation(RunRecords, RunState, RunRefinement, StepSchemes):
    """Load-stepping run of a scene (see the module docstring).

    Parameters
    ----------
    scene : Scene
    schedule : Schedule or float
        Load schedule (mm); a number means monotonic loading from 0 to that value.
    control : AdaptiveStepControl, optional
        Step-size rule; default constant steps of 1/20 of the first segment.
    scheme : "single-pass", "staggered", "monolithic" or "path-following"
        How the equations of a step are solved (:mod:`ngtmc.stepping.schemes`).
    staggered_tol : float
        Largest change of alpha between two passes for "staggered", dimensionless.
    max_staggered : int
        Pass limit for "staggered" (the step counts as failed beyond it).
    coupled : dict, optional
        Options of the "monolithic" scheme: ``alpha_tol``, ``max_iterations``, ``linear_solver``,
        ``relax_dissipation`` of :class:`ngtmc.coupled.monolithic.CoupledNewton`; ``fallback`` ("single-pass", "capped" or
        "staggered", where the coupled Newton fails at a fixed load: the monolithic scheme's steps
        and path following's displacement steps taken instead of a dissipation step; see
        ``StepSchemes._attempt_monolithic``); ``damage_cap`` (default 0.25) and
        ``max_substeps`` (default 200) of its capped sub-steps; ``fallback_passes`` (default 400)
        and ``newton_every`` (default 10) of its staggered fallback;
        ``path`` (None, or "dissipation" for path following, the default of
        ``scheme="path-following"``), ``crack_advance`` (mm per dissipation step, default the
        mean l0 of the fracture regions) and, in 3D, ``crack_front`` (mm, the length of the crack
        front that advances; default the thinnest side of the fracture regions' bounding box;
        :mod:`ngtmc.stepping.path`), ``growth_ceiling`` (True: a cut-back of a dissipation step caps the
        growth of the next ones, :data:`ngtmc.stepping.sizing.GROWTH_CEILING_STEPS`; default "auto": a ceiling
        where the crack, the elements with alpha >= 0.5, is meshed no coarser than 1.5 l0
        (:data:`ngtmc.stepping.sizing.CEILING_MAX_H`),
        :meth:`ngtmc.stepping.sizing.DissipationSizing.ceiling_applies`), ``prescale`` (True: after a
        dissipation step, a dissipation step whose secant predictor moves the load by more than
        du_max is scaled down before it is solved, rule 3 of :mod:`ngtmc.stepping.path`; default False: only
        after), ``chord`` (True: rule 3's solve at the smaller dD starts from the chord to the long
        step's converged state; default False: from the secant predictor) and ``weak_stop`` (default True,
        :data:`ngtmc.coupled.settings.WEAK_STOP`).
    newton : NewtonOptions, optional
    progress : bool or callable
        True prints a progress line to stderr about every 5 s (:class:`ngtmc.simulation.plugins.Progress`, the
        one progress printer of ngtmc); a callable receives each row dict.
    max_steps : int
        Safety limit on accepted steps.
    stop_after_drop : float, optional
        Stop once the force has fallen below this fraction of its largest value so far, after
        that peak (dimensionless, in (0, 1); None, the default: the whole schedule). For runs that
        need the peak and the drop (the crack has run), not the post-failure tail, which can cost
        most of a run (the quick Miehe set-up of the three-point bending: the tail from half the
        peak to 0.06 mm took about three quarters of its time). :attr:`finished` is then True.
        Monotonic schedules only (unloading would drop the force too).
    compile : "auto", True, "real" or False
        How the energy expressions are compiled (see :class:`ngtmc.discrete.solver.Solver`).
    adapt : Adaptivity, optional
        Refine the mesh during the run where the crack is or is about to be (and, with
        ``h_void``, where the void is squeezed), re-solving each step on the refined mesh
        (:mod:`ngtmc.adapt`). The run refines a copy of the scene's mesh (the scene passed in is
        not changed); the final mesh is ``solver.mesh`` and the scene on it ``solver.scene``. The
        history gains the columns ``dofs`` and ``elements``.
    """

    def __init__(self, scene: Scene, schedule: Schedule | float, control: AdaptiveStepControl | None = None,
                 scheme: str = "single-pass", staggered_tol: float = 1e-3, max_staggered: int = 30,
                 newton: NewtonOptions | None = None, progress: bool | Callable = False,
                 max_steps: int = 100000, compile: bool | str = "auto", coupled: dict | None = None,
                 adapt=None, stop_after_drop: float | None = None, **unknown):
        if unknown:   # a removed or misspelt keyword: named, with its replacement
            check_options(unknown, simulation_keywords(type(self)), "ngtmc.Simulation")
        if not isinstance(scene, Scene):
            raise TypeError(f"scene must be an ngtmc.Scene, got {type(scene).__name__}")
        if not isinstance(schedule, Schedule):
            check_number("schedule (a Schedule, or the final load)", schedule, "mm")
            schedule = Schedule.monotonic(float(schedule))
        if control is not None and not isinstance(control, AdaptiveStepControl):
            hint = (f"; write AdaptiveStepControl(**{control!r})" if isinstance(control, dict) else "")
            raise TypeError(f"control must be an ngtmc.AdaptiveStepControl (du_max mm, k_u 1/N, du_min mm, n_s), "
                            f"or None for constant steps; got {type(control).__name__}{hint}")
        if control is None:
            control = AdaptiveStepControl(du_max=abs(schedule.points[1]) / 20.0, du_min=abs(schedule.points[1]) * 1e-9)
        self._check_scheme(scheme, staggered_tol)
        check_supported(scene, adapt)
        if adapt is not None:
            if not isinstance(adapt, Adaptivity):
                raise TypeError(f"adapt must be an ngtmc.Adaptivity (h_crack mm, ...), got {type(adapt).__name__}")
            scene = private_scene(scene)  # the run refines its own copy of the mesh
        self.adapt = adapt
        self.scene = scene
        self.schedule = schedule
        self.control = control
        self.progress = progress
        if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1:
            raise ValueError(f"max_steps = {max_steps!r} must be an integer >= 1 (a safety limit on accepted steps)")
        self.max_steps = int(max_steps)
        if stop_after_drop is not None:
            check_stop_after_drop(stop_after_drop, schedule)
        self.stop_after_drop = stop_after_drop
        self._solver_options = dict(newton=newton, compile=compile, refine_to=None if adapt is None else adapt.h_crack)
        self.solver = Solver(scene, **self._solver_options)     # checks the scene first
        check_load_scale(scene, schedule.points)
        #: the size restrictions of a run refined by remeshing (:class:`ngtmc.adapt.remesh.Remesher`)
        self._remesher = None
        if adapt is not None:
            check_solver(self.solver, remesh=adapt.remesh_maxh is not None, adapt=adapt)
            self.adapt = adapt = adapt.resolved(self.solver)   # corridor "auto" -> its half width, mm
            if adapt.remesh_maxh is not None:
                self._remesher = Remesher(scene.mesh, adapt.remesh_maxh)
        #: refinements of the run (:class:`ngtmc.adapt.RefinementRecord`, with the step they followed)
        self.refinements: list = []
        self.control = control = self._init_scheme(scheme, staggered_tol, max_staggered, coupled, control)
        self.t = 0.0
        self.step = 0
        self.rows: list[dict] = []
        self.last_delta_wf = 0.0
        #: run state of the step control (scale, successes); the control itself holds none
        self.control_state: ControlState = control.initial_state()
        self._wf_prev = 0.0
        self._elapsed_before = 0.0
        self._t_start = None
        #: force unit of this scene's history (:func:`ngtmc.simulation.history.force_unit`)
        self.force_unit = force_unit(scene.dim, scene.thickness)
        # a scene distributed over MPI ranks: every rank holds the same history; rank 0 reports it
        self._progress = Progress(progress if scene.mesh.comm.rank == 0 else False, "[ngtmc]", self.force_unit)
        self._record(step_size=0.0, newton_iterations=0, staggered_iterations=0, cutbacks=0,
                     solve_time=0.0, assembly_time=0.0, projected=0)

    @property
    def finished(self) -> bool:
        """True at the end of the schedule, or once the force has dropped (``stop_after_drop``)."""
        return self.t >= self.schedule.total_time * (1 - 1e-14) or self.dropped

    @property
    def dropped(self) -> bool:
        """Whether the force has fallen below ``stop_after_drop`` times its largest value so far,
        after that peak (False without ``stop_after_drop``)."""
        if self.stop_after_drop is None or len(self.rows) < 2:
            return False
        f = np.array([r["force"] for r in self.rows], dtype=float)
        i = peak_index(f)
        return bool(i is not None and f[i] > 0 and i < f.size - 1 and f[-1] < self.stop_after_drop * f[i])

    # ------------------------------------------------------------------ one step

    def advance(self) -> dict:
        """Take one accepted step (with cut-backs as needed); return its history row. numpy's and
        scipy's BLAS run on one thread meanwhile (:mod:`ngtmc.discrete.blas_threads`).

        Raises StepFailure when the step fails at the minimum increment."""
        with blas_limited():
            return self._advance()

    def _advance(self) -> dict:
        if self._t_start is None:
            self._t_start = time.perf_counter()
        s = self.solver
        ctrl = self.control
        t_turn = self.schedule.next_turning_time(self.t)
        # under dissipation control the dissipation per step is bounded by the path, not by Eq. 20
        du = ctrl.proposal(0.0 if self._path is not None else self.last_delta_wf, self.control_state)
        saved = s.get_state()
        cutbacks = after_refinement = 0
        n_refinements = len(self.refinements)   # a cut-back after one of this step's refinements is the mesh's doing
        totals = {"newton_iterations": 0, "solve_time": 0.0, "assembly_time": 0.0}
        while True:
            if self.t + du >= t_turn - 1e-12 * max(1.0, t_turn) or t_turn - (self.t + du) < 1e-3 * ctrl.du_min:
                t_new = t_turn
            else:
                t_new = self.t + du
            ok, info = self._attempt(t_new)
            for k in totals:
                totals[k] += info[k]
            if ok and self.adapt is not None:
                ok, info, saved = self._refine_and_resolve(t_new, info, saved, totals)
                s = self.solver   # a remeshed run has a new solver
            if ok:
                t_new = info.get("t_new", t_new)  # path following solves for the load
                break
            s.set_state(saved)
            cutbacks += 1
            after_refinement += len(self.refinements) > n_refinements
            self.control_state, smaller = ctrl.failed(self.control_state, t_new - self.t)
            if smaller is None:
                unit = "" if self.scene.force_controlled else " mm"  # lambda scales tractions
                msg = (f"step from load {self.schedule.load(self.t):.6g}{unit} failed at the minimum increment "
                       f"du_min = {ctrl.du_min:g} mm ({info.get('message', '')}); {len(self.rows)} accepted steps are in "
                       f"the history carried by this exception")
                peak = self._force_control_peak()
                if peak:
                    msg = peak + " " + msg
                raise StepFailure(msg, self.history, saved)
            du = smaller
        step_size = abs(self.schedule.load(t_new) - self.schedule.load(self.t)) if t_new != self.t else 0.0
        if s.alpha is not None:
            s.update_history(info["H_trial"])
        self._remember_displacement(saved)
        self.t = t_new
        self.step += 1
        self.control_state = ctrl.accepted(self.control_state, n_s=PATH_N_S if self._path is not None else None)
        wf = s.fracture_energy_per_thickness()
        row = self._record(wf=wf, step_size=step_size, staggered_iterations=info["staggered_iterations"],
                           cutbacks=cutbacks, projected=info["projected"], **totals)
        self.last_delta_wf = wf - self._wf_prev
        self._wf_prev = wf
        if self._path is not None:
            # a failed re-solve on a refined mesh, and a failed attempt after it from the state
            # carried to that mesh, are the mesh's doing, not the step size's: they cut the step
            # back, but set no ceiling on dD (docs/adaptivity.md, "A refinement's failed re-solve
            # sets no ceiling on dD", "The corridor's line on the crack, its strip kept, and no
            # ceiling after a refinement")
            self._path.accepted(step_size, totals["newton_iterations"], cutbacks - after_refinement)
        self._report_progress(row)
        return row

    def _force_control_peak(self) -> str:
        """Under force control (only Traction loads), a message when the last accepted steps show a
        falling stiffness d force / d displacement of the force load: the failed step is then past a
        limit point, which force control cannot pass. Empty string otherwise."""
        sc = self.scene
        if not sc.force_controlled or len(self.rows) < 3:
            return ""
        name = sc.force_load.label
        f = np.array([r["force"] for r in self.rows[-3:]])
        u = np.array([r[f"displacement_{name}"] for r in self.rows[-3:]])
        du = np.diff(u)
        if np.any(du == 0.0):
            return ""
        k = np.diff(f) / du
        if not (abs(k[1]) < abs(k[0])):
            return ""
        return (f"force control cannot pass a peak: the stiffness of traction {name!r} fell from {k[0]:.4g} to "
                f"{k[1]:.4g} N/mm over the last steps and no equilibrium was found beyond force {f[-1]:.6g} N "
                f"(displacement {u[-1]:.6g} mm); the force-displacement curve has a limit point here. Use a "
                f"displacement load (DisplacementLoad or DisplacementField) to follow the curve past it.")

    # ------------------------------------------------------------------ whole run
    def steps(self) -> Iterator[dict]:
        """Advance to the end of the schedule, yielding the history row of each accepted step (a
        dict, units in :attr:`units`) as soon as it is accepted; the simulation's state is then
        that of the step (fields, :meth:`get_state`, :attr:`finished`)::

            for row in sim.steps():
                print(row["load"], row["force"])

        Raises StepFailure (with the history so far) if a step fails at the minimum increment, or
        when ``max_steps`` is reached. A run folder's outputs are plugins on these rows
        (:mod:`ngtmc.simulation.plugins`)."""
        while not self.finished:
            if self.step >= self.max_steps:
                raise StepFailure(f"max_steps = {self.max_steps} reached at load {self.solver.load:.6g} mm",
                                  self.history, self.solver.get_state())
            yield self.advance()

    def run(self, callbacks: Sequence[Callable[["Simulation", dict], None]] = ()) -> SimulationResult:
        """Advance to the end of the schedule (:meth:`steps`). ``callbacks`` are called as
        f(simulation, row) after every accepted step (snapshots, checkpoints). Raises StepFailure
        (with the history so far) if a step fails at the minimum increment."""
        for row in self.steps():
            for cb in callbacks:
                cb(self, row)
        return SimulationResult(self.history, self.units, self.solver, self._elapsed())
