"""The history schema: every column of a run's history with its unit, the columns a scene's loads
add, the unit of the reaction force, and the one definition of the peak of a force-load curve.
The simulation records its rows by it, the run folder writes ``history.csv`` by it
(``docs/run-directory.md``), and the report reads it back by it."""
from __future__ import annotations

import numpy as np

__all__ = ["HISTORY_UNITS", "HISTORY_COLUMNS", "history_units", "force_unit", "peak", "peak_index"]

#: Columns of a Simulation's history, in order, with their units (``history.csv`` has a ``case``
#: column first). In 2D, force and energies are for the scene thickness: the force of a study run
#: with thickness 1 mm is in N per mm (``force_unit`` in metadata.json). The one definition used
#: by :data:`ngtmc.HISTORY_UNITS`, :data:`HISTORY_COLUMNS` and the report. A scene
#: with several loads or a traction adds columns after these by the rule of :func:`history_units`.
HISTORY_UNITS = {
    "step": "-",
    "load": "mm",
    "force": "N",
    "fracture_energy": "N mm",
    "dissipated_energy": "N mm",
    "elastic_energy": "N mm",
    "regularisation_energy": "N mm",
    "max_alpha": "-",
    "min_J": "-",
    "newton_iterations": "-",
    "staggered_iterations": "-",
    "cutbacks": "-",
    "alpha_projected": "-",
    "step_size": "mm",
    "wall_time": "s",
    "solve_time": "s",
    "assembly_time": "s",
    "residual": "N",            # free-dof residual norm of the accepted state (docs/run-directory.md)
    "floor_accepts": "-",       # solves of the step accepted at NewtonOptions.floor_rtol, not rtol
}



def history_units(loads: dict | None = None) -> dict:
    """Columns of the history of a scene, with units: :data:`HISTORY_UNITS`, then the columns of
    its loads by the one rule for extra columns. ``loads``: load name -> kind (class name,
    "DisplacementLoad", "DisplacementField" or "Traction"), in the scene's order.

    * two or more loads: ``force_<name>`` (N) for every load (``force`` stays the force of
      ``Scene.force_from``);
    * every ``Traction`` load: ``displacement_<name>`` (mm), its work-conjugate displacement.

    A scene with one displacement load has exactly :data:`HISTORY_UNITS`."""
    out = dict(HISTORY_UNITS)
    loads = dict(loads or {})
    if len(loads) > 1:
        out.update({f"force_{n}": "N" for n in loads})
    out.update({f"displacement_{n}": "mm" for n, kind in loads.items() if kind == "Traction"})
    return out


def peak_index(force) -> int | None:
    """Row of the peak of a force column: the largest finite force (the first row where it occurs
    when it occurs more than once; NaN and infinite forces are skipped), or None when no force is
    finite. The one definition of "the peak" in ngtmc: the runner's results, the report, the
    benchmarks and :class:`ngtmc.SimulationResult` use it (through :func:`peak`)."""
    f = np.asarray(force, dtype=float).ravel()
    finite = np.isfinite(f)
    if not finite.any():
        return None
    return int(np.argmax(np.where(finite, f, -np.inf)))


def peak(force, load) -> tuple[float, float] | tuple[None, None]:
    """The peak of a force-load curve: ``(peak force, load at it)`` as floats, in the units of the
    inputs (force unit, mm), at the row of :func:`peak_index`; ``(None, None)`` when no force is
    finite. ``force`` and ``load``: one value per row. A curve loaded mostly in the negative
    direction has its peak at its most negative force (not the 0 N of its start)."""
    f = np.asarray(force, dtype=float).ravel()
    x = np.asarray(load, dtype=float).ravel()
    if f.size != x.size:
        raise ValueError(f"peak: {f.size} forces but {x.size} loads; give one load per force")
    xs = x[np.isfinite(x)]
    negative = xs.size and -xs.min() > xs.max()
    i = peak_index(-f if negative else f)
    if i is None:
        return None, None
    return float(f[i]), float(x[i])

#: Columns of a run folder's ``history.csv``: the case of a study, then :data:`HISTORY_UNITS`.
HISTORY_COLUMNS = ["case", *HISTORY_UNITS]


def force_unit(dim: int, thickness: float | None) -> str:
    """Unit of the reaction force of a scene: ``"N"`` in 3D; in 2D (plane strain) the force is for the
    scene thickness, ``"N/mm"`` (per mm of thickness) when that thickness is 1 mm, else ``"N"``."""
    if int(dim) == 2 and (thickness is None or abs(float(thickness) - 1.0) < 1e-12):
        return "N/mm"
    return "N"
