"""The displacement energy of :class:`ngtmc.discrete.solver.Solver`: its terms (the degraded elastic
energy of Eq. 2 or of a split, the undegraded one elsewhere, the Hessian regulariser of Eq. 3),
their integration rules (the one owner of the rules), the form Newton solves with, and the
energies a history row records.

:class:`DisplacementEnergy` is a base of :class:`ngtmc.discrete.solver.Solver`, on whose spaces, fields and
material coefficients it works; the form wrappers are :mod:`ngtmc.discrete.energy_forms`.

Units: mm, N, MPa (densities in MPa, energies in N mm for the scene thickness in 2D).
"""
from __future__ import annotations

import functools
import math

import ngsolve as ngs

from ngtmc.model import regularisation as creg
from ngtmc.model import fracture
from ngtmc.model import splits
from ngtmc.discrete.spaces import bilinear_form, real_compile, term_rules
from ngtmc.discrete.energy_forms import QuadraticPlus, merged_terms
from ngtmc.discrete.newton import DisplacementNewton, DisplacementProblem, NewtonResult
from ngtmc.model import deformation_gradient, psi_dev, psi_vol
from ngtmc.scene import regex, region_names

__all__ = ["DisplacementEnergy"]




class DisplacementEnergy:
    """Energy terms, rules, forms and recorded energies (a base of :class:`ngtmc.discrete.solver.Solver`)."""

    def _maybe_compile(self, cf):
        """``cf`` compiled as ``compile`` says (C++ code, symbolic, or not at all). The same object
        is compiled once: a C++ compilation costs about 3.4 s whatever the expression (the
        undegraded energy of the void and of the other regions is one object)."""
        cache = self._compiled
        hit = cache.get(id(cf))
        if hit is not None and hit[0] is cf:
            return hit[1]
        compiled = None
        if self._compile == "real":
            compiled = real_compile(cf)
            if compiled is None:
                self._compile = True  # fall back for the remaining terms too (warned once)
        if compiled is None:
            compiled = cf.Compile() if self._compile else cf
        cache[id(cf)] = (cf, compiled)
        return compiled

    def energy_terms(self, u, alpha=None, F=None):
        """List of (name, energy density CF, region regex) of the displacement problem for field or trial u.

        Names: "elastic_vol", "elastic_dev" (Psi_bar parts, degraded by g(alpha) in fracture
        regions) and "regularisation" (Phi_bar). Densities in MPa, integrated over the regions.
        With ``Scene.formulation == "anisotropic"`` the fracture regions carry instead
        "elastic_plus" (g(alpha) Psi_plus) and "elastic_minus" (Psi_minus) of the scene's split
        (:mod:`ngtmc.model.splits`; Miehe et al. 2010, Eq. 3.13).
        ``alpha``: phase field to degrade with (a trial function for the coupled problem), default
        the solver's alpha GridFunction. ``F``: deformation gradient of the elastic terms, default
        I + grad u; pass the 3 x 3 one of :func:`~ngtmc.model.materials.full_deformation_gradient` made a
        variable (``MakeVariable``) to differentiate the energy for the stress (:mod:`ngtmc.runner.vtk`)."""
        F = deformation_gradient(u) if F is None else F
        terms = []
        sc = self.scene
        if self.alpha is not None:
            g = fracture.degradation(self.alpha if alpha is None else alpha, sc.residual_stiffness)
            if sc.formulation == "anisotropic":
                plus, minus = splits.split_energy(sc.split, F, self.K, self.G)
                terms.append(("elastic_plus", g * plus, self.regions.fracture_regex))
                terms.append(("elastic_minus", minus, self.regions.fracture_regex))
            else:
                terms.append(("elastic_vol", g * psi_vol(F, self.K), self.regions.fracture_regex))
                terms.append(("elastic_dev", g * psi_dev(F, self.G), self.regions.fracture_regex))
        vol, dev = psi_vol(F, self.K), psi_dev(F, self.G)  # one object each: compiled once (_maybe_compile)
        for others in (self._high_re, self._low_re):
            if others:
                terms.append(("elastic_vol", vol, others))
                terms.append(("elastic_dev", dev, others))
        reg = sc.regulariser
        if reg is not None:
            k_r = creg.regularisation_stiffness(reg.kbar_r, reg.length, self.K0)
            phi = creg.phi_bar(u, k_r, indicator=1 - self.rho, damping=reg.damping)
            terms.append(("regularisation", phi, regex(region_names(reg.regions))))
        return terms

    def energy_measure(self, name: str, regions: str):
        """Integration measure (with its explicit rule) of the displacement energy term ``name`` on
        ``regions`` (one of the region regexes of :meth:`energy_terms`). The one owner of the
        integration rules: Newton, the reaction, the energies and the adjoint all use it.

        * Elastic terms where the displacement has order p >= 2: the rule of order 2p (6 points on
          a triangle for p = 2), not NGSolve's default for a Variation (order 2p - 2: 3 points).
          With the default rule the energy does not see J between its 3 points: in a squeezed void
          an element can fold towards J = 0 at no energy cost, the J > 0 guard then cuts every
          Newton step and Newton stalls (three-point bending after the peak). In the fracture
          regions these are the history points, so energy, J guard and history agree.
        * Elastic terms on order-1 elements (a scene without regulariser, or the elements outside
          the regulariser's regions when the order varies per element): the rule of the history
          (order 2, 3 points on a triangle) where some elements border order-2 ones or carry
          the history, else :func:`~ngtmc.discrete.spaces.term_rules` "elastic_p1" (one point on
          a straight simplex, where F is constant; the full rule elsewhere).
        * The Hessian regulariser: :func:`~ngtmc.discrete.spaces.term_rules` "regularisation"
          (exact on every straight element type; where exact:
          :data:`~ngtmc.discrete.spaces.RULE_EXACTNESS`)."""
        p = self.order
        meas = functools.partial(ngs.dx, definedon=self.mesh.Materials(regions))
        if name == "regularisation":
            return meas(intrules=term_rules(self.mesh, "regularisation", p))
        if p == 1:
            return meas(intrules=term_rules(self.mesh, "elastic_p1", p))
        if regions == self._high_re or not self._variable_order:
            return meas(intrules=self._guard_irs.GetIntegrationRules())
        return meas(intrules=self.irs.GetIntegrationRules())

    def _energy_form(self, trial, extra=None, parts=None):
        """The displacement energy as a form with Apply / Energy / AssembleLinearization / mat.

        A term whose energy is quadratic in u (the Hessian regulariser without damping) has a
        constant tangent: it is assembled once and added (:class:`QuadraticPlus`) instead of
        being re-assembled at every Newton iteration. ``parts`` (a dict): filled with the
        integrands by recorded energy ("elastic_energy", "regularisation_energy"), for
        :meth:`energies`."""
        a = bilinear_form(self.fes_u, symmetric=True)
        quadratic = None
        for name, density, regions in merged_terms(self.energy_terms(trial)):
            key = "regularisation_energy" if name == "regularisation" else "elastic_energy"
            if name == "regularisation" and self.scene.regulariser.damping == "none":
                # assembled once: not worth a compilation
                density_q, measure_q = density, self.energy_measure(name, regions)
                quadratic = bilinear_form(self.fes_u, symmetric=True)
                quadratic += ngs.Variation(density_q * measure_q)
                # a zero term on every element gives K the sparsity pattern of the tangent
                quadratic += ngs.Variation(ngs.Parameter(0.0) * ngs.InnerProduct(trial, trial) * ngs.dx)
                if parts is not None:
                    parts.setdefault(key, []).append(density_q * measure_q)
                continue
            integrand = self._maybe_compile(density) * self.energy_measure(name, regions)
            if parts is not None:
                parts.setdefault(key, []).append(integrand)
            a += ngs.Variation(integrand)
        if extra is not None:
            a += ngs.Variation(extra)
        if quadratic is None:
            return a
        if self.ranks.parallel:  # the constant-tangent wrapper adds local matrices: fold the term in
            a += ngs.Variation(density_q * measure_q)
            return a
        q = QuadraticPlus(a, quadratic, self._design_key)
        self._quadratic_forms.append(q)
        return q

    def elastic_rule_is_history_rule(self) -> bool:
        """True when the elastic terms of the fracture regions are integrated at the history points
        (:meth:`energy_measure`: displacement order >= 2), so that a term at the history points
        and one with the elastic measure there can be summed into one integrand
        (tests/test_monolithic.py checks the two rules against each other)."""
        return self.order >= 2

    def _design_key(self) -> tuple:
        """Everything a constant tangent depends on besides u: the pseudo-density and the material
        parameters (both change between runs of an optimisation or a finite-difference check)."""
        rho = self.rho.vec.FV().NumPy()
        pars = tuple(q.Get() for m in self.material_parameters.values() for q in m.values())
        return (hash(rho.tobytes()), pars, self.gamma0.Get())

    def energies(self, wf: float | None = None) -> dict:
        """Current energies, N mm (for the scene thickness): elastic_energy (int g Psi_bar),
        regularisation_energy (int Phi_bar), fracture_energy (W_f of Eq. 19) and
        dissipated_energy (W_f / c_w, the crack surface energy of Eq. 5). ``wf``: W_f of the
        current state per unit thickness (:meth:`fracture_energy_per_thickness`) where the
        caller has it already.

        The first two are the energies of the displacement form's own integrands, term by term
        (the same rules and compiled code as Newton; ``Integrate`` of the same densities took
        about twice as long: 32 against 14.8 ms on the quick L-panel, docs/performance.md)."""
        if self._energy_forms is None:
            self._energy_forms = {}
            for key, integrands in self._energy_parts.items():
                f = bilinear_form(self.fes_u, symmetric=True)
                for integrand in integrands:
                    f += ngs.Variation(integrand)
                self._energy_forms[key] = f
        out = {"elastic_energy": 0.0, "regularisation_energy": 0.0}
        for key, f in self._energy_forms.items():
            # a distributed mesh: each rank's part (the form is a plain BilinearForm there), summed
            out[key] = self.ranks.sum(float(f.Energy(self.u.vec)))
        t = self.thickness
        out = {k: v * t for k, v in out.items()}
        wf = self.fracture_energy_per_thickness() if wf is None else wf
        out["fracture_energy"] = wf * t
        out["dissipated_energy"] = wf * t / fracture.C_W
        return out

    def _inverse(self, kind: str) -> str:
        """The sparse direct solver to pass as ``inverse=``: ``kind``, or on a mesh distributed over
        MPI ranks NGSolve's "masterinverse" (the matrix gathered and factorized on rank 0)."""
        return "masterinverse" if self.ranks.parallel else kind

    def _factorize(self, a):
        if a is self.a_u:
            if self._inv is None or self.ranks.parallel:  # NGSolve's masterinverse has no Update
                self._inv = a.mat.Inverse(self.free, inverse=self._inverse(self.newton.linear_solver))
            else:
                self._inv.Update()
            return self._inv
        return a.mat.Inverse(self.free, inverse=self._inverse(self.newton.linear_solver))

    def _energy(self, vec) -> float:
        try:
            e = self.a_u.Energy(vec)
        except Exception:  # pragma: no cover - NGSolve raises on some invalid states
            e = math.nan
        # a distributed mesh: each rank's part (the form is a plain BilinearForm there), summed
        return self.ranks.sum(e)

    def _shift_form(self):
        if self._a_shift is None:
            self._mu = ngs.Parameter(0.0)
            self._u_anchor = ngs.GridFunction(self.fes_u)
            uT = self.fes_u.TrialFunction()
            extra = 0.5 * self._mu * ngs.InnerProduct(uT - self._u_anchor, uT - self._u_anchor) * ngs.dx
            self._a_shift = self._energy_form(uT, extra=extra)
        return self._a_shift

    def displacement_problem(self) -> DisplacementProblem:
        """The problem the displacement Newton is handed (:class:`~ngtmc.discrete.newton.DisplacementProblem`):
        this solver's energy form, displacement, free and Dirichlet dofs, boundary values,
        tolerance scale, J > 0 guard, factorization, Levenberg shift and work vectors."""
        return DisplacementProblem(
            form=self.a_u, u=self.u, free=self._free_np, fixed=self._dir_np, target=self.dirichlet_target,
            scale=self.equilibrium_scale, energy=self._energy, admissible=lambda: self.min_J() > 0.0,
            factorize=self._factorize, shifted=lambda: (self._shift_form(), self._mu, self._u_anchor),
            mu0=lambda: 1e-4 * self.E_max / self.ranks.min(self.h) ** 2, ranks=self.ranks,
            vectors=(self._r, self._du, self._w, self._tmp, self._u0), timings=self.timings)

    def solve_displacement(self, load: float) -> NewtonResult:
        """Newton solve for u at the imposed displacement ``load`` (mm) with alpha fixed
        (:meth:`ngtmc.discrete.newton.DisplacementNewton.solve`, which says how). On success the
        solver's load is ``load``; an acceptance at the residual floor is counted in
        ``floor_accepts``. On failure u is left at the last iterate; the caller restores the state."""
        self._r_valid = False
        self._lam_ext = load       # the tractions' work at this load
        newton = DisplacementNewton(self.newton, self.displacement_rtol, self.floor_rtol)
        res = newton.solve(self.displacement_problem(), load)
        self.energy_noise_switches += res.noise_switches
        if res.converged:
            self.load = load
            self._r_valid = not res.floor       # the work vector r holds the residual of u
            self.floor_accepts += int(res.floor)
        return res
