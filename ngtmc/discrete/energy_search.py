"""The energy line search of the displacement Newton (:class:`ngtmc.discrete.newton.DisplacementNewton`):
backtracking along a Newton or Levenberg direction on the stored energy (Armijo), the residual
norm where the energy's round-off hides the decrease, the guards of a trial state, and the
lengthening of a full Levenberg step along negative curvature.

Units: mm, N, MPa (energies in N mm, residuals in N, for the scene thickness in 2D).
"""
from __future__ import annotations

from typing import Callable
import math

__all__ = ["energy_line_search", "energy_noise", "expand", "NOISE_STEP", "NOISE_FRACTION", "EXPANSION_LINEARITY"]

#: Round-off of the stored energy against the Newton slope. The energy sums densities of the size
#: of E_max over the volume, so its evaluation error does not shrink with the strains: on the quick
#: L-panel at 0.1-0.5 mm of the approach (2026-12-03) the energy moved by +-1.6e-8 N mm along a
#: Newton step whose predicted decrease was 1.9e-10 N mm, while E0 was 7.5e-4 N mm (so the test
#: |slope| < 1e-8 |E0| did not see it). The Armijo test then rejected full steps at random, half
#: steps followed (the residual halved exactly, one more iteration), and where every length failed
#: the Levenberg shift was compiled and used. Where the Armijo test fails, or where the step
#: predicts a decrease below 1e-8 of the energy (then a passed test may be round-off too: at the
#: paper L-panel's stall the energy, 27 N mm, moved by 1e-8 N mm between evaluations against
#: predicted decreases of 1e-9 N mm, and steps so accepted, then lengthened, raised the residual),
#: the line search measures the round-off once by the second difference E(u0 + e du) + E(u0 - e du)
#: - 2 E0 with e = NOISE_STEP (exactly e^2 |slope| for a quadratic energy, 1e-4 |slope|); where it
#: exceeds NOISE_FRACTION |slope|, the energy cannot resolve the step and the residual norm
#: decides, and the step is not lengthened.
NOISE_STEP = 1e-2
NOISE_FRACTION = 1e-2

#: An accepted full Levenberg step is doubled (``NewtonOptions.levenberg_expansion`` times at most)
#: while the energy at the longer step stays below EXPANSION_LINEARITY times its linear prediction
#: (:func:`expand`).
EXPANSION_LINEARITY = 0.9


def energy_noise(energy: Callable, u, u0, du, E0: float) -> float:
    """Round-off of the stored energy ``energy(vec)`` (N mm) at ``u0`` along ``du``: |E(u0 + e du) +
    E(u0 - e du) - 2 E0| with e = NOISE_STEP (see NOISE_FRACTION); inf where either energy is not
    finite. Leaves the vector ``u`` at u0 - e du."""
    total = -2.0 * E0
    for e in (NOISE_STEP, -NOISE_STEP):
        u.data = u0 + e * du
        total += energy(u)
    return abs(total) if math.isfinite(total) else math.inf


def energy_line_search(p, opt, du, E0: float, slope: float, res: float, lifted: bool,
                       expand_full_step: bool = False) -> tuple[bool, int]:
    """Backtracking from ``p.u`` along ``du`` (:class:`ngtmc.discrete.newton.DisplacementProblem`
    ``p``, :class:`ngtmc.discrete.newton.NewtonOptions` ``opt``); returns (accepted, 1 where the
    energy's round-off was found to hide the step, else 0). ``E0``: the energy at the start (N mm,
    nan while the boundary values are lifted, ``lifted``); ``slope``: r . du; ``res``: the residual
    norm on the free dofs at the start (N). With ``expand_full_step`` (a Levenberg direction) a
    full step that passed the energy test is lengthened (:func:`expand`). The accepted iterate is
    left in ``p.u``; on failure ``p.u`` is restored.

    Energy (Armijo) while the energy can resolve the predicted decrease; near convergence |slope|
    falls below the energy's round-off and the test switches to a decrease of the residual norm
    (measured where the Armijo test fails or |slope| < 1e-8 |E0|, :data:`NOISE_FRACTION`).
    Guard: finite energy (J > 0 at the energy's quadrature points) and ``p.admissible()`` (J > 0
    at the history points too: Psi_plus there feeds the history; NaN would poison it)."""
    u = p.u.vec
    _, _, _, tmp, u0 = p.vectors
    switched = 0
    # the step predicts a decrease below 1e-8 of the energy: its round-off may hide it
    near_converged = (not lifted) and abs(slope) < 1e-8 * max(abs(E0), 1e-300)
    noise_known = False
    s = 1.0
    for _ in range(opt.max_line_search):
        u.data = u0 + s * du
        E = p.energy(u)
        if math.isfinite(E) and p.admissible():
            armijo = E <= E0 + opt.armijo * s * slope
            if not lifted and not noise_known and (near_converged or not armijo):
                # the energy's verdict is in doubt: measure its round-off once along this direction
                noise_known = True
                near_converged = energy_noise(p.energy, u, u0, du, E0) > NOISE_FRACTION * abs(slope)
                switched += near_converged
                u.data = u0 + s * du
            if near_converged:   # the energy cannot resolve the step: the residual norm decides
                p.form.Apply(u, tmp)
                if p.ranks.masked_norm(tmp, p.free) <= (1 - 1e-4 * s) * res:
                    return True, switched
            elif lifted or armijo:
                if expand_full_step and s == 1.0 and not lifted:
                    expand(p, du, E0, slope, int(opt.levenberg_expansion))
                return True, switched
        s *= 0.5
    u.data = u0
    return False, switched


def expand(p, du, E0: float, slope: float, doublings: int) -> float:
    """A full Levenberg step from ``u0`` (``p.vectors``) along ``du`` was accepted: double its
    length while the energy at the longer step stays below EXPANSION_LINEARITY times its linear
    prediction E0 + s slope (the energy along the direction is straight or bends down: the
    direction follows negative curvature) and the state is admissible, at most ``doublings``
    times (``NewtonOptions.levenberg_expansion``). ``p.u`` is left at the last length that passed,
    which is returned. Where the energy bends up along the direction the doubling stops at a fifth
    of the way to the minimum along it, so it does not carry the iterate into another well.

    Why: where the tangent is indefinite (a squeezed void near a snap: the coupled Newton's
    displacement relaxation at the paper three-point bending's contact onset, docs/performance.md)
    the shifted direction creeps along the negative curvature in steps that the shift bounds, not
    the energy (there 16 steps of 4e-8 N mm each before the plain Newton step took over)."""
    u = p.u.vec
    u0 = p.vectors[4]
    s_best = 1.0
    for _ in range(doublings):
        s = 2.0 * s_best
        u.data = u0 + s * du
        E = p.energy(u)
        if not (math.isfinite(E) and E - E0 <= EXPANSION_LINEARITY * s * slope and p.admissible()):
            break
        s_best = s
    u.data = u0 + s_best * du
    return s_best
