"""A user's own scene through the runner: :func:`scene_study` wraps it in a one-case study whose
PARAMETERS describe the scene, schedule and control, and :func:`run_scene`
(``ngtmc.simulate(..., out_dir=...)``) writes its run folder as for a named study.
"""
from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from ngtmc.model import check_number
from ngtmc.runner.folder import CONTROL_SETTINGS
from ngtmc.runner.study_run import execute
from ngtmc.scene import check_supported
from ngtmc.scene import region_names
from ngtmc.scene import Scene
from ngtmc.simulation import HISTORY_UNITS
from ngtmc.simulation import Simulation, SimulationResult
from ngtmc.simulation import RUN_FOLDER_OPTIONS, check_options, simulation_keywords
from ngtmc.stepping import AdaptiveStepControl, Schedule
from ngtmc.study import StudyError, normalise_name
from ngtmc.study import Case
from ngtmc.study import read_metadata

__all__ = ["scene_study", "run_scene", "simulate"]


def _value_text(v) -> str:
    """A reproducible text for a field or traction: a callable by its qualified name, a
    CoefficientFunction by its expression, a vector by its numbers (no memory addresses)."""
    if callable(v) and hasattr(v, "__qualname__"):
        return f"{getattr(v, '__module__', '')}.{v.__qualname__}"
    if isinstance(v, (list, tuple, np.ndarray)):
        return str([float(x) for x in np.ravel(v)])
    return " ".join(str(v).split())


def _load_text(ld) -> str:
    """One load of a scene as recorded in a user scene's parameters."""
    text = f"{type(ld).__name__} {ld.label!r} on {ld.boundary}"
    if hasattr(ld, "direction"):
        text += f": {ld.direction}" + (", tangential held" if ld.hold_tangential else "")
    if hasattr(ld, "field"):
        text += f": components {ld.components or 'all'}, field {_value_text(ld.field)}"
    if hasattr(ld, "traction"):
        text += f": traction {_value_text(ld.traction)} MPa per unit lambda"
    return text


def _scene_parameters(scene, schedule, control, options: dict) -> dict:
    """PARAMETERS (name -> (value, unit, description)) describing a scene, its schedule, step control
    and options: what the run folder records, and what a resume compares."""
    import hashlib
    out = {}
    for region, m in scene.materials.items():
        out[f"{region}.E"] = (float(m.E), "MPa", f"Young's modulus in region {region!r}")
        out[f"{region}.nu"] = (float(m.nu), "-", f"Poisson's ratio in region {region!r}")
        if scene.has_fracture:
            out[f"{region}.Gc"] = (float(m.Gc), "N/mm", f"critical energy release rate in region {region!r}")
            out[f"{region}.l0"] = (float(m.l0), "mm", f"phase-field length scale in region {region!r}")
    out["fracture_regions"] = (", ".join(scene.fracture_region_names) or "none", "-",
                               "regions where the phase field lives (regular expressions)")
    if scene.has_fracture:
        out["split"] = (str(scene.split), "-", "tension/compression split of the elastic energy")
        out["formulation"] = (str(scene.formulation), "-", "where the split acts")
    if isinstance(scene.density, dict) or hasattr(scene.density, "items"):
        for region, v in scene.density.items():
            out[f"rho.{region}"] = (float(v), "-", f"pseudo-density in region {region!r} (1 solid, 0 void)")
    elif scene.density is not None:
        rho = np.asarray(scene.density, dtype=float).ravel()
        out["rho"] = (f"{rho.size} values, sha256:{hashlib.sha256(rho.tobytes()).hexdigest()[:16]}", "-",
                      "pseudo-density per element (1 solid, 0 void)")
    if scene.has_void:
        out["gamma0"] = (float(scene.gamma0), "-", "void stiffness ratio (Eq. 17)")
    if scene.has_fracture and scene.has_void:
        out["gc_a"] = (float(scene.gc_a), "-", "toughness interpolation parameter a (Eq. 18)")
        out["gc_b"] = (float(scene.gc_b), "-", "toughness interpolation parameter b (Eq. 18)")
    out["residual_stiffness"] = (float(scene.residual_stiffness), "-", "added to the degradation g(alpha)")
    if scene.regulariser is not None:
        r = scene.regulariser
        out["regulariser_regions"] = (", ".join(region_names(r.regions)), "-", "regions of the contact regulariser")
        out["regulariser_length"] = (float(r.length), "mm", "characteristic length L of the regulariser")
        out["kbar_r"] = (float(r.kbar_r), "-", "regulariser factor")
        out["regulariser_damping"] = (str(r.damping), "-", "damping of the regulariser")
    if scene.dim == 2:
        out["thickness"] = (float(scene.thickness), "mm", "out-of-plane thickness (plane strain)")
    out["displacement_order"] = (int(scene.displacement_order), "-", "polynomial order of the displacement")
    mesh = scene.mesh
    coords = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    out["mesh"] = (f"{mesh.ne} elements, {mesh.nv} vertices, sha256:"
                   f"{hashlib.sha256(coords.tobytes()).hexdigest()[:16]}", "-", "the mesh (vertex coordinates hashed)")
    out["supports"] = ("; ".join(f"{s.boundary}: " + "".join(a for a in "xyz" if getattr(s, a, False))
                                 for s in scene.supports), "-", "held boundaries and components")
    out["load"] = ("; ".join(_load_text(ld) for ld in scene.loads), "-", "loads: kind, name, where, what")
    if len(scene.loads) > 1:
        out["force_from"] = (str(scene.force_load.label), "-", "load behind the force column")
    out["schedule"] = ([float(x) for x in schedule.points], "mm", "load schedule (turning points)")
    if control is not None:
        for a in CONTROL_SETTINGS:
            v = getattr(control, a, None)
            if v is not None:
                out[f"control.{a}"] = (v, {"du_max": "mm", "du_min": "mm", "du_first": "mm", "k_u": "1/N"}.get(a, "-"),
                                       f"step control {type(control).__name__}: {a}")
    for k, v in options.items():
        if isinstance(v, (int, float, str, bool)):
            out[f"option.{k}"] = (v, "-", f"Simulation option {k}")
    adapt = options.get("adapt")
    if adapt is not None:
        import dataclasses
        units = {"h_crack": "mm", "h_void": "mm"}
        for f in dataclasses.fields(adapt):
            v = getattr(adapt, f.name)
            out[f"adapt.{f.name}"] = (v, units.get(f.name, "-"), f"adaptive refinement (ngtmc.Adaptivity): {f.name}")
    return out


def scene_study(scene, schedule, control=None, *, name: str | None = None, title: str | None = None,
                summary: str | None = None, snapshot_loads: Sequence[float] | None = None,
                references: Sequence[dict] = (), targets: Sequence[dict] = (), section: tuple | None = None,
                **options) -> ModuleType:
    """A one-case study module (the interface of ``docs/study-interface.md``) around a user's own
    scene, so that the runner writes its run folder as for a named study.

    ``name`` defaults to ``scene.name``; ``snapshot_loads`` (mm) default to 8 loads evenly along the
    schedule; ``references`` and ``targets`` in the metadata format; ``options``: keyword arguments
    of :class:`ngtmc.Simulation` (e.g. ``scheme``). ``section`` (3D): the plane ``(axis, mm)`` of
    :class:`ngtmc.study.registry.Case`. PARAMETERS describe the scene, schedule and control (materials,
    densities, mesh, ...), so a resume with another scene is refused.
    """
    if not isinstance(schedule, Schedule):
        check_number("schedule (a Schedule, or the final load)", schedule, "mm")
        schedule = Schedule.monotonic(float(schedule))
    if snapshot_loads is None:
        total = schedule.total_time
        snapshot_loads = [float(schedule.load(t)) for t in np.linspace(0.0, total, 9)[1:]]
    study_name = normalise_name(name or getattr(scene, "name", None) or "scene")
    mod = ModuleType(f"ngtmc_scene_{study_name}")
    mod.NAME = study_name
    mod.TITLE = title or f"Scene {study_name}"
    mod.SUMMARY = summary or (f"Scene {study_name!r} ({scene.dim}D, {scene.mesh.ne} elements"
                              f"{', with fracture' if scene.has_fracture else ''}"
                              f"{', with a third medium (void)' if scene.has_void else ''}), loaded along "
                              f"{[float(x) for x in schedule.points]} mm.")
    mod.PARAMETERS = _scene_parameters(scene, schedule, control, options)
    mod.RESOLUTIONS = {"custom": {}}
    mod.DEFAULT_RESOLUTION = "custom"
    case = Case(name="main", label=getattr(scene, "name", None) or study_name, scene=scene, schedule=schedule,
                control=control, options=dict(options), snapshot_loads=list(snapshot_loads), section=section)
    mod.cases = lambda p: [case]
    mod.references = lambda p: list(references)
    mod.targets = lambda p: list(targets)
    return mod


def run_scene(scene, schedule, control=None, out_dir: str | Path | None = None, *, resume: bool = False,
              report: bool | None = None, progress: bool | Callable = False, vtk: bool = True,
              threads: int | None = None, checkpoint_every: int = 25, checkpoint_seconds: float = 30.0,
              callbacks: Sequence[Callable] = (), name: str | None = None, title: str | None = None,
              summary: str | None = None, snapshot_loads: Sequence[float] | None = None,
              references: Sequence[dict] = (), targets: Sequence[dict] = (), section: tuple | None = None,
              **options):
    """Run a user's own scene into the run folder ``out_dir``, with the machinery of a named study
    (history.csv, metadata.json, snapshots.npz, vtk/, checkpoint/, report.html); see
    :func:`scene_study` and :func:`run_study`. Returns the :class:`ngtmc.SimulationResult`, its
    ``run_dir`` set. ``ngtmc.simulate(..., out_dir=...)`` calls this."""
    if out_dir is None:
        raise StudyError("run_scene needs out_dir, the run folder to write")
    mod = scene_study(scene, schedule, control, name=name, title=title, summary=summary,
                      snapshot_loads=snapshot_loads, references=references, targets=targets, section=section,
                      **options)
    run = execute(mod, None, out_dir, None, report, resume, progress, threads, checkpoint_every,
                   checkpoint_seconds, vtk, callbacks)
    sim = run.simulations.get("main")
    rows = run.rows.get("main") or []
    units = sim.units if sim is not None else dict(HISTORY_UNITS, force=run.force_unit or
                                                   (read_metadata(run.out) or {}).get("force_unit", "N"))
    history = pd.DataFrame(rows).reindex(columns=list(units))
    return SimulationResult(history, units, sim.solver if sim is not None else None,
                            float(run.results.get("main", {}).get("wall_time_s") or run.wall_time()),
                            run_dir=run.out)


def simulate(scene: Scene, schedule: Schedule | float, control: AdaptiveStepControl | None = None,
             out_dir=None, **options) -> SimulationResult:
    """Run ``scene`` through ``schedule`` and return the :class:`SimulationResult`.

    Without ``out_dir``: a shortcut for ``Simulation(scene, schedule, control, **options).run()``,
    the history kept in memory.

    With ``out_dir`` (a folder): the run folder of a named study is written there by the same
    machinery (:func:`ngtmc.runner.run_scene`): ``history.csv``, ``metadata.json``,
    ``snapshots.npz``, ``vtk/``, ``checkpoint/`` and ``report.html`` (``docs/run-directory.md``).
    Further keywords then: ``resume``, ``report``, ``vtk``, ``progress``, ``threads``,
    ``callbacks``, ``name``, ``title``, ``summary``, ``snapshot_loads`` (mm), ``references``,
    ``targets``, ``section`` (3D: a plane ``(axis, mm)`` where the snapshots sample alpha); the rest go to :class:`Simulation`. The result's ``run_dir`` is the folder.
    """
    if out_dir is not None:
        check_supported(scene, out_dir=out_dir)
        return run_scene(scene, schedule, control, out_dir, **options)
    callbacks = options.pop("callbacks", ())
    folder_only = sorted(set(options) & RUN_FOLDER_OPTIONS)
    if folder_only:
        raise TypeError(f"ngtmc.simulate: {', '.join(folder_only)} {'needs' if len(folder_only) == 1 else 'need'} a "
                        "run folder; pass out_dir='runs/my_scene' as well (or leave "
                        f"{'it' if len(folder_only) == 1 else 'them'} out for a run kept in memory)")
    check_options(options, simulation_keywords(Simulation), "ngtmc.simulate")
    return Simulation(scene, schedule, control, **options).run(callbacks=callbacks)
