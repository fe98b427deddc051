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
