"""Mesh of the L-panel study (``studies/l_panel.py``), in mm: the Winkler panel (500 x 500 with a
250 x 250 cut-out), its indenter under the arm and the void between them, or (``load_introduction
= 'segment'``, diagnostic) the panel alone with the displacement imposed on the arm's lower face."""
from __future__ import annotations


def _segment(p: dict) -> bool:
    mode = str(p.get("load_introduction", "indenter"))
    if mode not in ("indenter", "segment"):
        raise ValueError(f"l_panel: load_introduction = {mode!r} is not one of 'indenter', 'segment'")
    return mode == "segment"


def effective_gap(p: dict) -> float:
    """Gap crossed before the panel is loaded, mm: ``gap`` with the indenter, 0 for segment loading."""
    return 0.0 if _segment(p) else float(p["gap"])


def effective_schedule(p: dict) -> list:
    """Imposed displacement turning points, mm (the schedule minus the gap for segment loading)."""
    shift = float(p["gap"]) - effective_gap(p)
    sched = [float(x) for x in p["schedule"]]
    return [sched[0]] + [x - shift for x in sched[1:]]


def build_mesh(p: dict):
    """Mesh with regions ``band``, ``contact_zone``, ``panel``, ``clamp_strip`` (the panel),
    ``indenter`` and ``void``; boundaries ``clamp`` (y = 0) and ``load`` (indenter's flat edge).
    With ``load_introduction = 'segment'``: no indenter and no void, ``load`` is the arm's lower
    face from x = load_x to 500 mm."""
    from netgen.occ import Circle, Glue, MoveTo, OCCGeometry, Pnt, Y
    import ngsolve as ngs

    gap, R, xl = float(p["gap"]), float(p["indenter_radius"]), float(p["load_x"])
    margin, cs = float(p["void_margin"]), float(p["clamp_strip"])
    if not (xl + R < 500 and xl - R - margin > 250):
        raise ValueError("l_panel geometry: the indenter and its void must fit under the arm (250 < x < 500)")
    outer = MoveTo(0, 0).LineTo(250, 0).LineTo(250, 250).LineTo(500, 250).LineTo(500, 500).LineTo(0, 500).Close().Face()
    bl = float(p.get("band_left", 150.0))
    if not 0.0 <= bl < 250.0:
        raise ValueError(f"l_panel geometry: band_left = {bl} mm must lie in [0, 250) (the band ends at x = 260 mm)")
    band = MoveTo(bl, 230).Rectangle(260 - bl, 90).Face() * outer
    if _segment(p):  # a vertex at x = load_x splits the arm's lower face: the load segment is its own edge
        cz = MoveTo(xl - 40, 250).LineTo(xl, 250).LineTo(500, 250).LineTo(500, 270).LineTo(xl - 40, 270).Close().Face()
    else:
        cz = MoveTo(xl - 40, 250).Rectangle(500 - (xl - 40), 20).Face()
    cstrip = MoveTo(0, 0).Rectangle(250, cs).Face()
    rest = outer - band - cz - cstrip
    band.faces.name = "band"
    band.faces.maxh = float(p["h_band"])
    cz.faces.name = "contact_zone"
    cz.faces.maxh = float(p["h_contact"])
    cstrip.faces.name = "clamp_strip"
    rest.faces.name = "panel"
    cstrip.edges.Min(Y).name = "clamp"
    if _segment(p):
        shape = Glue([band, cz, cstrip, rest])
        for e in shape.edges:
            c = e.center
            if abs(c.y - 250) < 1e-9 and xl < c.x < 500:
                e.name = "load"
        return ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=float(p["h_far"])))
    yb = 250 - gap - R
    half = Circle(Pnt(xl, yb), R).Face() * MoveTo(xl - R - 1, yb).Rectangle(2 * R + 2, R + 1).Face()
    half.faces.name = "indenter"
    half.faces.maxh = float(p["h_void"])
    half.edges.Min(Y).name = "load"
    void = MoveTo(xl - R - margin, yb).Rectangle(500 - (xl - R - margin), 250 - yb).Face() - half
    void.faces.name = "void"
    void.faces.maxh = float(p["h_void"])
    shape = Glue([band, cz, cstrip, rest, half, void])
    return ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=float(p["h_far"])))
