"""Loads as fields, several loads, vertex conditions, tractions, and their validation (issue 11)."""
import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from scenes import bar_mesh, tension_bar

MAT = {"bar": ngtmc.Material(1000.0, 0.3)}


def _rotation(x, y, lam):
    """(R(theta) - I) X with theta = lam * 90 degrees."""
    th = lam * np.pi / 2
    c, s = np.cos(th), np.sin(th)
    return ((c - 1) * x - s * y, s * x + (c - 1) * y)


@pytest.mark.parametrize("order", [1, 2])
def test_rigid_rotation_by_90_degrees_has_no_force_and_no_energy(order):
    mesh = bar_mesh()
    rot = ngtmc.Scene(mesh, MAT, supports=[], load=ngtmc.DisplacementField("left", _rotation), order=order)
    res = ngtmc.simulate(rot, 1.0, ngtmc.AdaptiveStepControl(du_max=0.1, du_min=1e-6))
    # scale: the force of a 1 % stretch of the same bar
    stretch = ngtmc.simulate(tension_bar(fracture=False, order=order), 0.01).history["force"].iloc[-1]
    h = res.history
    assert h["load"].iloc[-1] == pytest.approx(1.0)
    assert np.max(np.abs(h["force"])) < 1e-9 * stretch
    assert np.max(np.abs(h["elastic_energy"])) < 1e-12 * stretch * 0.01
    assert h["min_J"].min() == pytest.approx(1.0)
    # the far corner went round with the body: (1, 0.2) -> (-0.2, 1)
    assert np.allclose(res.solver.u(mesh(1.0, 0.2)), (-1.2, 0.8), atol=1e-9)


def test_rotated_stretch_has_the_energy_of_the_stretch():
    """Objectivity: a stretch then a rigid rotation by 30 degrees gives the stretch's energy."""
    mesh = bar_mesh()
    eps, th = 0.01, np.pi / 6

    def field(x, y, lam):
        c, s = np.cos(lam * th), np.sin(lam * th)
        sx = (1 + lam * eps) * x      # stretch along x, y held: every boundary is prescribed
        return (c * sx - s * y - x, s * sx + c * y - y)

    rot = ngtmc.Scene(mesh, MAT, supports=[], load=ngtmc.DisplacementField("left|right|top|bottom", field))
    e_rot = ngtmc.simulate(rot, 1.0).history["elastic_energy"].iloc[-1]
    plain = ngtmc.Scene(mesh, MAT, supports=[],
                        load=ngtmc.DisplacementField("left|right|top|bottom", lambda x, y, lam: (lam * eps * x, 0 * y)))
    e_plain = ngtmc.simulate(plain, 1.0).history["elastic_energy"].iloc[-1]
    assert e_plain > 0
    assert e_rot == pytest.approx(e_plain, rel=1e-9)


@pytest.mark.parametrize("order", [1, 2])
def test_uniform_field_gives_the_uniform_load(order):
    """A CoefficientFunction field (1, 0) on the x component is DisplacementLoad("right", "x")."""
    ref = ngtmc.simulate(tension_bar(fracture=False, order=order), 0.01).history
    sc = tension_bar(fracture=False, order=order)
    sc.load = ngtmc.DisplacementField("right", ngs.CF((1.0, 0.0)), components="x")
    h = ngtmc.simulate(sc, 0.01).history
    assert np.allclose(h["force"], ref["force"], rtol=1e-12, atol=0)
    sc.load = ngtmc.DisplacementField("right", lambda x, y, lam: (lam, 0.0), components="x")
    h = ngtmc.simulate(sc, 0.01).history
    assert np.allclose(h["force"], ref["force"], rtol=1e-7, atol=0)


def _two_loads(**kw):
    return ngtmc.Scene(bar_mesh(), MAT, supports=[ngtmc.Support("bottom", y=True)],
                       load=[ngtmc.DisplacementLoad("left", "-x"), ngtmc.DisplacementLoad("right", "x")], **kw)


def test_two_opposite_loads_give_equal_and_opposite_reactions():
    res = ngtmc.simulate(_two_loads(), 0.005)
    h, units = res.history, res.units
    assert units["force_left"] == units["force_right"] == units["force"] == "N/mm"  # 2D, thickness 1 mm
    assert list(h.columns)[:len(ngtmc.HISTORY_UNITS)] == list(ngtmc.HISTORY_UNITS)
    assert h["force_right"].iloc[-1] > 0
    # each resists its own motion (+), so along x they are equal and opposite
    assert h["force_left"].to_numpy() == pytest.approx(h["force_right"].to_numpy(), rel=1e-8, abs=1e-12)
    assert np.array_equal(h["force"], h["force_left"])          # default: the first load
    # stretching from both ends by lam is the one-sided stretch by 2 lam
    one = ngtmc.simulate(tension_bar(fracture=False), 0.01).history["force"].iloc[-1]
    assert h["force_right"].iloc[-1] == pytest.approx(one, rel=1e-7)
    named = ngtmc.simulate(_two_loads(force_from="right"), 0.005).history
    assert np.array_equal(named["force"], named["force_right"])


def test_point_load_reaction_is_the_residual_at_the_vertex():
    mesh = bar_mesh()
    tip = ngtmc.Point(near=(1.0, 0.2))
    sc = ngtmc.Scene(mesh, MAT, supports=[ngtmc.Support("left", x=True, y=True)],
                     load=ngtmc.DisplacementLoad(tip, "-y"), order=2)
    res = ngtmc.simulate(sc, 0.01)
    s = res.solver
    v = tip.vertex(mesh)
    assert np.allclose(mesh.ngmesh.Coordinates()[v], (1.0, 0.2))
    r = s.u.vec.CreateVector()
    s.a_u.Apply(s.u.vec, r)
    dof = s._vertex_dof(v, 1)
    assert res.history["force"].iloc[-1] == pytest.approx(-r[dof] * sc.thickness, rel=1e-12)
    assert res.history["force"].iloc[-1] > 0
    assert s.u(mesh(1.0, 0.2))[1] == pytest.approx(-0.01, abs=1e-12)


def test_named_point_support():
    """Lateral contraction pinned at one named corner instead of the whole bottom edge: uniform
    uniaxial stretch either way, so the same force."""
    from netgen.occ import OCCGeometry, Rectangle, X, Y
    face = Rectangle(1.0, 0.2).Face()
    face.faces.name = "bar"
    face.edges.Min(X).name = "left"
    face.edges.Max(X).name = "right"
    face.vertices.Min(X + Y).name = "origin"
    mesh = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.1))
    sc = ngtmc.Scene(mesh, MAT, supports=[ngtmc.Support("left", x=True), ngtmc.Support(ngtmc.Point("origin"), y=True)],
                     load=ngtmc.DisplacementLoad("right", "x"))
    f = ngtmc.simulate(sc, 0.01).history["force"].iloc[-1]
    ref = ngtmc.simulate(tension_bar(fracture=False), 0.01).history["force"].iloc[-1]
    assert f == pytest.approx(ref, rel=1e-7)


def test_force_control_reproduces_displacement_control():
    """A bar stretched by 20 %: the traction-driven curve (force, work-conjugate displacement)
    lies on the displacement-driven one."""
    disp = ngtmc.simulate(tension_bar(fracture=False), 0.2).history
    sc = tension_bar(fracture=False)
    F_end = float(disp["force"].iloc[-1])
    sc.load = ngtmc.Traction("right", (F_end / 0.2, 0.0))        # MPa per unit lambda, 0.2 mm high
    res = ngtmc.simulate(sc, ngtmc.Schedule([0.0, 1.0]), ngtmc.AdaptiveStepControl(du_max=0.1, du_min=1e-6))
    h = res.history
    assert res.units["displacement_right"] == "mm"
    assert h["force"].iloc[-1] == pytest.approx(F_end, rel=1e-12)
    assert h["displacement_right"].iloc[-1] == pytest.approx(0.2, rel=1e-6)
    # displacement control through the displacements reached under force control
    again = ngtmc.simulate(tension_bar(fracture=False), ngtmc.Schedule(list(h["displacement_right"])),
                           ngtmc.AdaptiveStepControl(du_max=1.0, du_min=1e-9)).history
    assert np.allclose(again["load"], h["displacement_right"], rtol=1e-12, atol=0)
    assert np.allclose(again["force"], h["force"], rtol=1e-7, atol=1e-9 * F_end)


def test_force_control_stops_clearly_at_the_peak():
    sc = tension_bar(maxh=0.2, Gc=1e-3, l0=1.0)
    sc.load = ngtmc.Traction("right", (1.0, 0.0))       # MPa per unit lambda; the peak is near 0.34
    with pytest.raises(ngtmc.StepFailure, match=r"force control cannot pass a peak.*stiffness of traction 'right' fell"):
        ngtmc.simulate(sc, 1.0, ngtmc.AdaptiveStepControl(du_max=0.1, du_min=1e-3), scheme="staggered",
                       max_staggered=12)


def test_adjoint_with_a_field_load_and_refusal_of_tractions():
    """The adjoint takes displacement fields (here a callable, so d u_D / d lambda is evaluated at
    each lambda_n): the reaction of an elastic bar is linear in E, so dF/dE = F / E."""
    from ngtmc import sensitivities as S
    sc = tension_bar(fracture=False)
    sc.load = ngtmc.DisplacementField("right", lambda x, y, lam: (lam + 0 * x, 0 * y), components="x")
    g, path = S.differentiate(sc, 0.01, S.ReactionAtStep(-1), wrt=("E",), newton=ngtmc.NewtonOptions(rtol=1e-12))
    assert g["E"] == pytest.approx(g["value"] / 1000.0, rel=1e-6)
    # a replay takes the runs' own step (ngtmc.stepping.schemes.alpha_u_passes): with nothing that may
    # break, the history stays as recorded (zero), not Psi_plus of the elastic bar
    r = S.replay(path)
    assert np.allclose(r.forces, path.forces, rtol=1e-10, atol=0)
    assert not np.any(path.states[-1]["H"]) and not np.any(r.states[-1]["H"])
    sc.load = ngtmc.Traction("right", (1.0, 0.0))
    with pytest.raises(ValueError, match=r"adjoint does not handle Traction loads.*\['right'\]"):
        S.record_path(sc, 0.1)


def _bar(**kw):
    args = dict(supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True)],
                load=ngtmc.DisplacementLoad("right", "x"))
    args.update(kw)
    return ngtmc.Scene(bar_mesh(maxh=0.2), MAT, **args)


def _nan_field(x, y, lam):
    return (np.where(y > 0.1, np.nan, lam), 0 * y)


#: Each invalid set-up and the message it gets, before any solve (the table of the README).
VALIDATION = [
    ("unknown boundary", dict(load=ngtmc.DisplacementField("rigth", ngs.CF((1, 0)))),
     r"DisplacementField: unknown boundary 'rigth'; the mesh has boundaries \['bottom', 'left', 'right', 'top'\]"),
    ("unknown point", dict(supports=[ngtmc.Support(ngtmc.Point("tip"), x=True, y=True)]),
     r"Point\('tip'\): unknown point name 'tip'; the mesh has named points \[\]"),
    ("point of the wrong dimension", dict(load=ngtmc.DisplacementLoad(ngtmc.Point(near=(1, 0.2, 0)), "x")),
     r"Point\(near=\(1.0, 0.2, 0.0\)\): the coordinate has 3 entries; the mesh is 2D"),
    ("CF field of the wrong dimension", dict(load=ngtmc.DisplacementField("right", ngs.CF((1, 0, 0)))),
     r"DisplacementField 'right' on 'right': the field has 3 components; the mesh is 2D"),
    ("callable of the wrong shape", dict(load=ngtmc.DisplacementField("right", lambda x, y, lam: (lam * x,))),
     r"DisplacementField 'right' on 'right': the callable returned \(1, \d+\); expected 2 components"),
    ("callable with the wrong arguments", dict(load=ngtmc.DisplacementField("right", lambda x, lam: (x, x))),
     r"DisplacementField 'right' on 'right': calling the field with 2 coordinate arrays and lam failed"),
    ("callable returning NaN", dict(load=ngtmc.DisplacementField("right", _nan_field)),
     r"DisplacementField 'right' on 'right': the field is not finite \(NaN or inf\) at \(1.0, 0.2\) mm, lam = 0"),
    ("traction of the wrong shape", dict(load=ngtmc.Traction("right", (1.0, 0.0, 0.0))),
     r"Traction 'right' on 'right': traction has shape \(3,\); expected \(2,\) for a 2D mesh"),
    ("two supports on one component", dict(supports=[ngtmc.Support("left", x=True), ngtmc.Support("left", x=True, y=True)]),
     r"two conditions on component x of 'left': Support on 'left' and Support on 'left'"),
    ("two loads on one component", dict(load=[ngtmc.DisplacementLoad("right", "x", name="a"),
                                              ngtmc.DisplacementField("right", ngs.CF((1, 0)), name="b")]),
     r"two conditions on component x of 'right': DisplacementLoad 'a' on 'right' and DisplacementField 'b' on 'right'"),
    ("load on a held component", dict(load=ngtmc.DisplacementLoad("left", "x")),
     r"DisplacementLoad 'left' on 'left' acts on component x that Support on 'left' already holds"),
    ("traction on a held component", dict(load=ngtmc.Traction("bottom", (0.0, 1.0))),
     r"Traction 'bottom' on 'bottom' acts on component y that Support on 'bottom' already holds"),
    ("two loads with one name", dict(load=[ngtmc.DisplacementLoad("right", "x"), ngtmc.DisplacementLoad("top", "y", name="right")]),
     r"loads \['right'\] share a name"),
    ("force_from naming no load", dict(force_from="top"),
     r"Scene.force_from = 'top' names no load; the loads are \['right'\]"),
]


@pytest.mark.parametrize("what, kw, message", VALIDATION, ids=[v[0] for v in VALIDATION])
def test_invalid_conditions_are_refused_before_any_solve(what, kw, message):
    sc = _bar(**kw)
    with pytest.raises(ValueError, match=message):
        ngtmc.Simulation(sc, 0.01)


def test_readme_loads_example_runs():
    import pathlib
    import re
    text = (pathlib.Path(__file__).resolve().parents[1] / "README.md").read_text()
    code = re.findall(r"```python\n(.*?)```", text, flags=re.S)[1]
    assert "DisplacementField" in code and len(code.strip().splitlines()) <= 25
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    h = namespace["history"]
    assert h["load"].iloc[-1] == pytest.approx(1.0)
    assert np.max(np.abs(h["force"])) < 1e-9 and np.max(np.abs(h["elastic_energy"])) < 1e-12


def test_several_loads_and_a_field_get_a_run_folder(tmp_path):
    """A user scene with two loads and a scene with a displacement field go through
    ``simulate(out_dir=)``: the folder's history keeps the per-load columns, and the recorded
    parameters describe every load without memory addresses (so a resume can compare them)."""
    import json
    import pandas as pd
    res = ngtmc.simulate(_two_loads(force_from="right"), 0.005, out_dir=tmp_path / "two")
    h = pd.read_csv(tmp_path / "two" / "history.csv")
    assert np.allclose(h["force_left"], res.history["force_left"], rtol=1e-12)
    assert np.array_equal(h["force"], h["force_right"])
    meta = json.loads((tmp_path / "two" / "metadata.json").read_text())
    text = json.dumps(meta)
    assert "DisplacementLoad 'left' on left: -x" in text and "DisplacementLoad 'right' on right: x" in text

    def shear(x, y, lam):
        return (lam * y, 0.0 * x)

    sc = ngtmc.Scene(bar_mesh(), MAT, supports=[ngtmc.Support("left", x=True, y=True)],
                     load=ngtmc.DisplacementField("right", shear, components="x"))
    ngtmc.simulate(sc, 0.005, out_dir=tmp_path / "field")
    text = (tmp_path / "field" / "metadata.json").read_text()
    assert "shear" in text and "0x" not in text
    assert (tmp_path / "field" / "report.html").stat().st_size > 0
