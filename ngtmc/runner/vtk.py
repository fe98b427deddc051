"""VTK output for ParaView: one ``.vtu`` file per snapshot and a ``.pvd`` series with the load as time.

    >>> from ngtmc.runner.vtk import VtkWriter, write_pvd
    >>> w = VtkWriter(solver)                       # doctest: +SKIP
    >>> w.write("vtk/main_0000.vtu")                # doctest: +SKIP
    >>> write_pvd("vtk/main.pvd", [(0.01, "main_0000.vtu")])   # doctest: +SKIP

The files are VTK XML UnstructuredGrid files (inline base64 binary, the byte-count header encoded
apart from the data as VTK itself writes them), readable by ParaView, VTK and meshio. Points are the
mesh vertices, always with three coordinates (z = 0 in 2D); cells are the mesh's volume elements
(triangles and quadrilaterals in 2D, tetrahedra, hexahedra, prisms and pyramids in 3D) in VTK's
orientation, drawn with straight sides.

Fields: :data:`FIELDS` (name with its unit, point or cell data, unit, meaning, written only where
the scene models fracture), tabled in ``docs/run-directory.md``. The displacement is the active
vector of the point data, so ParaView's Warp By Vector uses it without choosing an array.

Element means use the integration points of the displacement energy (:meth:`Solver.energy_measure`)
for J and the stress, and the history points for Psi_plus and H, so a homogeneous state gives its
value exactly. The stress is sigma = P F^T / J with P = dPsi/dF, differentiated from the solver's
own energy terms (:meth:`Solver.energy_terms`) with the 3 x 3 F (F33 = 1 in plane strain, so
sigma_33 counts in the von Mises value). The contact regulariser Phi_bar (a term in the second
gradient of u, not a stress) is left out.
"""
from __future__ import annotations

import base64
from pathlib import Path
from typing import Iterable
from xml.sax.saxutils import quoteattr

import numpy as np
import ngsolve as ngs

from ngtmc.model import deformation_gradient, full_deformation_gradient
from ngtmc.discrete import merged_terms
from ngtmc.study import write_atomic

__all__ = ["FIELDS", "DISPLACEMENT", "VtkGeometry", "VtkWriter", "pvd_text", "vtu_bytes", "write_pvd", "write_vtu"]

#: Name of the displacement array (the active vector of the point data).
DISPLACEMENT = "displacement [mm]"

#: (name, "point" or "cell", unit, meaning, only where the scene models fracture)
FIELDS = (
    (DISPLACEMENT, "point", "mm", "displacement u at the vertices, 3 components (z = 0 in 2D); the active vector, "
     "so Warp By Vector uses it without further choices", False),
    ("alpha [-]", "point", "-", "phase field (0 intact, 1 broken) at the vertices; 0 outside the fracture regions", True),
    ("density [-]", "cell", "-", "pseudo-density rho (1 solid, 0 void)", False),
    ("J [-]", "cell", "-", "det F, mean over the element", False),
    ("von Mises [MPa]", "cell", "MPa", "von Mises stress of the Cauchy stress of the elastic energy (Psi_bar degraded by "
     "g(alpha), scaled by gamma(rho); plane strain: sigma_33 included), mean over the element", False),
    ("Psi_plus [MPa]", "cell", "MPa", "tensile energy density Psi_plus of Eq. 6 (undegraded), mean over the element's "
     "history points; 0 outside the fracture regions", True),
    ("H [MPa]", "cell", "MPa", "history H = max Psi_plus of Eq. 7 (committed), mean over the element's history points; "
     "0 outside the fracture regions", True),
)

# VTK cell type of each NGSolve element type (vertex order as NGSolve's, orientation made VTK's)
_VTK_TYPE = {ngs.ET.TRIG: 5, ngs.ET.QUAD: 9, ngs.ET.TET: 10, ngs.ET.HEX: 12, ngs.ET.PRISM: 13, ngs.ET.PYRAMID: 14}


# vertex permutation that reverses an element's orientation
_FLIP = {ngs.ET.TRIG: [0, 2, 1], ngs.ET.QUAD: [0, 3, 2, 1], ngs.ET.TET: [0, 2, 1, 3],
         ngs.ET.HEX: [0, 3, 2, 1, 4, 7, 6, 5], ngs.ET.PRISM: [0, 2, 1, 3, 5, 4], ngs.ET.PYRAMID: [0, 3, 2, 1, 4]}


def _negative(points: np.ndarray, nodes: np.ndarray, dim: int) -> np.ndarray:
    """Elements (rows of vertex numbers) of negative VTK orientation: in 2D clockwise, in 3D a base
    face (the first three vertices) whose right-hand normal points away from the other vertices."""
    p0, p1, p2 = (points[nodes[:, i]] for i in range(3))
    n = np.cross(p1 - p0, p2 - p0)
    if dim == 2:
        return n[:, 2] < 0
    return np.einsum("ij,ij->i", n, points[nodes[:, 3:]].mean(axis=1) - p0) < 0


def _von_mises(sigma) -> ngs.CoefficientFunction:
    """sqrt(3/2 s:s) of a 3 x 3 stress CF, s its deviator; MPa for sigma in MPa."""
    s = sigma - ngs.Trace(sigma) / 3 * ngs.Id(3)
    return ngs.sqrt(1.5 * ngs.InnerProduct(s, s))


class VtkWriter:
    """Writes the fields of a :class:`~ngtmc.discrete.solver.Solver`'s current state as ``.vtu`` files.

    Built once per solver (the mesh's points and cells and the element-mean forms are kept); each
    :meth:`write` evaluates the solver's current u, alpha and history."""

    def __init__(self, solver, geometry: bool = True):
        self.solver = s = solver
        mesh = s.mesh
        self.nv = mesh.nv
        self.fracture = s.alpha is not None
        #: points and cells of the solver's mesh (None with ``geometry=False``: fields only, as on
        #: MPI ranks, whose fields rank 0 writes on the serial mesh)
        self.geometry = VtkGeometry(mesh) if geometry else None

        # element means: int_T f / int_T 1 with the rule the solver uses for f (L2 order 0: dof i = element i)
        l2 = ngs.L2(mesh, order=0)
        v = l2.TestFunction()
        F3 = full_deformation_gradient(deformation_gradient(s.u)).MakeVariable()
        self._lf_J, self._lf_vm, self._lf_area = (ngs.LinearForm(l2) for _ in range(3))
        J = ngs.Det(F3)
        for name, density, regions in merged_terms(s.energy_terms(s.u, F=F3)):  # one elastic density per region set
            if not name.startswith("elastic"):
                continue
            dx = s.energy_measure(name, regions)
            sigma = density.Diff(F3) * F3.trans / J
            self._lf_J += J * v * dx
            self._lf_vm += _von_mises(sigma).Compile() * v * dx
            self._lf_area += v * dx
        if self.fracture:
            dx_h = ngs.dx(definedon=mesh.Materials(s.regions.fracture_regex), intrules=s.irs.GetIntegrationRules())
            self._psi_plus = ngs.GridFunction(s.irs)
            self._H = ngs.GridFunction(s.irs)
            self._lf_pp, self._lf_H, self._lf_area_h = (ngs.LinearForm(l2) for _ in range(3))
            self._lf_pp += self._psi_plus * v * dx_h
            self._lf_H += self._H * v * dx_h
            self._lf_area_h += v * dx_h
            self._lf_area_h.Assemble()
        self._lf_area.Assemble()

    @staticmethod
    def _mean(lf, area) -> np.ndarray:
        lf.Assemble()
        a = area.vec.FV().NumPy()
        return np.divide(lf.vec.FV().NumPy(), a, out=np.zeros(len(a)), where=a > 0)

    def point_data(self) -> dict[str, np.ndarray]:
        """Point fields of the current state, by name (see :data:`FIELDS`)."""
        s = self.solver
        u = np.zeros((self.nv, 3))
        for i in range(s.dim):
            u[:, i] = s.u.components[i].vec.FV().NumPy()[:self.nv]
        out = {DISPLACEMENT: u}
        if self.fracture:
            out["alpha [-]"] = s.alpha.vec.FV().NumPy()[:self.nv].copy()
        return out

    def cell_data(self) -> dict[str, np.ndarray]:
        """Cell fields of the current state, by name (see :data:`FIELDS`)."""
        s = self.solver
        out = {"density [-]": s.rho.vec.FV().NumPy().copy(),
               "J [-]": self._mean(self._lf_J, self._lf_area),
               "von Mises [MPa]": self._mean(self._lf_vm, self._lf_area)}
        if self.fracture:
            self._psi_plus.vec.FV().NumPy()[:] = s.psi_plus_values()
            self._H.vec.FV().NumPy()[:] = s.H_committed
            out["Psi_plus [MPa]"] = self._mean(self._lf_pp, self._lf_area_h)
            out["H [MPa]"] = self._mean(self._lf_H, self._lf_area_h)
        return out

    def vtu_bytes(self) -> bytes:
        """The ``.vtu`` file of the current state."""
        return vtu_bytes(self.geometry, self.point_data(), self.cell_data())

    def write(self, path) -> Path:
        """Write the current state to ``path`` (a ``.vtu`` file; through a temporary file)."""
        return write_vtu(path, self.vtu_bytes())


class VtkGeometry:
    """Points (nv, 3) in mm (z = 0 in 2D) and cells (VTK types, connectivity, offsets) of a mesh's
    volume elements in VTK's orientation."""

    def __init__(self, mesh):
        self.nv = mesh.nv
        pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)[:self.nv]
        self.points = np.zeros((self.nv, 3))
        self.points[:, :pts.shape[1]] = pts
        cells = []
        for el in mesh.Elements(ngs.VOL):
            if el.type not in _VTK_TYPE:
                raise ValueError(f"VTK output: element type {el.type} is not supported")
            cells.append((el.type, [v.nr for v in el.vertices]))
        self.types = np.asarray([_VTK_TYPE[t] for t, _ in cells], dtype=np.uint8)
        for t, flip in _FLIP.items():  # VTK's orientation (netgen's tetrahedra are the other way round)
            idx = [i for i, (ti, _) in enumerate(cells) if ti == t]
            if idx:
                nodes = np.asarray([cells[i][1] for i in idx], dtype=np.int64)
                nodes = np.where(_negative(self.points, nodes, mesh.dim)[:, None], nodes[:, flip], nodes)
                for i, row in zip(idx, nodes):
                    cells[i] = (t, list(row))
        self.connectivity = np.asarray([n for _, c in cells for n in c], dtype=np.int64)
        self.offsets = np.cumsum([len(c) for _, c in cells], dtype=np.int64)


def vtu_bytes(geometry: VtkGeometry, point: dict, cell: dict) -> bytes:
    """A ``.vtu`` file of ``geometry`` with the point and cell fields (:data:`FIELDS`) by name."""
    scalars = "alpha [-]" if "alpha [-]" in point else None
    pd_attr = f" Vectors={quoteattr(DISPLACEMENT)}" + (f" Scalars={quoteattr(scalars)}" if scalars else "")
    g = geometry
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
             "  <UnstructuredGrid>",
             f'    <Piece NumberOfPoints="{g.nv}" NumberOfCells="{len(g.types)}">',
             "      <Points>", _array("Points", g.points), "      </Points>",
             "      <Cells>", _array("connectivity", g.connectivity), _array("offsets", g.offsets),
             _array("types", g.types), "      </Cells>",
             f"      <PointData{pd_attr}>", *(_array(k, a) for k, a in point.items()), "      </PointData>",
             f"      <CellData Scalars={quoteattr('von Mises [MPa]')}>",
             *(_array(k, a) for k, a in cell.items()), "      </CellData>",
             "    </Piece>", "  </UnstructuredGrid>", "</VTKFile>", ""]
    return "\n".join(lines).encode()


def write_vtu(path, data: bytes) -> Path:
    """Write the ``.vtu`` bytes ``data`` to ``path`` (through a temporary file)."""
    path = Path(path)
    write_atomic(path, data)
    return path


_VTK_DTYPE = {np.dtype("float64"): "Float64", np.dtype("int64"): "Int64", np.dtype("uint8"): "UInt8"}


def _array(name: str, a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    a = a.astype(a.dtype.newbyteorder("<"), copy=False)
    ncomp = a.shape[1] if a.ndim == 2 else 1
    data = a.tobytes()
    # VTK's own layout: base64 of the UInt64 byte count, then base64 of the data, encoded apart
    text = (base64.b64encode(np.array([len(data)], dtype="<u8").tobytes()) + base64.b64encode(data)).decode()
    return (f'        <DataArray type="{_VTK_DTYPE[a.dtype]}" Name={quoteattr(name)} NumberOfComponents="{ncomp}" '
            f'format="binary">{text}</DataArray>')


def pvd_text(entries: Iterable[tuple[float, str]]) -> str:
    """A ParaView collection (``.pvd``) of ``(load in mm, file name relative to the .pvd)`` pairs:
    the load is the series' time."""
    items = [f'    <DataSet timestep="{float(load)!r}" group="" part="0" file={quoteattr(str(name))}/>'
             for load, name in entries]
    return ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            "  <Collection>\n" + "".join(i + "\n" for i in items) + "  </Collection>\n</VTKFile>\n")


def write_pvd(path, entries: Iterable[tuple[float, str]]) -> Path:
    """Write :func:`pvd_text` to ``path`` (through a temporary file)."""
    path = Path(path)
    write_atomic(path, pvd_text(entries))
    return path
