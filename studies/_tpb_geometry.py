"""Meshes of the three-point-bending study (``studies/three_point_bending.py``), in mm.

Two ways of loading the same notched beam (parameter ``loading``):

* ``"indenter"`` (the paper's): a solid half-disc above mid-span, across a gap filled with a
  third-medium void. Regions ``beam``, ``band``, ``support_zone``, ``void`` (within
  ``regularised_half_width`` of the indenter's axis), ``void_far`` (the rest of the void
  rectangle, if any), ``indenter``;
  boundaries ``support_left``, ``support_right`` and ``load`` (the indenter's flat top).
* ``"window"`` (Ambati et al. 2015's own set-up): no indenter, no void; the boundary ``load`` is
  a window of width ``window_width`` centred on the top edge at mid-span. Regions ``beam``,
  ``band``, ``support_zone``; the window lies inside the band, so the band is cut in three pieces
  by vertical lines through the window's ends (all three named ``band``).

Variants of the beam (issue 15, fidelity; the defaults give the paper's mesh unchanged):

* ``notch_shape``: ``"flat"`` (a rectangle ``notch_width`` x ``notch_depth``, flat tip),
  ``"v"`` (a triangle of the same mouth width and depth, sharp tip at mid-span) or ``"slit"``
  (a rectangle ``h_band`` wide, the narrowest notch the band's mesh resolves, flat tip);
* ``indenter_exclusion`` = a > 0: a rectangle [L/2 - a, L/2 + a] x [H - a, H] under the load
  (indenter or window), region ``load_zone``, meshed to ``h_band``, where the scene models no
  fracture (like the support zones); cut out of the band and the beam;
* ``notch_depth`` = 0: no notch (the linear-elastic reference of the unnotched beam);
* ``support_zone`` = ``support_length``: no zone beyond the support squares (the squares
  ``support_length`` wide stay, named ``support_zone``).

The file name starts with an underscore: it is a helper, not a study (``ngtmc.study.registry.list_studies``
skips it).
"""
from __future__ import annotations

LOADINGS = ("indenter", "window")
NOTCH_SHAPES = ("flat", "v", "slit")


def notch_width(p: dict) -> float:
    """Mouth width of the notch, mm: ``notch_width``, or ``h_band`` for the slit."""
    return float(p["h_band"]) if p.get("notch_shape", "flat") == "slit" else float(p["notch_width"])


def check_geometry(p: dict):
    """Raise ValueError if the sizes of ``p`` cannot make the mesh of ``p["loading"]``."""
    for key, value in p.items():   # the mesh sizes (h_crack, the adaptive target, may be 0: none)
        if key.startswith("h_") and key != "h_crack" and not float(value) > 0:
            raise ValueError(f"three_point_bending geometry: the mesh size {key} = {value!r} mm must be > 0")
    L = float(p["beam_length"])
    nw, bw = notch_width(p), float(p["band_half_width"])
    sl, zs = float(p["support_length"]), float(p["support_zone"])
    if not (sl <= zs < L / 2 and nw / 2 < bw):
        raise ValueError("three_point_bending geometry: need support_length <= support_zone < beam_length/2 and "
                         "notch_width/2 < band_half_width")
    if not 0 <= float(p["notch_depth"]) < float(p["beam_height"]):
        raise ValueError("three_point_bending geometry: need 0 <= notch_depth < beam_height")
    a = float(p.get("indenter_exclusion", 0.0))
    if not (0 <= a < min(float(p["beam_height"]) - float(p["notch_depth"]), L / 2 - zs)):
        raise ValueError(f"three_point_bending geometry: need 0 <= indenter_exclusion < beam_height - notch_depth "
                         f"and < beam_length/2 - support_zone; got indenter_exclusion = {a:g} mm")
    if p.get("loading", "indenter") == "indenter":
        if not float(p["indenter_radius"]) < float(p["void_half_width"]):
            raise ValueError("three_point_bending geometry: need indenter_radius < void_half_width")
        if not float(p["regularised_half_width"]) > 0:
            raise ValueError("three_point_bending geometry: need regularised_half_width > 0; got "
                             f"{float(p['regularised_half_width']):g} mm")
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
    nd, nw = float(p["notch_depth"]), notch_width(p)
    bw, zs, sl = float(p["band_half_width"]), float(p["support_zone"]), float(p["support_length"])
    xm = L / 2
    beam = Rectangle(L, Hb).Face()
    band = MoveTo(xm - bw, 0).Rectangle(2 * bw, Hb).Face()
    if nd <= 0:
        notch = None
    elif p.get("notch_shape", "flat") == "v":
        notch = MoveTo(xm - nw / 2, 0).LineTo(xm + nw / 2, 0).LineTo(xm, nd).Close().Face()
    else:
        notch = MoveTo(xm - nw / 2, 0).Rectangle(nw, nd).Face()
    zone_l = Rectangle(zs, zs).Face()
    zone_r = MoveTo(L - zs, 0).Rectangle(zs, zs).Face()
    sq_l = Rectangle(sl, sl).Face()
    sq_r = MoveTo(L - sl, 0).Rectangle(sl, sl).Face()
    rest = beam - band - zone_l - zone_r
    zones = [sq_l, sq_r]
    if zs > sl:  # else no zone beyond the support squares
        zones = [zone_l - sq_l, zone_r - sq_r] + zones
    ww = float(p["window_width"]) if window else 0.0
    cut = (lambda f: f - notch) if nd > 0 else (lambda f: f)  # notch_depth = 0: the unnotched beam
    if window:
        mid = MoveTo(xm - ww / 2, 0).Rectangle(ww, Hb).Face()
        bands = [band - mid, cut(mid)]
    else:
        bands = [cut(band)]
    loaded = []
    a = float(p.get("indenter_exclusion", 0.0))
    if a > 0:  # no fracture under the load: cut out of the band (and the beam), pieces along the window's ends
        under = MoveTo(xm - a, Hb - a).Rectangle(2 * a, a).Face()
        rest = rest - under
        bands = [b - under for b in bands]
        loaded = [f for f in ([under * mid, under - mid] if window else [under]) if len(f.faces)]
    rest.faces.name = "beam"
    for b in bands:
        b.faces.name = "band"
        b.faces.maxh = float(p["h_band"])
    for f in loaded:
        f.faces.name = "load_zone"
        f.faces.maxh = float(p["h_band"])
    for f in zones:
        f.faces.name = "support_zone"
        f.faces.maxh = float(p["h_beam"]) / 2
    parts = [rest, *bands, *zones, *loaded]
    if not window:
        gap, R, vw = float(p["gap"]), float(p["indenter_radius"]), float(p["void_half_width"])
        yc = Hb + gap + R
        half = Circle((xm, yc), R).Face() * MoveTo(xm - R, yc - R).Rectangle(2 * R, R).Face()
        void = MoveTo(xm - vw, Hb).Rectangle(2 * vw, gap + R).Face() - half
        rw = float(p["regularised_half_width"])
        voids = [void]
        if rw < vw:   # beyond rw of the axis the void is never squeezed: 'void_far' (order 1, no regulariser)
            near = MoveTo(xm - rw, Hb).Rectangle(2 * rw, gap + R).Face()
            voids = [void * near, void - near]
            voids[1].faces.name = "void_far"
        voids[0].faces.name = "void"
        half.faces.name = "indenter"
        for v in voids:
            v.faces.maxh = float(p["h_void"])
        half.faces.maxh = float(p["h_indenter"])
        parts += [*voids, half]
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
        elif abs(c.y - y_load) < tol and abs(c.x - xm) < max(tol, ww / 2):  # window: may be in pieces
            e.name = "load"
    mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=float(p["h_beam"])))
    if not window:
        mesh.Curve(2)
    return mesh
