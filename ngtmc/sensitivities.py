"""Exact gradients of a recorded load path: the discrete adjoint of the scheme that was run.

    path = record_path(scene, Schedule([0, 0.2]), AdaptiveStepControl(du_max=0.0125),
                       newton=NewtonOptions(rtol=1e-12))
    g = gradient(path, ExternalWork(), wrt=("rho", "E", "Gc", "l0", "gamma0"))
    # or in one call: g, path = differentiate(scene, Schedule([0, 0.2]), ExternalWork(), control)
    g["value"]        # J, in the objective's unit (N mm for ExternalWork)
    g["rho"]          # dJ/drho, one entry per element (numpy array, J-unit per unit density)
    g["E"]            # dJ/dE, J-unit per MPa

Schemes: ``record_path(..., scheme=...)`` with

* ``"single-pass"`` (the default): this module, described below;
* ``"monolithic"`` (load control) and ``"path-following"`` (dissipation control where the crack
  grows): :mod:`ngtmc.sensitivities_coupled`, reached through the same functions (``record_path``
  returns a :class:`~ngtmc.sensitivities_coupled.CoupledPath`; ``replay``, ``gradient``,
  ``directional_fd``, ``taylor_test`` dispatch on it). There every step is the converged coupled
  solve (u_n, alpha_n) with the step's own history H_n(u_n) and the bounds alpha_{n-1} <= alpha_n
  <= 1 as active sets; held fixed are the step types and, per step, the load lambda_n of a
  displacement step or the dissipation target dD_n of a dissipation step (whose load is then a
  state variable, differentiated through the dissipation constraint);
* ``"staggered"``: not differentiated (refused).

What is differentiated for ``scheme="single-pass"`` (see ``docs/sensitivities.md`` for the
derivation): the scheme that :class:`~ngtmc.simulation.Simulation` actually solved. At every recorded
load step n, with the imposed displacement lambda_n held fixed,

1. alpha_n = P_n(A(H_{n-1})^{-1} f(H_{n-1})), P_n the projection onto [alpha_{n-1}, 1];
2. R(u_n; alpha_n, rho) = 0 on the free dofs (Dirichlet values u_D(lambda_n) of every displacement
   load, independent of rho; the reaction F_n = <R, d u_D / d lambda> of the force load
   ``Scene.force_from``). Traction loads are refused by :func:`record_path`;
3. H_n = max(H_{n-1}, Psi_plus(u_n)) at the history quadrature points.

The energy of (2) and the Psi_plus of (3) are those of the scene's ``split`` and ``formulation``
(:mod:`ngtmc.splits`): the adjoint follows every pair, since it differentiates the solver's own
expressions symbolically (checked against finite differences for the default, for "vol-dev-small"
hybrid, "vol-dev-log" hybrid and "spectral" anisotropic in ``tests/test_sensitivities.py``; the
derivatives are one-sided where a principal strain, tr eps or ln J is exactly zero). Measured: the
gradient sweep with "vol-dev-log" is slow (8 steps on the coarse notched plate of that test: 243 s
against 14 s with "spectral"), so that case is not in the test suite.

**Held fixed:** the sequence of loads lambda_1..lambda_N chosen by the adaptive step control (its
decisions depend on W_f and on Newton failures, which are not differentiable events), the active
sets of the projection in (1) and of the max in (3) (derivatives are taken along the branch that
was active; they are one-sided where a branch is tied), and the Newton iterates (only the converged
u_n enters, through the implicit function theorem). :func:`replay` re-runs exactly this load
sequence without adaptivity, which is what a finite-difference check must compare against.

**Memory:** every accepted state is stored (u_n, alpha_n, H_n as float64 arrays):
``Path.memory_bytes`` = 8 (N + 1) (ndof_u + ndof_alpha + n_history_points) bytes, or with
``record_path(..., checkpoint_every=k)`` only every k-th state (the others are recomputed segment by
segment during the sweep, for one extra forward run; see :class:`Path`). The reverse sweep
re-assembles the tangent K_n and the phase-field matrix A_n from the stored states (one assembly
and one factorization of each per step) instead of storing factorizations.

**Cost:** one gradient = per step one assembly + factorization + solve of K_n and of A_n plus a few
linear-form assemblies; the forward run needs several Newton iterations per step, so a gradient
costs about one forward run or less (measured in ``tests/test_sensitivities.py``).

Parameters that can be differentiated (``wrt``): ``"rho"`` (element densities), ``"gamma0"``, and
the material constants ``"E"``, ``"nu"``, ``"Gc"``, ``"l0"`` of the *default material* (the material
of the first fracture region, or of the first region if nothing may break). ``"E:region"`` names the
material of another region. The regulariser stiffness k_r = kbar_r L^2 K0 depends on E and nu and is
differentiated with them.

Units: mm, N, MPa. Forces and energies are for the scene thickness in 2D.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import re
import time
from typing import Callable, Iterable, Sequence

import numpy as np
import ngsolve as ngs

from . import fracture
from .materials import deformation_gradient
from .conditions import Traction
from .scene import Scene
from .simulation import Simulation
from .discretisation import rules
from .solver import NewtonOptions, Solver
from .stepping import AdaptiveStepControl, Schedule

__all__ = [
    "Path", "record_path", "replay", "gradient", "differentiate", "evaluate", "parameter_value", "design_mask",
    "Objective", "ReactionAtStep", "ExternalWork", "FinalFractureEnergy", "ComplianceAtStep",
    "UserObjective", "ForceCurveObjective", "directional_fd", "taylor_test",
]

_MATERIAL_KEYS = ("E", "nu", "Gc", "l0")


# ====================================================================== recorded path
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
    """One step of the single-pass scheme at a fixed load (as Simulation does it)."""
    s.solve_phase_field()
    res = s.solve_displacement(load)
    if not res.converged:
        raise RuntimeError(f"replay: Newton failed at step {n} (load {load:.6g} mm): {res.message}")
    H = s.trial_history() if s.alpha is not None else None
    if H is not None and not np.all(np.isfinite(H)):
        raise RuntimeError(f"replay: history not finite at step {n} (J <= 0 at a history point)")
    s.update_history(H)


def _thin(states: list, k: int | None):
    """Drop the state before the last one unless it is a checkpoint (index multiple of k)."""
    m = len(states) - 2
    if k and m > 0 and m % k != 0:
        states[m] = None


def record_path(scene: Scene, schedule: Schedule | float, control: AdaptiveStepControl | None = None,
                newton: NewtonOptions | None = None, checkpoint_every: int | None = None, **options) -> Path:
    """Run ``scene`` through ``schedule`` (adaptive steps as in :class:`~ngtmc.simulation.Simulation`)
    and store every accepted state for :func:`gradient`.

    ``options`` go to :class:`~ngtmc.simulation.Simulation`; ``scheme="single-pass"`` (the paper's
    scheme, the default), ``"monolithic"`` and ``"path-following"`` can be differentiated (the two
    monolithic ones by :mod:`ngtmc.sensitivities_coupled`, which returns a
    :class:`~ngtmc.sensitivities_coupled.CoupledPath`; no checkpointing there). For gradients that
    agree with finite differences to 1e-4, converge Newton tightly, e.g.
    ``newton=NewtonOptions(rtol=1e-12)``, and for the monolithic schemes also the phase field,
    ``coupled={"alpha_tol": 1e-12}``. ``checkpoint_every``: store only every k-th state (see
    :class:`Path`). Returns a :class:`Path`."""
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
    if scheme != "single-pass":
        from .sensitivities_coupled import record_coupled_path
        return record_coupled_path(scene, schedule, control, newton=newton, checkpoint_every=checkpoint_every,
                                   **options)
    t0 = time.perf_counter()
    sim = Simulation(scene, schedule, control, newton=newton, **options)
    s = sim.solver
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
                checkpoint_every=checkpoint_every)


def replay(path: Path, rho: np.ndarray | None = None, parameters: dict | None = None) -> Path:
    """Re-run the SAME load sequence as ``path`` (no adaptivity, no cut-backs) with another design
    ``rho`` (per element) and/or other ``parameters`` ({name: value}, names as in ``wrt`` of
    :func:`gradient`, e.g. ``{"E": 1010.0, "gamma0": 2e-4}``). Unnamed values are those of ``path``.

    Uses the solver of ``path`` (its fields are overwritten). Raises RuntimeError if Newton fails at a
    step. Returns a new :class:`Path` (sharing the solver). A path of a monolithic scheme is replayed
    by :func:`ngtmc.sensitivities_coupled.replay_coupled` (same step types, loads and dissipation
    targets)."""
    refuse_changed_mesh(path.solver)
    if getattr(path, "coupled", None) is not None:
        from .sensitivities_coupled import replay_coupled
        return replay_coupled(path, rho, parameters)
    s = path.solver
    t0 = time.perf_counter()
    new_rho = path.rho.copy() if rho is None else np.asarray(rho, dtype=float).copy()
    if new_rho.shape != path.rho.shape:
        raise ValueError(f"rho has shape {new_rho.shape}; the mesh has {path.rho.size} elements")
    pars = dict(path.parameters)
    for name, v in (parameters or {}).items():
        pars[_resolve(s, name)] = float(v)
    s.rho.vec.FV().NumPy()[:] = new_rho
    _set_parameters(s, pars)
    _reset(s)
    states = [_capture(s)]
    forces = [s.reaction()]
    for n, load in enumerate(path.loads[1:], start=1):
        _step(s, float(load), n)
        states.append(_capture(s))
        forces.append(s.reaction())
        _thin(states, path.checkpoint_every)
    return Path(solver=s, loads=path.loads.copy(), states=states, forces=np.asarray(forces), rho=new_rho,
                parameters=pars, forward_time=time.perf_counter() - t0, checkpoint_every=path.checkpoint_every)


# ====================================================================== objectives
@dataclass
class Seeds:
    """Partial derivatives of an objective at one step (explicit dependence only).

    force: dJ/dF_n (F_n the reaction of step n, N), handled through the residual;
    cfs: list of (CF, region regex or None, weight): J contains weight * thickness * int CF dx,
    differentiated symbolically with respect to u, alpha, rho and the parameters."""

    force: float = 0.0
    cfs: list = field(default_factory=list)

    def __iadd__(self, other: "Seeds"):
        self.force += other.force
        self.cfs.extend(other.cfs)
        return self


class Objective:
    """Base class: J = sum over recorded steps of functionals of (u_n, alpha_n, rho, parameters).

    A subclass implements ``value(path) -> float`` and ``seeds(path, n) -> Seeds | None`` (the
    explicit partial derivatives at step n, as a weight on the reaction F_n and/or CFs to
    differentiate symbolically). Objectives can be added and scaled: ``ExternalWork() - 0.1 *
    FinalFractureEnergy()``."""

    unit = ""

    def value(self, path: Path) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def seeds(self, path: Path, n: int) -> Seeds | None:  # pragma: no cover - abstract
        raise NotImplementedError

    def load_seeds(self, path: Path) -> np.ndarray:
        """dJ/dlambda_n, n = 0..N (explicit dependence on the recorded loads; J-unit per mm). Needed
        only where the load is an unknown: the dissipation steps of a path-following path
        (:mod:`ngtmc.sensitivities_coupled`)."""
        raise NotImplementedError(f"{type(self).__name__} gives no derivative with respect to the loads "
                                  f"(load_seeds), which the dissipation steps of a path-following path need")

    def __add__(self, other):
        return _Combination([(1.0, self), (1.0, other)])

    def __sub__(self, other):
        return _Combination([(1.0, self), (-1.0, other)])

    def __mul__(self, c):
        return _Combination([(float(c), self)])

    __rmul__ = __mul__

    def __neg__(self):
        return _Combination([(-1.0, self)])


class _Combination(Objective):
    def __init__(self, terms):
        self.terms = []
        for c, o in terms:
            if isinstance(o, _Combination):
                self.terms.extend((c * c2, o2) for c2, o2 in o.terms)
            else:
                self.terms.append((c, o))

    def value(self, path):
        return sum(c * o.value(path) for c, o in self.terms)

    def load_seeds(self, path):
        return sum(c * np.asarray(o.load_seeds(path), dtype=float) for c, o in self.terms)

    def seeds(self, path, n):
        out = Seeds()
        for c, o in self.terms:
            s = o.seeds(path, n)
            if s is not None:
                out.force += c * s.force
                out.cfs.extend((cf, reg, c * w) for cf, reg, w in s.cfs)
        return out


def _step_index(path: Path, step: int) -> int:
    n = step if step >= 0 else path.n_steps + 1 + step
    if not 1 <= n <= path.n_steps:
        raise ValueError(f"step {step} is outside the recorded steps 1..{path.n_steps}")
    return n


class ReactionAtStep(Objective):
    """J = F_n, the reaction of the scene's force load (``Scene.force_from``, default the first
    load; the history's ``force`` column) at recorded step ``step`` (negative counts from the end), N."""

    unit = "N"

    def __init__(self, step: int = -1):
        self.step = step

    def value(self, path):
        return float(path.forces[_step_index(path, self.step)])

    def seeds(self, path, n):
        return Seeds(force=1.0) if n == _step_index(path, self.step) else None

    def load_seeds(self, path):
        return np.zeros(path.n_steps + 1)


class ComplianceAtStep(Objective):
    """J = F_n lambda_n, N mm: the work of the reaction on the imposed displacement at step ``step``
    (the end compliance of displacement control; twice the stored energy in linear elasticity)."""

    unit = "N mm"

    def __init__(self, step: int = -1):
        self.step = step

    def value(self, path):
        n = _step_index(path, self.step)
        return float(path.forces[n] * path.loads[n])

    def seeds(self, path, n):
        return Seeds(force=float(path.loads[n])) if n == _step_index(path, self.step) else None

    def load_seeds(self, path):
        out = np.zeros(path.n_steps + 1)
        n = _step_index(path, self.step)
        out[n] = path.forces[n]
        return out


class ExternalWork(Objective):
    """J = sum_n (F_n + F_{n-1})/2 (lambda_n - lambda_{n-1}), N mm: trapezoidal external work along
    the whole recorded path (energy absorbed; unloading steps count negatively)."""

    unit = "N mm"

    def _weights(self, path):
        lam = path.loads
        c = np.zeros_like(lam)
        d = np.diff(lam)
        c[1:] += d / 2
        c[:-1] += d / 2
        return c

    def value(self, path):
        return float(np.dot(self._weights(path), path.forces))

    def seeds(self, path, n):
        return Seeds(force=float(self._weights(path)[n]))

    def load_seeds(self, path):
        F = np.asarray(path.forces, dtype=float)
        out = np.zeros_like(F)
        out[1:] += (F[1:] + F[:-1]) / 2   # + lambda_n in (lambda_n - lambda_{n-1})
        out[:-1] -= (F[1:] + F[:-1]) / 2  # - lambda_n in (lambda_{n+1} - lambda_n)
        out[0] = 0.0
        return out


class FinalFractureEnergy(Objective):
    """J = W_f at the last step, N mm (Eq. 19 times the thickness, as the history's
    ``fracture_energy`` column): int Gc(rho) (alpha_N^2/l0 + l0 |grad alpha_N|^2)."""

    unit = "N mm"

    def value(self, path):
        return _cf_value(path, path.n_steps, self.seeds(path, path.n_steps).cfs)

    def seeds(self, path, n):
        if n != path.n_steps:
            return None
        s = path.solver
        if s.alpha is None:
            return Seeds()
        cache = self.__dict__.setdefault("_cf", {})
        if id(s) not in cache:
            cache[id(s)] = (s, fracture.fracture_energy_density(s.alpha, s.Gc, s.l0))
        return Seeds(cfs=[(cache[id(s)][1], s._frac_re, 1.0)])

    def load_seeds(self, path):
        return np.zeros(path.n_steps + 1)


class UserObjective(Objective):
    """J = sum_n thickness * int density(solver, n) dx, differentiated automatically.

    density(solver, n) -> CoefficientFunction or None, built from the solver's fields
    ``solver.u``, ``solver.alpha``, ``solver.rho`` (which hold u_n, alpha_n, rho when it is called)
    and its coefficient functions (``solver.K``, ``solver.G``, ``solver.Gc``, ``solver.l0``,
    parameters): every dependence on them is differentiated with ``CF.Diff``. Return None at steps
    that do not contribute. The integral uses the history quadrature rule (exact for polynomials of
    degree 2p) over ``region`` (regex; None = whole mesh). ``unit``: unit of J, for reports. Return
    the SAME CF object at every step if possible (its derivative forms are then built once)."""

    def __init__(self, density: Callable, region: str | None = None, unit: str = ""):
        self.density = density
        self.region = region
        self.unit = unit

    def seeds(self, path, n):
        cf = self.density(path.solver, n)
        return None if cf is None else Seeds(cfs=[(cf, self.region, 1.0)])

    def load_seeds(self, path):
        """Zero: the density may depend on the fields, rho and the parameters, not on the load."""
        return np.zeros(path.n_steps + 1)

    def value(self, path):
        total = 0.0
        for n in range(1, path.n_steps + 1):
            path.activate(n)
            s = self.seeds(path, n)
            if s is not None:
                total += _cf_value(path, n, s.cfs, activated=True)
        return total


class ForceCurveObjective(Objective):
    """J = phi(F_1, ..., F_N), a function of the recorded reaction forces (e.g. the misfit to a
    measured curve, for calibration). ``phi(forces, loads) -> (value, dphi/dforces)``, forces and
    loads arrays of length N + 1 (index 0 = unloaded state); phi may return dphi/dloads as a third
    item (needed on the dissipation steps of a path-following path, where the loads depend on
    the design).

    :meth:`least_squares` builds the usual misfit 1/2 sum_n (F_n - F_meas(lambda_n))^2, N^2, with
    F_meas interpolated linearly in the measured (load, force) points."""

    def __init__(self, phi: Callable, unit: str = ""):
        self.phi = phi
        self.unit = unit

    @classmethod
    def least_squares(cls, measured_loads, measured_forces):
        ml = np.asarray(measured_loads, dtype=float)
        mf = np.asarray(measured_forces, dtype=float)

        def phi(forces, loads):
            r = forces - np.interp(loads, ml, mf)
            r[0] = 0.0
            h = 1e-7 * max(float(np.ptp(ml)), 1e-300)  # slope of the interpolant (mean of both sides at a node)
            slope = (np.interp(loads + h, ml, mf) - np.interp(loads - h, ml, mf)) / (2 * h)
            return 0.5 * float(r @ r), r, -r * slope

        return cls(phi, unit="N^2")

    def value(self, path):
        return float(self.phi(path.forces, path.loads)[0])

    def seeds(self, path, n):
        if not hasattr(path, "_phi_cache") or path._phi_cache[0] is not self:
            path._phi_cache = (self, np.asarray(self.phi(path.forces, path.loads)[1], dtype=float))
        return Seeds(force=float(path._phi_cache[1][n]))

    def load_seeds(self, path):
        out = self.phi(path.forces, path.loads)
        if len(out) < 3:
            return super().load_seeds(path)
        return np.asarray(out[2], dtype=float)


def evaluate(path: Path, objective: Objective) -> float:
    """Value of ``objective`` on ``path``."""
    return float(objective.value(path))


# ====================================================================== adjoint engine
class _FormSet:
    """Linear forms of the partial derivatives of sum_i int cf_i, built on first use."""

    def __init__(self, eng, pieces, with_alpha):
        self.eng = eng
        self.pieces = pieces
        self.with_alpha = with_alpha
        self.forms = {}

    def __contains__(self, key):
        if key == "alpha":
            return self.with_alpha and self.eng.s.alpha is not None
        return key == "rho" or key in self.eng.params or key in self.forms

    def __setitem__(self, key, lf):
        self.forms[key] = lf

    def __getitem__(self, key):
        if key not in self.forms:
            eng, s = self.eng, self.eng.s
            if key == "rho":
                lf = ngs.LinearForm(eng.fes_rho)
                for cf, meas in self.pieces:
                    lf += cf.Diff(s.rho, eng.q) * meas
            elif key == "alpha":
                lf = ngs.LinearForm(s.fes_a)
                for cf, meas in self.pieces:
                    lf += cf.Diff(s.alpha, eng.b) * meas
            else:
                p = eng.params[key]
                lf = ngs.LinearForm(eng.fes_rho)
                for cf, meas in self.pieces:
                    lf += cf.Diff(p) * eng.q * meas
            self.forms[key] = lf
        return self.forms[key]


class _Engine:
    """Forms for the partial derivatives of the discrete scheme, built once per solver."""

    def __init__(self, solver: Solver):
        s = self.s = solver
        mesh = s.mesh
        self.fes_rho = s.rho.space
        self.q = self.fes_rho.TestFunction()
        self.v = s.fes_u.TestFunction()
        self.params = _all_parameters(s)
        self.terms = s.energy_terms(s.u)
        self.term_measures = [s.energy_measure(name, reg) for name, _, reg in self.terms]
        # adjoint-carrying GridFunctions
        self.z_u = ngs.GridFunction(s.fes_u)      # residual contraction vector
        self.z_H = ngs.GridFunction(s.irs)        # adjoint density of Psi_plus at the history points
        self._forms = {}
        if s.alpha is not None:
            self.b = s.fes_a.TestFunction()
            self.a_trial = ngs.GridFunction(s.fes_a)  # unprojected alpha solution
            self.mu = ngs.GridFunction(s.fes_a)       # phase-field adjoint
            self.frac_ind = mesh.MaterialCF({r: 1.0 for r in set(mesh.GetMaterials())
                                             if any(re.fullmatch(f, r) for f in s.fracture_regions)}, default=0.0)
            self.dx_Hf = ngs.dx(definedon=mesh.Materials(s._frac_re), intrules=s.irs.GetIntegrationRules())
            self.dx_af = ngs.dx(definedon=mesh.Materials(s._frac_re), intrules=rules(mesh, 2))
        self._build()

    # ---------------------------------------------------------------- forms
    def _scalar_forms(self, pieces, with_alpha=True):
        """pieces: list of (CF, measure). Returns a lazily built dict of LinearForms for the partial
        derivatives of sum int CF: "alpha" (on the phase-field space), "rho" (one entry per element)
        and one per parameter key (on the rho space; the derivative is the sum of its entries)."""
        return _FormSet(self, pieces, with_alpha)

    def _build(self):
        s = self.s
        # <R(u; alpha, rho, p), z_u>: partials with respect to alpha, rho, p
        # the measures of the solver's energy terms: the partial derivatives of the residual use
        # the very rules that Newton used
        self.res_pieces = [(dens.Diff(s.u, self.z_u), meas) for (_, dens, _), meas in zip(self.terms, self.term_measures)]
        self.res_forms = self._scalar_forms(self.res_pieces)
        if s.alpha is not None:
            # history: sum_k w_k z_H(x_k) Psi_plus(u, rho, p)(x_k) over the fracture regions
            pp = s.crack_driving_density(deformation_gradient(s.u))
            self.psi_cf = pp
            piece = [(self.z_H * pp, self.dx_Hf)]
            self.hist_forms = self._scalar_forms(piece)
            self.hist_u = ngs.LinearForm(s.fes_u)
            self.hist_u += self.z_H * pp.Diff(s.u, self.v) * self.dx_Hf
            # <R_a(a_trial; H, rho, p), mu> without the H terms (those are handled pointwise)
            ga, mu = self.a_trial, self.mu
            Sa = s.Gc / s.l0 * ga * mu + s.Gc * s.l0 * ngs.InnerProduct(ngs.Grad(ga), ngs.Grad(mu))
            self.alpha_forms = self._scalar_forms([(Sa, self.dx_af)], with_alpha=False)
            self._irs_tmp = ngs.GridFunction(s.irs)

    def cf_forms(self, cf, region):
        key = (id(cf), region)
        if key not in self._forms:
            s = self.s
            reg = region if region is not None else ".*"
            meas = ngs.dx(definedon=s.mesh.Materials(reg), intrules=s.irs.GetIntegrationRules())
            forms = self._scalar_forms([(cf, meas)])
            lf_u = ngs.LinearForm(s.fes_u)
            lf_u += cf.Diff(s.u, self.v) * meas
            forms["u"] = lf_u
            self._forms[key] = (cf, forms)  # keep cf alive so id() stays unique
        return self._forms[key][1]


def _integrate_rule(path: Path, cf, region):
    s = path.solver
    reg = region if region is not None else ".*"
    meas = ngs.dx(definedon=s.mesh.Materials(reg), intrules=s.irs.GetIntegrationRules())
    lf = ngs.LinearForm(s.rho.space)
    lf += cf * s.rho.space.TestFunction() * meas
    lf.Assemble()
    return float(np.sum(lf.vec.FV().NumPy()))


def _cf_value(path: Path, n: int, cfs, activated: bool = False) -> float:
    if not activated:
        path.activate(n)
    t = path.solver.thickness
    return sum(w * t * _integrate_rule(path, cf, reg) for cf, reg, w in cfs)


def _engine(path: Path) -> _Engine:
    s = path.solver
    eng = getattr(s, "_sensitivity_engine", None)
    if eng is None:
        eng = _Engine(s)
        s._sensitivity_engine = eng
    return eng


def _wrt_keys(solver, wrt):
    out = []
    for name in wrt:
        if name == "rho":
            continue
        out.append((name, _resolve(solver, name)))
    return out


class _Accumulator:
    """The sums dJ/drho (one entry per element) and dJ/dp of a reverse sweep."""

    def __init__(self, solver: Solver, wrt: tuple, keys: list):
        self.want_rho = "rho" in wrt
        self.keys = keys
        self.rho = np.zeros(solver.rho.space.ndof)
        self.par = {k: 0.0 for _, k in keys}

    def add(self, forms, sign=1.0, alpha_acc=None):
        """Add ``sign`` times the partial derivatives of a :class:`_FormSet` (assembled now) with
        respect to rho and the parameters; with ``alpha_acc``, add its alpha partial there."""
        if self.want_rho:
            forms["rho"].Assemble()
            self.rho += sign * forms["rho"].vec.FV().NumPy()
        for _, k in self.keys:
            forms[k].Assemble()
            self.par[k] += sign * float(np.sum(forms[k].vec.FV().NumPy()))
        if alpha_acc is not None and "alpha" in forms:
            forms["alpha"].Assemble()
            alpha_acc += sign * forms["alpha"].vec.FV().NumPy()

    def result(self, value: float, t0: float, forward_time: float) -> dict:
        """The dict returned by :func:`gradient`."""
        out = {"value": value}
        if self.want_rho:
            out["rho"] = self.rho
        for name, k in self.keys:
            out[name] = self.par[k]
        out["time"] = time.perf_counter() - t0
        out["forward_time"] = forward_time
        return out


def history_adjoint(eng, H_prev: np.ndarray, eta: np.ndarray):
    """Split the adjoint ``eta`` of H_n = max(H_{n-1}, Psi_plus(u_n)) (per history point, at the
    engine's current u_n) by the active branch: returns (the part passed on to H_{n-1}, the u_n
    residual term of the part where Psi_plus was taken or None if there is none, the boolean
    mask of the points where it was taken). The engine's ``hist_forms`` then carry the parameter
    terms of that part (weight 1)."""
    eng._irs_tmp.Interpolate(eng.psi_cf)
    psi = eng._irs_tmp.vec.FV().NumPy()
    mask = psi > H_prev
    zH = np.where(mask, eta, 0.0)
    eta = np.where(mask, 0.0, eta)
    if not np.any(zH != 0.0):
        return eta, None, mask
    eng.z_H.vec.FV().NumPy()[:] = zH
    eng.hist_u.Assemble()
    return eta, eng.hist_u.vec.FV().NumPy().copy(), mask


def gradient(path: Path, objective: Objective, wrt: Iterable[str] = ("rho", "E", "Gc", "l0", "gamma0")) -> dict:
    """dJ/drho and dJ/dparameters of ``objective`` on the recorded ``path`` by one reverse sweep.

    Returns a dict: ``"value"`` (J), ``"rho"`` (array, one entry per element, dJ/drho_e) if asked,
    one float per scalar parameter name in ``wrt`` (dJ/dE in J-unit/MPa, dJ/dGc in J-unit/(N/mm),
    dJ/dl0 in J-unit/mm, dJ/dgamma0 dimensionless), ``"time"`` (wall time of the sweep, s) and
    ``"forward_time"`` (wall time of the path's forward run, s).

    The derivative is exact for the discrete scheme with the recorded load steps and active sets
    held fixed (see the module docstring). Only the solver's fields are changed; the solver is
    left in the final state of the path. A path of a monolithic scheme is differentiated by
    :func:`ngtmc.sensitivities_coupled.coupled_gradient`."""
    refuse_changed_mesh(path.solver)
    if getattr(path, "coupled", None) is not None:
        from .sensitivities_coupled import coupled_gradient
        return coupled_gradient(path, objective, wrt)
    t0 = time.perf_counter()
    wrt = tuple(wrt)
    s = path.solver
    path.activate()
    eng = _engine(path)
    keys = _wrt_keys(s, wrt)
    value = objective.value(path)
    N = path.n_steps
    t = s.thickness
    free = s._free_np
    acc = _Accumulator(s, wrt, keys)
    add_scalar = acc.add
    has_a = s.alpha is not None
    eta = np.zeros(s.irs.ndof)                      # adjoint density of H_n (per unit quadrature weight)
    abar_carry = np.zeros(s.fes_a.ndof) if has_a else None
    Kinv = None
    Ainv = None

    for n in range(N, 0, -1):
        st_prev = path.state(n - 1)  # (may recompute a segment: before the solver fields are set)
        path.activate(n)
        seeds = objective.seeds(path, n) or Seeds()
        ubar = np.zeros(s.fes_u.ndof)
        abar = abar_carry.copy() if has_a else None
        # ---- explicit partials of CF terms of the objective
        for cf, reg, w in seeds.cfs:
            forms = eng.cf_forms(cf, reg)
            forms["u"].Assemble()
            ubar += w * t * forms["u"].vec.FV().NumPy()
            add_scalar(forms, w * t, abar)
        # ---- (3) history H_n = max(H_{n-1}, Psi_plus(u_n))
        if has_a:
            H_prev = st_prev["H"]
            eta, u_term, _ = history_adjoint(eng, H_prev, eta)
            if u_term is not None:
                ubar += u_term
                add_scalar(eng.hist_forms, 1.0, abar)
        # ---- (2) displacement equilibrium: reaction seeds and the adjoint solve with K_n
        s.a_u.AssembleLinearization(s.u.vec)
        e_np = s.reaction_weight(lam=float(path.loads[n]))  # d u_D / d lambda of the force load at lambda_n
        if seeds.force != 0.0:
            Ke = s.a_u.mat.CreateColVector()
            ev = s.a_u.mat.CreateColVector()
            ev.FV().NumPy()[:] = e_np
            Ke.data = s.a_u.mat * ev
            ubar += seeds.force * t * Ke.FV().NumPy()
        z = seeds.force * t * e_np
        ubar[~free] = 0.0
        if np.any(ubar != 0.0):
            if Kinv is None:
                Kinv = s.a_u.mat.Inverse(s.free, inverse=s.newton.linear_solver)
            else:
                Kinv.Update()
            rhs = s.a_u.mat.CreateColVector()
            rhs.FV().NumPy()[:] = ubar
            lam = s.a_u.mat.CreateColVector()
            lam.data = Kinv * rhs
            lamN = lam.FV().NumPy()
            lamN[~free] = 0.0
            z = z - lamN
        if np.any(z != 0.0):
            eng.z_u.vec.FV().NumPy()[:] = z
            add_scalar(eng.res_forms, 1.0, abar)
        # ---- (1) phase field: unprojected solve from H_{n-1} and the projection onto [alpha_{n-1}, 1]
        if has_a:
            a_prev = st_prev["alpha"]
            s.H.vec.FV().NumPy()[:] = st_prev["H"]
            s.a_alpha.Assemble()
            s.f_alpha.Assemble()
            if Ainv is None:
                Ainv = s.a_alpha.mat.Inverse(s.fes_a.FreeDofs(), inverse="sparsecholesky")
            else:
                Ainv.Update()
            eng.a_trial.vec.data = Ainv * s.f_alpha.vec
            at = eng.a_trial.vec.FV().NumPy()
            prev = at < a_prev
            free_a = (~prev) & (at <= 1.0)
            abar_carry = np.where(prev, abar, 0.0)
            abar_t = np.where(free_a, abar, 0.0)
            if np.any(abar_t != 0.0):
                rhs = s.a_alpha.mat.CreateColVector()
                rhs.FV().NumPy()[:] = abar_t
                eng.mu.vec.data = Ainv * rhs
                # d/dH of <mu, R_a> = 2 (a_trial - 1) mu per unit weight, at the history points
                eng._irs_tmp.Interpolate(eng.frac_ind * 2 * (eng.a_trial - 1) * eng.mu)
                eta = eta - eng._irs_tmp.vec.FV().NumPy()
                add_scalar(eng.alpha_forms, -1.0)
    path.activate(N)
    return acc.result(value, t0, path.forward_time)


def differentiate(scene: Scene, schedule: Schedule | float, objective: Objective,
                  control: AdaptiveStepControl | None = None,
                  wrt: Iterable[str] = ("rho", "E", "Gc", "l0", "gamma0"), **options) -> tuple[dict, Path]:
    """One call: run ``scene`` through ``schedule`` (:func:`record_path`, ``options`` as there) and
    return (``gradient(path, objective, wrt)``, path). Newton defaults to ``rtol=1e-12`` here, and
    for the monolithic schemes the coupled solver's ``alpha_tol`` to 1e-12."""
    options.setdefault("newton", NewtonOptions(rtol=1e-12))
    if options.get("scheme") in ("monolithic", "path-following"):
        options["coupled"] = {"alpha_tol": 1e-12, **(options.get("coupled") or {})}
    path = record_path(scene, schedule, control, **options)
    return gradient(path, objective, wrt), path


# ====================================================================== checks
def _perturbed(path: Path, direction: dict, eps: float) -> Path:
    rho = path.rho + eps * np.asarray(direction["rho"]) if "rho" in direction else None
    pars = {k: parameter_value(path, k) + eps * v for k, v in direction.items() if k != "rho"}
    return replay(path, rho=rho, parameters=pars)


def directional_fd(path: Path, objective, direction: dict, eps: float, return_paths: bool = False):
    """Central finite difference (J(p + eps d) - J(p - eps d)) / (2 eps) by two :func:`replay` runs.

    objective: an Objective or a list of them (all evaluated on the same two replays; a list gives
    a numpy array). direction: {"rho": array, "E": dE, ...} (absent entries are zero). With
    ``return_paths`` also returns the two replayed paths (for :func:`active_set_changes`)."""
    objs = objective if isinstance(objective, (list, tuple)) else [objective]
    paths = [_perturbed(path, direction, sgn * eps) for sgn in (1.0, -1.0)]
    fd = np.array([(o.value(paths[0]) - o.value(paths[1])) / (2 * eps) for o in objs])
    path.activate()
    out = fd if isinstance(objective, (list, tuple)) else float(fd[0])
    return (out, paths) if return_paths else out


def active_sets(path: Path) -> list:
    """Per step n = 1..N the active branches of the scheme: ``"history"`` (bool per history point:
    H_n > H_{n-1}, i.e. the max took Psi_plus), ``"alpha_held"`` (bool per phase-field dof:
    alpha_n == alpha_{n-1}, irreversibility or the upper bound active) and ``"alpha_one"``
    (alpha_n == 1)."""
    out = []
    for n in range(1, path.n_steps + 1):
        a, b = path.state(n - 1), path.state(n)
        d = {"history": b["H"] > a["H"]}
        if "alpha" in b:
            d["alpha_held"] = b["alpha"] == a["alpha"]
            d["alpha_one"] = b["alpha"] >= 1.0
        out.append(d)
    return out


def active_set_changes(path_a: Path, path_b: Path) -> dict:
    """Number of history points and phase-field dofs whose active branch differs between two paths
    of the same load sequence (a finite difference across a switch is not a derivative)."""
    sa, sb = active_sets(path_a), active_sets(path_b)
    out = {"history": 0, "alpha_held": 0, "alpha_one": 0}
    for x, y in zip(sa, sb):
        for k in out:
            if k in x:
                out[k] += int(np.count_nonzero(x[k] != y[k]))
    return out


def directional_derivative(grad: dict, direction: dict) -> float:
    """<dJ/dp, d> for a gradient dict of :func:`gradient` and a direction as in :func:`directional_fd`."""
    total = 0.0
    for k, v in direction.items():
        total += float(np.dot(grad[k], v)) if k == "rho" else float(grad[k]) * float(v)
    return total


def taylor_test(path: Path, objective: Objective, direction: dict, grad: dict, eps_list=(4e-2, 2e-2, 1e-2, 5e-3)) -> dict:
    """Remainders |J(p + eps d) - J(p) - eps <dJ, d>| for decreasing eps; they shrink as eps^2 when
    the gradient is right. Returns {"eps": [...], "remainder": [...], "order": [...], "switches":
    [...]} (observed orders between consecutive eps; history points whose branch of the max differs
    from the path's at each eps: a remainder across a switch is not that of a derivative).

    The path's own states are read before the replays (which overwrite the solver's fields)."""
    J0 = grad["value"]
    dJ = directional_derivative(grad, direction)
    rem, switches = [], []
    for eps in eps_list:
        pert = _perturbed(path, direction, eps)
        J = objective.value(pert)
        rem.append(abs(J - J0 - eps * dJ))
        switches.append(active_set_changes(path, pert)["history"])
    path.activate()
    orders = [float(np.log(rem[i] / rem[i + 1]) / np.log(eps_list[i] / eps_list[i + 1])) for i in range(len(rem) - 1)]
    return {"eps": list(eps_list), "remainder": rem, "order": orders, "switches": switches}


__all__ += ["Seeds", "directional_derivative", "active_sets", "active_set_changes"]
