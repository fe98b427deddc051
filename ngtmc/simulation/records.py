"""What a load-stepping run records: the history row of each accepted step, its units, the run's
elapsed time and the solver's safeguard counters. The base of :class:`ngtmc.simulation.loop.Simulation`
(its attributes ``solver``, ``scene``, ``rows``, ``step``, ``adapt``, ``coupled``, ``_path``,
``force_unit``, ``progress`` and ``_progress`` are set there); the history columns and their units
are defined once, in :mod:`ngtmc.study.run_files`."""
from __future__ import annotations

import time

import numpy as np
import pandas as pd

from ngtmc.simulation.history import history_units

__all__ = ["RunRecords"]


class RunRecords:
    """History rows, units, elapsed time and counters of a :class:`~ngtmc.simulation.loop.Simulation`."""

    def _elapsed(self) -> float:
        if self._t_start is None:
            return self._elapsed_before
        return self._elapsed_before + time.perf_counter() - self._t_start

    def _record(self, wf: float | None = None, **info):
        """Append and return the history row of the current state; ``wf``: its W_f per unit
        thickness where the caller has computed it."""
        s = self.solver
        t0 = time.perf_counter()
        en = s.energies(wf)
        forces = s.reactions(reuse_residual=self.step > 0)
        floors = self.solver.floor_accepts + (self.coupled.floor_accepts if self.coupled is not None else 0)
        seen, self._floors_recorded = getattr(self, "_floors_recorded", None), floors   # None before the first row
        row = {
            "step": self.step,
            "load": s.load,
            "force": forces[self.scene.force_load.label],
            "fracture_energy": en["fracture_energy"],
            "dissipated_energy": en["dissipated_energy"],
            "elastic_energy": en["elastic_energy"],
            "regularisation_energy": en["regularisation_energy"],
            "max_alpha": s.max_alpha(),
            "min_J": s.min_J(),
            "newton_iterations": info["newton_iterations"],
            "staggered_iterations": info["staggered_iterations"],
            "cutbacks": info["cutbacks"],
            "alpha_projected": info["projected"],
            "step_size": info["step_size"],
            "wall_time": self._elapsed(),
            "solve_time": info["solve_time"],
            "assembly_time": info["assembly_time"],
            "residual": s.residual_norm(after_reactions=True) * s.thickness,
            "floor_accepts": 0 if seen is None else floors - seen,
        }
        if self.adapt is not None:
            row["dofs"] = s.fes_u.ndof + (s.fes_a.ndof if s.fes_a is not None else 0)
            row["elements"] = s.mesh.ne
        if len(forces) > 1:
            row.update({f"force_{n}": f for n, f in forces.items()})
        row.update({f"displacement_{n}": v for n, v in s.load_displacements().items()})
        self.rows.append(row)
        s.timings["record"] += time.perf_counter() - t0
        return row

    @property
    def history(self) -> pd.DataFrame:
        """Accepted steps so far as a DataFrame (units in :attr:`units`: :data:`HISTORY_UNITS` and the
        columns of the scene's loads, see :func:`ngtmc.simulation.history.history_units`)."""
        return pd.DataFrame(self.rows, columns=list(self.units))


    def _report_progress(self, row):
        if self.progress:
            self._progress.step(self, row)

    def counters(self) -> dict:
        """The solver's safeguard counters since this process built it (a resumed run counts from
        the resume): displacement solves accepted at the residual floor (``floor_accepts``), line
        searches decided by the residual because the energy's round-off hid the step
        (``energy_noise_switches``) and, for the monolithic schemes, the coupled Newton's floor
        accepts and its worst relative residual there (-), Levenberg steps, relaxations, GMRES
        solves and their mean iterations, block-GMRES's u-u factors made and reused
        (:data:`ngtmc.coupled.settings.FACTOR_REUSE`), and path following's dissipation steps.
        Counts, no unit."""
        s = self.solver
        out = {"floor_accepts": int(getattr(s, "floor_accepts", 0)),
               "energy_noise_switches": int(getattr(s, "energy_noise_switches", 0))}
        c = self.coupled
        if c is not None:
            gm = list(getattr(c, "gmres_iterations", []) or [])
            out["coupled"] = {"floor_accepts": int(c.floor_accepts),
                              "floor_worst_relative_residual": float(c.floor_worst),
                              "levenberg_steps": int(c.levenberg_steps), "relaxations": int(c.relaxations),
                              "gmres_solves": len(gm),
                              "gmres_iterations_mean": float(np.mean(gm)) if gm else None,
                              "u_factorizations": int(c.lin.u_factorizations),
                              "u_factor_reuses": int(c.lin.u_factor_reuses),
                              "bordered_solves": int(c.lin.bordered_solves),
                              "bordered_fallbacks": int(c.lin.bordered_fallbacks),
                              "dissipation_steps": int(getattr(self._path, "dissipation_steps", 0) or 0),
                              "dissipation_prescaled": int(getattr(self._path, "prescaled_steps", 0) or 0),
                              "dissipation_resolved": int(getattr(self._path, "rescaled_steps", 0) or 0)}
        return out

    @property
    def units(self) -> dict:
        """History column -> unit for this scene (:func:`ngtmc.simulation.history.history_units`), forces in
        this scene's unit (:attr:`force_unit`: ``"N/mm"`` in 2D with thickness 1 mm, else ``"N"``),
        as in a run folder's metadata."""
        units = history_units({ld.label: type(ld).__name__ for ld in self.scene.loads})
        if self.adapt is not None:
            units.update(dofs="-", elements="-")
        return {k: (self.force_unit if (k == "force" or k.startswith("force_")) else v) for k, v in units.items()}
