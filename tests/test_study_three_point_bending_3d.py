"""The 3D study (studies/three_point_bending_3d.py): its meshes, its parameters, and the adjoint in 3D.

The slab against its 2D twin at quick resolution is recorded in the study's records (minutes of
3D runs); the exact agreement of a plane-strain slab with 2D is tests/test_extrude.py."""
import dataclasses
import math

import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from ngtmc import sensitivities as S
from ngtmc.study import load_study
from ngtmc.study import StudyError
from ngtmc.study import study_parameters

study = load_study("three_point_bending_3d")


def test_the_study_is_registered_and_refuses_bad_parts():
    assert "three_point_bending_3d" in ngtmc.list_studies()
    _, p = study_parameters(study, "quick", {"parts": "everything"})
    with pytest.raises(StudyError, match="parts"):
        study.cases(p)
    _, p = study_parameters(study, "quick", {"sphere_symmetry": "eighth"})
    with pytest.raises(StudyError, match="sphere_symmetry"):
        study.cases(p)
    _, p = study_parameters(study, "quick", {"sphere_radius": 0.6})
    with pytest.raises(StudyError, match="sphere_radius"):
        study.cases(p)
    for parts in ("all", "slab"):   # a slab thicker than h_crack: refused before any case runs
        _, p = study_parameters(study, "quick", {"h_crack": 0.01, "parts": parts})   # quick: 0.03 mm thick
        with pytest.raises(StudyError, match="slab_thickness = 0.03 mm.*h_crack"):
            study.cases(p)
    _, p = study_parameters(study, "quick", {"h_crack": 0.02, "parts": "slab", "slab_thickness": 0.02,
                                             "amr_h_void": 0.01})
    with pytest.raises(StudyError, match="slab_thickness = 0.02 mm.*amr_h_void"):
        study.cases(p)
    _, p = study_parameters(study, "quick", {"h_crack": 0.02, "parts": "slab", "slab_thickness": 0.02})
    assert [c.options["adapt"].h_crack for c in study.cases(p)] == [0.02, 0.02]   # the 2D twin and the slab
    # the default corridor ("auto") is none in 3D, so the slab's 2D twin has none either; a width
    # given reaches both
    assert [c.options["adapt"].corridor for c in study.cases(p)] == [0.0, "auto"]
    _, p = study_parameters(study, "quick", {"h_crack": 0.02, "parts": "slab", "slab_thickness": 0.02, "amr_corridor": 0.1})
    assert [c.options["adapt"].corridor for c in study.cases(p)] == [0.1, 0.1]
    _, p = study_parameters(study, "quick", {"h_crack": 0.01, "parts": "hemisphere", "amr_remesh_maxh": 0.5})
    with pytest.raises(StudyError, match="remeshing.*2D only"):
        study.cases(p)
    _, p = study_parameters(study, "quick", {"h_crack": 0.01, "parts": "hemisphere"})
    (case,) = study.cases(p)
    assert case.options["adapt"].h_crack == 0.01 and case.options["adapt"].remesh_maxh is None


def test_cases_follow_parts():
    for parts, names in (("all", ["plane_strain_2d", "slab", "hemisphere"]), ("slab", ["plane_strain_2d", "slab"]),
                         ("hemisphere", ["hemisphere"])):
        _, p = study_parameters(study, "quick", {"parts": parts})
        assert [c.name for c in study.cases(p)] == names


def test_slab_is_the_2d_mesh_extruded():
    _, p = study_parameters(study, "quick", {"parts": "slab"})
    sc2, sc3 = study.build_plane_strain_scene(p), study.build_slab_scene(p)
    t = float(p["slab_thickness"])
    assert sc3.mesh.dim == 3 and sc3.mesh.ne == sc2.mesh.ne and sc2.thickness == t
    assert ngs.Integrate(1, sc3.mesh) == pytest.approx(t * ngs.Integrate(1, sc2.mesh), rel=1e-12)
    assert {"front", "back", "load", "support_left", "support_right"} <= set(sc3.mesh.GetBoundaries())


@pytest.mark.parametrize("symmetry", ["half", "quarter"])
def test_hemisphere_mesh_has_its_regions_volumes_and_faces(symmetry):
    """The half model (z >= 0) and the quarter model (also x <= L/2): volumes of the regions and
    areas of the named faces by hand; the quarter is the half cut at the mid-span plane."""
    _, p = study_parameters(study, "quick", {"parts": "hemisphere", "sphere_h_band": 0.08, "sphere_h_void": 0.1,
                                             "sphere_h_beam": 0.4, "sphere_symmetry": symmetry})
    sc = study.build_hemisphere_scene(p)
    m = sc.mesh
    f = 0.5 if symmetry == "quarter" else 1.0      # the part of the half model that is modelled
    vol = {r: ngs.Integrate(1, m, definedon=m.Materials(r)) for r in set(m.GetMaterials())}
    L, H, W = 4.0, 1.0, 0.5
    R, gap, vw = 0.25, 0.025, 0.5
    beam = f * (L * H * W - 0.04 * 0.2 * W)
    solid = sum(vol[r] for r in ("beam", "band", "support_zone", "load_zone"))
    assert solid == pytest.approx(beam, rel=1e-9)
    quarter_ball = math.pi * R**3 / 3           # the hemisphere's half (z >= 0)
    assert vol["indenter"] == pytest.approx(f * quarter_ball, rel=2e-3)   # curved to order 2
    # (1e-6, not 1e-9: the curved cylinder face between 'void' and 'void_far' is interior and
    # netgen's order-2 curving leaves 5e-7 of the block's volume in the half model, measured)
    assert vol["void"] + vol["void_far"] + vol["indenter"] == pytest.approx(f * 2 * vw * (gap + R) * W, rel=1e-6)
    # the regularised void: the cylinder of radius sphere_regularised_radius (0.3 mm) around the axis
    rr = float(p["sphere_regularised_radius"])
    assert rr == 0.3
    assert vol["void"] + vol["indenter"] == pytest.approx(f * math.pi * rr**2 / 2 * (gap + R), rel=2e-3)
    faces = set(m.GetBoundaries())
    area = {b: ngs.Integrate(1, m, definedon=m.Boundaries(b)) for b in faces if b}
    assert area["load"] == pytest.approx(f * math.pi * R**2 / 2, rel=2e-3)
    assert area["support_left"] == pytest.approx(0.1 * W, rel=1e-9)
    assert area["sym"] == pytest.approx(f * (L * H - 0.04 * 0.2 + 2 * vw * (gap + R)), rel=1e-9)   # z = 0
    if symmetry == "quarter":
        assert "support_right" not in faces
        assert area["sym_x"] == pytest.approx((H - 0.2) * W + (gap + R) * W, rel=1e-9)   # ligament and void+ball
        assert {s.boundary for s in sc.supports} == {"support_left", "sym", "sym_x"}
    else:
        assert area["support_right"] == pytest.approx(0.1 * W, rel=1e-9)
        assert "sym_x" not in faces


def test_only_the_squeezed_void_carries_order_two_and_the_regulariser():
    """Model only what a scene needs, per element: the void beyond sphere_regularised_radius of the
    hemisphere's axis ('void_far', J >= 0.65 there in the fully regularised quick run, docs/three-d.md)
    has order-1 displacements and no regulariser. Order 2 in 3D adds one dof per edge and
    component, so the space has 3 (vertices + edges of 'void' elements) dofs exactly; with the
    radius over the whole block there is no 'void_far' and every void edge carries order 2."""
    def space(radius):
        _, p = study_parameters(study, "quick", {"parts": "hemisphere", "sphere_h_band": 0.08, "sphere_h_void": 0.1,
                                                 "sphere_h_contact": 0.05, "sphere_h_beam": 0.4,
                                                 "sphere_regularised_radius": radius})
        s = ngtmc.Solver(study.build_hemisphere_scene(p))
        m = s.mesh
        edges = {e.nr for el in m.Elements(ngs.VOL) if el.mat == "void" for e in el.edges}
        assert s.fes_u.ndof == 3 * (m.nv + len(edges))
        assert [r for name, _, r in s.energy_terms(s.u) if name == "regularisation"] == ["void"]
        return s, len(edges)

    s, n_edges = space(0.3)
    assert "void_far" in s.mesh.GetMaterials()
    far = [el for el in s.mesh.Elements(ngs.VOL) if el.mat == "void_far"]
    centres = np.array([np.mean([s.mesh[v].point for v in el.vertices], axis=0) for el in far])
    assert np.hypot(centres[:, 0] - 2.0, centres[:, 2]).min() > 0.3 - 0.1   # within an element of the radius
    assert np.all(s.rho.vec.FV().NumPy()[[el.nr for el in far]] == 0.0)     # still void (rho = 0)
    whole, n_all = space(10.0)
    assert "void_far" not in whole.mesh.GetMaterials() and n_all > 1.5 * n_edges
    _, p = study_parameters(study, "quick", {"parts": "hemisphere", "sphere_regularised_radius": 0.2})
    with pytest.raises(StudyError, match="sphere_regularised_radius"):
        study.cases(p)   # 0.2 < sqrt(2) sphere_contact_box: the contact patch's block would be cut


def test_adjoint_in_3d_against_finite_differences():
    """#13: the adjoint on a small 3D scene with contact and a growing crack. The design study's
    coarse scene (notched beam, third-medium pad under an indenter; tests/test_sensitivities.py)
    extruded into two layers of prisms, u_z held on the front face only, so the fields vary
    along z. Eight steps to 0.2 mm: the pad closes, then a crack grows (max alpha above 0.5).
    Measured: relative errors about 1e-8 (eps = 1e-5)."""
    from ngtmc.studies import design_for_contact as D
    p = D._params("quick", h_band=0.2, h_pad=0.1, h=0.5, du=0.025, l0=0.3, Gc=0.1)
    sc2 = D.build_scene(p)
    sc2.mesh.Curve(1)
    sc = dataclasses.replace(sc2, mesh=ngtmc.extrude(sc2.mesh, 0.2, layers=2), thickness=None,
                             supports=list(sc2.supports) + [ngtmc.Support("front", z=True)])
    path = S.record_path(sc, D.schedule(p), D.control(p), newton=ngtmc.NewtonOptions(rtol=1e-12))
    h = path.history
    assert h["max_alpha"].iloc[-1] > 0.5 and h["force"].iloc[-1] < h["force"].max()    # the crack grew
    assert h["force"].iloc[1] < 0.05 * h["force"].max()                                 # contact closed later
    assert np.abs(path.solver.u.components[2].vec.FV().NumPy()).max() > 0
    rng = np.random.default_rng(1)
    pad = S.design_mask(path, "pad")
    d = rng.standard_normal(path.rho.size)
    d[pad] = 5e-3 * rng.uniform(-1.0, 1.0, int(pad.sum()))
    direction = {"rho": d, "E": 100.0, "Gc": 0.01}
    objs = [S.ExternalWork(), S.ReactionAtStep(-1), S.FinalFractureEnergy()]
    adj = np.array([S.directional_derivative(S.gradient(path, o, wrt=("rho", "E", "Gc")), direction) for o in objs])
    fd = S.directional_fd(path, objs, direction, 1e-5)
    rel = np.abs(fd - adj) / np.abs(adj)
    print("\n3D adjoint: relative FD errors", [f"{r:.1e}" for r in rel])
    assert np.all(rel <= 1e-4)


def test_slab_with_the_indenter_follows_its_2d_twin_into_contact():
    """The study's slab and its 2D twin on a coarse mesh (h_band = 0.06 mm), to 0.07 mm: the void
    is squeezed from 0.05 mm on and the force rises 10x. The two differ by the regulariser's 1/d
    (3D stiffer) and the void elements' dofs along z (3D softer); the study's docstring gives
    the measured split. Stated tolerance: 0.5 % of the final force at every step (a relative
    measure is ill-conditioned where the force is still small: -0.51 % where it is a tenth of its
    final value). Measured: the slab is softer by 0.03-0.15 % from a quarter of the final force on,
    growing as the void is squeezed; at most 0.15 % of the final force. (At the quick run's peak,
    after the crack: -0.02 %, the study's record quick_slab.)"""
    _, p = study_parameters(study, "quick", {"parts": "slab", "h_band": 0.06, "h_void": 0.08, "h_indenter": 0.2,
                                             "h_beam": 0.5, "slab_thickness": 0.06, "stop_load": 0.07,
                                             "scheme": "single-pass"})
    h = {}
    for case in study.cases(p):
        r = ngtmc.simulate(case.build_scene(), case.schedule,
                           case.control, **case.options)
        h[case.name] = r.history
    h2, h3 = h["plane_strain_2d"], h["slab"]
    f2 = h2["force"].to_numpy()
    f3 = np.interp(h2["load"], h3["load"], h3["force"])   # Eq. 20 gives both about, not exactly, the same steps
    assert f2[-1] > 10 * np.interp(0.05, h2["load"], f2)      # contact carried the load
    after = f2 > 0.1 * f2[-1]
    print("\nslab / 2D - 1 after contact:", np.round(f3[after] / f2[after] - 1, 5), "steps", len(h2), len(h3))
    print("max |slab - 2D| / final force:", np.abs(f3 - f2).max() / f2[-1])
    assert np.abs(f3 - f2).max() < 5e-3 * f2[-1]
