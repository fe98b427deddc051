"""Classical frictionless penalty contact between two bodies: the reference for third-medium contact.

Third-medium contact (TMC) lets bodies touch through a very soft "void" whose stiffness is a small
fraction gamma0 of the solid's. Its result depends on gamma0: before contact the void transmits a
parasitic force proportional to gamma0, after contact the force converges to that of a classical
contact formulation as gamma0 falls. This module supplies that classical solution for the same
bodies (no void mesh at all): the same hyperelastic energy as :mod:`ngtmc.model.materials` (Neo-Hookean,
Eq. 2 of Ciceri et al. 2026, undamaged, rho = 1), plus a penalty energy on the penetration of a
*minion* boundary into a *master* boundary,

    Pi_c(u) = int_master  eps/2 <p(u)>_+^2  ds,      p(u) = (X + u - (X' + u')) . n,

found with NGSolve's :class:`ngsolve.ContactBoundary`: for each integration point X of the master
boundary, X' is the closest point of the minion boundary (searched in the deformed configuration
of the current iterate, re-paired at every Newton iteration) and n is the master's outward
reference normal. p > 0 is penetration (p = -gap while the bodies are apart). ``eps`` is the
penalty stiffness, N/mm^3 (force per length of master boundary per mm of penetration, per mm of
thickness in 2D); the exact contact constraint is recovered as eps -> infinity, and
:func:`penalty_sweep` shows how fast.

Units: mm, N, MPa. In 2D (plane strain) forces are for ``thickness`` mm of depth.

Example::

    ref = PenaltyContact(mesh, {".*": Material(E=1000, nu=0.3)}, supports=[Support("clamp", x=True, y=True)],
                         load=DisplacementLoad("load", "-y"), master="lower_top", minion="upper_bottom",
                         penalty=1e5)
    history = ref.run(Schedule([0, 0.3]), du=0.01)   # DataFrame: load, force, penetration, ...
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import re
import time
from typing import Mapping, Sequence

import numpy as np
import pandas as pd
import ngsolve as ngs

from ngtmc.model import Material, deformation_gradient, psi_dev, psi_vol
from ngtmc.scene import DisplacementLoad, Support
from ngtmc.stepping import Schedule
from ngtmc.discrete import lifted_direction, meets, residual_split

__all__ = ["PenaltyContact", "ContactResult", "penalty_sweep"]


@dataclass
class ContactResult:
    """Outcome of one load step of :class:`PenaltyContact`."""

    converged: bool
    iterations: int
    residual: float
    message: str = ""


class PenaltyContact:
    """Hyperelastic bodies with frictionless penalty contact between two named boundaries.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        2D (plane strain) or 3D mesh of the bodies only (no void region).
    materials : mapping region-name regex -> Material
        Material of every region (only E and nu are used).
    supports : list of Support
    load : DisplacementLoad
        Displacement imposed on a boundary; the recorded force is the reaction in its direction.
    master, minion : str
        Boundary names of the contact pair (integration on ``master``; the closest point is
        searched on ``minion``).
    penalty : float
        Penalty stiffness eps, N/mm^3 (> 0). A good start is 10 .. 1000 E / h.
    order : int
        Polynomial order of the displacement (default 2, as the TMC scenes with a regulariser).
    thickness : float
        Out-of-plane thickness in 2D, mm.
    intorder : int
        Integration order on the master boundary for the contact term.
    maxdist : float
        Largest distance, mm, at which a minion point is paired with a master point. Must exceed
        the initial gap so that the contact is found before it closes.
    max_iterations, rtol : Newton limits (relative residual tolerance against the reaction scale).
    inverse : str
        Direct solver for the tangent: "sparsecholesky" (default; the tangent is the Hessian of an
        energy, hence symmetric) or "umfpack".
    regions : str, optional
        Regex of the regions that are solved (default: all). With it, the mesh of a third-medium
        scene can be reused with its void left out, so that reference and TMC solution share the
        discretisation of the bodies exactly; the contact boundaries are then interfaces with the
        (ignored) void, and the sign of the master normal is checked on the undeformed state.
    """

    def __init__(self, mesh: ngs.Mesh, materials: Mapping[str, Material], supports: Sequence[Support],
                 load: DisplacementLoad, master: str, minion: str, penalty: float, order: int = 2,
                 thickness: float = 1.0, intorder: int = 6, maxdist: float = 1.0,
                 max_iterations: int = 30, rtol: float = 1e-9, regions: str | None = None,
                 inverse: str = "sparsecholesky"):
        if not (math.isfinite(penalty) and penalty > 0):
            raise ValueError(f"penalty = {penalty!r} N/mm^3 is outside the allowed range: finite and > 0")
        for b in (master, minion, load.boundary, *[s.boundary for s in supports]):
            for part in b.split("|"):
                if part not in mesh.GetBoundaries():
                    raise ValueError(f"unknown boundary {part!r}; the mesh has {sorted(set(mesh.GetBoundaries()))}")
        self.mesh = mesh
        self.dim = d = mesh.dim
        self.penalty = float(penalty)
        self.thickness = float(thickness) if d == 2 else 1.0
        self.intorder = int(intorder)
        self.maxdist = float(maxdist)
        self.max_iterations = int(max_iterations)
        self.rtol = float(rtol)
        self.load_bc = load
        self.inverse = inverse

        dirichlet = [[] for _ in range(d)]
        for s in supports:
            for c in s.components():
                dirichlet[c].append(s.boundary)
        dirichlet[load.component].append(load.boundary)
        if load.hold_tangential:
            for c in range(d):
                if c != load.component:
                    dirichlet[c].append(load.boundary)
        kw = {key: "|".join(dirichlet[c]) for c, key in zip(range(d), ("dirichletx", "dirichlety", "dirichletz")) if dirichlet[c]}
        if regions is not None:
            kw["definedon"] = mesh.Materials(regions)
        self.fes = ngs.VectorH1(mesh, order=order, **kw)
        self.u = ngs.GridFunction(self.fes, name="displacement")
        self._free = np.array(list(self.fes.FreeDofs()), dtype=bool)
        self._dir = ~self._free
        e = ngs.GridFunction(self.fes)
        e.components[load.component].Set(load.sign, definedon=mesh.Boundaries(load.boundary))
        self._e = e.vec.FV().NumPy().copy()
        self.load = 0.0

        all_regions = mesh.GetMaterials()
        regions_used = [r for r in all_regions if regions is None or re.fullmatch(regions, r)]

        def mat(r):
            for k, m in materials.items():
                if re.fullmatch(k, r):
                    return m
            raise ValueError(f"region {r!r} has no material")

        self.E_max = max(mat(r).E for r in regions_used)
        K0 = mesh.MaterialCF({r: mat(r).K0 for r in regions_used}, default=0)
        G0 = mesh.MaterialCF({r: mat(r).G0 for r in regions_used}, default=0)
        dxr = ngs.dx(definedon=mesh.Materials("|".join(regions_used)))

        ut = self.fes.TrialFunction()
        F = deformation_gradient(ut)
        self.a = ngs.BilinearForm(self.fes, symmetric=False)
        self.a += ngs.Variation(psi_vol(F, K0).Compile() * dxr)
        self.a += ngs.Variation(psi_dev(F, G0).Compile() * dxr)
        X = ngs.CF((ngs.x, ngs.y) if d == 2 else (ngs.x, ngs.y, ngs.z))
        # orientation of the master normal: the signed distance must be negative (open) at u = 0
        probe = ngs.BilinearForm(self.fes)
        cb0 = ngs.ContactBoundary(mesh.Boundaries(master), mesh.Boundaries(minion))
        cb0.AddEnergy((X + ut - (X.Other() + ut.Other())) * cb0.normal)
        cb0.Update(self.u, probe, intorder, maxdist)
        self.normal_sign = -1.0 if probe.Energy(self.u.vec) > 0 else 1.0
        self._cb_probe = (cb0, probe)  # kept alive: ContactBoundary must outlive its forms
        self.cb = ngs.ContactBoundary(mesh.Boundaries(master), mesh.Boundaries(minion))
        pen = self.normal_sign * (X + ut - (X.Other() + ut.Other())) * self.cb.normal
        self.cb.AddEnergy(ngs.IfPos(pen, self.penalty / 2 * pen * pen, 0))
        self._r = self.u.vec.CreateVector()
        self._du = self.u.vec.CreateVector()
        self._u0 = self.u.vec.CreateVector()
        pts = np.asarray(mesh.ngmesh.Coordinates())
        self.length_scale = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
        self.atol = 1e-12 * self.E_max * self.length_scale ** (d - 1)

    # ------------------------------------------------------------------ pieces
    def _update_pairs(self):
        self.cb.Update(self.u, self.a, self.intorder, self.maxdist)

    def energy(self) -> float:
        """Elastic + penalty energy of the current state, N mm per unit thickness (NaN if J <= 0)."""
        try:
            return float(self.a.Energy(self.u.vec))
        except Exception:  # pragma: no cover
            return math.nan

    def reaction(self) -> float:
        """Reaction on the loaded boundary in the load direction, N (for the thickness): <r(u), e>."""
        self.a.Apply(self.u.vec, self._r)
        return float(np.dot(self._r.FV().NumPy(), self._e)) * self.thickness

    # ------------------------------------------------------------------ Newton
    def solve(self, load: float) -> ContactResult:
        """Newton for u at the imposed displacement ``load`` (mm), contact pairs re-searched every
        iteration, energy line search with a J > 0 guard (NaN energy rejected), the Dirichlet
        increment carried by the Newton increment."""
        u = self.u.vec
        r, du, u0 = self._r, self._du, self._u0
        target = np.where(self._dir, load * self._e, 0.0)
        moved = self._e != 0.0     # the loaded dofs: their reaction is the equilibrium scale
        res = math.inf
        for it in range(self.max_iterations + 1):
            self._update_pairs()
            self.a.Apply(u, r)
            rem, lifted, res, reac = residual_split(r, u, target, self._free, self._dir, load)
            if not math.isfinite(res):
                return ContactResult(False, it, res, "residual is not finite")
            if not lifted:
                if meets(res, float(np.linalg.norm(r.FV().NumPy()[moved])), self.rtol, self.atol):
                    self.load = load
                    return ContactResult(True, it, res)
            if it == self.max_iterations:
                break
            self.a.AssembleLinearization(u)
            inv = self.a.mat.Inverse(self.fes.FreeDofs(), inverse=self.inverse)
            lifted_direction(self.a.mat, inv, r, rem, self._dir, u.CreateVector(), u.CreateVector(), du)
            u0.data = u
            E0 = self.energy()
            slope = float(np.dot(r.FV().NumPy(), du.FV().NumPy()))
            s = 1.0
            ok = False
            for _ in range(20):
                u.data = u0 + s * du
                E = self.energy()
                if math.isfinite(E) and (lifted or E <= E0 + 1e-4 * s * slope or abs(slope) < 1e-10 * max(abs(E0), 1e-300)):
                    ok = True
                    break
                s *= 0.5
            if not ok:
                u.data = u0
                return ContactResult(False, it, res, "line search failed")
        return ContactResult(False, self.max_iterations, res, f"no convergence in {self.max_iterations} iterations")

    def run(self, schedule: Schedule | float, du: float, du_min: float | None = None, progress=None) -> pd.DataFrame:
        """Step through ``schedule`` (mm) with increments ``du`` (halved on failure down to
        ``du_min``, default du/1024, then grown back). Returns a DataFrame with one row per accepted
        step, load (mm), force (N, for the thickness), energy (elastic + penalty, N mm),
        newton_iterations, cutbacks, step_size (mm), wall_time (s)."""
        if not isinstance(schedule, Schedule):
            schedule = Schedule.monotonic(float(schedule))
        du_min = du / 1024 if du_min is None else du_min
        t0 = time.perf_counter()
        rows = [dict(step=0, load=0.0, force=self.reaction(), energy=0.0, newton_iterations=0, cutbacks=0,
                     step_size=0.0, wall_time=0.0)]
        t = 0.0
        step = 0
        h = du
        T = schedule.total_time
        while t < T * (1 - 1e-14):
            t_turn = schedule.next_turning_time(t)
            cut = 0
            its = 0
            while True:
                t_new = min(t + h, t_turn)
                if t_turn - t_new < 1e-9 * du:
                    t_new = t_turn
                saved = self.u.vec.FV().NumPy().copy()
                res = self.solve(schedule.load(t_new))
                its += res.iterations
                if res.converged:
                    break
                self.u.vec.FV().NumPy()[:] = saved
                cut += 1
                h /= 2
                if h < du_min:
                    raise RuntimeError(f"penalty contact: step from load {schedule.load(t):.6g} mm failed at the "
                                       f"minimum increment {du_min:g} mm ({res.message})")
            step += 1
            rows.append(dict(step=step, load=schedule.load(t_new), force=self.reaction(),
                             energy=self.energy() * self.thickness, newton_iterations=its, cutbacks=cut,
                             step_size=abs(schedule.load(t_new) - schedule.load(t)),
                             wall_time=time.perf_counter() - t0))
            if progress:
                progress(rows[-1])
            t = t_new
            if cut == 0:
                h = min(du, 2 * h)
        return pd.DataFrame(rows)


def penalty_sweep(build, penalties: Sequence[float], schedule: Schedule | float, du: float,
                  at: Sequence[float]) -> pd.DataFrame:
    """Run ``build(penalty) -> PenaltyContact`` for each penalty and tabulate the force at the loads
    ``at`` (linear interpolation of the history). Columns: penalty, then one per load. Use it to show
    that the reference is converged in the penalty (the force changes by ~1/eps)."""
    out = []
    for eps in penalties:
        hist = build(eps).run(schedule, du)
        row = {"penalty": eps}
        for a in at:
            row[f"force_at_{a:g}"] = float(np.interp(a, hist["load"], hist["force"]))
        out.append(row)
    return pd.DataFrame(out)
