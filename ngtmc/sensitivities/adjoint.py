"""The reverse sweep of the single-pass scheme: the adjoint engine and :func:`gradient`
(``ngtmc.sensitivities``; the derivation is in ``docs/sensitivities.md``).

Units: mm, N, MPa; derivatives in the objective's unit per unit of each parameter.
"""
from __future__ import annotations

import re
import time
from typing import Iterable

import numpy as np
import ngsolve as ngs

from ngtmc.model import deformation_gradient
from ngtmc.discrete import rules
from ngtmc.discrete import Solver
from ngtmc.discrete import blas_limited
from ngtmc.sensitivities.objectives import Objective, Seeds
from ngtmc.sensitivities.path import Path, _all_parameters, _resolve, refuse_changed_mesh


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
            self.dx_Hf = ngs.dx(definedon=mesh.Materials(s.regions.fracture_regex), intrules=s.irs.GetIntegrationRules())
            self.dx_af = ngs.dx(definedon=mesh.Materials(s.regions.fracture_regex), intrules=rules(mesh, 2))
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
    :func:`ngtmc.sensitivities.coupled.coupled_gradient`."""
    with blas_limited():   # numpy's and scipy's BLAS on one thread (ngtmc.discrete.blas_threads)
        return _gradient(path, objective, wrt)


def _gradient(path: Path, objective: Objective, wrt) -> dict:
    """:func:`gradient` (its BLAS threads limited by the caller)."""
    refuse_changed_mesh(path.solver)
    if getattr(path, "coupled", None) is not None:
        return path.gradient(objective, wrt)          # CoupledPath.gradient
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
