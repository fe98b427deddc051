"""What a load-stepping run resumes from: the state of a :class:`ngtmc.simulation.loop.Simulation`
(solver fields, pseudo-time, step, step control, history rows, path following's rule and
predictor, and the refinements of its mesh), written by the run folder's checkpoints
(:mod:`ngtmc.runner.checkpoints`) and set back on a new simulation of the same scene."""
from __future__ import annotations

import numpy as np

from ngtmc.stepping import ControlState
from ngtmc.adapt import RefinementRecord
from ngtmc.adapt import replay
from ngtmc.adapt import move

__all__ = ["RunState"]


class RunState:
    """:meth:`get_state` and :meth:`set_state` of a :class:`~ngtmc.simulation.loop.Simulation`."""

    def get_state(self) -> dict:
        """Everything needed to resume: solver fields, pseudo-time, step, controller, history rows,
        the displacement secant's previous point (``u_before``, ``load_before``), and with path
        following its rule's state (``path``, scalars) and predictor (``arrays``)."""
        st = {"solver": self.solver.get_state(), "t": self.t, "step": self.step,
              "control": self.control_state.as_dict(), "last_delta_wf": self.last_delta_wf, "wf_prev": self._wf_prev,
              "elapsed": self._elapsed(), "rows": [dict(r) for r in self.rows]}
        arrays = {}
        if self._path is not None:
            st["path"] = self._path.get_state()
            arrays.update(self._path.get_arrays())
        before = self._u_before
        if before is not None and before[2] == self.solver.mesh_generation:  # the displacement secant's point
            arrays["u_before"] = before[0]
            st["load_before"] = before[1]
        if self.refinements:  # the mesh of the state: the initial one refined as recorded (bisection.replay)
            st["refinements"] = [{"step": step, **rec.as_dict()} for step, rec in self.refinements]
            arrays["refined_elements"] = np.concatenate([rec.elements for _, rec in self.refinements])
            if self._remesher is not None:   # the mesh is the geometry meshed with these restrictions
                arrays["remesh_restrictions"] = self._remesher.restrictions.copy()
        if arrays:
            st["arrays"] = arrays
        return st

    def set_state(self, st: dict):
        """Resume from a state of :meth:`get_state`. The state of a run whose mesh was refined
        (``refinements``) is set on this simulation's mesh refined in the same way
        (:func:`ngtmc.adapt.bisection.replay`), which must then be the run's initial mesh or a mesh of the
        same run refined fewer times."""
        self._replay_refinements(st)
        self.solver.set_state(st["solver"])
        self.t = float(st["t"])
        self.step = int(st["step"])
        self.control_state = ControlState.from_dict(st["control"])
        self.last_delta_wf = float(st["last_delta_wf"])
        self._wf_prev = float(st["wf_prev"])
        self._elapsed_before = float(st["elapsed"])
        self._t_start = None
        self.rows = [dict(r) for r in st["rows"]]
        arrays = st.get("arrays") or {}
        self._u_before = None
        if "u_before" in arrays and np.size(arrays["u_before"]) == self.solver.fes_u.ndof:
            self._u_before = (np.array(arrays["u_before"], dtype=float), float(st["load_before"]),
                              self.solver.mesh_generation)
        if self._path is not None:
            if "path" in st:
                self._path.set_state(st["path"], arrays)
            else:  # a state of a run without path following: start the rule from this state
                self._path.set_state({"rate": 0.0, "d_prev": self.coupled.D.value(), "dissipation_steps": 0})

    def _replay_refinements(self, st: dict):
        """Bring the mesh to the one of state ``st``: refine it by the refinements that ``st``
        records beyond those this simulation has done (:func:`ngtmc.adapt.bisection.replay`)."""
        recorded = list(st.get("refinements") or [])
        if len(recorded) == len(self.refinements):
            return
        if self.adapt is None:
            raise ValueError(f"this state is on a mesh refined {len(recorded)} times during its run; resume it with "
                             "the run's adapt= (an ngtmc.Adaptivity)")
        if len(recorded) < len(self.refinements):
            raise ValueError(f"this state is on a mesh refined {len(recorded)} times, this simulation's mesh has been "
                             f"refined {len(self.refinements)} times: a mesh is not coarsened; set the state on a new "
                             "Simulation of the same scene")
        flat = np.asarray((st.get("arrays") or {}).get("refined_elements", np.zeros(0)), dtype=np.int64)
        counts = [int(r["marked"]) for r in recorded]
        if flat.size != sum(counts):
            raise ValueError(f"the state records {sum(counts)} refined elements in {len(recorded)} refinements but "
                             f"holds {flat.size}: it is damaged")
        marks = np.split(flat, np.cumsum(counts)[:-1])
        new = range(len(self.refinements), len(recorded))
        rows = (st.get("arrays") or {}).get("remesh_restrictions")
        if rows is not None and self._remesher is None:
            raise ValueError("this state is on a mesh refined by remeshing; resume it with the run's Adaptivity "
                             "(remesh_maxh as recorded)")
        if self._remesher is not None:   # remeshed: the geometry meshed with the recorded restrictions
            if rows is None:
                raise ValueError("this state of a refined run records no remeshing restrictions: it was refined by "
                                 "bisection; resume it without Adaptivity remesh_maxh")
            self._remesher.restrictions = np.asarray(rows, dtype=float).reshape(-1, 3)
            move(self, self._remesher.mesh())
        else:
            replay(self.solver, [marks[k] for k in new])
            if self.coupled is not None:
                self.coupled.mesh_changed()
        for k in new:
            r = recorded[k]
            self.refinements.append((int(r["step"]), RefinementRecord.from_dict(r, marks[k])))
        last = recorded[-1]
        if self.solver.mesh.ne != int(last["elements_after"]) or self.solver.fes_u.ndof != int(last["dofs_after"]):
            raise ValueError(f"replaying the recorded refinements gave {self.solver.mesh.ne} elements and "
                             f"{self.solver.fes_u.ndof} displacement dofs, the run had {last['elements_after']} and "
                             f"{last['dofs_after']}: the state does not belong to this scene")
