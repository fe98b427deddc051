"""det F at the guard points from the sparse matrix of grad u (ngtmc.discrete.guard) against
NGSolve's interpolation of det F, on every element type and order the package accepts, and
against hand values: a homogeneous stretch, a rigid rotation, a fold that inverts."""
import math

import numpy as np
import ngsolve as ngs
from ngsolve.meshes import MakeStructured2DMesh, MakeStructured3DMesh
import pytest

import ngtmc
from ngtmc import adapt
from ngtmc.discrete import guard
from ngtmc.model import deformation_gradient
from scenes import bar_mesh, two_blocks


def _scene(kind, order):
    if kind == "trig":
        mesh = bar_mesh(height=0.5, maxh=0.15)
    elif kind == "quad":
        mesh = MakeStructured2DMesh(quads=True, nx=5, ny=3, mapping=lambda x, y: (x + 0.1 * y * y, 0.5 * y))
    elif kind == "prism":
        mesh = ngtmc.extrude(bar_mesh(height=0.5, maxh=0.25), 0.2)
    else:
        mesh = MakeStructured3DMesh(hexes=kind == "hex", nx=3, ny=2, nz=2,
                                    mapping=lambda x, y, z: (x + 0.1 * z * y, 0.5 * y, 0.4 * z))
    region, side = mesh.GetMaterials()[0], mesh.GetBoundaries()[0]
    return ngtmc.Scene(mesh, {region: ngtmc.Material(1000.0, 0.3, 1e-3, 0.1)}, supports=[],
                       load=ngtmc.DisplacementLoad(side, "x"), fracture_regions=region, order=order)


def _field(dim):
    """A smooth non-affine displacement (mm) with gradients of about 0.1."""
    x, y, z = ngs.x, ngs.y, ngs.z
    if dim == 2:
        return ngs.CF((0.1 * x * y + 0.05 * x * x, -0.08 * y + 0.1 * ngs.sin(x)))
    return ngs.CF((0.1 * x * y + 0.05 * z * z, -0.08 * y + 0.1 * ngs.sin(x), 0.07 * x * z - 0.05 * y))


def _interpolated(s):
    g = ngs.GridFunction(s._guard_irs)
    g.Interpolate(ngs.Det(deformation_gradient(s.u)))
    return g.vec.FV().NumPy().copy()


@pytest.mark.parametrize("kind", ["trig", "quad", "tet", "hex", "prism"])
@pytest.mark.parametrize("order", [1, 2])
def test_the_matrix_gives_the_interpolated_det_f_point_by_point(kind, order):
    """Every guard point's det F (in the space's order, which the refinement's marking reads
    element by element) equals NGSolve's interpolation to 1e-12, on a state whose det F varies
    within the elements by more than 1e-3."""
    s = ngtmc.Solver(_scene(kind, order), compile=False)
    s.u.Set(_field(s.dim))
    J = s.J_values().copy()
    assert isinstance(s._J_op, guard.GradientAtPoints)
    ref = _interpolated(s)
    assert J.shape == ref.shape and np.ptp(ref) > 1e-2
    assert np.max(np.abs(J - ref)) < 1e-12
    assert s.min_J() == pytest.approx(ref.min(), abs=1e-12)
    counted = guard.counted_entries(s.fes_u, s._guard_irs, s.dim)
    assert s._J_op.matrix.nnz <= counted <= guard.estimated_entries(s.fes_u, s._guard_irs, s.dim)


@pytest.mark.parametrize("kind", ["trig", "hex"])
def test_hand_values_stretch_rotation_and_an_inverted_element(kind):
    """u = (a x, b y[, c z]): det F = (1 + a)(1 + b)(1 + c) at every point; a rigid rotation by
    0.7 rad: 1 to round-off (1e-12: the projection of Set; the large rotation, not a small-strain
    one); x folded over
    itself (u_x = -2.5 x): det F = -1.5, so the guard sees the inversion."""
    s = ngtmc.Solver(_scene(kind, 2), compile=False)
    x, y, z = ngs.x, ngs.y, ngs.z
    stretch = (0.1, -0.2, 0.05)[:s.dim]
    s.u.Set(ngs.CF(tuple(c * v for c, v in zip(stretch, (x, y, z)))))
    assert np.allclose(s.J_values(), math.prod(1 + c for c in stretch), rtol=0, atol=1e-12)
    t = 0.7
    rot = ((math.cos(t) - 1) * x - math.sin(t) * y, math.sin(t) * x + (math.cos(t) - 1) * y)
    s.u.Set(ngs.CF(rot if s.dim == 2 else rot + (0 * z,)))
    assert np.allclose(s.J_values(), 1.0, rtol=0, atol=1e-12)
    s.u.Set(ngs.CF((-2.5 * x,) + (0 * y,) * (s.dim - 1)))
    assert s.min_J() == pytest.approx(-1.5, abs=1e-12)


def test_a_variable_order_scene_and_a_refined_mesh():
    """Order 2 only in the regularised void (``variable_order``), and after a bisection of part
    of the mesh: the matrix is built again for the new mesh and still matches."""
    scene = two_blocks(order=None, variable_order=True)
    s = ngtmc.Solver(scene, compile=False)
    s.u.Set(_field(2))
    assert np.max(np.abs(s.J_values() - _interpolated(s))) < 1e-12
    op = s._J_op

    adapt.refine(s, np.arange(s.mesh.ne) % 3 == 0)
    s.u.Set(_field(2))
    J = s.J_values()
    assert s._J_op is not op
    assert np.max(np.abs(J - _interpolated(s))) < 1e-12


def test_interpolation_where_the_matrix_is_not_built(monkeypatch):
    """NGTMC_J_GUARD=interpolate, or a mesh whose matrix would exceed GUARD_MAX_ENTRIES: det F
    is interpolated, with the same values; a misspelt setting is an error."""
    monkeypatch.setenv(guard.GUARD_ENV, "interpolate")
    s = ngtmc.Solver(_scene("trig", 2), compile=False)
    s.u.Set(_field(2))
    J = s.J_values().copy()
    assert s._J_op is False
    monkeypatch.delenv(guard.GUARD_ENV)
    t = ngtmc.Solver(_scene("trig", 2), compile=False)
    t.u.Set(_field(2))
    assert np.max(np.abs(t.J_values() - J)) < 1e-12
    monkeypatch.setattr(guard, "GUARD_MAX_ENTRIES", guard.counted_entries(t.fes_u, t._guard_irs, 2) - 1)
    small = ngtmc.Solver(_scene("trig", 2), compile=False)
    small.u.Set(_field(2))
    assert np.max(np.abs(small.J_values() - J)) < 1e-12 and small._J_op is False
    monkeypatch.setenv(guard.GUARD_ENV, "interpolated")
    with pytest.raises(ValueError, match="NGTMC_J_GUARD"):
        ngtmc.Solver(_scene("trig", 2), compile=False).J_values()
