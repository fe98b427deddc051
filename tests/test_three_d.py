"""The same model in 3D: a cube in uniaxial compression through a void layer."""
import numpy as np
import ngsolve as ngs
import pytest
from netgen.occ import Box, Glue, OCCGeometry, Pnt, Z

import ngtmc


def test_cube_under_uniaxial_stress_matches_small_strain_modulus():
    box = Box(Pnt(0, 0, 0), Pnt(1, 1, 1))
    box.faces.Min(Z).name = "bottom"
    box.faces.Max(Z).name = "top"
    from netgen.occ import X, Y
    box.faces.Min(X).name = "xmin"
    box.faces.Min(Y).name = "ymin"
    box.solids.name = "cube"
    mesh = ngs.Mesh(OCCGeometry(box).GenerateMesh(maxh=0.5))
    E, nu = 1000.0, 0.3
    scene = ngtmc.Scene(mesh, {"cube": ngtmc.Material(E, nu)},
                        supports=[ngtmc.Support("bottom", z=True), ngtmc.Support("xmin", x=True), ngtmc.Support("ymin", y=True)],
                        load=ngtmc.DisplacementLoad("top", "-z"))
    res = ngtmc.simulate(scene, 1e-4, ngtmc.AdaptiveStepControl(du_max=1e-4))
    # homogeneous uniaxial stress: force = E * strain * area (small strain)
    assert res.history["force"].iloc[-1] == pytest.approx(E * 1e-4, rel=1e-3)


def test_void_layer_in_3d_stays_soft_then_stiffens():
    lower = Box(Pnt(0, 0, 0), Pnt(1, 1, 0.4))
    lower.solids.name = "lower"
    void = Box(Pnt(0, 0, 0.4), Pnt(1, 1, 0.5))
    void.solids.name = "void"
    upper = Box(Pnt(0, 0, 0.5), Pnt(1, 1, 0.9))
    upper.solids.name = "upper"
    shape = Glue([lower, void, upper])
    shape.faces.Min(Z).name = "bottom"
    shape.faces.Max(Z).name = "top"
    mesh = ngs.Mesh(OCCGeometry(shape).GenerateMesh(maxh=0.35))
    scene = ngtmc.Scene(mesh, {".*": ngtmc.Material(1000.0, 0.3)}, density={"void": 0.0}, gamma0=1e-5,
                        supports=[ngtmc.Support("bottom", x=True, y=True, z=True)],
                        load=ngtmc.DisplacementLoad("top", "-z", hold_tangential=True))
    h = ngtmc.simulate(scene, 0.09, ngtmc.AdaptiveStepControl(du_max=0.015, du_min=1e-6)).history
    assert np.all(np.isfinite(h["force"]))
    assert h["min_J"].iloc[-1] < 0.3
    assert h["force"].iloc[-1] > 20 * np.interp(0.045, h["load"], h["force"])
