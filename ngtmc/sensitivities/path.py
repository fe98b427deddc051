"""The recorded load path of the adjoint: every accepted state of a run, its loads and parameters,
and the replay of the same load sequence with other parameters (``ngtmc.sensitivities``).

Units: mm, N, MPa.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import re
import time
from typing import Sequence

import numpy as np
import ngsolve as ngs

from ngtmc.scene import Traction
from ngtmc.scene import Scene
from ngtmc.stepping import alpha_u_passes
from ngtmc.simulation import Simulation
from ngtmc.discrete import NewtonOptions, Solver
from ngtmc.stepping import AdaptiveStepControl, Schedule

_MATERIAL_KEYS = ("E", "nu", "Gc", "l0")


#: What the adjoint says about a run whose mesh changed (adaptive refinement, :mod:`ngtmc.adapt`).
CHANGED_MESH = ("the adjoint needs one mesh for the whole load path, and {what} (adaptive refinement): record "
                "the path on the final mesh instead, without adapt: record_path(result.solver.scene, ...) with the "
                "scene of the adaptive run's final mesh (its density follows the refined elements)")


def refuse_changed_mesh(solver, what: str = "this path's mesh changed after it was recorded"):
    """ValueError (:data:`CHANGED_MESH`) when the solver's mesh was refined (``mesh_generation``)."""
    if getattr(solver, "mesh_generation", 0):
        raise ValueError(CHANGED_MESH.format(what=what))


@dataclass
class Path:
    """A recorded load path: the solver, the load sequence and every accepted state.

    Attributes
    ----------
    solver : Solver
        The solver that ran the path (reused by :func:`replay` and :func:`gradient`).
    loads : ndarray (N + 1,)
        Imposed displacement of each state, mm; ``loads[0] = 0`` is the unloaded initial state.
    states : list of dict
        ``states[n]`` holds ``u``, ``alpha`` (alpha_n) and ``H`` (H_n) as numpy arrays.
    forces : ndarray (N + 1,)
        Reaction on the loaded boundary at each state, N (for the scene thickness).
    rho : ndarray (n_elements,)
        Pseudo-density the path was computed with.
    parameters : dict
        Values of the differentiable scalar parameters (``gamma0``, ``E``, ``nu``, ``Gc``, ``l0`` of
        every material, keyed ``"E@<id>"``) the path was computed with.
    forward_time : float
        Wall time of the forward run, s.
    newton_iterations : int or None
        Newton iterations of the whole run (a :func:`replay` counts its own; None where not counted).
    checkpoint_every : int or None
        None: every state is stored. k: only states 0, k, 2k, ... and N are stored; the others are
        recomputed from the previous stored state when needed (:meth:`state`), one segment of at
        most k - 1 states at a time (the reverse sweep then costs one extra forward run).
    """

    solver: Solver
    loads: np.ndarray
    states: list
    forces: np.ndarray
    rho: np.ndarray
    parameters: dict
    forward_time: float = 0.0
    history: object = None
    checkpoint_every: int | None = None
    newton_iterations: int | None = None
    _segment: dict = field(default_factory=dict, repr=False)

    @property
    def n_steps(self) -> int:
        """Number of load steps N (states 1..N)."""
        return len(self.states) - 1

    @property
    def state_bytes(self) -> int:
        """Bytes of one state: 8 (ndof_u + ndof_alpha + n_history_points)."""
        s = self.solver
        return 8 * (s.fes_u.ndof + (s.fes_a.ndof if s.alpha is not None else 0) + s.irs.ndof)

    @property
    def memory_bytes(self) -> int:
        """Bytes held by the stored states (u, alpha, H per stored state)."""
        return int(sum(a.nbytes for st in self.states if st is not None for a in st.values() if isinstance(a, np.ndarray)))

    @property
    def peak_memory_bytes(self) -> int:
        """Stored states plus the largest recomputed segment (checkpointing), bytes."""
        k = self.checkpoint_every
        return self.memory_bytes + (0 if not k else (k - 1) * self.state_bytes)

    def state(self, n: int) -> dict:
        """State n (dict of u, alpha, H arrays), recomputed from the last stored state before it if
        it was not stored (checkpointing). Recomputation overwrites the solver's fields."""
        st = self.states[n]
        if st is not None:
            return st
        if n not in self._segment:
            self._recompute_segment(n)
        return self._segment[n]

    def _recompute_segment(self, n: int):
        c = max(i for i in range(n) if self.states[i] is not None)
        end = min(i for i in range(n, len(self.states)) if self.states[i] is not None)
        s = self.solver
        self.activate()
        st = self.states[c]
        full = {"u": st["u"], "H": st["H"], "load": np.array(self.loads[c])}
        if s.alpha is not None:
            full["alpha"] = st["alpha"]
            full["alpha_committed"] = st["alpha"]
        s.set_state(full)
        self._segment = {}
        for m in range(c + 1, end):
            _step(s, float(self.loads[m]), m)
            self._segment[m] = _capture(s)

    def activate(self, n: int | None = None):
        """Put the path's rho and parameters into the solver; with ``n``, also load state n
        (u_n, alpha_n, H_n into ``solver.u``, ``solver.alpha``, ``solver.H``)."""
        s = self.solver
        if n is not None:
            st = self.state(n)
        s.rho.vec.FV().NumPy()[:] = self.rho
        _set_parameters(s, self.parameters)
        if n is not None:
            s.u.vec.FV().NumPy()[:] = st["u"]
            if s.alpha is not None:
                s.alpha.vec.FV().NumPy()[:] = st["alpha"]
            s.H.vec.FV().NumPy()[:] = st["H"]
            s.load = float(self.loads[n])
            s._r_valid = False


def _all_parameters(solver: Solver) -> dict:
    out = {"gamma0": solver.gamma0}
    for mid, pars in solver.material_parameters.items():
        for k, p in pars.items():
            out[f"{k}@{mid}"] = p
    return out


def _snapshot_parameters(solver: Solver) -> dict:
    return {k: float(p.Get()) for k, p in _all_parameters(solver).items()}


def _set_parameters(solver: Solver, values: dict):
    pars = _all_parameters(solver)
    for k, v in values.items():
        pars[k].Set(float(v))


def _default_region(solver: Solver) -> str:
    if solver.fracture_regions:
        for r in solver.mesh.GetMaterials():
            if any(re.fullmatch(f, r) for f in solver.fracture_regions):
                return r
    return solver.mesh.GetMaterials()[0]


def _resolve(solver: Solver, name: str) -> str:
    """Internal key (``"gamma0"`` or ``"E@<id>"``) of a user-facing parameter name."""
    if name == "gamma0":
        return "gamma0"
    key, _, region = name.partition(":")
    if key not in _MATERIAL_KEYS:
        raise ValueError(f"unknown parameter {name!r}; use 'rho', 'gamma0', one of {_MATERIAL_KEYS} or e.g. 'E:<region>'")
    region = region or _default_region(solver)
    if region not in solver.mesh.GetMaterials():
        raise ValueError(f"parameter {name!r}: unknown region {region!r}; regions: {sorted(set(solver.mesh.GetMaterials()))}")
    return f"{key}@{id(solver.scene.material_of(region))}"


def parameter_value(path: Path, name: str) -> float:
    """Value of a scalar parameter (``"E"``, ``"Gc:beam"``, ``"gamma0"``, ...) on a path."""
    return path.parameters[_resolve(path.solver, name)]


def design_mask(path_or_solver, regions: str | Sequence[str]) -> np.ndarray:
    """Boolean mask over elements of the named regions (regex, or a list of them)."""
    s = path_or_solver.solver if isinstance(path_or_solver, Path) else path_or_solver
    pats = [regions] if isinstance(regions, str) else list(regions)
    mats = s.mesh.GetMaterials()
    ids = [i for i, m in enumerate(mats) if any(re.fullmatch(p, m) for p in pats)]
    idx = np.array([el.index for el in s.mesh.Elements(ngs.VOL)])
    return np.isin(idx, ids)


# ====================================================================== forward
def _reset(solver: Solver):
    st = {"u": np.zeros(solver.fes_u.ndof), "H": np.zeros(solver.irs.ndof), "load": np.array(0.0)}
    if solver.alpha is not None:
        st["alpha"] = np.zeros(solver.fes_a.ndof)
        st["alpha_committed"] = np.zeros(solver.fes_a.ndof)
    solver.set_state(st)


def _capture(solver: Solver) -> dict:
    st = {"u": solver.u.vec.FV().NumPy().copy(), "H": solver.H_committed.copy()}
    if solver.alpha is not None:
        st["alpha"] = solver.alpha_committed.copy()
    return st


def _step(s: Solver, load: float, n: int):
    """One step of the single-pass scheme at a fixed load, by the runs' own
    :func:`ngtmc.stepping.schemes.alpha_u_passes`, and its history committed."""
    ok, info = alpha_u_passes(s, load)
    if not ok:
        raise RuntimeError(f"replay: step {n} (load {load:.6g} mm) failed: {info['message']}")
    s.update_history(info["H_trial"])
    return int(info.get("newton_iterations", 0))


def _thin(states: list, k: int | None):
    """Drop the state before the last one unless it is a checkpoint (index multiple of k)."""
    m = len(states) - 2
    if k and m > 0 and m % k != 0:
        states[m] = None


def check_recordable(scene: Scene, checkpoint_every: int | None, options: dict) -> str:
    """The scheme of a run that :func:`ngtmc.sensitivities.api.record_path` can record, or a
    ValueError that says why the run cannot be differentiated."""
    if checkpoint_every is not None and int(checkpoint_every) < 1:
        raise ValueError(f"checkpoint_every = {checkpoint_every!r} must be None or >= 1")
    if options.get("adapt") is not None:
        raise ValueError(CHANGED_MESH.format(what="adapt= refines the mesh during the run"))
    scheme = options.get("scheme", "single-pass")
    if scheme not in ("single-pass", "monolithic", "path-following"):
        raise ValueError(f"record_path: scheme={scheme!r} cannot be differentiated so far; the schemes with an "
                         f"adjoint are 'single-pass', 'monolithic' and 'path-following'")
    tractions = [ld.label for ld in scene.loads if isinstance(ld, Traction)]
    if tractions:
        raise ValueError(f"record_path: the adjoint does not handle Traction loads (force control) so far: "
                         f"{tractions}; use displacement loads (DisplacementLoad, DisplacementField)")
    return scheme


def record_single_pass(scene: Scene, schedule: Schedule | float, control: AdaptiveStepControl | None = None,
                       newton: NewtonOptions | None = None, checkpoint_every: int | None = None,
                       **options) -> Path:
    """The recording of :func:`ngtmc.sensitivities.api.record_path` for the single-pass scheme."""
    t0 = time.perf_counter()
    sim = Simulation(scene, schedule, control, newton=newton, **options)
    s = sim.solver
    s.floor_rtol = None  # states at the residual floor would limit the gradient's accuracy
    # each step starts from the last accepted state, as replay() and the recomputation between
    # checkpoints do (_step), so that they reproduce the recorded states exactly
    sim.secant_predictor = False
    states = [_capture(s)]
    forces = [s.reaction()]

    def grab(sim_, row):
        states.append(_capture(sim_.solver))
        forces.append(float(row["force"]))
        _thin(states, checkpoint_every)

    result = sim.run(callbacks=[grab])
    loads = np.asarray(result.history["load"], dtype=float)
    return Path(solver=s, loads=loads, states=states, forces=np.asarray(forces), rho=s.rho.vec.FV().NumPy().copy(),
                parameters=_snapshot_parameters(s), forward_time=time.perf_counter() - t0, history=result.history,
                checkpoint_every=checkpoint_every,
                newton_iterations=int(result.history["newton_iterations"].fillna(0).sum()))


def replay_inputs(path, rho=None, parameters: dict | None = None):
    """The density (one entry per element, a copy) and the full parameter dict of a replay of
    ``path`` with ``rho`` and ``parameters`` changed (names resolved as in :func:`parameter_value`).
    Raises ValueError for a density of the wrong length."""
    new_rho = path.rho.copy() if rho is None else np.asarray(rho, dtype=float).copy()
    if new_rho.shape != path.rho.shape:
        raise ValueError(f"rho has shape {new_rho.shape}; the mesh has {path.rho.size} elements")
    pars = dict(path.parameters)
    for name, v in (parameters or {}).items():
        pars[_resolve(path.solver, name)] = float(v)
    return new_rho, pars


def replay(path: Path, rho: np.ndarray | None = None, parameters: dict | None = None) -> Path:
    """Re-run the SAME load sequence as ``path`` (no adaptivity, no cut-backs) with another design
    ``rho`` (per element) and/or other ``parameters`` ({name: value}, names as in ``wrt`` of
    :func:`gradient`, e.g. ``{"E": 1010.0, "gamma0": 2e-4}``). Unnamed values are those of ``path``.

    Uses the solver of ``path`` (its fields are overwritten). Raises RuntimeError if Newton fails at a
    step. Returns a new :class:`Path` (sharing the solver). A path of a monolithic scheme is replayed
    by :func:`ngtmc.sensitivities.coupled.replay_coupled` (same step types, loads and dissipation
    targets)."""
    refuse_changed_mesh(path.solver)
    if getattr(path, "coupled", None) is not None:
        return path.replay(rho, parameters)          # CoupledPath.replay
    s = path.solver
    t0 = time.perf_counter()
    new_rho, pars = replay_inputs(path, rho, parameters)
    s.rho.vec.FV().NumPy()[:] = new_rho
    _set_parameters(s, pars)
    _reset(s)
    states = [_capture(s)]
    forces = [s.reaction()]
    newton = 0
    for n, load in enumerate(path.loads[1:], start=1):
        newton += _step(s, float(load), n)
        states.append(_capture(s))
        forces.append(s.reaction())
        _thin(states, path.checkpoint_every)
    return Path(solver=s, loads=path.loads.copy(), states=states, forces=np.asarray(forces), rho=new_rho,
                parameters=pars, forward_time=time.perf_counter() - t0, checkpoint_every=path.checkpoint_every,
                newton_iterations=newton)

