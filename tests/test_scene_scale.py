"""The units-and-scale check (issue 58): numbers given in other units than mm, N, MPa are named
by a ScaleWarning, plausible ones pass silently, and a scene can silence it."""
import dataclasses
import warnings

import ngsolve as ngs
from netgen.occ import OCCGeometry, Rectangle, X
import pytest

import ngtmc
from scenes import tension_bar


def _scale_warnings(scene) -> list[str]:
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        scene.check()
    return [str(r.message) for r in rec if issubclass(r.category, ngtmc.ScaleWarning)]


def test_plausible_numbers_pass_silently():
    # the paper's three-point bending material (E 20.8 GPa, Gc 0.54 N/mm, l0 0.04 mm) on a 1 mm bar
    assert _scale_warnings(tension_bar(E=20.8e3, Gc=0.54, l0=0.04)) == []


@pytest.mark.parametrize("kw, words", [
    ({"E": 2.08e10, "l0": 0.1}, ["E = 2.08e+10 MPa", "E in Pa"]),
    ({"E": 1e-5, "Gc": 1e-9, "l0": 0.1}, ["E = 1e-05 MPa"]),
    ({"Gc": 5.4e3, "l0": 0.1}, ["Gc = 5400 N/mm", "kN/mm"]),
    ({"l0": 100.0}, ["l0 = 100 mm", "cannot localise"]),
    ({"E": 1.0, "Gc": 5.0, "l0": 0.1}, ["strength of AT-2", "strain of"]),
])
def test_implausible_numbers_are_named(kw, words):
    msgs = _scale_warnings(tension_bar(**kw))
    assert msgs, kw
    text = " ".join(msgs)
    for w in words:
        assert w in text, (w, text)
    assert "Scene(scale_check=False)" in text
    assert _scale_warnings(dataclasses.replace(tension_bar(**kw), scale_check=False)) == []


def test_a_body_drawn_in_metres_and_a_point_far_away_are_named():
    face = Rectangle(0.001, 0.0002).Face()          # a 1 mm x 0.2 mm bar drawn in metres
    face.faces.name = "bar"
    face.edges.Min(X).name = "left"
    face.edges.Max(X).name = "right"
    mesh = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.0001))
    sc = ngtmc.Scene(mesh, {"bar": ngtmc.Material(1000.0, 0.3)}, supports=[ngtmc.Support("left", x=True, y=True)],
                     load=ngtmc.DisplacementLoad("right", "x"))
    assert any("drawn in metres" in m for m in _scale_warnings(sc))
    far = tension_bar(l0=0.1)
    far = dataclasses.replace(far, supports=list(far.supports) + [ngtmc.Support(ngtmc.Point(near=(1e6, 1e6)), y=True)])
    msgs = _scale_warnings(far)
    assert any("Point(near=(1000000.0, 1000000.0))" in m and "nearest vertex" in m for m in msgs), msgs


def test_scale_check_must_be_a_bool():
    with pytest.raises(TypeError, match="scale_check"):
        dataclasses.replace(tension_bar(l0=0.1), scale_check="no").check()


def test_a_load_larger_than_the_body_is_named():
    """A final displacement of 5 mm on a bar of 1 mm (a load in micrometres read as mm, or a body
    drawn in metres): a ScaleWarning naming the load; 1 mm on it passes."""
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        ngtmc.Simulation(tension_bar(l0=0.1), 5.0)
        ngtmc.Simulation(tension_bar(l0=0.1), 1.0)
    msgs = [str(r.message) for r in rec if issubclass(r.category, ngtmc.ScaleWarning)]
    assert len(msgs) == 1 and "largest load, 5 mm, is more than the body's size" in msgs[0]
