"""Adaptive refinement of tetrahedral meshes (ngtmc.adapt, ngtmc.adapt.bisection in 3D): the transfer
loses nothing (H and alpha never decrease), reproduces a homogeneous state and an order-2 field
exactly, keeps a curved boundary curved, and the re-solved steps converge and agree with a mesh
refined beforehand; hexahedra and 3D remeshing are refused (prisms: tests/test_adapt_prisms.py)."""
import dataclasses

import numpy as np
import ngsolve as ngs
import pytest
from netgen.occ import Box, OCCGeometry, Pnt, Rectangle, Sphere, X, Y, Z

import ngtmc
from ngtmc import adapt
from ngtmc.adapt import Adaptivity
from scenes import damaged, homogeneous_state_kept_in_3d, plain_prolongation_error, refine_and_check_the_transfer_in_3d


def _block_mesh(maxh=0.25, notch=0.3, thickness=0.2):
    """Block [0, 1] x [0, 1] x [0, thickness] (mm) with a slit from the left face to x = notch at
    y = 0.5 (through the thickness, 0.01 wide; None: no slit); faces bottom, top, left, right,
    back (z = 0)."""
    body = Box(Pnt(0, 0, 0), Pnt(1, 1, thickness))
    if notch is not None:
        body = body - Box(Pnt(-0.01, 0.495, -0.01), Pnt(notch, 0.505, thickness + 0.01))
    body.solids.name = "block"
    body.faces.Min(Y).name = "bottom"
    body.faces.Max(Y).name = "top"
    body.faces.Min(X).name = "left"
    body.faces.Max(X).name = "right"
    body.faces.Min(Z).name = "back"
    return ngs.Mesh(OCCGeometry(body).GenerateMesh(maxh=maxh))


def notched_block(maxh=0.25, l0=0.1, thickness=0.2, **kw):
    """Single-edge-notched block in tension (the notched plate of tests/scenes.py with a
    ``thickness`` in z, mm, meshed by tetrahedra): bottom clamped, top pulled in y with x and z
    held."""
    return ngtmc.Scene(_block_mesh(maxh, thickness=thickness), {"block": ngtmc.Material(210e3, 0.3, 2.7, l0)},
                       supports=[ngtmc.Support("bottom", x=True, y=True, z=True)],
                       load=ngtmc.DisplacementLoad("top", "y", hold_tangential=True),
                       fracture_regions="block", **kw)


def test_history_and_alpha_never_decrease_across_refinement_of_tetrahedra():
    refine_and_check_the_transfer_in_3d(damaged(notched_block()), Adaptivity(h_crack=0.08, alpha_threshold=0.02))


@pytest.mark.parametrize("order", [1, 2])
def test_homogeneous_state_is_reproduced_exactly_on_tetrahedra(order):
    """Uniaxial tension of a block (x held on the left, y on the bottom, z on the back: free
    contraction): after two refinements of random elements the energies, the reaction and H are
    the same, and u is still the equilibrium."""
    mesh = _block_mesh(maxh=0.3, notch=None)
    scene = ngtmc.Scene(mesh, {"block": ngtmc.Material(1000.0, 0.3, 1e-3, 0.1)},
                        supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True),
                                  ngtmc.Support("back", z=True)],
                        load=ngtmc.DisplacementLoad("right", "x"), fracture_regions="block", order=order)
    homogeneous_state_kept_in_3d(ngtmc.Solver(scene, compile=True), order)


def test_order_two_field_is_transferred_exactly_on_tetrahedra():
    """The trap of tests/test_adapt.py in 3D: NGSolve's prolongation of an order-2 field is not
    exact without ``hoprolongation``; the transfer of ngtmc.adapt (which carries u through an
    ``hoprolongation`` space, exact on tetrahedra) keeps a quadratic field exactly."""
    x, y, z = ngs.x, ngs.y, ngs.z
    field = ngs.CF((1e-3 * x * y, -2e-3 * z * z, 1e-3 * x * x))
    assert plain_prolongation_error(_block_mesh(maxh=0.4, notch=None), field) > 1e-6
    scene = ngtmc.Scene(_block_mesh(maxh=0.4, notch=None), {"block": ngtmc.Material(1000.0, 0.3)},
                        supports=[ngtmc.Support("bottom", x=True, y=True, z=True)],
                        load=ngtmc.DisplacementLoad("top", "y"), order=2)
    s = ngtmc.Solver(scene, compile=True)
    s.u.Set(field)
    err = lambda: ngs.sqrt(ngs.Integrate(ngs.InnerProduct(s.u - field, s.u - field), s.mesh))
    assert err() < 1e-12
    adapt.refine(s, np.arange(s.mesh.ne) % 2 == 0)
    assert err() < 1e-12


def test_curved_boundary_stays_curved_on_tetrahedra():
    ball = Sphere(Pnt(0, 0, 0), 1.0)
    ball.solids.name = "ball"
    ball.faces.name = "surface"
    mesh = ngs.Mesh(OCCGeometry(ball).GenerateMesh(maxh=0.6))
    mesh.Curve(2)
    scene = adapt.private_scene(ngtmc.Scene(mesh, {"ball": ngtmc.Material(1000.0, 0.3)},
                                            supports=[ngtmc.Support("surface", x=True, z=True)],
                                            load=ngtmc.DisplacementLoad("surface", "y")))
    s = ngtmc.Solver(scene, compile=True)
    for _ in range(2):
        adapt.refine(s, np.ones(s.mesh.ne, dtype=bool))
    assert s.mesh.GetCurveOrder() == 2
    exact = 4.0 / 3.0 * np.pi
    assert abs(ngs.Integrate(1.0, s.mesh) - exact) < 2e-3 * exact
    flat = ngs.Mesh(s.mesh.ngmesh.Copy())   # the same vertices with straight edges
    assert abs(ngs.Integrate(1.0, flat) - exact) > 4e-3 * exact


def test_refined_resolve_converges_on_tetrahedra_and_agrees_with_a_mesh_refined_beforehand(tmp_path):
    """The notched block (0.1 mm thick) refined to h_crack = 1.25 l0 during a run into a run
    folder (840 -> 4883 tetrahedra in 4 refinements; the expressions not compiled, to keep the
    test to seconds): after the last refinement its forces agree within 2 % with a run on the
    final mesh from the start, the last state is an equilibrium, and the folder keeps every
    snapshot on its own mesh with the section through the block (z = 0.05 mm) in each group, which
    the report draws."""
    import json
    scene = notched_block(maxh=0.25, l0=0.1, thickness=0.1)
    sched = ngtmc.Schedule([0.0, 0.0055])
    control = lambda: ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=0.0, du_min=1e-8)
    res = ngtmc.simulate(scene, sched, control(), out_dir=tmp_path / "run", adapt=Adaptivity(h_crack=0.125),
                         compile=False, progress=False, threads=1, snapshot_loads=[0.003, 0.0055],
                         section=("z", 0.05))
    h = res.history
    refined = np.flatnonzero(np.diff(h["elements"].to_numpy())) + 1   # steps after which the mesh changed
    assert refined.size and h["elements"].iloc[-1] > h["elements"].iloc[0] == scene.mesh.ne
    s = res.solver
    assert s.solve_displacement(s.load).iterations == 0   # the last state is an equilibrium there
    final = s.scene
    ref = ngtmc.Simulation(dataclasses.replace(final, mesh=ngs.Mesh(final.mesh.ngmesh.Copy())), sched, control(),
                           compile=False).run()
    np.testing.assert_allclose(h["load"].to_numpy(), ref.history["load"].to_numpy(), rtol=0, atol=1e-15)
    last = refined[-1]
    np.testing.assert_allclose(h["force"].to_numpy()[last:], ref.history["force"].to_numpy()[last:], rtol=2e-2)
    # the run folder: one group of snapshots per mesh, each with its section, on ever finer meshes
    meta = json.loads((tmp_path / "run" / "metadata.json").read_text())
    assert meta["cases"][0]["refinements"] >= refined.size
    z = np.load(tmp_path / "run" / "snapshots.npz")
    groups = sorted({k.split("__")[0] for k in z.files})
    assert len(groups) == 2 and all(g.startswith("main@") for g in groups)
    for g in groups:
        assert z[f"{g}__vertices"].shape[1] == 3 and z[f"{g}__u"].shape[1:] == z[f"{g}__vertices"].shape
        sec = z[f"{g}__section_alpha"]
        assert sec.shape == (1, z[f"{g}__section_c1"].size, z[f"{g}__section_c2"].size)
        assert list(z[f"{g}__section_plane"]) == [2.0, 0.05] and np.nanmax(sec) > 0.0
    assert len(z[f"{groups[1]}__vertices"]) > len(z[f"{groups[0]}__vertices"])
    page = (tmp_path / "run" / "report.html").read_text()
    assert 'id="section3d-0"' in page and 'id="section3d-1"' in page and "surface triangles" in page


def test_hexahedra_and_remeshing_in_3d_are_refused():
    """Bisection needs triangles, tetrahedra or prisms, one kind (tests/test_adapt_prisms.py): a
    slab with hexahedra (a quadrilateral-dominated mesh extruded) is refused, and so is remeshing
    in 3D."""
    sched = ngtmc.Schedule([0.0, 1e-3])
    control = ngtmc.AdaptiveStepControl(du_max=1e-3)
    with pytest.raises(ValueError, match="remeshing.*2D meshes only"):
        ngtmc.Simulation(notched_block(), sched, control, adapt=Adaptivity(h_crack=0.05, remesh_maxh=0.25))
    face = Rectangle(1, 0.2).Face()
    face.faces.name = "bar"
    face.edges.Min(X).name = "left"
    face.edges.Max(X).name = "right"
    quads = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.1, quad_dominated=True))
    assert ngs.ET.QUAD in {el.type for el in quads.Elements(ngs.VOL)}   # (a few triangles too)
    slab = ngtmc.Scene(ngtmc.extrude(quads, 0.05), {"bar": ngtmc.Material(1000.0, 0.3, 1e-3, 0.1)},
                       supports=[ngtmc.Support("left", x=True, y=True, z=True)],
                       load=ngtmc.DisplacementLoad("right", "x"), fracture_regions="bar")
    with pytest.raises(ValueError, match="triangles.*tetrahedra or of prisms"):
        ngtmc.Simulation(slab, sched, control, adapt=Adaptivity(h_crack=0.05))


def test_report_names_a_refined_3d_mesh_by_its_surface_triangles():
    """A group of snapshots on one mesh of a refined run is labelled with its size: the elements
    in 2D, and in 3D the triangles of the solid's surface, which is what the snapshot holds and
    the report draws."""
    from ngtmc.report.page import snapshot_group_label
    cases = [{"name": "main", "label": "block"}]
    tri = np.zeros((472, 3), dtype=int)
    assert snapshot_group_label("main@2", {"triangles": tri, "vertices": np.zeros((300, 3))}, cases) == \
        "block, mesh 2 (472 surface triangles)"
    assert snapshot_group_label("main@1", {"triangles": tri, "vertices": np.zeros((300, 2))}, cases) == \
        "block, mesh 1 (472 elements)"
    assert snapshot_group_label("other", {}, cases) == "other"
