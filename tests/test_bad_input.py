"""Bad input: one row per case, each a clear error before any solve that names the parameter and
the allowed values (and, for a run, leaves no run folder behind)."""
from __future__ import annotations

import ngsolve as ngs
import pytest

import ngtmc
from ngtmc.runner import run_study
from ngtmc.study import StudyError

from test_runner import _tiny_scene, tiny_study  # noqa: E402

P = {"h": 0.1, "E": 1000.0, "Gc": 0.05, "l0": 0.1}
MAT = ngtmc.Material(E=1000.0, nu=0.3)


def _scene(**kw):
    """The tiny notched bar (region "bar"; boundaries "bottom", "top") with fields replaced."""
    import dataclasses
    return dataclasses.replace(_tiny_scene(P), **kw)


def _cube_mesh():
    from netgen.occ import Box, OCCGeometry, Pnt, Z
    box = Box(Pnt(0, 0, 0), Pnt(1, 1, 1))
    box.faces.Min(Z).name = "bottom"
    box.faces.Max(Z).name = "top"
    return ngs.Mesh(OCCGeometry(box).GenerateMesh(maxh=1.0))


def _scene_3d(**kw):
    return ngtmc.Scene(mesh=_cube_mesh(), materials={".*": MAT}, supports=[ngtmc.Support("bottom", x=True, y=True, z=True)],
                       load=ngtmc.DisplacementLoad("top", direction="z"), **kw)


def _empty_mesh_scene():
    import netgen.meshing
    return ngtmc.Scene(mesh=ngs.Mesh(netgen.meshing.Mesh(dim=2)), materials={".*": MAT},
                       supports=[ngtmc.Support("bottom", y=True)], load=ngtmc.DisplacementLoad("top"))


def _run(tmp_path, **kw):
    run_study(tiny_study(), output=tmp_path / "run", report=False, progress=False, vtk=False, **kw)


BAD = [  # id, what to do, exception, message (regular expression)
    ("material number as string", lambda t: ngtmc.Material(E="1000", nu=0.3),
     TypeError, r"Material parameter E must be a number \(MPa\), got str '1000' \(a string"),
    ("scene number as string", lambda t: _scene(gamma0="1e-4").check(),
     TypeError, r"Scene.gamma0 must be a number \(dimensionless\), got str '1e-4'"),
    ("control number as string", lambda t: ngtmc.AdaptiveStepControl(du_max="1e-3"),
     TypeError, r"AdaptiveStepControl du_max must be a number \(mm\), got str"),
    ("overlapping material patterns", lambda t: _scene(materials={".*": MAT, "bar": MAT}).check(),
     ValueError, r"Scene.materials: region 'bar' is matched by several patterns \['\.\*', 'bar'\]\. Region names "
                 r"are regular expressions"),
    ("overlapping density patterns", lambda t: _scene(density={"b.*": 1.0, "bar": 0.0}).check(),
     ValueError, r"Scene.density: region 'bar' is matched by several patterns .*regular expressions"),
    ("region pattern not a regex", lambda t: _scene(materials={"bar(": MAT}).check(),
     ValueError, r"Scene.materials: 'bar\(' is not a valid regular expression"),
    ("3D scene with a thickness", lambda t: _scene_3d(thickness=2.0).check(),
     ValueError, r"Scene.thickness = 2.0 mm is given for a 3D mesh: thickness applies to 2D"),
    ("threads -1", lambda t: _run(t, threads=-1),
     StudyError, r"threads = -1 is not allowed: give an integer >= 1"),
    ("threads 0", lambda t: _run(t, threads=0),
     StudyError, r"threads = 0 is not allowed: give an integer >= 1"),
    ("--set value of the wrong type", lambda t: _run(t, threads=1, overrides={"k_u": "fast"}),
     StudyError, r"override k_u = 'fast': k_u expects a number \(1/N\)"),
    ("--set value out of range", lambda t: _run(t, threads=1, overrides={"E": "-5"}),
     StudyError, r"case 'main': parameter E = -5.0 MPa is outside the allowed range"),
    ("control given as a dict", lambda t: ngtmc.Simulation(_scene(), 0.01, {"du_max": 1e-3}),
     TypeError, r"control must be an ngtmc.AdaptiveStepControl .*got dict; write AdaptiveStepControl\(\*\*"),
    ("empty mesh", lambda t: _empty_mesh_scene().check(),
     ValueError, r"Scene.mesh is empty \(0 elements\)"),
]


@pytest.mark.parametrize("make, error, message", [row[1:] for row in BAD], ids=[row[0] for row in BAD])
def test_bad_input_is_refused_clearly(tmp_path, make, error, message):
    with pytest.raises(error, match=message):
        make(tmp_path)
    assert not (tmp_path / "run").exists()     # a refused run leaves no folder behind


def test_cli_refuses_bad_threads(tmp_path, capsys):
    from ngtmc.cli import main
    for n in ("-1", "0"):
        assert main(["run", "three-point-bending", "--threads", n, "-o", str(tmp_path / "x")]) == 2
        assert f"threads = {n} is not allowed" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_region_names_are_regular_expressions_in_the_docs():
    import pathlib
    readme = (pathlib.Path(__file__).parents[1] / "README.md").read_text()
    assert "regular expression" in readme
    assert "Region names are regular expressions" in ngtmc.Scene.__doc__
