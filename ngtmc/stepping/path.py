"""Path following for the monolithic scheme: dissipation control where the crack grows.

Under displacement control a crack that runs unstably has no equilibrium near the last one at
the next load (a snap-back), so a fixed-load Newton fails there, and the alternating schemes
carry the crack about one element per pass. Under dissipation control (Gutierrez 2004; May,
Vignollet and de Borst 2016 for phase fields) the load is an unknown, and a step is closed by
prescribing how much energy it dissipates:

    D(alpha) - D(alpha_{n-1}) = dD,        D = int Gc (alpha^2 / l0 + l0 |grad alpha|^2) / c_w

(N mm per mm of thickness in 2D), so that the step advances the crack by about
``crack_advance = dD / Gc`` (mm) whatever the load does, and the load may fall back along a
snap-back.

The rule of a step, for the step size du (mm) that the step control proposes (Eq. 20 is not
applied: it bounds the dissipation per step, which the path now does itself):

1. Predict the dissipation of a displacement step from the rate dD / d(load) of the last step.
   If it stays below dD / 2, take a displacement step (the coupled Newton at fixed load); accept it if
   it dissipated at most 2 dD.
2. Otherwise, or if that step failed or dissipated more, take a dissipation step: a predictor at
   the load where the rate says dD is reached, then the coupled Newton with the load as unknown
   (:meth:`ngtmc.coupled.monolithic.CoupledNewton.solve` with ``dissipation``). Its load must stay on the
   current segment of the schedule; if it would pass the segment's end, the step is a
   displacement step to that end.
3. A dissipation step that moves the load by more than du_max is solved again with the
   dissipation scaled down in proportion (0.9 du_max / |load change|) (with ``chord``, from the
   chord to the state it converged to); if the load still moves too far, the crack has stopped and
   the step is a displacement step of du. So is the last attempt of a step (du below 2 du_min)
   whose dissipation solve failed (an arrested crack, or a solve stalled at every dD); only the
   last: doing so on every such failure turned legitimate snaps into displacement steps
   (tests/test_extrude.py). With ``prescale`` (off by default), where the secant predictor
   (rule 6) already moves the load by more than du_max, dD is scaled so before the first solve.
   A displacement step on a step's last attempt whose coupled Newton fails ends in the scheme's
   fallback (``coupled["fallback"]``; ``staggered_iterations`` > 0).
4. On a new segment of the schedule (after a turning point) the rule starts afresh: rate 0,
   displacement steps first (an unloading segment does not dissipate).
5. After a dissipation step the next step is a dissipation step too (in stable growth after a
   crack run a fixed-load Newton creeps: each element's advance is a small snap-back), unless
   the step had to be scaled below a quarter of dD (slow growth).
6. Every step starts from the secant predictor through the last two accepted states
   (:mod:`ngtmc.stepping.predictor`), or, without it, from the u solve with alpha_{n-1}.

dD = Gc_ref ``crack_advance`` (times the crack front's length ``crack_front`` in 3D) times the
step control's scale, which halves on a failed step and doubles back after successes like the load
increments (Gc_ref the mean Gc of the fracture regions, N/mm), times a growth factor that grows
where the damage grows stably and is held below a ceiling after cut-backs (:mod:`ngtmc.stepping.sizing`).

Units: mm, N, MPa; D per mm of thickness in 2D.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from ngtmc.stepping.predictor import SecantPredictor
from ngtmc.stepping.refine import PathAcrossRefinement
from ngtmc.stepping.sizing import DissipationSizing
from ngtmc.stepping.control import add_solve, attempt_info

__all__ = ["DissipationPath"]

#: Under path following the step control's scale doubles after every successful step, whatever its
#: n_s (the paper's 5 applies to the other schemes): the dissipation per step keeps its own memory
#: of cut-backs. With n_s = 5, crack runs went on in displacement steps near du_min for about a
#: hundred steps (the paper L-panel at 6.2078 mm; the three-point bending in Miehe's set-up; docs/
#: performance.md, "The step control's scale under path following").
N_S = 1

#: Rule 3: a dissipation step whose load moves (or is predicted to move) more than du_max is sized
#: to move it by this fraction of du_max.
BOUNDED_FRACTION = 0.9

class DissipationPath(PathAcrossRefinement):
    """Step rule of the path-following monolithic scheme (module docstring) for a
    :class:`ngtmc.simulation.loop.Simulation`; a refinement within a step goes on through the methods of
    :class:`~ngtmc.stepping.refine.PathAcrossRefinement`.

    Parameters
    ----------
    sim : Simulation
        With ``scheme="path-following"`` (or "monolithic" and ``coupled={"path": "dissipation"}``)
        on a scene with fracture regions.
    crack_advance : float, optional
        Crack advance per dissipation step, mm (default: the mean l0 of the fracture regions).
    crack_front : float, optional
        3D only: length of the crack front that advances, mm, so that a dissipation step is
        Gc crack_advance crack_front (N mm). Default: the thinnest side of the bounding box of the
        fracture regions (the slab's thickness for an extruded slab, so a plane-strain slab takes
        the steps of its 2D twin times its thickness; tests/test_extrude.py).
    growth_ceiling : bool or "auto"
        Whether cut-backs cap the growth of dD (:mod:`ngtmc.stepping.sizing`).
    prescale : bool
        Rule 3 before the solve as well as after it (module docstring). Off by default: it
        paid in the quick 3D hemisphere's tail and not in the quick 2D three-point bending.
    chord : bool
        Rule 3's solve at the smaller dD from the chord to the long step's converged state
        (:meth:`~ngtmc.stepping.predictor.SecantPredictor.chord`), not from the secant predictor.
        Off by default: measured in docs/performance.md ("Path following and its options").
    coupled_step, fixed_step : callable
        ``(load, info) -> (converged, info)``: the coupled Newton at a fixed load from the current
        state (restored on failure), and the same with the scheme's fallback where it fails
        (``coupled["fallback"]``); the simulation hands them in.
    """

    def __init__(self, sim, crack_advance: float | None = None, crack_front: float | None = None,
                 growth_ceiling: bool | str = "auto", prescale: bool = False, chord: bool = False, *,
                 coupled_step: Callable, fixed_step: Callable):
        self.sim, self.coupled_step, self.fixed_step = sim, coupled_step, fixed_step
        #: rule 3 before the solve, and its re-solve from the chord (module docstring)
        self.prescale, self.chord = bool(prescale), bool(chord)
        self.coupled = c = sim.coupled
        s = sim.solver
        #: the fracture regions' mean l0, mm (default crack advance; the crack's resolution of
        #: growth_ceiling="auto")
        self.l0_ref = float(c.D.fracture_mean(s.l0))
        self.crack_advance = float(crack_advance) if crack_advance is not None else self.l0_ref
        if s.dim == 3 and crack_front is None:
            lo, hi = s.fracture_box()
            crack_front = float(np.min(hi - lo))
        #: length of the advancing crack front, mm (3D); 1 in 2D, where D is per mm of thickness
        self.crack_front = float(crack_front) if s.dim == 3 else 1.0
        self.gc_ref = c.D.reference_toughness()
        #: dD / d(load) of the last accepted step, N mm per mm of load (per thickness in 2D)
        self.rate = 0.0
        self.d_prev = c.D.value()
        #: accepted steps taken under dissipation control
        self.dissipation_steps = 0
        #: dissipation attempts scaled down before their solve, and those solved again at a smaller
        #: dD after it (rule 3: the load moved, or was predicted to move, past du_max)
        self.prescaled_steps = 0
        self.rescaled_steps = 0
        #: True after a dissipation step: the next step is one too, until the load of a
        #: dissipation step moves more than the step control's increment
        self.dissipating = False
        #: the last two accepted states and loads, and the secant predictor through them
        self.predictor = SecantPredictor(sim)
        self.delta_d_prev = 0.0
        #: the growth factor of dD and its ceiling (:mod:`ngtmc.stepping.sizing`)
        self.sizing = DissipationSizing(s, self.l0_ref, growth_ceiling)
        #: (t_start, t_end) of the schedule segment of the last attempt
        self.segment = None
        self._last_kind = None  # "dissipation" or "displacement", of the last successful attempt
        self._factor_tried = None  # factor of dD of the last dissipation attempt
        self._factor_first = None  # factor of dD of the first dissipation attempt of the current step
        self._last_dD = None  # dD of the last successful dissipation attempt, N mm (resolve)
        #: the step control's scale when the current step began: its halvings within the step halve
        #: dD; across steps the growth factor and its ceiling carry the memory of cut-backs
        self._scale_ref = 1.0  # the step control's initial scale

    @property
    def target(self) -> float:
        """Dissipation per step dD, N mm (per mm of thickness in 2D), at the current scale and
        growth factor."""
        return self.gc_ref * self.crack_advance * self.crack_front * self.factor

    @property
    def factor(self) -> float:
        """Factor of the base dD: the growth factor (at most the ceiling a cut-back set,
        :mod:`ngtmc.stepping.sizing`), halved with each failed attempt of the current step (the step
        control's scale relative to its value when the step began)."""
        return self.sizing.growth * self.sim.control_state.scale / self._scale_ref

    def _segment(self):
        """(t_start, t_end) of the schedule segment the simulation is on."""
        sch = self.sim.schedule
        t = self.sim.t
        t_end = sch.next_turning_time(t)
        i = int(np.searchsorted(sch.times, t_end)) - 1
        return float(sch.times[max(i, 0)]), t_end

    def _time_of(self, load: float, t0: float, t1: float) -> float:
        sch = self.sim.schedule
        l0, l1 = sch.load(t0), sch.load(t1)
        return t0 + (load - l0) / (l1 - l0) * (t1 - t0)

    def attempt(self, t_new: float):
        """One attempt of a step towards pseudo-time ``t_new`` (the step control's proposal);
        returns (ok, info) as :meth:`ngtmc.stepping.schemes.StepSchemes._attempt`, with ``info["t_new"]`` the pseudo-time
        reached (may be below ``t_new``, or below the last step's after a snap-back)."""
        sim, s = self.sim, self.sim.solver
        sch = sim.schedule
        load_n = sch.load(sim.t)
        seg = list(self._segment())
        if self.segment is not None and seg != self.segment:
            # a new segment of the schedule (a turning point): the rate and the hysteresis of the
            # last segment say nothing about this one (unloading does not dissipate)
            self.dissipating = False
            self.rate = 0.0
            self.sizing.reset()
        self.segment = seg
        prescaled = None
        pr = self.predictor
        if self.prescale and self.dissipating and self.delta_d_prev > 0 and pr.load_prev is not None:
            # rule 3 before the solve, after a dissipation step: the secant through the last two
            # states (linear in dD) moves the load past du_max, so the growth factor shrinks, in
            # proportion, at once instead of after a converged solve, and grows again from there.
            # Not after a displacement step: its rate overestimates the load change where the
            # curve flattens at the peak. The growth factor must shrink with dD: scaling dD alone
            # let it run ahead of the steps taken, and the quick 2D three-point bending then took
            # one step of eight times the last dD at its peak
            predicted = self.target / self.delta_d_prev * abs(pr.load_n - pr.load_prev)
            if predicted > sim.control.du_max * (1 + 1e-9):
                prescaled = BOUNDED_FRACTION * sim.control.du_max / predicted
                self.sizing.shrink(prescaled)
                self.prescaled_steps += 1
        dD = self.target
        self._factor_tried = self.factor
        if self._factor_first is None:
            self._factor_first = self.factor
        info = attempt_info()
        saved = s.get_state()
        du = abs(sch.load(t_new) - load_n)
        last = self._last_attempt(du)
        if not self.dissipating and self.rate * du <= 0.5 * dD:
            ok, info = self._fixed(sch.load(t_new), info)
            if ok and self.coupled.D.value() - self.d_prev <= 2.0 * dD:
                info["t_new"] = t_new
                return True, info
            s.set_state(saved)
        t0, t1 = self._segment()
        l_a, l_b = sch.load(t0), sch.load(t1)
        direction = 1.0 if l_b > l_a else -1.0
        # the predictor's load: where the rate of the last step says dD is reached, at most du_max
        # (not the step control's du, which cut-backs shrink: from a state whose crack has
        # arrested, every alpha dof sits on its lower bound at a load increment of 1e-8 mm, the
        # bordered Newton sees no response of the damage to the load and asks for 1e13 mm, and
        # the cut-backs went on to du_min; the paper L-panel at 6.2078 mm)
        guess = du if self.rate <= 0 else min(sim.control.du_max, dD / self.rate)
        load_guess = load_n + direction * guess
        load_sec = pr.set(dD / self.delta_d_prev) if self.delta_d_prev > 0 else None
        if load_sec is not None:
            load_guess = load_sec
        else:
            res = s.solve_displacement(load_guess)
            add_solve(info, res)
            if not res.converged:
                # no u at the guessed load (near a snap-back the guess may lie beyond the limit
                # point): the dissipation solve starts from the last accepted state and load
                s.set_state(saved)
                load_guess = load_n
        keep = s.get_state()
        lo, hi = min(l_a, l_b), max(l_a, l_b)
        du_max = sim.control.du_max
        slow = prescaled is not None and prescaled < 0.25
        dD_small = None
        r = self.coupled.solve(load_guess, dissipation=dD, load_bounds=(lo, hi))
        add_solve(info, r)
        if r.converged and abs(self.coupled.load_solved - load_n) > du_max * (1 + 1e-9):
            # the load moved more than a displacement step may: dissipate less, in proportion
            # (the same bound on the load change as a displacement step, at converged damage)
            dD_small = BOUNDED_FRACTION * dD * du_max / abs(self.coupled.load_solved - load_n)
            self.rescaled_steps += 1
            long_step = s.get_state() if self.chord else None
            s.set_state(keep)   # the solve starts from the chord to the long step (``chord``), else the predictor
            chord = pr.chord(long_step, self.coupled.load_solved, dD_small / dD) if self.chord else None
            r = self.coupled.solve(load_guess if chord is None else chord, dissipation=dD_small, load_bounds=(lo, hi))
            add_solve(info, r)
            if r.converged and abs(self.coupled.load_solved - load_n) > du_max * (1 + 1e-9):
                # still too far: the crack has stopped growing; a displacement step instead,
                # and leave dissipation control
                self.dissipating = False
                return self._displacement_step(saved, t_new, info, last)
            slow = dD_small < 0.25 * dD  # slow growth: try displacement steps again next
        if self._converged_dissipation(r, info, t0, t1):
            self.dissipation_steps += 1
            self.dissipating = not slow
            self._last_kind = "dissipation"
            self._last_dD = dD_small if dD_small is not None else dD
            return True, info
        s.set_state(keep)
        message = f"dissipation step of {dD:.4g} N mm: {r.message}"
        if last:
            # the step's last attempt before the run would fail at du_min, whether the crack has
            # arrested (the damage no longer responds to the load) or the dissipation solve
            # stalled at every dD (rule 3 of the module docstring): a displacement step of du,
            # with the fallback of the monolithic scheme where its coupled Newton stalls too, and
            # leave dissipation control
            ok, info = self._displacement_step(saved, t_new, info, last)
            if ok:
                self.dissipating = False
                return True, info
            info["message"] = f"{message}; then a displacement step: {info.get('message', '')}"
            return False, info
        out = self.coupled.load_out_of_bounds
        if out is not None and direction * (out - l_b) > 0:
            # the dissipation dD is not reached on this segment: a displacement step to its end
            # (the last attempt of that step when the end is closer than 2 du_min: a cut-back
            # would propose the same step)
            return self._displacement_step(saved, t1, info, self._last_attempt(abs(l_b - load_n)))
        info["message"] = message
        return False, info

    def _last_attempt(self, increment: float) -> bool:
        """Whether a step of ``increment`` (mm) is its step's last attempt: a cut-back would take
        it below du_min, and the run would fail."""
        return increment < 2.0 * self.sim.control.du_min

    def _displacement_step(self, saved: dict, t_new: float, info: dict, last: bool):
        """Instead of a dissipation step: from the state ``saved`` (the last accepted one), a
        displacement step to the load of pseudo-time ``t_new``; returns (ok, info) as :meth:`attempt`.
        Only on the step's ``last`` attempt (the run would fail next) does a failing coupled
        Newton end in the fallback: before that a cut-back retries the step with the coupled
        Newton alone, so that steps stay differentiable where they can."""
        self.sim.solver.set_state(saved)
        ok, info = self._fixed(self.sim.schedule.load(t_new), info, fallback=last)
        if ok:
            info["t_new"] = t_new
        return ok, info

    def _converged_dissipation(self, r, info: dict, t0: float, t1: float) -> bool:
        """Whether the dissipation solve ``r`` ended in an acceptable state: converged with a finite
        trial history. If so, ``info`` gets that history and the pseudo-time of the load found
        (on the segment from ``t0`` to ``t1``); if not, ``r.message`` says why."""
        if not r.converged:
            return False
        s = self.sim.solver
        H_trial = s.trial_history()
        if not s.ranks.all_finite(H_trial):
            r.message = "history not finite (J <= 0 at a history point)"
            return False
        info["H_trial"] = H_trial
        info["t_new"] = self._time_of(self.coupled.load_solved, t0, t1)
        return True

    def _fixed(self, load: float, info: dict, fallback: bool = False):
        """Displacement step: a predictor (the secant through the last two accepted states, else
        the u solve with alpha_{n-1}), then the coupled Newton at ``load``. With ``fallback``
        (a displacement step taken instead of a dissipation step, where no dissipation step is
        left to try), the u solve from the last accepted state, not the secant (which scales the last
        step's change by the load's: at a nearly constant load, a crack's advance), and where the coupled
        Newton fails the fallback (``coupled["fallback"]``, default staggered passes; ``fixed_step``)."""
        sim, s = self.sim, self.sim.solver
        saved = s.get_state() if fallback and sim.fallback == "single-pass" else None
        pr = self.predictor
        dl = pr.last_load_increment()
        if fallback or not (dl != 0.0 and pr.set((load - pr.load_n) / dl, load) is not None):
            res = s.solve_displacement(load)
            add_solve(info, res)
            if not res.converged:
                info["message"] = res.message
                return False, info
        if fallback:
            return self.fixed_step(load, info, saved)
        return self.coupled_step(load, info)

    def accepted(self, step_size: float, iterations: int = 0, cutbacks: int = 0):
        """After an accepted step of |load change| ``step_size`` (mm), ``iterations`` Newton
        iterations and ``cutbacks`` cut-backs: update the rate dD/d(load), the growth factor of dD
        and the last two states of the secant predictor."""
        s = self.sim.solver
        forward = (s.load - self.predictor.load_n) * self._direction() > 0
        tried = self._factor_tried if self._factor_tried is not None else self.factor
        first = self._factor_first if self._factor_first is not None else tried * 2.0 ** cutbacks
        self.sizing.accepted(self._last_kind, iterations, cutbacks, forward, tried, first)
        self._last_kind = None
        self._factor_first = None
        self._scale_ref = self.sim.control_state.scale
        d = self.coupled.D.value()
        delta = d - self.d_prev
        self.d_prev = d
        self.delta_d_prev = delta
        self.predictor.accepted()
        if step_size > 0:
            self.rate = max(delta, 0.0) / step_size
        else:
            self.rate = math.inf if delta > 0 else self.rate

    def _direction(self) -> float:
        """+1 where the schedule segment the simulation is on raises the load, else -1."""
        t0, t1 = self._segment()
        sch = self.sim.schedule
        return 1.0 if sch.load(t1) >= sch.load(t0) else -1.0

    def get_state(self) -> dict:
        """The rule's scalars (JSON-able); its arrays are :meth:`get_arrays`."""
        return {**self.sizing.get_state(), "scale_ref": self._scale_ref, "segment": self.segment,
                "rate": self.rate, "d_prev": self.d_prev, "dissipation_steps": self.dissipation_steps,
                "prescaled_steps": self.prescaled_steps, "rescaled_steps": self.rescaled_steps,
                "dissipating": self.dissipating, **self.predictor.get_state(),
                "delta_d_prev": self.delta_d_prev}

    def get_arrays(self) -> dict:
        """The last two accepted states of the secant predictor (numpy arrays by name)."""
        return self.predictor.get_arrays()

    def set_state(self, st: dict, arrays: dict | None = None):
        """Restore :meth:`get_state` (and :meth:`get_arrays`; without them the predictor starts
        from the solver's current state)."""
        self.predictor.set_state(st, arrays)
        self.delta_d_prev = float(st.get("delta_d_prev", 0.0))
        self.rate, self.d_prev, self.dissipation_steps = float(st["rate"]), float(st["d_prev"]), int(st["dissipation_steps"])
        self.prescaled_steps, self.rescaled_steps = int(st.get("prescaled_steps", 0)), int(st.get("rescaled_steps", 0))
        self.dissipating = bool(st.get("dissipating", False))
        self.sizing.set_state(st)
        self._scale_ref = float(st.get("scale_ref", self.sim.control_state.scale))
        self.segment = st.get("segment")

