"""Meshes of the 3D study (``studies/three_point_bending_3d.py``), in mm.

* :func:`slab_meshes`: the 2D three-point-bending mesh of ``studies/_tpb_geometry.py`` made
  straight-sided, and its extrusion into one layer of prisms (:func:`ngtmc.extrude`), so that
  the 3D slab and its 2D twin have the same mesh in the plane.
* :func:`hemisphere_mesh`: a notched beam indented by a hemisphere, half of it across the width
  (symmetry plane z = 0), tetrahedra curved to order 2. Regions ``beam``, ``band`` (the refined
  slab above the notch), ``support_zone``, ``load_zone`` (a block of the beam top under the
  hemisphere, ``sphere_load_zone`` wide and deep, where fracture is not modelled), ``void`` (the
  void within ``sphere_regularised_radius`` of the hemisphere's axis, the part it squeezes),
  ``void_far`` (the rest of the void block, if any), ``indenter``; boundaries ``sym`` (z = 0),
  ``support_left``, ``support_right`` (strips of the bottom face across the width) and ``load``
  (the hemisphere's flat top).

The file name starts with an underscore: it is a helper, not a study.
"""
from __future__ import annotations

import math


def slab_meshes(p2: dict, thickness: float):
    """(2D mesh, 3D slab) for the 2D study's parameter dict ``p2`` (the 2D mesh straight-sided,
    Curve(1)); ``thickness`` in mm."""
    import ngtmc
    from ngtmc.studies import _tpb_geometry
    mesh2 = _tpb_geometry.build_mesh(p2)
    mesh2.Curve(1)
    return mesh2, ngtmc.extrude(mesh2, thickness)


def check_hemisphere(p: dict):
    """Raise ValueError if the sizes of ``p`` (the ``sphere_*`` parameters) cannot make the mesh."""
    L, H, W = (float(p[k]) for k in ("sphere_beam_length", "sphere_beam_height", "sphere_beam_width"))
    nd, R = float(p["sphere_notch_depth"]), float(p["sphere_radius"])
    bw, zs, sl = float(p["sphere_band_half_width"]), float(p["sphere_support_zone"]), float(p["sphere_support_length"])
    if not (0 < nd < H and 0 < R < min(W / 2, float(p["sphere_void_half_width"])) and sl <= zs < L / 2 - bw
            and float(p["sphere_notch_width"]) / 2 < bw and float(p["sphere_gap"]) > 0
            and 0 <= float(p["sphere_load_zone"]) < min(H - nd, W / 2, L / 2 - zs)
            and float(p["sphere_regularised_radius"]) > math.sqrt(2) * float(p["sphere_contact_box"])):
        raise ValueError("three_point_bending_3d hemisphere: need 0 < sphere_notch_depth < sphere_beam_height, "
                         "0 < sphere_radius < sphere_beam_width/2 and < sphere_void_half_width, "
                         "sphere_support_length <= sphere_support_zone < sphere_beam_length/2 - sphere_band_half_width, "
                         "sphere_notch_width/2 < sphere_band_half_width, sphere_gap > 0, "
                         "0 <= sphere_load_zone < sphere_beam_height - sphere_notch_depth, "
                         "sphere_regularised_radius > sqrt(2) sphere_contact_box (the contact patch's block "
                         "lies within it)")


def hemisphere_mesh(p: dict):
    """The hemisphere scene's mesh for the plain parameter dict ``p`` (see the study's PARAMETERS;
    sizes ``sphere_h_band``, ``sphere_h_void``, ``sphere_h_contact`` (the void in a block of half
    side ``sphere_contact_box`` under the hemisphere's lowest point), ``sphere_h_indenter``,
    ``sphere_h_beam``)."""
    import ngsolve as ngs
    from netgen.occ import Box, Cylinder, Glue, OCCGeometry, Pnt, Sphere, Y

    check_hemisphere(p)
    L, H = float(p["sphere_beam_length"]), float(p["sphere_beam_height"])
    W = float(p["sphere_beam_width"]) / 2     # the half modelled, z in [0, W]
    nd, nw = float(p["sphere_notch_depth"]), float(p["sphere_notch_width"])
    R, gap, vw = float(p["sphere_radius"]), float(p["sphere_gap"]), float(p["sphere_void_half_width"])
    bw, zs, sl = float(p["sphere_band_half_width"]), float(p["sphere_support_zone"]), float(p["sphere_support_length"])
    h_beam = float(p["sphere_h_beam"])
    quarter = p["sphere_symmetry"] == "quarter"
    xm = L / 2
    a = float(p["sphere_load_zone"])
    c = float(p["sphere_contact_box"])
    yc = H + gap + R
    body = Box(Pnt(0, 0, 0), Pnt(L, H, W)) - Box(Pnt(xm - nw / 2, -1, -1), Pnt(xm + nw / 2, nd, W + 1))
    band_box = Box(Pnt(xm - bw, 0, 0), Pnt(xm + bw, H, W))
    zone_l, zone_r = Box(Pnt(0, 0, 0), Pnt(zs, zs, W)), Box(Pnt(L - zs, 0, 0), Pnt(L, zs, W))
    sq_l, sq_r = Box(Pnt(0, 0, 0), Pnt(sl, sl, W)), Box(Pnt(L - sl, 0, 0), Pnt(L, sl, W))
    under = Box(Pnt(xm - a, H - a, 0), Pnt(xm + a, H, a)) if a > 0 else None
    rest = body - band_box - zone_l - zone_r
    band = body * band_box
    if under is not None:
        rest, band = rest - under, band - under
    ball = Sphere(Pnt(xm, yc, 0), R) * Box(Pnt(xm - R, yc - R, 0), Pnt(xm + R, yc, R))
    void = Box(Pnt(xm - vw, H, 0), Pnt(xm + vw, yc, W)) - ball
    near = Box(Pnt(xm - c, H, 0), Pnt(xm + c, min(H + gap + c, yc), c)) if c > 0 else None
    # (solid, region name, maxh or None)
    parts = [(rest, "beam", None), (band, "band", float(p["sphere_h_band"])),
             (ball, "indenter", float(p["sphere_h_indenter"])), (sq_l, "support_zone", h_beam / 2),
             (sq_r, "support_zone", h_beam / 2)]
    if zs > sl:
        parts += [(zone_l - sq_l, "support_zone", h_beam / 2), (zone_r - sq_r, "support_zone", h_beam / 2)]
    if under is not None:
        parts.append((under, "load_zone", float(p["sphere_h_band"])))
    outer = void - near if near is not None else void
    rr = float(p["sphere_regularised_radius"])
    if rr * rr < vw * vw + W * W:   # the cylinder leaves part of the block out: that part is 'void_far'
        cyl = Cylinder(Pnt(xm, H - 1, 0), Y, r=rr, h=yc - H + 2)
        parts += [(outer * cyl, "void", float(p["sphere_h_void"])), (outer - cyl, "void_far", float(p["sphere_h_void"]))]
    else:
        parts.append((outer, "void", float(p["sphere_h_void"])))
    if near is not None:   # the contact patch: finer void under the hemisphere's lowest point
        parts.append((void * near, "void", float(p["sphere_h_contact"])))
    if quarter:   # the mid-span half too: x <= L/2 (symmetry plane x = L/2)
        keep = Box(Pnt(-1, -1, -1), Pnt(xm, yc + 1, W + 1))
        parts = [(s * keep, name, h) for s, name, h in parts if s.center.x < xm + 1e-9]
    for s, name, h in parts:
        s.solids.name = name
        if h is not None:
            s.solids.maxh = h
        if name == "indenter":
            s.faces.Max(Y).name = "load"   # the flat face (the void's top face around it stays free)
    shape = Glue([s for s, _, _ in parts])
    tol = 1e-9
    for f in shape.faces:
        fc = f.center
        if abs(fc.z) < tol:
            f.name = "sym"
        elif quarter and abs(fc.x - xm) < tol:
            f.name = "sym_x"
        elif abs(fc.y) < tol and fc.x < sl:
            f.name = "support_left"
        elif abs(fc.y) < tol and fc.x > L - sl:
            f.name = "support_right"
    mesh = ngs.Mesh(OCCGeometry(shape).GenerateMesh(maxh=h_beam))
    mesh.Curve(2)
    return mesh
