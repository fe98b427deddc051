"""ngtmc.read_gmsh: gmsh files of format 2.2 and 4.1, ASCII and binary, triangles, quadrilaterals
and tetrahedra, their physical groups as regions and boundaries; what a file would lose is
refused with a message naming it (issue 58)."""
import warnings

import numpy as np
import pytest

import ngtmc

meshio = pytest.importorskip("meshio")


def _square(n=2, quads=False, tag_all=True, names=True):
    """The unit square (mm) in n x n cells, physical groups plate (2D, tag 1), left (1D, tag 2),
    right (3), bottom (4)."""
    nodes = np.array([(i / n, j / n, 0.0) for j in range(n + 1) for i in range(n + 1)])
    node = lambda i, j: j * (n + 1) + i                                      # noqa: E731
    cells = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)
            cells += [(a, b, c, d)] if quads else [(a, b, c), (a, c, d)]
    body_tag = np.ones(len(cells), dtype=int)
    if not tag_all:
        body_tag[: len(cells) // 2] = 0                                       # half the body in no group
    sides = [[(node(0, k), node(0, k + 1)) for k in range(n)], [(node(n, k), node(n, k + 1)) for k in range(n)],
             [(node(k, 0), node(k + 1, 0)) for k in range(n)]]            # one block per curve entity
    lines = [e for side in sides for e in side]
    line_tag = np.repeat([2, 3, 4], n)
    tags = [body_tag] + [np.full(n, t) for t in (2, 3, 4)]
    geometrical = [np.ones(len(cells), dtype=int)] + [np.full(n, t) for t in (2, 3, 4)]
    mesh = meshio.Mesh(nodes, [("quad" if quads else "triangle", np.array(cells))] + [("line", np.array(e)) for e in sides],
                       cell_data={"gmsh:physical": tags, "gmsh:geometrical": geometrical},
                       point_data={"gmsh:dim_tags": _dim_tags(len(nodes), lines, line_tag)})
    if names:
        mesh.field_data = {"plate": np.array([1, 2]), "left": np.array([2, 1]), "right": np.array([3, 1]),
                           "bottom": np.array([4, 1])}
    return mesh


def _dim_tags(n_nodes, lines, line_tag):
    """The gmsh entity (dim, tag) of each node, as format 4 stores nodes per entity: the surface
    (2, 1), or the first curve (1, tag) the node lies on."""
    out = np.tile([2, 1], (n_nodes, 1))
    for (a, b), tag in zip(lines, line_tag):
        for v in (a, b):
            if out[v, 0] == 2:
                out[v] = (1, tag)
    return out


def _stretch_force(mesh) -> float:
    scene = ngtmc.Scene(mesh, {"plate": ngtmc.Material(E=1000.0, nu=0.3)},
                        supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True)],
                        load=ngtmc.DisplacementLoad("right", "x"))
    return ngtmc.simulate(scene, 1e-4).history["force"].iloc[-1]


@pytest.mark.parametrize("fmt, binary", [("gmsh22", False), ("gmsh", False), ("gmsh", True)])
@pytest.mark.parametrize("quads", [False, True])
def test_every_format_reads_with_its_names_and_gives_the_hand_force(tmp_path, fmt, binary, quads):
    """Plane-strain uniaxial stress of the unit square stretched by 1e-4 mm: E / (1 - nu^2) * 1e-4 =
    0.10989 N per mm of thickness by the linear hand calculation, to 5e-4 (the finite strain of
    1e-4 moves it by about that much: 1.3e-4 measured), whatever the format (gmsh22: 2.2 ASCII;
    gmsh: 4.1); and every format the same to 1e-12."""
    path = tmp_path / "plate.msh"
    meshio.write(path, _square(quads=quads), file_format=fmt, binary=binary)
    mesh = ngtmc.read_gmsh(path)
    assert mesh.GetMaterials() == ("plate",)
    assert set(mesh.GetBoundaries()) == {"left", "right", "bottom"}
    assert mesh.ne == (4 if quads else 8)
    force = _stretch_force(mesh)
    assert force == pytest.approx(1000 / 0.91 * 1e-4, rel=5e-4)
    ref = tmp_path / "ref.msh"
    meshio.write(ref, _square(quads=quads), file_format="gmsh22", binary=False)
    assert force == pytest.approx(_stretch_force(ngtmc.read_gmsh(ref)), rel=1e-12)


def test_a_body_cell_in_no_physical_group_is_refused(tmp_path):
    path = tmp_path / "half.msh"          # format 2.2: gmsh's Mesh.SaveAll writes physical tag 0
    meshio.write(path, _square(tag_all=False), file_format="gmsh22", binary=False)
    with pytest.raises(ValueError, match=r"4 triangle cells belong to no physical surface: they would be dropped"):
        ngtmc.read_gmsh(path)


def test_unnamed_groups_get_names_and_a_warning(tmp_path):
    path = tmp_path / "unnamed.msh"
    meshio.write(path, _square(names=False), file_format="gmsh22", binary=False)
    with pytest.warns(UserWarning, match="physical groups without a name"):
        mesh = ngtmc.read_gmsh(path)
    assert mesh.GetMaterials() == ("physical1",)
    assert set(mesh.GetBoundaries()) == {"physical2", "physical3", "physical4"}


def test_tetrahedra_read_with_their_volume(tmp_path):
    """The unit cube as 6 tetrahedra (tag 1, "block"): volume 1 mm^3, orientation accepted."""
    import ngsolve as ngs
    pts = np.array([(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    tets = np.array([[0, 1, 3, 7], [0, 1, 7, 5], [0, 5, 7, 4], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7]])
    m = meshio.Mesh(pts, [("tetra", tets)], cell_data={"gmsh:physical": [np.ones(6, dtype=int)],
                                                       "gmsh:geometrical": [np.ones(6, dtype=int)]},
                    field_data={"block": np.array([1, 3])})
    path = tmp_path / "cube.msh"
    meshio.write(path, m, file_format="gmsh22", binary=True)
    mesh = ngtmc.read_gmsh(path)
    assert mesh.GetMaterials() == ("block",) and mesh.ne == 6
    assert ngs.Integrate(1, mesh) == pytest.approx(1.0, rel=1e-12)


def test_what_cannot_be_read_is_named(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        ngtmc.read_gmsh(tmp_path / "missing.msh")
    bad = tmp_path / "bad.msh"
    bad.write_text("this is no mesh\n")
    with pytest.raises(ValueError, match="cannot be read as a gmsh file"):
        ngtmc.read_gmsh(bad)
