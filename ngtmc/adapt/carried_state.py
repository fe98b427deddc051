"""A state carried to a new mesh (:mod:`ngtmc.adapt.remesh`) brought to equilibrium there.

Fields carried across non-nested meshes are no equilibrium of the new mesh: u set across meshes
smears an open crack's opening over elements that are not fully broken, alpha interpolated at the
new vertices lies below the phase field of the carried history, and where a crack runs in a
snap-back the carried state is past the new mesh's critical load. In the order a remesh applies
them:

* :func:`balance`: u solved at the carried alpha and load;
* :func:`equilibrate`: the state before the step brought to equilibrium at its load (coupled
  Newton, else, except under path following, converged staggered passes) and committed;
* where that fails, :func:`consistent`: alpha raised to the phase field of the carried H, u
  balanced at it; and under path following :func:`settle`: the consistent state brought to
  equilibrium at the first of a few loads below its own.

Measured on the quick three-point bending's crack run (docs/adaptivity.md, "Refinement by
remeshing"). Units: mm, N; D per mm of thickness in 2D.
"""
from __future__ import annotations

__all__ = ["balance", "equilibrate", "consistent", "settle", "SETTLE_LOADS"]


def balance(solver, state: dict, in_place: bool = False) -> dict:
    """``state`` (carried to a new mesh) with u solved at its alpha and load (H as carried; the
    carried u where the solve fails). With ``in_place`` the solver keeps the result, else its
    state is restored.

    Why: u set across meshes smears an open crack's opening over new elements that are not fully
    broken. In the quick three-point bending's crack tail (0.0977 mm) the carried step state's
    elastic energy rose from 0.293 to 0.488 N mm per mm, and the fixed-load equilibration from
    such a u grew the crack by 7 % of its D."""
    s = solver
    current = None if in_place else s.get_state()
    s.set_state(state)
    keep = s.u.vec.FV().NumPy().copy()
    if not s.solve_displacement(float(state["load"])).converged:
        s.u.vec.FV().NumPy()[:] = keep
    out = s.get_state()
    if current is not None:
        s.set_state(current)
    return out


def equilibrate(sim, state: dict) -> tuple[dict, bool]:
    """``state`` (carried to a new mesh) brought to equilibrium there at its load, and committed
    (H may only grow, alpha with it): :func:`_equilibrium` (the coupled Newton, and except under
    path following the converged staggered passes); where that fails, the state made
    :func:`consistent` with its history and, under path following, :func:`settle`-d below its
    load; the state as it is where the scene has no phase field. Returns (the state, whether it
    is an equilibrium of the new mesh: False where the settle found none either, and the state is
    only consistent).

    Why: the interpolated fields are not an equilibrium of the new mesh. The phase field that the
    carried history drives on the new mesh differs from the carried alpha, so the state before the
    step already holds a dissipation of its own: a path-following re-solve of a smaller dissipation
    has no solution, and its load runs off (the sheared plate) or its Newton stalls at every
    dissipation step down to 1/128 of the base (the quick three-point bending's fourth remesh)."""
    s = sim.solver
    if s.alpha is None:
        return state, True
    current = s.get_state()
    out = _equilibrium(sim, state, float(state["load"]))
    found = out is not None
    if not found:
        out = consistent(s, state)
        if sim._path is not None:
            settled = settle(sim, out)
            found, out = settled is not out, settled
    s.set_state(current)
    return out, found


def _equilibrium(sim, state: dict, load: float, u_first: bool = False) -> dict | None:
    """The equilibrium at ``load`` (mm) from ``state``, committed (H may only grow, alpha with
    it): the coupled Newton (after a u solve at the state's alpha with ``u_first``), else, except
    under path following, the converged staggered passes; None where these fail. Leaves the
    solver at the result.

    Why no passes under path following: where the coupled Newton finds no equilibrium at the
    load, the carried crack is past the new mesh's critical load; passes at a fixed load then find
    an equilibrium the path does not pass through (how far its crack grew was not logged), or fail
    after up to ``max_staggered`` passes (the quick three-point bending's
    crack run: 8 of 27 equilibrations failed, 10.7 s each against 3.6 s for one that converged);
    :func:`settle` finds the path below the load instead."""
    s = sim.solver
    s.set_state(state)
    ok, H_trial = False, None   # None: update_history takes the trial history of the converged u
    if sim.coupled is not None and (not u_first or s.solve_displacement(load).converged):
        ok = sim.coupled.solve(load).converged
    if not ok and sim._path is not None:   # (path following always has the coupled Newton)
        return None
    if not ok:
        s.set_state(state)
        ok, info = sim._passes(load, sim.max_staggered)
        H_trial = info.get("H_trial")
    if not ok:
        return None
    s.update_history(H_trial)
    return s.get_state()


#: loads, as fractions of the carried one, at which :func:`settle` looks for an equilibrium
SETTLE_LOADS = (0.98, 0.95, 0.9, 0.8)


def settle(sim, state: dict) -> dict:
    """A :func:`consistent` ``state`` of a path-following run brought to equilibrium at the first
    load of SETTLE_LOADS (fractions of its own) where one is found: the coupled Newton (no
    staggered passes under path following, :func:`_equilibrium`); committed. Returns the state at that load (its ``load`` lower),
    or ``state`` where none is found.

    Why: where a crack runs in a snap-back, the state carried to a finer mesh is past its own
    critical load. At the carried load the phase field of its trial history releases 1.8 % of its
    D more and no equilibrium is near (the quick three-point bending at 0.0921 mm); at lower loads
    the release falls (0.6 % at 0.9, 0.23 % at 0.8 of the load), its crack holds, and the path
    follows on from there."""
    load = float(state["load"])
    for f in SETTLE_LOADS:
        out = _equilibrium(sim, state, f * load, u_first=True)
        if out is not None:
            return out
    return state


def consistent(solver, state: dict) -> dict:
    """``state`` (carried to a new mesh) made consistent with its own history where no equilibrium
    at its load is found (:func:`equilibrate`): alpha raised to the phase field that the carried
    H drives (never lowered; committed with it), then u solved at that alpha and the load (kept
    as carried where that solve fails). H stays as carried.

    Why: in the quick three-point bending's crack run (a snap-back, 0.092 mm) the carried alpha is
    below what the carried H drives (its nodal interpolation of the sharp profile loses 1.6 % of
    the dissipation) and the carried u strains the new elements beyond H at 1670 history points;
    from that state every step failed, down to 1e-8 mm. From the consistent state, settled, the run
    finishes its curve (docs/adaptivity.md, "Refinement by remeshing")."""
    s = solver
    s.set_state(state)
    s.solve_phase_field()             # the carried H, bounded below by the carried alpha
    s.alpha_committed = s.alpha.vec.FV().NumPy().copy()
    return balance(s, s.get_state(), in_place=True)
