"""Small scenes shared by the core tests (seconds each)."""
from __future__ import annotations

import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, X, Y

import ngtmc


def bar_mesh(length=1.0, height=0.2, maxh=0.1):
    """Rectangle [0, length] x [0, height], region "bar", boundaries left/right/bottom/top."""
    face = Rectangle(length, height).Face()
    face.faces.name = "bar"
    face.edges.Min(X).name = "left"
    face.edges.Max(X).name = "right"
    face.edges.Min(Y).name = "bottom"
    face.edges.Max(Y).name = "top"
    return ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=maxh))


def tension_bar(E=1000.0, nu=0.3, Gc=1e-3, l0=1.0, maxh=0.1, fracture=True, **kw):
    """Homogeneous uniaxial tension (plane strain, free lateral contraction): x held on the left,
    y held on the bottom, displacement in x imposed on the right."""
    mesh = bar_mesh(maxh=maxh)
    return ngtmc.Scene(mesh, {"bar": ngtmc.Material(E, nu, Gc, l0)},
                       supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True)],
                       load=ngtmc.DisplacementLoad("right", "x"),
                       fracture_regions="bar" if fracture else (), **kw)


def two_blocks(gap=0.05, gamma0=1e-5, maxh=0.05, void_maxh=0.02, kbar_r=1e-6, width=1.0, height=0.4,
               E=1000.0, nu=0.3, **kw):
    """Two ``width`` x ``height`` blocks separated by a void layer of thickness ``gap``; the lower
    block is clamped at the bottom, the upper one pushed down on its top edge. ``kbar_r=None``: no
    regulariser; ``kw``: further Scene fields (for example ``thickness``, ``order``)."""
    W, hb = width, height
    low = Rectangle(W, hb).Face()
    low.faces.name = "lower"
    void = MoveTo(0, hb).Rectangle(W, gap).Face()
    void.faces.name = "void"
    void.faces.maxh = void_maxh
    up = MoveTo(0, hb + gap).Rectangle(W, hb).Face()
    up.faces.name = "upper"
    shape = Glue([low, void, up])
    shape.edges.Min(Y).name = "bottom"
    shape.edges.Max(Y).name = "top"
    mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))
    return ngtmc.Scene(mesh, {".*": ngtmc.Material(E, nu)},
                       supports=[ngtmc.Support("bottom", x=True, y=True)],
                       load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True),
                       density={"void": 0.0}, gamma0=gamma0,
                       regulariser=None if kbar_r is None else ngtmc.Regulariser("void", length=1.0, kbar_r=kbar_r),
                       **kw)


def _slit_plate(maxh, h_band, l0, notch, direction, **kw):
    """Square 1 x 1 with a slit from the left edge to (notch, 0.5), a band along y = 0.5 refined to
    ``h_band`` (None: no band), region "plate" (E = 210e3 MPa, nu = 0.3, Gc = 2.7 N/mm); bottom
    clamped, top moved in ``direction`` with its other component held; mm."""
    half_w = 0.005
    plate = Rectangle(1.0, 1.0).Face()
    slit = MoveTo(-0.01, 0.5 - half_w).Rectangle(notch + 0.01, 2 * half_w).Face()
    body = plate - slit
    if h_band is None:
        shape = body
    else:
        band = MoveTo(0.0, 0.44).Rectangle(1.0, 0.12).Face()
        band.faces.maxh = h_band
        shape = Glue([body - band, body * band])
    shape.faces.name = "plate"
    shape.edges.Min(Y).name = "bottom"
    shape.edges.Max(Y).name = "top"
    mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))
    return ngtmc.Scene(mesh, {"plate": ngtmc.Material(210e3, 0.3, 2.7, l0)},
                       supports=[ngtmc.Support("bottom", x=True, y=True)],
                       load=ngtmc.DisplacementLoad("top", direction, hold_tangential=True),
                       fracture_regions="plate", **kw)


def notched_plate(maxh=0.08, h_band=0.02, l0=0.04, notch=0.3, **kw):
    """Single-edge-notched square 1 x 1 in tension: a slit from the left edge to (notch, 0.5),
    a refined band along y = 0.5; bottom clamped in y (and x at the left corner), top pulled in y."""
    return _slit_plate(maxh, h_band, l0, notch, "y", **kw)


def sheared_plate(maxh=0.1, l0=0.05, notch=0.5, **kw):
    """Single-edge-notched square 1 x 1 in shear (the shear test of Miehe, Hofacker and Welschinger
    2010, CMAME 199, 2765-2778, Sec. 4.2, at a larger l0): a slit from the left edge to
    (notch, 0.5), no band, bottom clamped, top moved in x with y held. The crack leaves the notch
    tip curving down towards the bottom right corner: no band can be placed along it beforehand.
    E = 210e3 MPa, nu = 0.3, Gc = 2.7 N/mm; mm."""
    return _slit_plate(maxh, None, l0, notch, "x", **kw)


def damaged(scene, loads=(0.004, 0.006, 0.007)):
    """A solver of ``scene`` after single-pass steps to ``loads`` (mm): alpha and H vary from point
    to point (the notched plates' transfer tests)."""
    s = ngtmc.Solver(scene, compile=True)
    for load in loads:
        s.solve_phase_field()
        assert s.solve_displacement(load).converged
        s.update_history()
    return s


def refined_twice_from_homogeneous(s, seed, load=2e-3):
    """Solve ``s`` (a Solver of a homogeneous tension scene) at ``load`` (mm), commit the history,
    then refine a random 30 % of its elements twice (ngtmc.adapt.refine, seeded). Returns the
    energies, reaction and committed history before, and the energies and reaction after (the
    refined state stays in ``s``)."""
    import numpy as np
    from ngtmc import adapt
    assert s.solve_displacement(load).converged
    s.update_history()
    e0, f0, H0 = s.energies(), s.reaction(), s.H_committed.copy()
    rng = np.random.default_rng(seed)
    for _ in range(2):
        adapt.refine(s, rng.random(s.mesh.ne) < 0.3)
    return e0, f0, H0, s.energies(), s.reaction()


def refine_and_check_the_transfer_in_3d(s, adapt_settings):
    """Mark and refine the damaged 3D solver ``s`` once (``adapt_settings``: an Adaptivity), and
    check that nothing heals: every child of a refined element has at least its parent's largest
    H at every point (the parent located by the child's centroid in a copy of the old mesh), the
    elements not refined keep their values, and alpha at every new vertex is the old field there.
    Returns the number of elements marked."""
    import numpy as np
    import ngsolve as ngs
    import pytest
    from ngtmc import adapt
    assert s.mesh.dim == 3 and np.ptp(s.H_committed) > 0 and s.max_alpha() > 0.01
    old_mesh = ngs.Mesh(s.mesh.ngmesh.Copy())
    ne_old = s.mesh.ne
    H_old = s.H_committed.copy().reshape(ne_old, -1)
    a_old = ngs.GridFunction(ngs.H1(old_mesh, order=1))
    a_old.vec.FV().NumPy()[:] = s.alpha_committed
    marked = adapt.mark(s, adapt_settings)
    assert 0 < marked.sum() < ne_old
    adapt.refine(s, marked)
    assert s.mesh.ne > ne_old and s.mesh.dim == 3
    coords = np.asarray(s.mesh.ngmesh.Coordinates())
    centroid = np.array([coords[[v.nr for v in el.vertices]].mean(axis=0) for el in s.mesh.Elements(ngs.VOL)])
    owner = np.array([old_mesh(*c).nr for c in centroid])
    assert np.all(owner >= 0)
    refined = np.zeros(ne_old, dtype=bool)
    refined[owner[ne_old:]] = True
    child = refined[owner]
    H_new = s.H_committed.reshape(s.mesh.ne, -1)
    assert np.all(H_new[child] >= H_old[owner[child]].max(axis=1, keepdims=True) * (1 - 1e-15))
    np.testing.assert_array_equal(H_new[:ne_old][~refined], H_old[~refined])   # not refined: kept
    for v in range(s.mesh.nv):
        (dof,) = s.fes_a.GetDofNrs(ngs.NodeId(ngs.VERTEX, v))
        assert s.alpha_committed[dof] == pytest.approx(a_old(old_mesh(*coords[v])), abs=1e-14)
    return int(marked.sum())


def homogeneous_state_kept_in_3d(s, order, load=2e-3):
    """:func:`refined_twice_from_homogeneous` on a 3D solver and its checks: energies, reaction
    and H to 1e-10 (the order-2 Newton solution's own noise: 3.8e-11 relative in the elastic
    energy, measured on tetrahedra), and u still the equilibrium to the Newton's tolerance: in 3D
    the carried boundary values differ from their target by round-off (a few 1e-16 mm), which
    costs one lifting iteration where 2D needs none; it moves u by less than the Newton's relative
    tolerance (8e-10 measured, order 2)."""
    import numpy as np
    import pytest
    from ngtmc.discrete.newton import DISPLACEMENT_RTOL
    e0, f0, H0, e1, f1 = refined_twice_from_homogeneous(s, order, load)
    assert np.ptp(H0) < 1e-10 * H0.max()
    for k in e0:
        assert e1[k] == pytest.approx(e0[k], rel=1e-10, abs=1e-300)
    assert f1 == pytest.approx(f0, rel=1e-10)
    np.testing.assert_allclose(s.H_committed, H0.max(), rtol=1e-10)
    u1 = s.u.vec.FV().NumPy().copy()
    res = s.solve_displacement(load)
    assert res.converged and res.iterations <= 1
    assert np.linalg.norm(s.u.vec.FV().NumPy() - u1) <= DISPLACEMENT_RTOL * np.linalg.norm(u1)


def plain_prolongation_error(mesh, field, order=2):
    """The trap of NGSolve's plain prolongation: ``field`` (a vector CoefficientFunction) set in
    a VectorH1 space of ``order`` on ``mesh``, every other element bisected (``mesh.Refine()``,
    the mesh changed in place), the GridFunction updated by NGSolve; returns its L2 error (mm
    times the field's unit)."""
    import ngsolve as ngs
    g = ngs.GridFunction(ngs.VectorH1(mesh, order=order))
    g.Set(field)
    for el in mesh.Elements(ngs.VOL):
        mesh.SetRefinementFlag(el, el.nr % 2 == 0)
    mesh.Refine()
    g.space.Update()
    g.Update()
    return float(ngs.sqrt(ngs.Integrate(ngs.InnerProduct(g - field, g - field), mesh)))
