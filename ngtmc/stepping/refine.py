"""The path following of :class:`ngtmc.stepping.path.DissipationPath` across a refinement of the mesh within a
step (:mod:`ngtmc.adapt`, ``Simulation._refine_and_resolve``): the predictor and the dissipation
taken again on the new mesh (:meth:`~PathAcrossRefinement.mesh_changed`), the step solved again
there (:meth:`~PathAcrossRefinement.resolve`), and, where a remesh's carried state has no
equilibrium near its load, the crack grown at that load instead
(:meth:`~PathAcrossRefinement.grow_at_load`). A base of :class:`~ngtmc.stepping.path.DissipationPath`, whose
attributes (``sim``, ``coupled``, ``predictor``, the kind and dD of the last step) and step
helpers it uses. Units: mm, N; D per mm of thickness in 2D."""
from __future__ import annotations

import numpy as np

from ngtmc.stepping.control import add_solve, attempt_info

__all__ = ["PathAcrossRefinement"]


class PathAcrossRefinement:
    """The refinement part of :class:`ngtmc.stepping.path.DissipationPath` (module docstring)."""

    def mesh_changed(self, before: dict, previous: list[dict] = ()):
        """After a refinement of the mesh within a step (:mod:`ngtmc.adapt`, the coupled Newton
        having followed it): ``before`` is the state before the step (the last accepted one)
        transferred to the refined mesh, ``previous`` the predictor's
        :meth:`~ngtmc.stepping.predictor.SecantPredictor.states` transferred with it. The secant
        predictor goes on through those two states (without ``previous`` it restarts from
        ``before``), and the dissipation of the last accepted state is taken again on
        the refined mesh (the same P1 field, so the same value to round-off). Where ``before``
        was settled below its load on the new mesh (:func:`ngtmc.adapt.carried_state.settle`), the run
        goes on from that load: the simulation's pseudo-time and the last load follow it."""
        self.predictor.mesh_changed(before, previous)
        self.d_prev = self.coupled.D.value(np.asarray(before["alpha_committed"], dtype=float))
        load = float(before["load"])
        if load != self.predictor.load_n:   # settled below its load
            self.sim.t = self._time_of(load, *self._segment())
        self.predictor.load_n = load

    def resolve(self, load: float, t_new: float, at_load: bool = False):
        """Solve the step just converged on the old mesh again on the refined one (predictor-
        corrector of :mod:`ngtmc.adapt`): the same kind of step, a dissipation step of the same dD
        (which may leave the load elsewhere) or a displacement step to the same ``load`` (mm),
        from the solver's current u and alpha (the transferred solution, with the boundary values
        of ``load``) and its committed state (the one before the step). ``t_new``: the pseudo-time
        the old mesh's step reached. ``at_load``: solve at ``load`` whatever the kind of step (a
        remeshed run, :mod:`ngtmc.adapt.remesh`: from a state carried across non-nested meshes a
        dissipation step's load ran off). Returns (ok, info) as :meth:`attempt`."""
        sim, s = self.sim, self.sim.solver
        info = attempt_info()
        if at_load or self._last_kind != "dissipation":
            ok, info = self.coupled_step(load, info)
            if ok:
                info["t_new"] = t_new
            return ok, info
        t0, t1 = self._segment()
        sch = sim.schedule
        lo, hi = sorted((sch.load(t0), sch.load(t1)))
        keep = s.get_state()
        r = self.coupled.solve(load, dissipation=self._last_dD, load_bounds=(lo, hi))
        add_solve(info, r)
        if self._converged_dissipation(r, info, t0, t1):
            return True, info
        s.set_state(keep)
        info["message"] = f"dissipation step of {self._last_dD:.4g} N mm on the refined mesh: {r.message}"
        return False, info

    def grow_at_load(self, before: dict):
        """After a remesh whose carried state ``before`` (the state before the step, made
        consistent with its history on the new mesh) has no equilibrium near its load, not even
        below it (:func:`ngtmc.adapt.carried_state.equilibrate`): instead of the re-solve, a displacement
        step at the load of ``before`` with the monolithic scheme's fallback (converged staggered
        passes), in which the crack grows at that load to an equilibrium; the path goes on from
        there with displacement steps. Returns (ok, info) as :meth:`attempt`, ``info["t_new"]``
        the pseudo-time of that load (the simulation's own: no load change).

        Why: from such a state every dissipation step failed, down to a dD of 3e-8 N mm and a
        step of 1e-8 mm, where the step's last attempt took this displacement step. Measured on
        the paper three-point bending with a corridor of 0.1 mm, remeshed at 9.7 N/mm: 18
        cut-backs and 418 Newton iterations to the state that this step reaches in 287, with no
        cut-back (docs/adaptivity.md, "The secant predictor restarts after a remesh, and a carried
        state with no equilibrium grows its crack at its load")."""
        info = attempt_info()
        ok, info = self._displacement_step(before, self._time_of(float(before["load"]), *self._segment()), info,
                                           last=True)
        if ok:
            self.dissipating = False
            self._last_kind = None
        return ok, info
