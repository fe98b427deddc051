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
  grows): :mod:`ngtmc.sensitivities.coupled`, reached through the same functions (``record_path``
  returns a :class:`~ngtmc.sensitivities.coupled.CoupledPath`; ``replay``, ``gradient``,
  ``directional_fd``, ``taylor_test`` dispatch on it). There every step is the converged coupled
  solve (u_n, alpha_n) with the step's own history H_n(u_n) and the bounds alpha_{n-1} <= alpha_n
  <= 1 as active sets; held fixed are the step types and, per step, the load lambda_n of a
  displacement step or the dissipation target dD_n of a dissipation step (whose load is then a
  state variable, differentiated through the dissipation constraint);
* ``"staggered"``: not differentiated (refused).

What is differentiated for ``scheme="single-pass"`` (see ``docs/sensitivities.md`` for the
derivation): the scheme that :class:`~ngtmc.simulation.loop.Simulation` actually solved. At every recorded
load step n, with the imposed displacement lambda_n held fixed,

1. alpha_n = P_n(A(H_{n-1})^{-1} f(H_{n-1})), P_n the projection onto [alpha_{n-1}, 1];
2. R(u_n; alpha_n, rho) = 0 on the free dofs (Dirichlet values u_D(lambda_n) of every displacement
   load, independent of rho; the reaction F_n = <R, d u_D / d lambda> of the force load
   ``Scene.force_from``). Traction loads are refused by :func:`record_path`;
3. H_n = max(H_{n-1}, Psi_plus(u_n)) at the history quadrature points.

The energy of (2) and the Psi_plus of (3) are those of the scene's ``split`` and ``formulation``
(:mod:`ngtmc.model.splits`): the adjoint follows every pair, since it differentiates the solver's own
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

from ngtmc.sensitivities.adjoint import gradient
from ngtmc.sensitivities.api import differentiate, record_path
from ngtmc.sensitivities.checks import (
    active_set_changes, active_sets, directional_derivative, directional_fd, taylor_test,
)
from ngtmc.sensitivities.objectives import (ComplianceAtStep, ExternalWork, FinalFractureEnergy, ForceCurveObjective,
                                           Objective, ReactionAtStep, Seeds, UserObjective, evaluate)
from ngtmc.sensitivities.path import Path, design_mask, parameter_value, replay

__all__ = [
    "Path", "record_path", "replay", "gradient", "differentiate", "evaluate", "parameter_value", "design_mask",
    "Objective", "ReactionAtStep", "ExternalWork", "FinalFractureEnergy", "ComplianceAtStep",
    "UserObjective", "ForceCurveObjective", "directional_fd", "taylor_test",
    "Seeds", "directional_derivative", "active_sets", "active_set_changes",
]
