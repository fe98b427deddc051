"""Meshes of the three-point-bending study (``studies/three_point_bending.py``), in mm.

Two ways of loading the same notched beam (parameter ``loading``):

* ``"indenter"`` (the paper's): a solid half-disc above mid-span, across a gap filled with a
  third-medium void. Regions ``beam``, ``band``, ``support_zone``, ``void``, ``indenter``;
  boundaries ``support_left``, ``support_right`` and ``load`` (the indenter's flat top).
* ``"window"`` (Ambati et al. 2015's own set-up): no indenter, no void; the boundary ``load`` is
  a window of width ``window_width`` centred on the top edge at mid-span. Regions ``beam``,
  ``band``, ``support_zone``; the window lies inside the band, so the band is cut in three pieces
  by vertical lines through the window's ends (all three named ``band``).

The file name starts with an underscore: it is a helper, not a study (``ngtmc.study.list_studies``
skips it).
"""
from __future__ import annotations

LOADINGS = ("indenter", "window")


def check_geometry(p: dict):
    """Raise ValueError if the sizes of ``p`` cannot make the mesh of ``p["loading"]``."""
    L = float(p["beam_length"])
    nw, bw = float(p["notch_width"]), float(p["band_half_width"])
    sl, zs = float(p["support_length"]), float(p["support_zone"])
    if not (sl <= zs < L / 2 and nw / 2 < bw):
        raise ValueError("three_point_bending geometry: need support_length <= support_zone < beam_length/2 and "
                         "notch_width/2 < band_half_width")
    if p.get("loading", "indenter") == "indenter":
        if not float(p["indenter_radius"]) < float(p["void_half_width"]):
            raise ValueError("three_point_bending geometry: need indenter_radius < void_half_width")
    else:
        ww = float(p["window_width"])
        if not (0 < ww and ww / 2 < bw):
            raise ValueError(f"three_point_bending geometry: need 0 < window_width < 2 band_half_width "
                             f"(= {2 * bw:g} mm); got window_width = {ww:g} mm")


def build_mesh(p: dict):
    """The NGSolve mesh for the plain parameter dict ``p`` (see the study's PARAMETERS)."""
    from netgen.occ import Circle, Glue, MoveTo, OCCGeometry, Rectangle
    import ngsolve as ngs

    check_geometry(p)
    window = p.get("loading", "indenter") == "window"
    L, Hb = float(p["beam_length"]), float(p["beam_height"])
    nd, nw = float(p["notch_depth"]), float(p["notch_width"])
    bw, zs, sl = float(p["band_half_width"]), float(p["support_zone"]), float(p["support_length"])
    xm = L / 2
    beam = Rectangle(L, Hb).Face()
    band = MoveTo(xm - bw, 0).Rectangle(2 * bw, Hb).Face()
    notch = MoveTo(xm - nw / 2, 0).Rectangle(nw, nd).Face()
    zone_l = Rectangle(zs, zs).Face()
    zone_r = MoveTo(L - zs, 0).Rectangle(zs, zs).Face()
    sq_l = Rectangle(sl, sl).Face()
    sq_r = MoveTo(L - sl, 0).Rectangle(sl, sl).Face()
    rest = beam - band - zone_l - zone_r
    zone_l = zone_l - sq_l
    zone_r = zone_r - sq_r
    if window:
        ww = float(p["window_width"])
        mid = MoveTo(xm - ww / 2, 0).Rectangle(ww, Hb).Face()
        bands = [band - mid, mid - notch]
    else:
        bands = [band - notch]
    rest.faces.name = "beam"
    for b in bands:
        b.faces.name = "band"
        b.faces.maxh = float(p["h_band"])
    for f in (zone_l, zone_r, sq_l, sq_r):
        f.faces.name = "support_zone"
        f.faces.maxh = float(p["h_beam"]) / 2
    parts = [rest, *bands, zone_l, zone_r, sq_l, sq_r]
    if not window:
        gap, R, vw = float(p["gap"]), float(p["indenter_radius"]), float(p["void_half_width"])
        yc = Hb + gap + R
        half = Circle((xm, yc), R).Face() * MoveTo(xm - R, yc - R).Rectangle(2 * R, R).Face()
        void = MoveTo(xm - vw, Hb).Rectangle(2 * vw, gap + R).Face() - half
        void.faces.name = "void"
        half.faces.name = "indenter"
        void.faces.maxh = float(p["h_void"])
        half.faces.maxh = float(p["h_indenter"])
        parts += [void, half]
        y_load = yc
    else:
        y_load = Hb
    shape = Glue(parts)
    tol = 1e-9
    for e in shape.edges:
        c = e.center
        if abs(c.y) < tol and c.x < sl:
            e.name = "support_left"
        elif abs(c.y) < tol and c.x > L - sl:
            e.name = "support_right"
        elif abs(c.y - y_load) < tol and abs(c.x - xm) < tol:
            e.name = "load"
    mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=float(p["h_beam"])))
    if not window:
        mesh.Curve(2)
    return mesh
