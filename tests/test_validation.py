"""Bad input gives clear errors naming the parameter and the allowed range; failures keep the history."""
import dataclasses
import warnings

import numpy as np
import pytest

import ngtmc
from scenes import bar_mesh, tension_bar, two_blocks


@pytest.mark.parametrize("kwargs, match", [
    ({"E": 0.0, "nu": 0.3}, r"E = 0.0 MPa .*> 0"),
    ({"E": -5.0, "nu": 0.3}, r"E = -5.0"),
    ({"E": 1.0, "nu": 0.5}, r"nu .*\(-1, 0.5\)"),
    ({"E": 1.0, "nu": -1.0}, r"nu .*\(-1, 0.5\)"),
    ({"E": 1.0, "nu": 0.3, "l0": 0.0}, r"l0 = 0.0 mm"),
    ({"E": 1.0, "nu": 0.3, "Gc": -1.0}, r"Gc = -1.0 N/mm"),
    ({"E": float("nan"), "nu": 0.3}, r"E = nan"),
])
def test_material_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ngtmc.Material(**kwargs)


def test_density_outside_unit_interval():
    sc = tension_bar(density={"bar": 1.2})
    with pytest.raises(ValueError, match=r"rho must lie in \[0, 1\]"):
        sc.check()
    mesh = bar_mesh()
    sc = tension_bar(density=-0.1 * np.ones(mesh.ne))
    with pytest.raises(ValueError, match="rho"):
        sc.check()


def test_density_array_of_wrong_length():
    with pytest.raises(ValueError, match="elements"):
        tension_bar(density=np.ones(3)).check()


def test_unknown_region_and_boundary_names_list_the_valid_ones():
    with pytest.raises(ValueError, match=r"unknown region 'beam'.*\['bar'\]"):
        dataclasses.replace(tension_bar(), fracture_regions="beam").check()
    sc = tension_bar()
    sc.load = ngtmc.DisplacementLoad("rigth", "x")
    with pytest.raises(ValueError, match=r"unknown boundary 'rigth'.*'right'"):
        sc.check()
    sc = tension_bar()
    sc.supports = [ngtmc.Support("lft", x=True)]
    with pytest.raises(ValueError, match="unknown boundary 'lft'"):
        sc.check()


def test_missing_material_and_support_without_component():
    sc = two_blocks()
    sc.materials = {"lower": ngtmc.Material(1.0, 0.3)}
    with pytest.raises(ValueError, match="have no material"):
        sc.check()
    sc = tension_bar()
    sc.supports = [ngtmc.Support("left")]
    with pytest.raises(ValueError, match="holds no component"):
        sc.check()


def test_regulariser_needs_order_two():
    sc = dataclasses.replace(two_blocks(), order=1)
    with pytest.raises(ValueError, match="order >= 2"):
        sc.check()
    with pytest.raises(ValueError, match="kbar_r"):
        ngtmc.Regulariser("void", length=1.0, kbar_r=0.0)


def test_scene_scalars():
    for field, value, match in [("gamma0", 0.0, "gamma0"), ("gamma0", 1.5, "gamma0"), ("thickness", 0.0, "thickness"),
                                ("residual_stiffness", -1e-6, "residual_stiffness"), ("gc_b", -1.0, "gc_b")]:
        with pytest.raises(ValueError, match=match):
            dataclasses.replace(tension_bar(), **{field: value}).check()
    with pytest.raises(ValueError, match="direction"):
        ngtmc.DisplacementLoad("right", "up")


def test_schedule_and_step_control():
    with pytest.raises(ValueError, match="start at 0"):
        ngtmc.Schedule([0.1, 1.0])
    with pytest.raises(ValueError, match="two equal consecutive"):
        ngtmc.Schedule([0, 1.0, 1.0])
    with pytest.raises(ValueError, match="at least two"):
        ngtmc.Schedule([0])
    with pytest.raises(ValueError, match="du_max"):
        ngtmc.AdaptiveStepControl(du_max=0.0)
    with pytest.raises(ValueError, match="du_min"):
        ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-2)
    with pytest.raises(ValueError, match="k_u"):
        ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=-1)
    with pytest.raises(ValueError, match="scheme"):
        ngtmc.Simulation(tension_bar(), 0.01, scheme="twice")


def test_unresolved_length_scale_warns():
    with pytest.warns(ngtmc.ResolutionWarning, match=r"l0/2"):
        tension_bar(l0=0.05, maxh=0.1).check()
    with warnings.catch_warnings():
        warnings.simplefilter("error", ngtmc.ResolutionWarning)
        tension_bar(l0=0.5, maxh=0.1).check()


def test_a_run_that_refines_the_crack_path_is_judged_by_its_target_size():
    """With adaptive refinement the initial mesh is coarse on purpose: the warning judges h_crack
    (the size the crack's path is refined to), not the initial mesh."""
    coarse = tension_bar(l0=0.05, maxh=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ngtmc.ResolutionWarning)
        coarse.check(refine_to=0.0125)
        ngtmc.Simulation(coarse, 0.01, ngtmc.AdaptiveStepControl(du_max=1e-3), adapt=ngtmc.Adaptivity(h_crack=0.0125))
    with pytest.warns(ngtmc.ResolutionWarning, match=r"h_crack = 0.04 mm, larger than l0/2 = 0.025 mm"):
        coarse.check(refine_to=0.04)


def test_failure_at_minimum_step_keeps_the_history():
    """Newton limited to 3 iterations and no halving possible: the step where the void is squeezed
    hard fails, and the exception carries every accepted step."""
    sim = ngtmc.Simulation(two_blocks(), 0.06, ngtmc.AdaptiveStepControl(du_max=0.005, du_min=0.005),
                           newton=ngtmc.NewtonOptions(max_iterations=3))
    with pytest.raises(ngtmc.StepFailure, match="minimum increment") as info:
        sim.run()
    h = info.value.history
    assert len(h) >= 5
    assert list(h["step"]) == list(range(len(h)))
    assert np.all(np.isfinite(h["force"]))
    assert info.value.state is not None


def test_a_load_and_a_support_on_one_component_of_a_shared_corner_are_refused():
    """Support("left", x, y) and a load on "top" in y meet at the corner (0, 0.2): the corner's y
    cannot be both held and moved (the load used to win silently); named with the vertex. A
    load's held tangential components and a support both hold 0 there, which agrees."""
    from scenes import bar_mesh
    m = bar_mesh()
    mat = {"bar": ngtmc.Material(1000.0, 0.3)}
    sc = ngtmc.Scene(m, mat, supports=[ngtmc.Support("left", x=True, y=True)], load=ngtmc.DisplacementLoad("top", "-y"))
    with pytest.raises(ValueError, match=r"vertex \d+ at \(0, 0.2\) mm, where boundaries meet: component y"):
        sc.check()
    ok = ngtmc.Scene(m, mat, supports=[ngtmc.Support("left", x=True)],
                     load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True))
    ok.check()     # x held by both at the corner: both hold 0


def test_options_of_the_api_are_type_checked_naming_the_parameter():
    from scenes import tension_bar
    sc = tension_bar(fracture=False)
    one = ngtmc.Scene(sc.mesh, sc.materials, supports=ngtmc.Support("left", x=True), load=sc.load)
    assert len(one.supports) == 1                 # one Support without a list is taken as the list
    with pytest.raises(TypeError, match="coupled must be a dict"):
        ngtmc.Simulation(sc, 0.01, coupled="yes")
    with pytest.raises(TypeError, match=r"newton: unknown option\(s\) \['tol'\]; NewtonOptions takes"):
        ngtmc.Simulation(sc, 0.01, newton={"tol": 1e-8})
    with pytest.raises(TypeError, match="newton must be an ngtmc.NewtonOptions"):
        ngtmc.Simulation(sc, 0.01, newton=1e-8)
    assert ngtmc.Simulation(sc, 0.01, newton={"rtol": 1e-9}).solver.newton.rtol == 1e-9


def test_the_peak_of_a_negative_loading_is_its_most_negative_force():
    """A compression (final load -0.01 mm) reported its peak as the 0 N of its start before."""
    from scenes import tension_bar
    res = ngtmc.simulate(tension_bar(fracture=False), -0.01)
    assert res.peak_load == pytest.approx(-0.01)
    assert res.peak_force == pytest.approx(res.history["force"].min()) and res.peak_force < -1.0


def test_an_element_of_zero_size_is_refused_naming_it():
    import netgen.meshing as nm
    import ngsolve as ngs
    m = nm.Mesh(dim=2)
    p = [m.Add(nm.MeshPoint(nm.Pnt(x, y, 0))) for x, y in [(0, 0), (1, 0), (1, 1), (0, 1), (2, 0)]]
    r = m.AddRegion("plate", dim=2)
    for tri in ((0, 1, 2), (0, 2, 3), (0, 1, 4)):          # the third is flat: zero area
        m.Add(nm.Element2D(r, [p[i] for i in tri]))
    for name, edge in (("left", (3, 0)), ("right", (1, 2))):
        m.Add(nm.Element1D([p[i] for i in edge], index=m.AddRegion(name, dim=1)))
    sc = ngtmc.Scene(ngs.Mesh(m), {"plate": ngtmc.Material(1000.0, 0.3)},
                     supports=[ngtmc.Support("left", x=True, y=True)], load=ngtmc.DisplacementLoad("right", "x"))
    with pytest.raises(ValueError, match=r"1 element\(s\) of zero or negative size \(mm\^2\): 2 \(plate, 0\)"):
        sc.check()


def test_a_curved_element_inverted_at_its_integration_points_is_refused_naming_it():
    """A square plate with a hole, one element's free vertex moved between its edge on the hole and
    that edge's arc: the straight element is valid, mesh.Curve(2) bends the edge past the vertex,
    det J < 0 at integration points. The scene is refused, naming the element and its region; made
    straight again (mesh.Curve(1)) it is accepted."""
    import ngsolve as ngs
    from netgen.meshing import MeshPoint, Pnt
    from netgen.occ import Circle, OCCGeometry, Rectangle, X
    shape = Rectangle(2.0, 2.0).Face() - Circle((1.0, 1.0), 0.5).Face()
    shape.faces.name = "plate"
    shape.edges.Min(X).name, shape.edges.Max(X).name = "left", "right"
    ngmesh = OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.4)
    mesh = ngs.Mesh(ngmesh)
    pts = np.array([p.p for p in ngmesh.Points()])
    on_hole = np.abs(np.hypot(pts[:, 0] - 1.0, pts[:, 1] - 1.0) - 0.5) < 1e-9
    for el in mesh.Elements(ngs.VOL):
        v = [x.nr for x in el.vertices]
        if on_hole[v].sum() == 2:
            (a, b), c = [i for i in v if on_hole[i]], [i for i in v if not on_hole[i]][0]
            mid = (pts[a] + pts[b]) / 2
            out = (mid - np.array([1.0, 1.0, 0.0])) / np.linalg.norm(mid - np.array([1.0, 1.0, 0.0]))
            ngmesh.Points()[c + 1] = MeshPoint(Pnt(*(mid + 0.002 * out)))   # 2 um off the chord
            moved = el.nr
            break
    mesh = ngs.Mesh(ngmesh)
    mesh.Curve(2)

    def scene():
        return ngtmc.Scene(mesh, {"plate": ngtmc.Material(1000.0, 0.3)}, supports=[ngtmc.Support("left", x=True, y=True)],
                           load=ngtmc.DisplacementLoad("right", "x"))
    with pytest.raises(ValueError, match=rf"curved \(mesh.Curve\(2\)\) and 1 element\(s\) are inverted at integration "
                                         rf"points \(det J <= 0\): {moved} \(plate\)"):
        scene().check()
    mesh.Curve(1)
    scene().check()
