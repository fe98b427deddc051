"""How much a dissipation step of the path-following scheme dissipates: the growth factor of dD
and the ceiling that cut-backs set on it (:class:`DissipationSizing`).

dD = Gc_ref ``crack_advance`` (times ``crack_front`` in 3D) times the step control's scale (halved
by a failed attempt within the step) times the growth factor kept here (:mod:`ngtmc.stepping.path`, which
owns the step rule). Where the damage grows stably (the load goes on in the direction of the
schedule) and a dissipation step converged in at most GROWTH_ITERATIONS Newton iterations without
a cut-back, the next dD is twice as large, up to GROWTH_MAX times the base; after a displacement
step the factor is GROWTH_START (below 1: fine samples at the peak), and it doubles back to 1 along
a snap-back. A cut-back sets a ceiling on the factor: the factor at which the step then converged
(at least CEILING_MIN, unless the factor that failed had failed before: CEILING_REPEAT);
GROWTH_CEILING_STEPS easy steps at it, or one very easy step where it is not held by
CEILING_REPEAT, double it again (up to GROWTH_MAX). With ``growth_ceiling="auto"`` the ceiling
applies only where the crack is meshed finer than about l0 (:meth:`DissipationSizing.ceiling_applies`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["DissipationSizing", "GROWTH_MAX", "GROWTH_ITERATIONS", "GROWTH_START", "GROWTH_CEILING_STEPS",
           "CEILING_EASY_ITERATIONS", "CEILING_MIN", "CEILING_REPEAT", "CRACK_ALPHA", "CEILING_MAX_H"]

#: dD grows by 2 after each dissipation step of stable growth (the load went on in the direction
#: of the schedule) that took at most GROWTH_ITERATIONS Newton iterations and no cut-back, up to
#: GROWTH_MAX times its base value; a snap-back step (the load went back), a displacement step or a
#: cut-back resets it. Where damage grows diffusely (the post-failure tail, under the indenter) a
#: step dissipates without moving a crack tip, and the base dD of about l0 of crack would take
#: hundreds of steps there.
GROWTH_MAX = 16.0
GROWTH_ITERATIONS = 6

#: After a displacement step dD is GROWTH_START times its base (so the first dissipation steps,
#: where the peak of the curve lies, sample it finely), and it doubles with each dissipation step
#: up to the base (snap-back steps) or up to GROWTH_MAX (stable growth, as above). With the base dD
#: from the start the quick three-point bending's sampled peak was 1.2 % below the converged one.
GROWTH_START = 0.25

#: A cut-back of a dissipation step sets a ceiling on the factor of dD (the step control's scale
#: times the growth factor): the factor at which the step then converged, g s / 2**cutbacks (at
#: least CEILING_MIN);
#: GROWTH_CEILING_STEPS easy steps at the ceiling double it again (up to GROWTH_MAX). Without it, the
#: post-failure tail of the three-point bending at the paper's resolution went in cycles of five
#: steps (growth 1, 2, 4, 8, then 16 failed in about 14 Newton iterations and was cut back), so a
#: third of its iterations were failed attempts. A ceiling on the growth factor alone (at least 1)
#: still let the crack run go in cycles of six steps: four easy ones at half the base dD while the
#: step control's scale recovered from the cut-back, one of 16-22 iterations at the base, one more
#: cut-back.
GROWTH_CEILING_STEPS = 16

#: A step at the ceiling that took at most CEILING_EASY_ITERATIONS Newton iterations doubles the
#: ceiling at once, forward or snap-back. Measured in the crack runs of the L-panel: at quick
#: (elements of 1.7 l0) steps at half the base dD took 2-3 iterations, and a ceiling that waited for
#: 16 easy steps made the monotonic case take 409 steps and 1344 iterations against 121 and 610
#: without a ceiling, 207 and 1124 with this rule; at the paper's resolution (l0/2.4) steps at half
#: the base took 5-8 iterations and steps at the base failed in half the attempts. Where the ceiling
#: is "auto" it changes nothing measured: the quick three-point bending 82 steps and 391 iterations,
#: the quick 3D hemisphere 61 and 459, with the rule and without (docs/performance.md).
CEILING_EASY_ITERATIONS = 3

#: The lowest ceiling a cut-back sets, as a factor of the base dD (one l0 of crack). Measured in the
#: crack run of the three-point bending at the paper's resolution: steps at a quarter of the base
#: took 4 Newton iterations, at half of it 6, at the base 16-22 or failed; so half the base moves
#: the crack furthest per iteration. With a ceiling of at least 1 the crack run went in cycles of
#: six steps (four easy ones at half the base while the step control's scale recovered from a
#: cut-back, one of 16-22 iterations at the base, one more cut-back); with a floor of 1/4 it took
#: more steps and iterations than with 1 (docs/performance.md).
CEILING_MIN = 0.5

#: A cut-back whose first attempt's factor of dD is no larger than that of the last cut-back's
#: first attempt (a factor failed again) sets the ceiling at half that factor at most, below
#: CEILING_MIN if need be, and only GROWTH_CEILING_STEPS easy steps raise it again (not one very
#: easy step, CEILING_EASY_ITERATIONS). Measured in the crack run of the quick 3D hemisphere: steps at a
#: quarter of the base took 3 Newton iterations (2.5 s), steps at half of it 5-19 or failed after
#: 12-32; with the ceiling held at CEILING_MIN every easy quarter step was followed by a half step,
#: and seven of them failed (docs/performance.md).
CEILING_REPEAT = True

#: The crack of ``growth_ceiling="auto"`` (DissipationSizing.ceiling_applies): the elements with
#: alpha >= CRACK_ALPHA at a vertex.
CRACK_ALPHA = 0.5

#: ``growth_ceiling="auto"`` sets the ceiling where the crack's median element (longest edge) is at
#: most CEILING_MAX_H times l0. Measured (docs/performance.md): at 1.11 l0 (the 3D study's 2D twin
#: at quick) the ceiling takes 71 steps and 298 Newton iterations (3 cut-backs) against 69, 408 and
#: 17 without it; at 2.2 l0 (the quick L-panel's crack path) it took 207 steps and 1124 iterations
#: against 121 and 610 without it. The bound lies between the two; 1.0 (until 2026-12-03) switched
#: the ceiling off for the first.
CEILING_MAX_H = 1.5


class DissipationSizing:
    """The growth factor of dD and its ceiling (module docstring) for the path of ``solver``.

    ``option``: ``growth_ceiling`` of the path, True, False or "auto"; ``l0_ref``: the fracture
    regions' mean l0 (mm), the crack's resolution that "auto" compares with."""

    def __init__(self, solver, l0_ref: float, option: bool | str = "auto"):
        self.solver = solver
        self.l0_ref = float(l0_ref)
        #: whether a cut-back sets a ceiling on the growth of dD (GROWTH_CEILING_STEPS): True,
        #: False, or "auto", where the crack is meshed finer than l0 (:meth:`ceiling_applies`)
        self.option = option
        self.reset()

    def reset(self):
        """A new segment of the schedule (a turning point): no memory of the last one."""
        #: growth factor of dD (GROWTH_START .. GROWTH_MAX)
        self.growth = GROWTH_START
        #: ceiling of the growth factor, and the easy steps taken at it
        self.ceiling = GROWTH_MAX
        self.at_ceiling = 0
        #: the factor of the first attempt of the last step that was cut back (CEILING_REPEAT), and
        #: whether the ceiling it set waits for GROWTH_CEILING_STEPS easy steps
        self.failed_factor = None
        self.ceiling_held = False

    def shrink(self, factor: float):
        """Scale the growth factor by ``factor`` (< 1): a dissipation step sized down before its
        solve (rule 3 of :mod:`ngtmc.stepping.path`), so that the next steps grow from the dD taken, not from
        the one proposed."""
        self.growth *= factor

    def ceiling_applies(self) -> bool:
        """Whether a cut-back sets a ceiling: ``option`` True or False, or with "auto"
        where the crack is meshed finely enough: the median longest edge of the elements that
        hold alpha >= CRACK_ALPHA at a vertex is at most CEILING_MAX_H times the fracture regions'
        mean l0 (True where nothing is cracked yet). Measured: with elements several times smaller than l0 a step of one
        l0 of crack breaks several elements, and its Newton failed in about half the attempts (the
        paper L-panel's crack run, l0/2.4: steps at half the base took 5-8 iterations, at the base
        5-7 or a failed attempt of about 15); the quick three-point bending (l0/2) took 454 instead
        of 684 iterations with the ceiling. With elements larger than l0 a step of one l0 is a
        fraction of an element and the ceiling only holds the steps back (the quick L-panel, 2.2 l0
        on its crack path: 207 steps and 1124 iterations with it, 121 and 610 without;
        docs/performance.md); at 1.11 l0 it still helps (CEILING_MAX_H)."""
        if self.option != "auto":
            return bool(self.option)
        s = self.solver
        a = s.alpha.vec.FV().NumPy()
        nodes = s.scene.element_vertices()
        cracked = a[nodes].max(axis=1) >= CRACK_ALPHA
        h = s.h[cracked]   # the solver's element sizes (longest edges), kept with the mesh
        n, fine = s.ranks.sum(float(h.size)), s.ranks.sum(float(np.sum(h <= CEILING_MAX_H * self.l0_ref)))
        return n == 0 or fine >= 0.5 * n

    def accepted(self, kind: str | None, iterations: int, cutbacks: int, forward: bool,
                 tried: float, first: float):
        """After an accepted step of ``kind`` ("dissipation", else a displacement step) that took
        ``iterations`` Newton iterations and ``cutbacks`` cut-backs, whose last dissipation attempt
        had the factor ``tried`` and its first one ``first``; ``forward``: whether the load went
        on in the direction of the schedule (else a snap-back)."""
        if self.option is False:   # also a ceiling restored from a checkpoint of a run that had one
            self.ceiling, self.at_ceiling = GROWTH_MAX, 0
        if kind != "dissipation":
            self.growth = GROWTH_START
        elif cutbacks and self.ceiling_applies():
            # the factor at which the step converged after its cut-backs
            repeat = (CEILING_REPEAT and self.failed_factor is not None
                      and first <= self.failed_factor * (1.0 + 1e-9))
            self.ceiling = max(CEILING_MIN, tried)
            if repeat:
                # the factor failed again: the ceiling goes below it, below CEILING_MIN if need be
                self.ceiling = min(self.ceiling, 0.5 * first)
            self.ceiling_held = repeat
            self.failed_factor = first
            self.at_ceiling = 0
            self.growth = min(tried, self.ceiling)
        else:
            if self.growth >= self.ceiling and iterations <= GROWTH_ITERATIONS:
                # an easy step at the ceiling: GROWTH_CEILING_STEPS of them, or one very easy
                # one (CEILING_EASY_ITERATIONS), double it
                self.at_ceiling += 1
                if self.at_ceiling >= GROWTH_CEILING_STEPS or (iterations <= CEILING_EASY_ITERATIONS
                                                               and not self.ceiling_held):
                    self.ceiling, self.at_ceiling = min(GROWTH_MAX, 2.0 * self.ceiling), 0
                    self.ceiling_held = False
            if not forward:
                # a snap-back: back to the base dD, not beyond (growth up to 4 times the base where
                # the steps were easy: the quick L-panel took 117 steps and 754 iterations against
                # 129 and 654, docs/performance.md)
                self.growth = min(1.0, self.ceiling, 2.0 * self.growth)
            elif iterations <= GROWTH_ITERATIONS:
                self.growth = min(self.ceiling, 2.0 * self.growth)

    def get_state(self) -> dict:
        """The sizing's part of the path's checkpoint state (JSON-able)."""
        return {"growth": self.growth, "ceiling": self.ceiling, "at_ceiling": self.at_ceiling,
                "failed_factor": self.failed_factor, "ceiling_held": self.ceiling_held}

    def set_state(self, st: dict):
        """Restore :meth:`get_state` (missing keys: the values of a fresh segment)."""
        self.growth = float(st.get("growth", GROWTH_START))
        self.ceiling = float(st.get("ceiling", GROWTH_MAX))
        self.at_ceiling = int(st.get("at_ceiling", 0))
        ff = st.get("failed_factor")
        self.failed_factor = None if ff is None else float(ff)
        self.ceiling_held = bool(st.get("ceiling_held", False))
