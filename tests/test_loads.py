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
