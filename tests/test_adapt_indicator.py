"""The refinement indicator's lookahead (ngtmc.Adaptivity.buffer_length), a hysteresis: when the
indicator marks an element still to refine, marked are exactly the elements larger than their
target whose centroid lies within the given distance of an element the indicator marks by itself;
when it marks none, nothing is marked."""
import numpy as np
import pytest

from ngtmc import adapt

from ngtmc.adapt import corridor as adapt_corridor
from ngtmc.adapt import Adaptivity
from test_adapt import _damaged_notched_plate


def centroids(mesh):
    nodes = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    return np.asarray(mesh.ngmesh.Coordinates())[:, :2][nodes].mean(axis=1)


def test_lookahead_marks_every_element_within_its_distance():
    s = _damaged_notched_plate()
    base = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0))
    assert 0 < base.sum()
    ahead = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, buffer_length=0.15))
    c = centroids(s.mesh)
    dist = np.min(np.linalg.norm(c[:, None, :] - c[base][None, :, :], axis=-1), axis=1)
    expected = (dist <= 0.15) & (s.h > 0.03 * (1 + 1e-9))
    np.testing.assert_array_equal(ahead, expected)
    assert ahead.sum() > base.sum()
    # after the refinement of what the indicator alone marks, the lookahead is not triggered
    adapt.refine(s, base)
    for _ in range(5):
        base = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0))
        if not base.any():
            break
        adapt.refine(s, base)
    assert not base.any()
    assert not adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, buffer_length=0.15)).any()


def test_lookahead_must_be_a_length():
    with pytest.raises(ValueError, match="buffer_length"):
        Adaptivity(h_crack=0.01, buffer_length=-1.0)


def test_size_tolerance_refines_while_the_longest_edge_exceeds_it_times_the_target():
    """Adaptivity.size_tolerance: marked are the elements the indicator marks whose longest edge
    exceeds size_tolerance times the target; refined until none is, the crack's elements end
    between about half that bound and the bound, so with sqrt(2) the target lies inside, not at
    the top of, the range of sizes."""
    s = _damaged_notched_plate()
    strict = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0))
    loose = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, size_tolerance=2 ** 0.5))
    np.testing.assert_array_equal(loose, strict & (s.h > 0.03 * 2 ** 0.5 * (1 + 1e-9)))
    assert strict.sum() > loose.sum() > 0
    for _ in range(6):
        marked = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, size_tolerance=2 ** 0.5))
        if not marked.any():
            break
        adapt.refine(s, marked)
    assert not marked.any()
    indicated = adapt.mark(s, Adaptivity(h_crack=1e-9, alpha_threshold=0.5, buffer=0))  # every indicated element
    assert indicated.any() and s.h[indicated].max() <= 0.03 * 2 ** 0.5 * (1 + 1e-9)
    with pytest.raises(ValueError, match="size_tolerance"):
        Adaptivity(h_crack=0.01, size_tolerance=0.9)


def _plate_cracked_to(x_tip):
    """The coarse notched plate (slit from the left edge to (0.3, 0.5), fracture everywhere) with a
    damage field of a straight crack from the slit's end to (x_tip, 0.5): alpha = exp(-d / l0),
    d the distance to that segment (l0 = 0.1 mm)."""
    import ngsolve as ngs
    s = _damaged_notched_plate()
    xs = ngs.IfPos(ngs.x - x_tip, x_tip, ngs.IfPos(ngs.x - 0.3, ngs.x, 0.3))
    d = ngs.sqrt((ngs.x - xs) ** 2 + (ngs.y - 0.5) ** 2)
    s.alpha.Set(ngs.exp(-d / 0.1))
    return s


def test_corridor_refines_the_straight_path_ahead_of_the_front_only():
    """Adaptivity.corridor: with the front (the marked fracture elements) at the tip of a straight
    crack along y = 0.5, the corridor holds the coarse elements ahead of the front within the
    half width of the crack's line, up to the plate's right edge, and none behind the front or
    off the line; none without damage or without a marked fracture element."""
    from ngtmc.adapt import corridor_elements
    w = 0.12
    s = _plate_cracked_to(0.5)
    c = centroids(s.mesh)
    front = (np.abs(c[:, 0] - 0.55) < 0.06) & (np.abs(c[:, 1] - 0.5) < 0.06)
    assert front.any()
    a = Adaptivity(h_crack=0.03, corridor=w)
    extra = corridor_elements(s, a, front)
    assert extra.any() and not (extra & front).any()
    tip = c[front].mean(axis=0)
    # ahead of the front and near the crack's line (the ray's direction is within a few degrees of
    # +x: the damage's and the front's centroids both lie near y = 0.5)
    assert np.all(c[extra, 0] >= tip[0] - w)
    assert np.all(np.abs(c[extra, 1] - 0.5) <= w + 0.05)
    # every coarse element on the path ahead, to the right edge, is in it
    coarse = s.h > 0.03 * (1 + 1e-9)
    on_path = coarse & ~front & (c[:, 0] > tip[0] + w) & (np.abs(c[:, 1] - tip[1]) < 0.5 * w)
    assert on_path.any() and np.all(extra[on_path])
    assert c[extra, 0].max() > 0.85
    # nothing without a front, without damage, or with no width
    assert not corridor_elements(s, a, np.zeros_like(front)).any()
    assert not corridor_elements(s, Adaptivity(h_crack=0.03, corridor=0.0), front).any()
    s.alpha.vec.FV().NumPy()[:] = 0.0
    assert not corridor_elements(s, a, front).any()


def test_corridor_runs_on_the_crack_across_the_fronts_opening_not_along_an_off_line_ray():
    """The corridor's direction is the ray from the damaged zone to the front without its component
    along the front's largest principal strain, and its line lies on the damaged elements next to
    the front, across that strain: with the front's centroid 0.1 mm off a straight crack along
    y = 0.5 (the ray leans about 30 degrees) and the plate stretched in y (1 %), the corridor runs
    along x on the crack's line y = 0.5, not through the front's centroid; unstretched (no
    opening), it follows the ray from the front's centroid."""
    import ngsolve as ngs
    from ngtmc.adapt import corridor_elements
    w = 0.08
    s = _plate_cracked_to(0.5)
    c = centroids(s.mesh)
    front = (np.abs(c[:, 0] - 0.55) < 0.06) & (np.abs(c[:, 1] - 0.6) < 0.06)
    tip = c[front].mean(axis=0)
    a = Adaptivity(h_crack=0.03, corridor=w)
    s.u.vec[:] = 0.0
    leaning = corridor_elements(s, a, front)            # u = 0: no opening, the ray as it is
    assert c[leaning, 1].max() > tip[1] + w + 0.1
    s.u.Set(ngs.CoefficientFunction((0.0, 0.01 * ngs.y)))
    along = corridor_elements(s, a, front)
    assert along.any() and c[along, 0].max() > 0.85
    ahead = along & (c[:, 0] > tip[0] + w)
    assert np.all(np.abs(c[ahead, 1] - 0.5) <= w + 0.01)   # the damaged elements' centroid: y = 0.5 to the mesh's asymmetry
    assert abs(np.mean(c[ahead, 1]) - 0.5) < 0.2 * w     # centred on the crack, not on y = 0.6
    coarse = s.h > 0.03 * (1 + 1e-9)
    on_line = coarse & ~front & (c[:, 0] > tip[0] + w) & (np.abs(c[:, 1] - 0.5) < 0.5 * w)
    assert on_line.any() and np.all(along[on_line])


def test_corridor_must_be_a_length():
    with pytest.raises(ValueError, match="corridor"):
        Adaptivity(h_crack=0.01, corridor=-0.1)


def test_corridor_waits_for_the_crack_to_run_and_comes_once():
    """The simulation adds the corridor at the first refinement after the last accepted force
    fell below CORRIDOR_DROP of the largest so far, and at no later one (decided from the history
    and the refinements alone, so a resumed run decides as the uninterrupted one); the study
    setting amr_corridor reaches Adaptivity.corridor."""
    import ngtmc
    from ngtmc.study import simulation_options
    from scenes import notched_plate
    sim = ngtmc.Simulation(notched_plate(maxh=0.2, h_band=0.2, l0=0.1), ngtmc.Schedule([0.0, 0.007]),
                           ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7), compile=False,
                           adapt=Adaptivity(h_crack=0.025, corridor=0.1))
    assert not adapt_corridor.corridor_due(sim.rows, sim.refinements)
    peak = 600.0
    for forces, due in (([0.0, 400.0, peak], False), ([0.0, peak, 0.96 * peak], False),
                        ([0.0, peak, 0.94 * peak], True), ([0.0, peak, 0.5 * peak, 0.99 * peak], False)):
        sim.rows = [{"step": i, "force": f} for i, f in enumerate(forces)]
        assert adapt_corridor.corridor_due(sim.rows, sim.refinements) is due, forces
    # round-off about zero before contact (a fall of 1e-13 N/mm) does not count as the drop
    sim.rows = [{"step": i, "force": f} for i, f in enumerate([-0.0, 1e-12, 5e-13, peak, 0.9 * peak, 0.8 * peak])]
    sim.refinements = [(3, None)]           # before the drop (step 4): still due
    assert adapt_corridor.corridor_due(sim.rows, sim.refinements)
    sim.refinements = [(3, None), (5, None)]   # one after it: done
    assert not adapt_corridor.corridor_due(sim.rows, sim.refinements)
    sim.rows = [{"step": i, "force": f} for i, f in enumerate([0.0, peak, 0.9 * peak, 0.8 * peak])]
    sim.refinements = [(1, None)]           # before the drop (step 2): still due
    assert adapt_corridor.corridor_due(sim.rows, sim.refinements)
    sim.refinements = [(1, None), (3, None)]   # one after it: done
    assert not adapt_corridor.corridor_due(sim.rows, sim.refinements)
    assert adapt_corridor.CORRIDOR_DROP == 0.95
    assert simulation_options({"h_crack": 0.0075, "amr_corridor": 0.1})["adapt"].corridor == 0.1
    assert simulation_options({"h_crack": 0.0075})["adapt"].corridor == "auto"
    assert simulation_options({"h_crack": 0.0075, "amr_corridor": 0})["adapt"].corridor == 0.0
    # from the command line (strings): a number, "auto", or a clear refusal
    from ngtmc.study import StudyError
    from ngtmc.study import study_parameters
    from ngtmc.studies import three_point_bending as tpb
    for given, expected in (("0.12", 0.12), ("0", 0.0), ("auto", "auto"), (0.1, 0.1)):
        _, p = study_parameters(tpb, "quick", {"h_crack": "0.015", "amr_corridor": given})
        assert simulation_options(p)["adapt"].corridor == expected
    _, p = study_parameters(tpb, "quick", {"h_crack": "0.015", "amr_corridor": "wide"})
    with pytest.raises(StudyError, match="corridor = 'wide'"):
        simulation_options(p)
    with pytest.raises(StudyError, match="amr_corridor expects 'auto' or a number"):
        study_parameters(tpb, "quick", {"amr_corridor": True})


def test_the_default_corridor_is_four_l0_in_2d_and_none_in_3d():
    """Adaptivity(corridor="auto"), the default: a run resolves it to CORRIDOR_L0 = 4 times the
    fracture regions' mean l0 (area weighted) on a 2D mesh, to 0 in 3D and without a phase
    field; a number is kept as it is; a string other than "auto" is refused, and the strip of
    an unresolved "auto" is refused too."""
    import ngsolve as ngs
    import ngtmc
    from ngtmc.adapt import CORRIDOR_L0
    from ngtmc.discrete import Solver
    from scenes import notched_plate, tension_bar
    assert Adaptivity(h_crack=0.01).corridor == "auto" and CORRIDOR_L0 == 4.0
    with pytest.raises(ValueError, match="corridor = 'wide'"):
        Adaptivity(h_crack=0.01, corridor="wide")
    scene = notched_plate(maxh=0.2, h_band=0.2, l0=0.05)
    s = Solver(scene, compile=False)
    assert Adaptivity(h_crack=0.0125).resolved(s).corridor == pytest.approx(4 * 0.05, rel=1e-12)
    fixed = Adaptivity(h_crack=0.0125, corridor=0.3)
    assert fixed.resolved(s) is fixed
    with pytest.raises(ValueError, match="resolved"):
        adapt_corridor.strip(s, Adaptivity(h_crack=0.0125), np.ones(s.mesh.ne, dtype=bool))
    # two fracture regions of l0 1 and 3 mm, of areas 1 and 3 mm^2 (by hand: (1 + 9) / 4 = 2.5 mm)
    from netgen.geom2d import SplineGeometry
    geo = SplineGeometry()
    pts = [geo.AppendPoint(*p) for p in ((0, 0), (1, 0), (4, 0), (4, 1), (1, 1), (0, 1))]
    for a, b, l, r, bc in ((0, 1, 1, 0, "bottom"), (1, 2, 2, 0, "bottom"), (2, 3, 2, 0, "right"),
                           (3, 4, 2, 0, "top"), (4, 5, 1, 0, "top"), (5, 0, 1, 0, "left"), (1, 4, 1, 2, "inner")):
        geo.Append(["line", pts[a], pts[b]], leftdomain=l, rightdomain=r, bc=bc)
    geo.SetMaterial(1, "a")
    geo.SetMaterial(2, "b")
    mesh = ngs.Mesh(geo.GenerateMesh(maxh=0.3))
    two = ngtmc.Scene(mesh, {"a": ngtmc.Material(1000.0, 0.3, 1e-3, 1.0), "b": ngtmc.Material(1000.0, 0.3, 1e-3, 3.0)},
                      fracture_regions="a|b", supports=[ngtmc.Support("left", x=True, y=True)],
                      load=ngtmc.DisplacementLoad("right", "x"))
    s2 = Solver(two, compile=False)
    assert Adaptivity(h_crack=0.25).resolved(s2).corridor == pytest.approx(CORRIDOR_L0 * 2.5, rel=1e-12)
    # without a phase field, and in 3D: none
    assert Adaptivity(h_crack=0.01).resolved(Solver(tension_bar(fracture=False), compile=False)).corridor == 0.0
    from netgen.occ import Box, OCCGeometry, Pnt, X
    box = Box(Pnt(0, 0, 0), Pnt(1, 0.5, 0.5))
    box.faces.Min(X).name = "left"
    box.faces.Max(X).name = "right"
    block = ngtmc.Scene(ngs.Mesh(OCCGeometry(box).GenerateMesh(maxh=0.5)), {"default": ngtmc.Material(1000.0, 0.3, 1e-3, 2.0)},
                        fracture_regions=".*", supports=[ngtmc.Support("left", x=True, y=True, z=True)],
                        load=ngtmc.DisplacementLoad("right", "x"))
    s3 = Solver(block, compile=False)
    assert s3.mesh.dim == 3 and s3.alpha is not None
    assert Adaptivity(h_crack=0.1).resolved(s3).corridor == 0.0
    # a run resolves it
    sim = ngtmc.Simulation(scene, ngtmc.Schedule([0.0, 0.007]), ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7),
                           compile=False, adapt=Adaptivity(h_crack=0.0125))
    assert sim.adapt.corridor == pytest.approx(0.2, rel=1e-12)


def test_remeshed_corridor_refines_its_strip_not_the_coarse_elements_across_its_edges():
    """Remeshed (ngtmc.adapt.remesh), the corridor holds every coarse fracture element with its centroid
    or a vertex in the strip (more than by bisection, which refines whole elements by their
    centroids), and the remesher keeps their restrictions to the strip: the new mesh is fine
    along the crack's line ahead of the front and coarse beyond the strip's half width plus the
    grading, where the whole elements' restrictions reach further out."""
    import dataclasses
    import ngsolve as ngs
    import ngtmc
    from ngtmc.adapt import remesh
    from ngtmc.adapt import corridor_elements, strip
    w, h = 0.08, 0.03
    s = _plate_cracked_to(0.5)
    s.u.Set(ngs.CoefficientFunction((0.0, 0.01 * ngs.y)))
    c = centroids(s.mesh)
    front = (np.abs(c[:, 0] - 0.55) < 0.06) & (np.abs(c[:, 1] - 0.5) < 0.06)
    a = Adaptivity(h_crack=h, corridor=w, remesh_maxh=0.2)
    rm = remesh.Remesher(s.mesh, 0.2)
    line = strip(s, a, front)
    assert line is not None and abs(line.origin[1] - 0.5) < 0.01 and abs(line.direction[0]) > 0.999
    by_centroid = corridor_elements(s, a, front, line=line)
    extra = corridor_elements(s, a, front, remesher=rm, line=line)
    assert np.all(extra[by_centroid]) and extra.sum() > by_centroid.sum()
    t = adapt.targets(s, a)
    whole = remesh.Remesher(s.mesh, 0.2).add(s.mesh, extra, t)
    kept = rm.add(s.mesh, extra, t, within=line.contains)
    assert len(kept) and line.contains(kept[:, :2]).all() and not line.contains(whole[:, :2]).all()
    fine = ngtmc.Solver(dataclasses.replace(s.scene, mesh=rm.mesh()))
    cf = centroids(fine.mesh)
    ahead = (cf[:, 0] > line.origin[0] + w) & (cf[:, 0] < 0.95)
    on_line = ahead & (np.abs(cf[:, 1] - 0.5) < w - h)
    outside = ahead & (np.abs(cf[:, 1] - 0.5) > w + 3 * h)
    print(f"\nstrip: longest edges {np.median(fine.h[on_line]):.4f} mm (median), {fine.h[on_line].max():.4f} mm (max); "
          f"beyond it {np.median(fine.h[outside]):.4f} mm (median); target {h} mm")
    assert on_line.any() and np.median(fine.h[on_line]) <= 1.2 * h and fine.h[on_line].max() <= 1.3 * h
    assert outside.any() and np.median(fine.h[outside]) > 2 * h


def test_refinement_remeshes_by_default_where_the_study_states_its_maxh():
    """amr_remesh_maxh = "auto" (the default): remeshing with the global maxh the study states
    for its 2D mesh (the three-point bending's h_beam, the L-panel's h_far), bisection where it
    states none (the 3D study, a study file that does not pass one); a number or 0 as given."""
    from ngtmc.study import StudyError, simulation_options, study_parameters
    from ngtmc.studies import l_panel, three_point_bending as tpb
    from ngtmc.studies import three_point_bending_3d as tpb3d
    assert simulation_options({"h_crack": 0.01}, mesh_maxh=0.2)["adapt"].remesh_maxh == 0.2
    assert simulation_options({"h_crack": 0.01})["adapt"].remesh_maxh is None
    assert simulation_options({"h_crack": 0.01, "amr_remesh_maxh": 0}, mesh_maxh=0.2)["adapt"].remesh_maxh is None
    assert simulation_options({"h_crack": 0.01, "amr_remesh_maxh": "0.3"}, mesh_maxh=0.2)["adapt"].remesh_maxh == 0.3
    with pytest.raises(StudyError, match="amr_remesh_maxh = 'fine' must be 'auto'"):
        simulation_options({"h_crack": 0.01, "amr_remesh_maxh": "fine"}, mesh_maxh=0.2)
    _, p = study_parameters(tpb, "quick", {"h_crack": "0.015", "h_beam": "0.3"})
    assert tpb.cases(p)[0].options["adapt"].remesh_maxh == 0.3
    _, p = study_parameters(l_panel, "quick", {"h_crack": "2"})
    assert {c.options["adapt"].remesh_maxh for c in l_panel.cases(p)} == {25.0}
    _, p = study_parameters(tpb3d, "quick", {"h_crack": "0.01", "parts": "hemisphere"})
    assert tpb3d.cases(p)[0].options["adapt"].remesh_maxh is None


def test_the_lookahead_auto_is_the_larger_of_2_l0_and_3_h_crack_in_2d_and_none_in_3d():
    """Adaptivity(buffer_length="auto") (the study setting amr_lookahead's default) resolves for
    a run to max(LOOKAHEAD_L0 l0, LOOKAHEAD_H h_crack) on a 2D mesh (l0 the fracture regions'
    mean), to 0 in 3D (with the corridor); a word other than "auto" and a negative distance are
    refused, also as a study setting."""
    import ngtmc
    from ngtmc.adapt import LOOKAHEAD_H, LOOKAHEAD_L0
    from ngtmc.study import StudyError, simulation_options
    from scenes import notched_plate
    assert (LOOKAHEAD_L0, LOOKAHEAD_H) == (2.0, 3.0)
    solver = ngtmc.Solver(notched_plate(maxh=0.2, h_band=0.2, l0=0.05), compile=False)
    for h_crack, expected in ((0.0125, 0.1), (0.05, 0.15)):   # 2 l0 larger; 3 h_crack larger
        got = Adaptivity(h_crack=h_crack, buffer_length="auto").resolved(solver)
        assert got.buffer_length == pytest.approx(expected) and got.corridor == pytest.approx(0.2)
    assert Adaptivity(h_crack=0.0125, buffer_length=0.05).resolved(solver).buffer_length == 0.05
    slab = ngtmc.Solver(ngtmc.Scene(ngtmc.extrude(notched_plate(maxh=0.25, h_band=0.25).mesh, 0.1),
                                    {"plate": ngtmc.Material(210e3, 0.3, 2.7, 0.05)},
                                    supports=[ngtmc.Support("bottom", x=True, y=True, z=True)],
                                    load=ngtmc.DisplacementLoad("top", "y"), fracture_regions="plate"),
                        compile=False)
    got = Adaptivity(h_crack=0.0125, buffer_length="auto").resolved(slab)
    assert got.buffer_length == 0.0 and got.corridor == 0.0
    for bad in ("far", -0.1):
        with pytest.raises(ValueError, match="buffer_length"):
            Adaptivity(h_crack=0.025, buffer_length=bad)
    assert simulation_options({"h_crack": 0.01})["adapt"].buffer_length == "auto"
    assert simulation_options({"h_crack": 0.01, "amr_lookahead": 0})["adapt"].buffer_length == 0.0
    with pytest.raises(StudyError, match="amr_lookahead = 'far' must be 'auto'"):
        simulation_options({"h_crack": 0.01, "amr_lookahead": "far"})
