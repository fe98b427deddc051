"""Refinement during a run: after a converged step, mark, refine (bisection or remeshing) and
solve the step again on the refined mesh. The base of :class:`ngtmc.simulation.loop.Simulation` (its
attributes ``solver``, ``adapt``, ``coupled``, ``_path``, ``_remesher``, ``rows``, ``step`` and
``refinements`` are set there, and its ``_attempt`` solves a step); the indicators live in
:mod:`ngtmc.adapt` and :mod:`ngtmc.adapt.corridor`, the refinement and transfer in
:mod:`ngtmc.adapt.bisection` and :mod:`ngtmc.adapt.remesh`. Units: mm."""
from __future__ import annotations
from ngtmc.adapt import mark
from ngtmc.adapt import refine
from ngtmc.adapt import corridor_due, corridor_elements, strip
from ngtmc.adapt import remesh_step

__all__ = ["RunRefinement"]


class RunRefinement:
    """The predictor-corrector refinement of a :class:`~ngtmc.simulation.loop.Simulation`'s step."""

    def _refine_and_resolve(self, t_new: float, info: dict, saved: dict, totals: dict):
        """After a converged step to ``t_new``: mark (:func:`ngtmc.adapt.mark`, on the step's trial
        history), refine and transfer the state of the step and ``saved`` (the state before it),
        then solve the step again on the refined mesh from ``saved`` with the refined solution as
        predictor; repeat until nothing is marked (at most ``max_rounds`` times). Returns (ok,
        info, saved on the current mesh); on a failed re-solve the caller restores ``saved`` and
        cuts the step back as for any failed step."""
        rm = self._remesher
        for _ in range(self.adapt.max_rounds):
            s = self.solver
            marked = mark(s, self.adapt, info.get("H_trial"), remesher=rm)
            clip = None
            if self.adapt.corridor > 0 and marked.any() and corridor_due(self.rows, self.refinements):
                line = strip(s, self.adapt, marked)
                if line is not None:
                    extra = corridor_elements(s, self.adapt, marked, remesher=rm, line=line)
                    marked |= extra
                    clip = (extra, line.contains)
            if not marked.any():
                break
            # the secant predictor's state before the last one: carried by bisection (nested, exact);
            # not across a remesh, where the state before the step is equilibrated, settled or
            # made consistent on the new mesh and the older one only interpolated, so that the
            # secant through them points along the carry's error, not along the path
            # (docs/adaptivity.md, "The secant predictor restarts after a remesh, and a carried
            # state with no equilibrium grows its crack at its load")
            previous = self._path.predictor.states() if self._path is not None and rm is None else []
            if rm is not None:   # a new mesh from the geometry: a new solver, the state carried over
                record, (saved, *previous) = remesh_step(self, marked, [saved, *previous], clip=clip)
                s = self.solver
            else:
                record, (saved, *previous) = refine(s, marked, [saved, *previous])
                if self.coupled is not None:  # its compound space follows the solver's, its forms are kept
                    self.coupled.mesh_changed()
            self.refinements.append((self.step + 1, record))
            pred = s.get_state()   # the refined solution (its load: path following solves for it)
            s.set_state(saved)
            s.u.vec.FV().NumPy()[:] = pred["u"]
            if self._path is not None:
                # the same kind of step (dissipation dD, or displacement) from the refined solution
                self._path.mesh_changed(saved, previous)
                s.alpha.vec.FV().NumPy()[:] = pred["alpha"]
                if record.equilibrium:
                    ok, info = self._path.resolve(float(pred["load"]), info.get("t_new", t_new), at_load=rm is not None)
                else:   # no equilibrium of the carried state near its load: its crack grows at that load
                    ok, info = self._path.grow_at_load(saved)
            else:
                ok, info = self._attempt(t_new)
            for k in totals:
                totals[k] += info[k]
            if not ok:
                info["message"] = f"re-solve on the refined mesh failed ({info.get('message', '')})"
                return False, info, saved
        return True, info, saved
