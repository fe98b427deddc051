"""The units-and-scale check of a scene: ngtmc works in mm, N and MPa, and a number given in other
units (E in Pa or GPa, a body drawn in metres, Gc in kN/mm) is accepted by every other check. Here
each is compared with what is plausible in mm, N, MPa, and a :class:`ScaleWarning` names the
parameter, its value and the range. ``Scene(scale_check=False)`` silences it for a scene whose
numbers are meant. A mesh distributed over MPI ranks is not checked (each rank holds a part).

Plausible (the bounds are generous: a warning means "look again", not "wrong"):

* E of every material: 1e-4 to 2e6 MPa (a soft gel is 1e-3 MPa, diamond 1.2e6 MPa; 2.08e10 is E in
  Pa);
* Gc of the fracture regions' materials: 1e-6 to 1e3 N/mm (glass about 0.01, steels up to about
  200 N/mm);
* the strain at the strength of AT-2 under uniaxial stress, sigma_c / E with sigma_c = (3/16)
  sqrt(3 E Gc / l0): 1e-6 to 2 (E in GPa with Gc in N/mm gives strains of several hundred %);
* the body: its bounding box's diagonal 1e-2 to 1e5 mm (10 micrometres to 100 m; a 1 mm part
  drawn in metres is 1e-3);
* l0 of a fracture region: at most half of the region's bounding-box diagonal (an l0 of 100 mm on
  a 1 mm bar makes the phase field a constant);
* a ``Point(near=...)``: within 10 % of the body's diagonal of the vertex it takes;
* a displacement load's largest value over the schedule: at most the body's diagonal (a load in
  micrometres read as mm, or in mm on a body drawn in metres) (:func:`check_load_scale`).
"""
from __future__ import annotations

import math
import re
import warnings

import numpy as np

from ngtmc.scene.regions import box_diagonal, matches, regex, vertices_of
from ngtmc.scene.warnings import ScaleWarning
from ngtmc.scene.conditions import Point, Traction

__all__ = ["ScaleWarning", "check_scale", "check_load_scale", "E_RANGE", "GC_RANGE", "STRAIN_RANGE", "SIZE_RANGE", "L0_FRACTION",
           "POINT_FRACTION"]

#: Plausible ranges in mm, N, MPa (see the module docstring).
E_RANGE = (1e-4, 2e6)            # MPa
GC_RANGE = (1e-6, 1e3)           # N/mm
STRAIN_RANGE = (1e-6, 2.0)       # -
SIZE_RANGE = (1e-2, 1e5)         # mm
L0_FRACTION = 0.5                # of the fracture region's diagonal
POINT_FRACTION = 0.1             # of the body's diagonal


def _warn(message: str):
    warnings.warn(message + " (ngtmc works in mm, N, MPa; Scene(scale_check=False) if this is meant)",
                  ScaleWarning, stacklevel=5)


def check_load_scale(scene, loads) -> list[str]:
    """Warn (:class:`ScaleWarning`) when the largest |load| of the schedule's points ``loads`` (mm)
    exceeds the body's bounding-box diagonal while a displacement load drives the scene."""
    if not getattr(scene, "scale_check", True) or scene.mesh.comm.size > 1:   # serial meshes (the sizes are global)
        return []
    if all(isinstance(ld, Traction) for ld in scene.loads):
        return []
    diag = box_diagonal(np.asarray(scene.mesh.ngmesh.Coordinates())[:, :scene.mesh.dim])
    top = max(abs(float(x)) for x in loads)
    if top > diag:
        msg = (f"the schedule's largest load, {top:g} mm, is more than the body's size ({diag:.3g} mm): is the "
               "load in mm and the body drawn in mm?")
        _warn(msg)
        return [msg]
    return []


def check_scale(scene) -> list[str]:
    """Warn (:class:`ScaleWarning`) for each number of ``scene`` outside its plausible range in mm,
    N, MPa; returns the messages (empty when all is plausible or ``scene.scale_check`` is False)."""
    if not getattr(scene, "scale_check", True) or scene.mesh.comm.size > 1:   # serial meshes (the sizes are global)
        return []
    out = []

    def say(msg):
        out.append(msg)
        _warn(msg)

    mesh = scene.mesh
    d = mesh.dim
    pts = np.asarray(mesh.ngmesh.Coordinates())[:, :d]
    if pts.size == 0:
        return out
    diag = box_diagonal(pts)
    if not (SIZE_RANGE[0] <= diag <= SIZE_RANGE[1]):
        say(f"Scene.mesh: the body's size (bounding-box diagonal) is {diag:.3g} mm, outside the plausible "
            f"{SIZE_RANGE[0]:g} to {SIZE_RANGE[1]:g} mm: is it drawn in metres (or micrometres)?")
    frac = scene.fracture_region_names
    regions = mesh.GetMaterials()
    seen = set()
    for pattern, mat in scene.materials.items():
        if id(mat) in seen:
            continue
        seen.add(id(mat))
        where = f"Scene.materials[{pattern!r}]"
        if not (E_RANGE[0] <= mat.E <= E_RANGE[1]):
            hint = " (E in Pa?)" if mat.E > E_RANGE[1] else " (E in GPa or kN/mm^2?)"
            say(f"{where}.E = {mat.E:g} MPa is outside the plausible {E_RANGE[0]:g} to {E_RANGE[1]:g} MPa{hint}")
        cracks = [r for r in regions if matches(pattern, r) and any(matches(f, r) for f in frac)]
        if not cracks:
            continue
        if not (GC_RANGE[0] <= mat.Gc <= GC_RANGE[1]):
            say(f"{where}.Gc = {mat.Gc:g} N/mm is outside the plausible {GC_RANGE[0]:g} to {GC_RANGE[1]:g} N/mm "
                "(1 kN/mm = 1000 N/mm, 1 J/m^2 = 1e-3 N/mm)")
        sigma_c = 3.0 / 16.0 * math.sqrt(3.0 * mat.E * mat.Gc / mat.l0)
        strain = sigma_c / mat.E
        if not (STRAIN_RANGE[0] <= strain <= STRAIN_RANGE[1]):
            say(f"{where}: the strength of AT-2, (3/16) sqrt(3 E Gc / l0) = {sigma_c:.3g} MPa, is a strain of "
                f"{strain:.3g} at E = {mat.E:g} MPa, outside the plausible {STRAIN_RANGE[0]:g} to "
                f"{STRAIN_RANGE[1]:g}: are E, Gc and l0 in MPa, N/mm and mm?")
        verts = sorted(vertices_of(mesh, regex(re.escape(r) for r in cracks)))
        if verts:
            size = box_diagonal(pts[verts])
            if mat.l0 > L0_FRACTION * size:
                say(f"{where}.l0 = {mat.l0:g} mm is more than {L0_FRACTION:g} of the fracture region's size "
                    f"({size:.3g} mm): the phase field cannot localise into a crack there")
    for cond in list(scene.supports) + list(scene.loads):
        b = getattr(cond, "boundary", None)
        if isinstance(b, Point) and b.near is not None and len(b.near) == d:
            dist = float(np.min(np.linalg.norm(pts - np.asarray(b.near), axis=1)))
            if dist > POINT_FRACTION * diag:
                say(f"{b}: the nearest vertex is {dist:.3g} mm away, more than {POINT_FRACTION:g} of the body's "
                    f"size ({diag:.3g} mm): is the coordinate in mm and on the body?")
    return out
