"""VTK output (ngtmc.runner.vtk) read back as a ParaView user would: with meshio, and with VTK's own reader
where the vtk package is installed. Tiny homogeneous scenes whose fields have hand values."""
from __future__ import annotations

import math
import types
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest
from scipy.optimize import brentq

import ngtmc
from ngtmc.discrete import Solver
from ngtmc.study import Case
from ngtmc.runner.vtk import DISPLACEMENT, FIELDS, VtkWriter
from scenes import bar_mesh, tension_bar

E, NU = 1000.0, 0.3
K0, G0 = E / (3 * (1 - 2 * NU)), E / (2 * (1 + NU))
FRACTURE_FIELDS = {name for name, _, _, _, frac in FIELDS if frac}


def _solve(scene, load, steps=1):
    """Staggered steps (alpha from H_{n-1}, u, H_n) up to ``load`` mm; returns the solver."""
    s = Solver(scene)
    for k in range(1, steps + 1):
        s.solve_phase_field()
        assert s.solve_displacement(load * k / steps).converged
        s.update_history()
    return s


def _uniaxial_strain_scene():
    """Bar [0, 1] x [0, 0.2] stretched in x with y held on top and bottom: F = diag(1 + e, 1), J = 1 + e."""
    return ngtmc.Scene(bar_mesh(maxh=0.1), {"bar": ngtmc.Material(E, NU)},
                       supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True),
                                 ngtmc.Support("top", y=True)],
                       load=ngtmc.DisplacementLoad("right", "x"))


def _cauchy(l1, l2):
    """Hand Cauchy stress (MPa) of Psi = K/2 ln(J)^2 + G/2 (J^(-2/3) tr B - 3) at F = diag(l1, l2, 1):
    sigma = K ln(J)/J I + G J^(-5/3) (B - tr(B)/3 I), diagonal."""
    J = l1 * l2
    B = np.array([l1 ** 2, l2 ** 2, 1.0])
    return K0 * math.log(J) / J + G0 * J ** (-5 / 3) * (B - B.sum() / 3)


def _von_mises(sig):
    s1, s2, s3 = sig
    return math.sqrt(0.5 * ((s1 - s2) ** 2 + (s2 - s3) ** 2 + (s3 - s1) ** 2))


def _signed_size(m):
    """Signed area (triangles) or volume (tetrahedra) of meshio mesh m's cells, VTK's orientation."""
    c = m.cells[0].data
    p = [m.points[c[:, i]] for i in range(c.shape[1])]
    n = np.cross(p[1] - p[0], p[2] - p[0])
    return n[:, 2] / 2 if c.shape[1] == 3 else np.einsum("ij,ij->i", n, p[3] - p[0]) / 6


def _read(path):
    m = meshio.read(path)
    cell = {k: np.concatenate([np.ravel(b) for b in v]) for k, v in m.cell_data.items()}
    return m, cell


def test_uniaxial_strain_displacement_and_J(tmp_path):
    e = 0.05  # right edge moved by 0.05 mm on a 1 mm bar
    s = _solve(_uniaxial_strain_scene(), e)
    path = VtkWriter(s).write(tmp_path / "a.vtu")
    m, cell = _read(path)
    u = m.point_data[DISPLACEMENT]
    assert u.shape == (s.mesh.nv, 3)
    assert np.all(m.points[:, 2] == 0.0) and np.all(u[:, 2] == 0.0)
    for x, uu in zip(m.points, u):  # the solver's displacement evaluated at each vertex
        np.testing.assert_allclose(uu[:2], s.u(s.mesh(x[0], x[1])), rtol=0, atol=1e-12)
    np.testing.assert_allclose(u[:, 0], e * m.points[:, 0], atol=1e-10)
    np.testing.assert_allclose(cell["J [-]"], 1 + e, rtol=1e-10)
    # uniaxial strain: B = diag((1 + e)^2, 1, 1), von Mises = G J^(-5/3) |(1 + e)^2 - 1|
    np.testing.assert_allclose(cell["von Mises [MPa]"], G0 * (1 + e) ** (-5 / 3) * ((1 + e) ** 2 - 1), rtol=1e-9)
    np.testing.assert_allclose(cell["density [-]"], 1.0)
    assert [b.type for b in m.cells] == ["triangle"] and np.all(_signed_size(m) > 0)  # counterclockwise
    # no fracture in this scene: no phase-field fields
    assert set(m.point_data) | set(cell) == {name for name, *_ in FIELDS} - FRACTURE_FIELDS
    # the displacement is the active vector of the point data (Warp By Vector picks it)
    pd = ET.parse(path).getroot().find("UnstructuredGrid/Piece/PointData")
    assert pd.get("Vectors") == DISPLACEMENT


def test_uniaxial_stress_von_mises(tmp_path):
    """Plane strain, free lateral contraction: sigma_22 = 0, sigma_33 != 0 (F33 = 1)."""
    e = 0.05
    s = _solve(tension_bar(E=E, nu=NU, fracture=False), e)
    m, cell = _read(VtkWriter(s).write(tmp_path / "b.vtu"))
    l1 = 1 + e
    l2 = brentq(lambda l2: _cauchy(l1, l2)[1], 0.8, 1.0, xtol=1e-15)
    sig = _cauchy(l1, l2)
    np.testing.assert_allclose(cell["von Mises [MPa]"], _von_mises(sig), rtol=1e-7)
    np.testing.assert_allclose(cell["J [-]"], l1 * l2, rtol=1e-9)
    # the hand value itself against small strain: sigma_11 = E/(1 - nu^2) e, sigma_33 = nu sigma_11,
    # von Mises = sigma_11 sqrt(1 - nu + nu^2) (43.6 MPa; finite strain gives 47.0 MPa)
    assert _von_mises(sig) == pytest.approx(E / (1 - NU ** 2) * e * math.sqrt(1 - NU + NU ** 2), rel=0.1)


def test_fracture_fields(tmp_path):
    """Uniaxial tension with a phase field: alpha is uniform, Psi_plus and H have hand values."""
    Gc, l0, e = 1e-3, 1.0, 0.05
    s = _solve(tension_bar(E=E, nu=NU, Gc=Gc, l0=l0, fracture=True), e, steps=2)
    path = VtkWriter(s).write(tmp_path / "c.vtu")
    m, cell = _read(path)
    a = m.point_data["alpha [-]"].ravel()
    for x, ai in zip(m.points, a):
        assert ai == pytest.approx(s.alpha(s.mesh(x[0], x[1])), abs=1e-12)
    assert 0.5 < a.min() and np.ptp(a) < 1e-9
    # homogeneous state: l2 read from the written displacement of the top edge (height 0.2 mm)
    u = m.point_data[DISPLACEMENT]
    top = np.isclose(m.points[:, 1], 0.2)
    l1, l2 = 1 + e, 1 + float(np.mean(u[top, 1])) / 0.2
    J = l1 * l2
    psi_plus = K0 / 2 * math.log(J) ** 2 * (J >= 1) + G0 / 2 * (J ** (-2 / 3) * (l1 ** 2 + l2 ** 2 + 1) - 3)
    np.testing.assert_allclose(cell["Psi_plus [MPa]"], psi_plus, rtol=1e-8)
    np.testing.assert_allclose(cell["H [MPa]"], psi_plus, rtol=1e-8)  # H committed at this state, loading
    np.testing.assert_allclose(cell["J [-]"], J, rtol=1e-9)
    # the stress is that of the degraded energy: g(alpha) = (1 - alpha)^2 + residual times the intact one
    g = (1 - a[0]) ** 2 + s.scene.residual_stiffness
    np.testing.assert_allclose(cell["von Mises [MPa]"], g * G0 * J ** (-5 / 3) * _von_mises_B(l1, l2), rtol=1e-6)
    assert set(m.point_data) | set(cell) == {name for name, *_ in FIELDS}
    assert ET.parse(path).getroot().find("UnstructuredGrid/Piece/PointData").get("Vectors") == DISPLACEMENT


def _von_mises_B(l1, l2):
    return _von_mises([l1 ** 2, l2 ** 2, 1.0])


def test_cube_uniaxial_stress_3d(tmp_path):
    """3D tetrahedra: a unit cube compressed in z with free lateral faces (sigma_xx = sigma_yy = 0)."""
    import ngsolve as ngs
    from netgen.occ import Box, OCCGeometry, Pnt, X, Y, Z
    box = Box(Pnt(0, 0, 0), Pnt(1, 1, 1))
    box.faces.Min(Z).name, box.faces.Max(Z).name = "bottom", "top"
    box.faces.Min(X).name, box.faces.Min(Y).name = "xmin", "ymin"
    box.solids.name = "cube"
    scene = ngtmc.Scene(ngs.Mesh(OCCGeometry(box).GenerateMesh(maxh=0.6)), {"cube": ngtmc.Material(E, NU)},
                        supports=[ngtmc.Support("bottom", z=True), ngtmc.Support("xmin", x=True),
                                  ngtmc.Support("ymin", y=True)],
                        load=ngtmc.DisplacementLoad("top", "-z"))
    s = _solve(scene, 0.05)
    m, cell = _read(VtkWriter(s).write(tmp_path / "e.vtu"))
    assert [b.type for b in m.cells] == ["tetra"] and m.point_data[DISPLACEMENT].shape == (s.mesh.nv, 3)
    assert np.all(_signed_size(m) > 0)  # VTK's orientation: (p1 - p0) x (p2 - p0) . (p3 - p0) > 0
    for x, uu in zip(m.points, m.point_data[DISPLACEMENT]):
        np.testing.assert_allclose(uu, s.u(s.mesh(*x)), rtol=0, atol=1e-12)
    # hand: F = diag(lt, lt, lz), sigma = K ln(J)/J I + G J^(-5/3) (B - tr(B)/3 I), sigma_xx = 0
    lz = 0.95

    def sigma(lt):
        J, B = lt * lt * lz, np.array([lt ** 2, lt ** 2, lz ** 2])
        return K0 * math.log(J) / J + G0 * J ** (-5 / 3) * (B - B.sum() / 3)

    lt = brentq(lambda lt: sigma(lt)[0], 1.0, 1.1, xtol=1e-15)
    np.testing.assert_allclose(cell["J [-]"], lt * lt * lz, rtol=1e-9)
    np.testing.assert_allclose(cell["von Mises [MPa]"], abs(sigma(lt)[2]), rtol=1e-7)  # uniaxial: |sigma_zz|


def _study():
    """A one-case study on the 38-triangle tension bar, with three snapshots."""
    mod = types.ModuleType("vtk_study")
    mod.NAME, mod.TITLE, mod.SUMMARY = "vtk_tiny", "Tension bar", "test study"
    mod.PARAMETERS = {"E": (E, "MPa", "Young's modulus")}
    mod.RESOLUTIONS = {"quick": {}, "medium": {}, "paper": {}}
    mod.DEFAULT_RESOLUTION = "quick"
    mod.cases = lambda p: [Case(name="main", label="bar", scene=lambda: tension_bar(E=float(p["E"]), nu=NU, Gc=1e-3),
                                schedule=ngtmc.Schedule.monotonic(0.02),
                                control=ngtmc.AdaptiveStepControl(du_max=0.005, k_u=1.0, du_min=1e-5),
                                snapshot_loads=[0.005, 0.01])]
    mod.references = lambda p: []
    mod.targets = lambda p: []
    return mod


def test_runner_series(tmp_path):
    out = tmp_path / "run"
    ngtmc.run_study(_study(), output=out, report=False, progress=False, threads=1, vtk=True)
    z = np.load(out / "snapshots.npz")
    loads = z["main__loads"]
    assert len(loads) >= 3  # the two chosen loads and the final state
    root = ET.parse(out / "vtk" / "main.pvd").getroot()
    assert root.get("type") == "Collection"
    sets = root.findall("Collection/DataSet")
    assert [float(d.get("timestep")) for d in sets] == list(loads)
    assert [d.get("file") for d in sets] == [f"main_{k:04d}.vtu" for k in range(len(loads))]
    for k, d in enumerate(sets):
        m, cell = _read(out / "vtk" / d.get("file"))
        u = m.point_data[DISPLACEMENT]
        assert u.shape[1] == 3 and np.all(u[:, 2] == 0.0)
        np.testing.assert_allclose(u[:, :2], z["main__u"][k], rtol=0, atol=0)
        np.testing.assert_allclose(m.point_data["alpha [-]"].ravel(), z["main__alpha"][k], rtol=0, atol=0)
        assert {"J [-]", "von Mises [MPa]", "Psi_plus [MPa]", "H [MPa]", "density [-]"} <= set(cell)
    # at the final snapshot the right edge has moved by the load
    right = np.isclose(m.points[:, 0], 1.0)
    np.testing.assert_allclose(u[right, 0], loads[-1], atol=1e-12)


def test_vtk_reader_warps(tmp_path):
    """VTK's own reader (ParaView's) takes the file, and a warp with no array chosen moves the
    points by the displacement: the active vector."""
    vtk = pytest.importorskip("vtk")
    e = 0.05
    s = _solve(tension_bar(E=E, nu=NU, Gc=1e-3, fracture=True), e)
    path = VtkWriter(s).write(tmp_path / "d.vtu")
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    assert grid.GetNumberOfPoints() == s.mesh.nv and grid.GetNumberOfCells() == s.mesh.ne
    vec = grid.GetPointData().GetVectors()
    assert vec.GetName() == DISPLACEMENT and vec.GetNumberOfComponents() == 3
    warp = vtk.vtkWarpVector()
    warp.SetInputConnection(reader.GetOutputPort())
    warp.Update()
    from vtk.util.numpy_support import vtk_to_numpy
    x0 = vtk_to_numpy(grid.GetPoints().GetData())
    x1 = vtk_to_numpy(warp.GetOutput().GetPoints().GetData())
    np.testing.assert_allclose(x1 - x0, vtk_to_numpy(vec), atol=1e-12)
    assert np.max(np.abs(x1[:, 0] - x0[:, 0])) == pytest.approx(e)
    for name in ("J [-]", "von Mises [MPa]", "H [MPa]", "Psi_plus [MPa]"):
        assert grid.GetCellData().GetArray(name) is not None, name


def test_fields_documented():
    """docs/run-directory.md tables every field with its data kind, unit and when it is written."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "run-directory.md").read_text()
    rows = {r.split("|")[1].strip(): [c.strip() for c in r.split("|")[2:-1]]
            for r in doc[doc.index("## `vtk/`"):].splitlines() if r.startswith("| `")}
    assert list(rows) == [f"`{name}`" for name, *_ in FIELDS]
    for name, where, unit, _, fracture_only in FIELDS:
        data, doc_unit, _, written = rows[f"`{name}`"]
        assert data.startswith(where) and doc_unit == unit and (written == "fracture scenes") == fracture_only, name
