"""Refinement by remeshing (ngtmc.adapt.remesh): the geometry meshed again gives the scene's mesh back,
a wrong maxh is refused, the state crosses the non-nested meshes (a homogeneous state exactly, H
never below the old element's largest value where the mesh is refined, linear fields exactly
elsewhere, alpha the old field at the new vertices), the refined zone comes out at its target
size and is not refined twice, a remeshed path-following run converges and agrees with its final
mesh used from the start, and it resumes from a checkpoint on the same mesh."""
import dataclasses

import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from ngtmc import adapt
from ngtmc.adapt import carried_state
from ngtmc.adapt import remesh
from ngtmc.adapt import Adaptivity
from ngtmc.adapt.remesh import history_points
from ngtmc.scene import element_vertices
from scenes import damaged, notched_plate

MAXH = 0.2   # mm, the notched plate's global size below


def _plate(**kw):
    return adapt.private_scene(notched_plate(maxh=MAXH, h_band=0.2, l0=0.1, **kw))


def test_geometry_meshed_again_gives_the_mesh_back_and_a_wrong_maxh_is_refused():
    scene = _plate()
    rm = remesh.Remesher(scene.mesh, MAXH)
    again = rm.mesh()
    assert np.array_equal(np.asarray(again.ngmesh.Coordinates()), np.asarray(scene.mesh.ngmesh.Coordinates()))
    with pytest.raises(ValueError, match="remesh_maxh = 0.1 mm: the geometry meshed with it has"):
        remesh.Remesher(scene.mesh, 0.1)
    with pytest.raises(ValueError, match="remesh_maxh"):
        Adaptivity(h_crack=0.05, remesh_maxh=-1.0)
    with pytest.raises(ValueError, match="history_transfer"):
        Adaptivity(h_crack=0.05, history_transfer="mean")


def test_refined_zone_reaches_its_target_and_is_not_refined_again():
    scene = _plate()
    s = ngtmc.Solver(scene)
    rm = remesh.Remesher(scene.mesh, MAXH)
    a = Adaptivity(h_crack=0.025, remesh_maxh=MAXH)
    c = adapt.centroids(s.mesh)
    marked = np.hypot(c[:, 0] - 0.3, c[:, 1] - 0.5) < 0.15       # around the notch tip
    rm.add(s.mesh, marked, adapt.targets(s, a))
    fine = ngtmc.Solver(dataclasses.replace(scene, mesh=rm.mesh()))
    cf = adapt.centroids(fine.mesh)
    near = np.hypot(cf[:, 0] - 0.3, cf[:, 1] - 0.5) < 0.1
    print(f"\nremeshed: {s.mesh.ne} -> {fine.mesh.ne} elements; near the tip median longest edge "
          f"{np.median(fine.h[near]):.4f} mm (target 0.025 mm)")
    assert 0.6 * 0.025 < np.median(fine.h[near]) <= 1.2 * 0.025
    covered = rm.covered(fine.mesh, adapt.targets(fine, a))
    assert covered[near].all() and not covered[~near & (np.hypot(cf[:, 0] - 0.3, cf[:, 1] - 0.5) > 0.3)].any()


def test_homogeneous_state_is_reproduced_exactly():
    scene = _plate()
    s = ngtmc.Solver(scene, compile=True)
    # a homogeneous stretch of the plate (the top pulled 0.003 mm over its height 1 mm)
    s.u.Set(ngs.CF((0.0, 0.003 * ngs.y)))
    s.load = 0.003
    s.H_committed[:] = 7.0
    s.H.vec.FV().NumPy()[:] = 7.0
    s.alpha.vec.FV().NumPy()[:] = 0.125
    s.alpha_committed[:] = 0.125
    energy = s.energies()
    rm = remesh.Remesher(scene.mesh, MAXH)
    c = adapt.centroids(s.mesh)
    marked = np.hypot(c[:, 0] - 0.6, c[:, 1] - 0.3) < 0.2
    rm.add(s.mesh, marked, adapt.targets(s, Adaptivity(h_crack=0.03)))
    new = ngtmc.Solver(dataclasses.replace(scene, mesh=rm.mesh()), compile=True)
    remesh.transfer(s, new, refined=marked)
    assert new.mesh.ne > s.mesh.ne
    err = ngs.Integrate(ngs.InnerProduct(new.u - ngs.CF((0.0, 0.003 * ngs.y)), new.u - ngs.CF((0.0, 0.003 * ngs.y))),
                        new.mesh)
    assert np.sqrt(err) < 1e-12
    assert np.allclose(new.H_committed, 7.0, rtol=0, atol=1e-12)
    used = np.unique(element_vertices(new.mesh))
    assert np.allclose(new.alpha.vec.FV().NumPy()[used], 0.125, atol=1e-12)
    assert np.allclose(new.alpha_committed[used], 0.125, atol=1e-12)
    for k, v in new.energies().items():
        assert v == pytest.approx(energy[k], rel=1e-10, abs=1e-14), k


def test_history_never_decreases_where_refined_and_alpha_is_the_old_field_at_the_new_vertices():
    scene = _plate()
    s = damaged(scene)
    assert np.ptp(s.H_committed) > 0 and s.max_alpha() > 0.01
    a = Adaptivity(h_crack=0.03, alpha_threshold=0.02, remesh_maxh=MAXH)
    marked = adapt.mark(s, a)
    assert 0 < marked.sum() < s.mesh.ne
    rm = remesh.Remesher(scene.mesh, MAXH)
    rm.add(s.mesh, marked, adapt.targets(s, a))
    new = ngtmc.Solver(dataclasses.replace(scene, mesh=rm.mesh()), compile=True)
    remesh.transfer(s, new, refined=marked)
    H_old = s.H_committed.reshape(s.mesh.ne, -1)
    where = remesh.locate(s.mesh, history_points(new))
    H_new = new.H_committed
    up = marked[where]
    # in the refined elements: at least the largest value of the old element holding the point
    assert np.all(H_new[up] >= H_old.max(axis=1)[where[up]] - 1e-12)
    # everywhere: within the range of the old element's values (no new extremes)
    assert np.all(H_new >= H_old.min(axis=1)[where] - 1e-12) and np.all(H_new <= H_old.max(axis=1)[where] + 1e-12)
    # alpha: the old P1 field at every new vertex of the fracture region
    xy = adapt.coordinates(new.mesh)
    a_old = ngs.GridFunction(s.fes_a)
    a_old.vec.FV().NumPy()[:] = s.alpha_committed
    frac_vertices = np.unique(element_vertices(new.mesh))   # the plate is all fracture region
    old_at = np.array([a_old(s.mesh(*xy[v])) for v in frac_vertices])
    assert np.max(np.abs(new.alpha_committed[frac_vertices] - old_at)) < 1e-6


def test_consistent_state_raises_alpha_to_its_history_and_balances_u():
    """The fallback of a failed equilibration: alpha raised (never lowered) to the phase field of
    the carried H, committed with it; u an equilibrium at that alpha; H as carried."""
    scene = _plate()
    s = damaged(scene)
    a = Adaptivity(h_crack=0.03, alpha_threshold=0.02, remesh_maxh=MAXH)
    marked = adapt.mark(s, a)
    rm = remesh.Remesher(scene.mesh, MAXH)
    rm.add(s.mesh, marked, adapt.targets(s, a))
    new = ngtmc.Solver(dataclasses.replace(scene, mesh=rm.mesh()), compile=True)
    remesh.transfer(s, new, refined=marked)
    carried = new.get_state()
    assert new.solve_displacement(float(carried["load"])).iterations > 0   # the carried u is not balanced
    out = carried_state.consistent(new, carried)
    assert np.all(out["alpha"] >= carried["alpha"]) and np.any(out["alpha"] > carried["alpha"] + 1e-3)
    assert np.array_equal(out["alpha_committed"], out["alpha"]) and np.array_equal(out["H"], carried["H"])
    assert float(out["load"]) == float(carried["load"])
    # alpha is the phase field of the carried H: solving it again changes nothing
    new.set_state(out)
    new.solve_phase_field()
    assert np.max(np.abs(new.alpha.vec.FV().NumPy() - out["alpha"])) < 1e-12
    # u balances that alpha at the load: the displacement Newton has nothing to do
    new.set_state(out)
    assert new.solve_displacement(float(out["load"])).iterations == 0


def test_carried_displacement_that_folds_an_element_is_halved_until_it_does_not():
    s = ngtmc.Solver(_plate(), compile=True)
    s.u.Set(ngs.CoefficientFunction((1e-3 * ngs.x, -0.5e-3 * ngs.y)))      # a small stretch: admissible
    u = s.u.vec.FV().NumPy().copy()
    assert s.min_J() > 0 and np.array_equal(remesh._admissible(s, u), u)
    # x -> x - 1.5 x: J = -0.5 everywhere; halved once, x -> x - 0.75 x, J = 0.25
    s.u.Set(ngs.CoefficientFunction((-1.5 * ngs.x, 0.0)))
    fold = s.u.vec.FV().NumPy().copy()
    assert s.min_J() == pytest.approx(-0.5)
    out = remesh._admissible(s, fold)
    assert np.array_equal(s.u.vec.FV().NumPy(), fold)                   # the solver's u is left as it was
    assert np.allclose(out, 0.5 * fold)
    s.u.vec.FV().NumPy()[:] = out
    assert s.min_J() == pytest.approx(0.25)


def test_settled_state_is_an_equilibrium_below_its_load():
    """settle: the first load of SETTLE_LOADS below the state's own at which an equilibrium is
    found; the state there is committed (H and alpha never below the state's) and balanced."""
    scene = notched_plate(maxh=MAXH, h_band=0.2, l0=0.1)
    control = ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7)
    sim = ngtmc.Simulation(scene, ngtmc.Schedule([0.0, 0.005]), control, compile=True, scheme="path-following")
    sim.run()
    s = sim.solver
    state = s.get_state()
    assert s.max_alpha() > 0.05
    out = carried_state.settle(sim, state)
    assert float(out["load"]) == pytest.approx(carried_state.SETTLE_LOADS[0] * float(state["load"]), rel=1e-12)
    assert np.all(out["H"] >= state["H"]) and np.all(out["alpha"] >= state["alpha_committed"] - 1e-12)
    assert np.array_equal(out["alpha_committed"], out["alpha"])
    s.set_state(out)
    assert sim.coupled.solve(float(out["load"])).iterations == 0


def test_a_carried_state_without_equilibrium_is_reported_and_grows_its_crack_at_its_load(monkeypatch):
    """equilibrate reports whether the carried state is an equilibrium of the new mesh: where
    neither its load nor a settle below it has one, it returns the consistent state and False.
    From such a state (here an accepted state carried to a load 20 % higher, made consistent: its
    u there strains the crack beyond its history), DissipationPath.grow_at_load takes a displacement
    step at its load with the fallback: the crack grows at that load (D rises, alpha never falls)
    to an equilibrium there, and the path goes on with displacement steps."""
    scene = notched_plate(maxh=MAXH, h_band=0.2, l0=0.1)
    control = ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7)
    sim = ngtmc.Simulation(scene, ngtmc.Schedule([0.0, 0.012]), control, compile=True, scheme="path-following")
    while sim.solver.load < 0.005:
        sim.advance()
    s, path = sim.solver, sim._path
    state = s.get_state()
    out, found = carried_state.equilibrate(sim, state)
    assert found and float(out["load"]) == float(state["load"])
    raised = dict(state, load=np.array(1.2 * float(state["load"])))
    with monkeypatch.context() as m:
        m.setattr(carried_state, "_equilibrium", lambda *a, **k: None)
        out, found = carried_state.equilibrate(sim, raised)
    assert not found and float(out["load"]) == float(raised["load"])
    assert np.all(out["alpha"] >= state["alpha"] - 1e-12)
    s.set_state(out)
    assert sim.coupled.solve(float(out["load"])).iterations > 0   # not an equilibrium at its load
    d0 = sim.coupled.D.value(np.asarray(out["alpha_committed"], dtype=float))
    ok, info = path.grow_at_load(out)
    assert ok, info.get("message")
    assert s.load == pytest.approx(float(out["load"]), rel=1e-12)
    assert sim.schedule.load(info["t_new"]) == pytest.approx(s.load, rel=1e-12)
    assert sim.coupled.D.value() > d0 and np.all(s.alpha.vec.FV().NumPy() >= out["alpha_committed"] - 1e-12)
    assert not path.dissipating
    print(f"\ngrow at load {s.load:.6g} mm: D {d0:.5g} -> {sim.coupled.D.value():.5g} N mm/mm, "
          f"{info['newton_iterations']} Newton iterations, {info['staggered_iterations']} staggered passes")
    assert sim.coupled.solve(s.load).converged


def test_equilibration_under_path_following_tries_no_fixed_load_passes(monkeypatch):
    """Where the coupled Newton finds no equilibrium of a carried state at its load, path following
    goes to settle, not to staggered passes at that load (they would grow a crack past its
    critical load off the path); other schemes keep the passes."""
    scene = notched_plate(maxh=MAXH, h_band=0.2, l0=0.1)
    control = ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7)
    for scheme, passes_expected in (("path-following", 0), ("monolithic", 1)):
        sim = ngtmc.Simulation(scene, ngtmc.Schedule([0.0, 0.005]), control, compile=True, scheme=scheme)
        state = sim.solver.get_state()
        calls = []
        monkeypatch.setattr(sim.coupled, "solve", lambda *a, **k: type("R", (), {"converged": False})())
        monkeypatch.setattr(sim, "_passes", lambda *a, **k: calls.append(a) or (False, {}))
        assert carried_state._equilibrium(sim, state, 0.001) is None
        assert len(calls) == passes_expected, scheme


def test_linear_history_is_carried_exactly():
    scene = _plate()
    s = ngtmc.Solver(scene, compile=True)
    xy = history_points(s)
    s.H_committed[:] = 3.0 + 2.0 * xy[:, 0] - 1.5 * xy[:, 1]
    rm = remesh.Remesher(scene.mesh, MAXH)
    c = adapt.centroids(s.mesh)
    marked = np.hypot(c[:, 0] - 0.5, c[:, 1] - 0.5) < 0.2
    rm.add(s.mesh, marked, adapt.targets(s, Adaptivity(h_crack=0.03)))
    new = ngtmc.Solver(dataclasses.replace(scene, mesh=rm.mesh()), compile=True)
    remesh.transfer(s, new, history="linear")
    xy_new = history_points(new)
    # clipping to the old element's range moves a point of a new element only where it lies
    # beyond the old element's points (near its vertices); within them the plane is exact
    exact = 3.0 + 2.0 * xy_new[:, 0] - 1.5 * xy_new[:, 1]
    err = np.abs(new.H_committed - exact)
    assert np.median(err) < 1e-12 and np.max(err) < 2.0 * MAXH


def test_remeshed_path_following_run_converges_and_agrees_with_its_final_mesh():
    """The notched plate from its coarse mesh (maxh 0.2 mm, 202 elements) refined by remeshing to
    h_crack = l0/4 while the crack runs; its peak is that of the same scheme on the run's final
    mesh from the start to 2 %, every state accepted is an equilibrium, the dissipated energy
    never decreases, and the run resumes from its checkpoint on the same mesh. The path's secant
    predictor restarts after each remesh (no older state is carried to the new mesh)."""
    scene = notched_plate(maxh=MAXH, h_band=0.2, l0=0.1)
    control = ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7)
    a = Adaptivity(h_crack=0.025, remesh_maxh=MAXH)
    sim = ngtmc.Simulation(scene, ngtmc.Schedule([0.0, 0.007]), control, compile=True, scheme="path-following",
                           adapt=a)
    carried = []   # the secant predictor's older states carried across each remesh: none
    mesh_changed = sim._path.mesh_changed
    sim._path.mesh_changed = lambda before, previous=(): carried.append(len(previous)) or mesh_changed(before, previous)
    states = []
    for row in sim.steps():
        if len(states) < 1 and sim.refinements:
            states.append(sim.get_state())
    h = sim.history
    force = h["force"].to_numpy()
    assert sim.refinements and h["elements"].iloc[-1] > 5 * h["elements"].iloc[0]
    assert len(carried) == len(sim.refinements) and not any(carried)   # the secant restarts after a remesh
    assert sim._path.coupled is sim.coupled and sim.coupled.s is sim.solver
    assert np.all(np.diff(h["dissipated_energy"].to_numpy()) >= -1e-12 * h["dissipated_energy"].max())
    assert force[-1] < 0.1 * force.max()
    assert sim.coupled.solve(sim.solver.load).iterations == 0
    final = sim.solver.scene
    ref = ngtmc.Simulation(dataclasses.replace(final, mesh=ngs.Mesh(final.mesh.ngmesh.Copy())),
                           ngtmc.Schedule([0.0, 0.007]), control, compile=True, scheme="path-following").run().history
    print(f"\nremeshed run: {len(h) - 1} steps, {int(h['newton_iterations'].sum())} Newton iterations, "
          f"{len(sim.refinements)} remeshes, {h['elements'].iloc[0]} -> {h['elements'].iloc[-1]} elements, peak "
          f"{force.max():.6g} N/mm; final mesh from the start: {len(ref) - 1} steps, peak {ref['force'].max():.6g} N/mm")
    assert force.max() == pytest.approx(ref["force"].max(), rel=2e-2)
    # resume from the state after the first remesh: the same mesh, and the state is an equilibrium there
    again = ngtmc.Simulation(scene, ngtmc.Schedule([0.0, 0.007]), control, compile=True, scheme="path-following",
                             adapt=a)
    again.set_state(states[0])
    st = states[0]["solver"]
    assert again.solver.fes_u.ndof == st["u"].size and again.solver.irs.ndof == st["H"].size
    assert again.coupled.solve(again.solver.load).iterations == 0
    with pytest.raises(ValueError, match="refined by remeshing"):
        ngtmc.Simulation(scene, ngtmc.Schedule([0.0, 0.007]), control, compile=True, scheme="path-following",
                         adapt=Adaptivity(h_crack=0.025)).set_state(states[0])


def test_run_folder_of_a_remeshed_run_keeps_each_snapshot_on_its_mesh(tmp_path):
    """Snapshots, the ParaView series and the metadata of a run refined by remeshing (single
    pass): one snapshot group per mesh, each with arrays that fit its own vertices and triangles,
    and every VTK file with the points of its snapshot's mesh."""
    import re
    out = tmp_path / "run"
    res = ngtmc.simulate(notched_plate(maxh=MAXH, h_band=0.2, l0=0.1), ngtmc.Schedule([0.0, 0.0065]),
                         ngtmc.AdaptiveStepControl(du_max=5e-4, k_u=0.0, du_min=1e-7), out_dir=out,
                         adapt=Adaptivity(h_crack=0.07, remesh_maxh=MAXH), report=False, progress=False,
                         threads=1, compile=True, snapshot_loads=[0.002, 0.004, 0.005, 0.0055, 0.006, 0.0065])
    h = res.history
    assert h["elements"].iloc[-1] > 1.5 * h["elements"].iloc[0]
    z = np.load(out / "snapshots.npz")
    groups = sorted({k.split("__")[0] for k in z.files}, key=lambda g: int(g.split("@")[1]))
    assert len(groups) >= 2
    for g in groups:
        V, T, U, A = (z[f"{g}__{f}"] for f in ("vertices", "triangles", "u", "alpha"))
        k = len(z[f"{g}__loads"])
        assert U.shape == (k, len(V), 2) and A.shape == (k, len(V)) and T.max() == len(V) - 1
    vtus = sorted((out / "vtk").glob("main_*.vtu"))
    assert len(vtus) == 6
    last = vtus[-1].read_text()
    n_points = int(re.search(r'NumberOfPoints="(\d+)"', last).group(1))
    assert n_points == res.solver.mesh.nv
