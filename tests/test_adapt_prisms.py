"""Adaptive refinement of an extruded slab of prisms (ngtmc.scene.extrusion; ngtmc.adapt, ngtmc.adapt.bisection):
NGSolve bisects a prism across its triangles only, so the slab keeps its layers; u is carried
exactly at order 2 (through a copy of the mesh, where NGSolve's prolongation loses the quadratic
part and its exact prolongation is not available), H and alpha never decrease, a homogeneous
state is reproduced, and a plane-strain slab refined during a run follows its 2D twin refined
the same way, element for element."""
import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from ngtmc import adapt
from ngtmc.adapt import Adaptivity
from ngtmc.scene.extrusion import plane_strain_slab
from scenes import (bar_mesh, damaged, homogeneous_state_kept_in_3d, notched_plate, plain_prolongation_error,
                    refine_and_check_the_transfer_in_3d)


def test_prisms_are_bisected_across_their_triangles_and_an_order_two_field_is_carried_exactly():
    """The traps: NGSolve has no exact (``hoprolongation``) prolongation on prisms of order 2, and
    its plain prolongation loses the quadratic part (0.021 here, measured); ngtmc.adapt.bisection
    carries u through a copy of the mesh instead (6e-15 measured). The refined slab keeps its two
    faces and its prisms."""
    x, y, z = ngs.x, ngs.y, ngs.z
    field = ngs.CF((1e-3 * x * y, -2e-3 * y * y, 1e-3 * x * x * z))
    slab = ngtmc.extrude(bar_mesh(height=1.0, maxh=0.3), 0.1)
    with pytest.raises(Exception, match="only implemented for order==1"):
        ngs.VectorH1(slab, order=2, hoprolongation=True)
    plain = plain_prolongation_error(slab, field)
    assert plain > 1e-4 * 1e-3   # silently inexact

    scene = ngtmc.Scene(ngtmc.extrude(bar_mesh(height=1.0, maxh=0.3), 0.1), {"bar": ngtmc.Material(1000.0, 0.3, 1e-3, 0.1)},
                        supports=[ngtmc.Support("left", x=True, y=True, z=True)], fracture_regions="bar",
                        load=ngtmc.DisplacementLoad("right", "x"), order=2)
    s = ngtmc.Solver(scene, compile=True)
    s.u.Set(field)
    ne = s.mesh.ne
    adapt.refine(s, np.arange(ne) % 2 == 0)
    assert s.mesh.ne > ne
    assert {el.type for el in s.mesh.Elements(ngs.VOL)} == {ngs.ET.PRISM}
    assert sorted({round(p.point[2], 12) for p in s.mesh.vertices}) == [0.0, 0.1]   # no new layer
    err = np.sqrt(ngs.Integrate(ngs.InnerProduct(s.u - field, s.u - field), s.mesh))
    assert err < 1e-12 * 1e-3 and plain > 1e6 * err


def test_history_and_alpha_never_decrease_across_refinement_of_prisms():
    """H varies within a prism (its strain is not constant), so only the children of a refined
    prism are bounded below by their parent's largest value."""
    s = damaged(plane_strain_slab(notched_plate(maxh=0.2, h_band=0.2, l0=0.1), 0.05))
    refine_and_check_the_transfer_in_3d(s, Adaptivity(h_crack=0.1, alpha_threshold=0.02))


@pytest.mark.parametrize("order", [1, 2])
def test_homogeneous_state_is_reproduced_exactly_on_prisms(order):
    scene = ngtmc.Scene(ngtmc.extrude(bar_mesh(height=1.0, maxh=0.3), 0.1), {"bar": ngtmc.Material(1000.0, 0.3, 1e-3, 0.1)},
                        supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True),
                                  ngtmc.Support("front", z=True)],
                        load=ngtmc.DisplacementLoad("right", "x"), fracture_regions="bar", order=order)
    homogeneous_state_kept_in_3d(ngtmc.Solver(scene, compile=True), order)


def test_a_refined_slab_follows_its_refined_2d_twin_element_for_element():
    """The notched plate from a coarse mesh (202 triangles) under path following with
    ``h_crack = l0``, and its plane-strain slab of order-1 prisms: the same refinements (202 ->
    910 elements in 9 refinements, measured), and the forces agree to solver precision (3.5e-11
    of the peak at the peak, measured). No corridor in either: its default ("auto") is 4 l0 in 2D
    and none in 3D."""
    t = 0.05
    sc2 = notched_plate(maxh=0.2, h_band=0.2, l0=0.1)
    runs = {}
    for name, sc, scale in (("2d", sc2, 1.0), ("slab", plane_strain_slab(sc2, t), t)):
        sim = ngtmc.Simulation(sc, ngtmc.Schedule([0.0, 0.007]),
                               ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0 / scale, du_min=1e-7), compile=True,
                               scheme="path-following", adapt=Adaptivity(h_crack=0.1, corridor=0.0),
                               newton=ngtmc.NewtonOptions(linear_solver="umfpack"), coupled={"linear_solver": "umfpack"})
        h = sim.run().history
        runs[name] = (h, [r.elements_after for _, r in sim.refinements], scale)
    (h2, r2, _), (h3, r3, t) = runs["2d"], runs["slab"]
    assert r3 == r2 and len(r2) >= 3 and h3["elements"].iloc[-1] == h2["elements"].iloc[-1] > 4 * h2["elements"].iloc[0]
    F = h2["force"].max()
    assert h3["force"].max() / t == pytest.approx(F, rel=1e-8)
    n = min(len(h2), len(h3), int(h2["force"].idxmax()) + 1)
    np.testing.assert_allclose(h3["force"][:n] / t, h2["force"][:n], rtol=0, atol=1e-7 * F)


def test_an_interrupted_refined_slab_resumes_on_its_refined_mesh(tmp_path):
    """A resume replays the recorded refinements on the initial slab (bisection of prisms, their
    ancestors located in a copy of the mesh) and goes on from the checkpoint to the history and
    snapshots of the run that was not interrupted (measured: equal to the last bit)."""
    def run(out, **kw):
        scene = plane_strain_slab(notched_plate(maxh=0.2, h_band=0.2, l0=0.1), 0.05)
        return ngtmc.simulate(scene, ngtmc.Schedule([0.0, 0.0065]),
                              ngtmc.AdaptiveStepControl(du_max=5e-4, k_u=0.0, du_min=1e-7), out_dir=out,
                              adapt=Adaptivity(h_crack=0.07), report=False, progress=False, threads=1,
                              checkpoint_every=1, compile=True, snapshot_loads=[0.004, 0.006], **kw).history
    ref = run(tmp_path / "ref")
    assert ref["elements"].iloc[-1] > 4 * ref["elements"].iloc[0]
    stop_step = int(ref.index[ref["elements"] > ref["elements"].iloc[0]][0]) + 1

    def stop(sim, row):
        if row["step"] == stop_step:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(tmp_path / "run", callbacks=[stop])
    seen = []
    h = run(tmp_path / "run", resume=True, callbacks=[lambda sim, row: seen.append(row["step"])])
    assert seen[0] == stop_step + 1 and len(h) == len(ref)
    for col in ("load", "force", "dissipated_energy", "elements", "dofs", "newton_iterations"):
        np.testing.assert_allclose(h[col].to_numpy(dtype=float), ref[col].to_numpy(dtype=float),
                                   rtol=1e-9, atol=1e-12, err_msg=col)
    z, z_ref = np.load(tmp_path / "run" / "snapshots.npz"), np.load(tmp_path / "ref" / "snapshots.npz")
    assert sorted(z.files) == sorted(z_ref.files)
    for k in z.files:
        np.testing.assert_allclose(z[k], z_ref[k], rtol=1e-9, atol=1e-12, err_msg=k)


def test_a_slab_taller_than_its_target_is_refused():
    scene = plane_strain_slab(notched_plate(maxh=0.2, h_band=0.2, l0=0.1), 0.15)
    with pytest.raises(ValueError, match="prisms are up to 0.15 mm tall"):
        ngtmc.Simulation(scene, 0.007, scheme="path-following", adapt=Adaptivity(h_crack=0.1))
