"""Objectives of the adjoint: what is differentiated, as the partial derivatives ("seeds") of each
step (``ngtmc.sensitivities``).

Units: each objective states its own (N, N mm, ...).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import ngsolve as ngs

from ngtmc.model import fracture
from ngtmc.sensitivities.path import Path


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
        (:mod:`ngtmc.sensitivities.coupled`)."""
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
        return Seeds(cfs=[(cache[id(s)][1], s.regions.fracture_regex, 1.0)])

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
