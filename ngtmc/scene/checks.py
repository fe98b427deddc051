"""Validation of a :class:`~ngtmc.scene.scene.Scene`: every input checked before anything is built.

:func:`check_scene` (called by :meth:`ngtmc.scene.scene.Scene.check`) checks the mesh (2D or 3D, not
empty), the numbers (``gamma0``, ``gc_a``, ``gc_b``, ``residual_stiffness``, ``thickness``, ``order``),
the region patterns of ``materials``, ``density``, ``fracture_regions`` and the regulariser, the
pseudo-density, the supports and loads (known boundaries or vertices, one condition per component,
finite displacement fields) and the split; it raises ValueError or TypeError naming the parameter
and the allowed range. Where fracture may happen it warns (:class:`~ngtmc.scene.scene.ResolutionWarning`)
when the mesh, or the size a run refines the crack's path to, does not resolve l0/2.

Units: mm (lengths, mesh sizes, displacements), N (forces), MPa (tractions, moduli).
"""
from __future__ import annotations

import math
import re
import warnings
from typing import Mapping

import numpy as np
import ngsolve as ngs

from ngtmc.scene.conditions import LOAD_KINDS, DisplacementField, DisplacementLoad, Point, Support, Traction, _LETTERS, _where
from ngtmc.model import Material, check_number
from ngtmc.scene.regions import region_names, vertices_of
from ngtmc.scene.scale import check_scale
from ngtmc.scene.warnings import ElementWarning, ResolutionWarning
from ngtmc.model import check_split

__all__ = ["check_scene"]


def _boundary_points(mesh, boundary: str) -> np.ndarray:
    """Vertices (n x dim, mm) of the boundary elements whose name matches the regex ``boundary``,
    with the midpoints of their edges."""
    d = mesh.dim
    coords = np.asarray(mesh.ngmesh.Coordinates())[:, :d]
    vs, mids = set(), []
    for el in mesh.Elements(ngs.BND):
        if re.fullmatch(boundary, el.mat):
            nrs = [v.nr for v in el.vertices]
            vs.update(nrs)
            for i in range(len(nrs)):
                for j in range(i + 1, len(nrs)):
                    mids.append(0.5 * (coords[nrs[i]] + coords[nrs[j]]))
    out = [coords[sorted(vs)]]
    if mids:
        out.append(np.asarray(mids))
    return np.vstack(out)


def check_scene(scene, refine_to: float | None = None):
    """Validate every input of ``scene`` and warn about its resolution (the body of
    :meth:`ngtmc.scene.scene.Scene.check`, which documents it). Returns the scene."""
    mesh = scene.mesh
    if not isinstance(mesh, ngs.Mesh):
        raise TypeError(f"Scene.mesh must be an ngsolve.Mesh, got {type(mesh).__name__}")
    if mesh.dim not in (2, 3):
        raise ValueError(f"mesh dimension {mesh.dim} is not supported (2 or 3)")
    if (mesh.ne if mesh.comm.size == 1 else mesh.comm.Sum(mesh.ne)) == 0:  # rank 0 of an MPI run holds none
        raise ValueError("Scene.mesh is empty (0 elements): generate it from a geometry with faces (2D) or "
                         "solids (3D), e.g. ngsolve.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=...))")
    if mesh.dim == 3 and scene.thickness is not None:
        raise ValueError(f"Scene.thickness = {scene.thickness!r} mm is given for a 3D mesh: thickness applies to "
                         "2D (plane strain) meshes only; leave it unset (None) in 3D")
    for name, unit in (("gamma0", "dimensionless"), ("gc_a", "dimensionless"), ("gc_b", "dimensionless"),
                       ("residual_stiffness", "dimensionless"), ("thickness", "mm")):
        if getattr(scene, name) is not None or name != "thickness":   # only thickness may be None (1 mm in 2D)
            check_number(f"Scene.{name}", getattr(scene, name), unit)
    if 0.0 < float(scene.gamma0) < 1e-12:
        raise ValueError(f"Scene.gamma0 = {scene.gamma0!r} is below 1e-12: the void's stiffness would be lost in "
                         "round-off against the solid's (the studies use 1e-7 to 1e-4)")
    if scene.thickness is not None and not float(scene.thickness) <= 1e100:
        raise ValueError(f"Scene.thickness = {scene.thickness!r} mm is outside the range the solver can represent")
    if scene.order is not None and (isinstance(scene.order, bool) or not isinstance(scene.order, (int, np.integer))):
        raise TypeError(f"Scene.order must be an integer 1..4 or None, got {type(scene.order).__name__} {scene.order!r}")
    regions = set(mesh.GetMaterials())
    boundaries = set(mesh.GetBoundaries())
    _check_mesh(mesh)
    _check_patterns(scene, regions)
    p, k = scene.displacement_order, mesh.GetCurveOrder()
    if k > p:
        warnings.warn(f"Scene.mesh is curved to order {k} (mesh.Curve({k})) but the displacement has order {p} "
                      f"(Scene.order): a homogeneous deformation is not reproduced on the curved elements "
                      f"(the patch test fails). Use order >= {k}, or mesh.Curve({p})", ElementWarning, stacklevel=4)

    def need_region(name, what):
        if not any(re.fullmatch(name, r) for r in regions):
            raise ValueError(f"{what}: unknown region {name!r}; the mesh has regions {sorted(regions)}")

    def need_boundary(name, what):
        if not any(re.fullmatch(name, b) for b in boundaries):
            raise ValueError(f"{what}: unknown boundary {name!r}; the mesh has boundaries {sorted(boundaries)}")

    if not scene.materials:
        raise ValueError("Scene.materials is empty: give a Material for every region")
    for r in scene.materials:
        need_region(r, "Scene.materials")
        if not isinstance(scene.materials[r], Material):
            raise TypeError(f"Scene.materials[{r!r}] must be a Material")
    missing = [r for r in regions if not any(re.fullmatch(k, r) for k in scene.materials)]
    if missing:
        raise ValueError(f"Scene.materials: regions {sorted(missing)} have no material")
    if isinstance(scene.density, Mapping):
        for r, v in scene.density.items():
            need_region(r, "Scene.density")
    rho = scene.element_density()
    if rho.size and (not np.all(np.isfinite(rho)) or rho.min() < 0.0 or rho.max() > 1.0):
        raise ValueError(f"Scene.density: rho must lie in [0, 1]; got values in [{rho.min():g}, {rho.max():g}]")
    for r in scene.fracture_region_names:
        need_region(r, "Scene.fracture_regions")
    if scene.regulariser is not None:
        for r in region_names(scene.regulariser.regions):
            need_region(r, "Scene.regulariser.regions")
        if scene.displacement_order < 2:
            raise ValueError(
                f"Scene.order = {scene.order}: the Hessian regulariser needs displacement order >= 2 "
                "(it is identically zero on linear elements); use order=2 or None")
    if scene.displacement_order < 1 or scene.displacement_order > 4:
        raise ValueError(f"Scene.order = {scene.order} is outside the allowed range 1..4")
    _check_conditions(scene, need_boundary)
    if not (0.0 < float(scene.gamma0) < 1.0):
        raise ValueError(f"Scene.gamma0 = {scene.gamma0!r} is outside the allowed range (0, 1)")
    for name in ("gc_a", "gc_b") + (("thickness",) if mesh.dim == 2 else ()):
        v = getattr(scene, name)
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"Scene.{name} = {v!r} is outside the allowed range: finite and > 0")
    if not (math.isfinite(scene.residual_stiffness) and 0.0 <= scene.residual_stiffness < 1.0):
        raise ValueError(f"Scene.residual_stiffness = {scene.residual_stiffness!r} is outside the allowed range [0, 1)")
    check_split(scene.split, scene.formulation, mesh.dim)
    if not isinstance(scene.scale_check, bool):
        raise TypeError(f"Scene.scale_check must be True or False, got {scene.scale_check!r}")
    check_scale(scene)
    if scene.has_fracture:
        _check_resolution(scene, refine_to)
    return scene


#: The curved-element check of :func:`_check_mesh` samples det J at the points of a rule this much
#: above the default one (the energies on curved elements integrate to order 2p + 2).
CURVED_CHECK_BONUS = 6


def _check_mesh(mesh):
    """What a mesh would lose or break on: elements of zero (or negative) size, and curved elements
    inverted at integration points, named by number and region (a degenerate or inverted element
    makes J <= 0 before any load). Serial meshes only."""
    if mesh.comm.size > 1:
        return
    vol = np.asarray(ngs.Integrate(ngs.CF(1.0), mesh, element_wise=True), dtype=float).ravel()
    if vol.size == 0:
        return
    tiny = np.flatnonzero(~(vol > 1e-12 * float(np.max(np.abs(vol)))))
    if tiny.size:
        els = list(mesh.Elements(ngs.VOL))
        named = ", ".join(f"{i} ({els[i].mat}, {vol[i]:.3g})" for i in tiny[:5])
        raise ValueError(f"Scene.mesh has {tiny.size} element(s) of zero or negative size (mm^{mesh.dim}): {named}"
                         f"{' ...' if tiny.size > 5 else ''}; a degenerate or inverted element cannot be solved on")
    k = mesh.GetCurveOrder()
    if k > 1:
        # a curved element may be inverted where its size is not: det J <= 0 at integration points
        # (the energies integrate there with weights of the wrong sign, and Newton cannot converge)
        det = ngs.Det(ngs.specialcf.JacobianMatrix(mesh.dim))
        bad = np.asarray(ngs.Integrate(ngs.IfPos(det, 0.0, 1.0) * ngs.dx(bonus_intorder=CURVED_CHECK_BONUS), mesh,
                                       element_wise=True), dtype=float).ravel()
        inverted = np.flatnonzero(bad != 0.0)
        if inverted.size:
            els = list(mesh.Elements(ngs.VOL))
            regions = sorted({els[i].mat for i in inverted})
            named = ", ".join(f"{i} ({els[i].mat})" for i in inverted[:5])
            raise ValueError(f"Scene.mesh is curved (mesh.Curve({k})) and {inverted.size} element(s) are inverted at "
                             f"integration points (det J <= 0): {named}{' ...' if inverted.size > 5 else ''}, in "
                             f"region(s) {regions}; a curved face that nearly touches another face leaves thin "
                             "elements that curving turns inside out. Keep curved faces apart (no tangent "
                             "surfaces), mesh the thin part finer, or use mesh.Curve(1)")


def _check_conditions(scene, need_boundary):
    """Supports and loads: names, shapes, values, and no two conditions on one component."""
    mesh, d = scene.mesh, scene.mesh.dim
    if not scene.supports and not any(isinstance(ld, (DisplacementLoad, DisplacementField)) and
                                      not isinstance(ld.boundary, Point) for ld in scene.loads):
        raise ValueError("Scene.supports is empty: a scene needs supports (or a displacement load on a boundary)")
    if not scene.loads:
        raise ValueError("Scene.load is empty: give at least one load")
    verts = {}

    def where(b, what):
        if isinstance(b, Point):
            verts[b] = b.vertex(mesh)
            return ("vertex", verts[b])
        if not isinstance(b, str):
            raise TypeError(f"{what}: boundary must be a boundary name or a Point, got {type(b).__name__}")
        need_boundary(b, what)
        return ("boundary", b)

    held = {}   # (where, component) -> description of the condition holding it

    def claim(key, c, desc, is_load):
        k = (key, c)
        if k in held:
            other, other_is_load = held[k]
            if is_load and not other_is_load:
                raise ValueError(f"{desc} acts on component {_LETTERS[c]} that {other} already holds: "
                                 "a load on a held component does nothing; remove one of them")
            raise ValueError(f"two conditions on component {_LETTERS[c]} of {_where(key[1]) if key[0] == 'boundary' else 'vertex ' + str(key[1])}: "
                             f"{other} and {desc}; give each component of a boundary one condition")
        held[k] = (desc, is_load)

    for s in scene.supports:
        if not isinstance(s, Support):
            raise TypeError(f"Scene.supports must hold Support objects, got {type(s).__name__}")
        desc = f"Support on {_where(s.boundary)}"
        key = where(s.boundary, "Support")
        if not s.components():
            raise ValueError(f"{desc} holds no component: set x, y and/or z to True")
        if d == 2 and s.z:
            raise ValueError(f"{desc} holds z, but the mesh is 2D")
        for c in s.components():
            claim(key, c, desc, False)
    names = []
    moving = set()   # (where, component) that a load moves (not only holds)
    for ld in scene.loads:
        if not isinstance(ld, LOAD_KINDS):
            raise TypeError(f"Scene.load must be a DisplacementLoad, DisplacementField or Traction (or a list "
                            f"of them), got {type(ld).__name__}")
        kind = type(ld).__name__
        desc = f"{kind} {ld.label!r} on {_where(ld.boundary)}"
        if isinstance(ld, Traction) and isinstance(ld.boundary, Point):
            raise ValueError(f"{desc}: a traction acts on a boundary, not on a Point")
        key = where(ld.boundary, kind)
        names.append(ld.label)
        if isinstance(ld, DisplacementLoad) and ld.component >= d:
            raise ValueError(f"DisplacementLoad direction {ld.direction!r} does not exist in {d}D")
        if isinstance(ld, DisplacementField):
            _check_field(scene, ld, desc, key)
        if isinstance(ld, Traction):
            ld.vector(d)
            acting = range(d) if isinstance(ld.traction, ngs.CoefficientFunction) else \
                [c for c in range(d) if float(np.asarray(ld.traction, dtype=float)[c]) != 0.0]
            for c in acting:
                if (key, c) in held and not held[(key, c)][1]:
                    raise ValueError(f"{desc} acts on component {_LETTERS[c]} that {held[(key, c)][0]} already "
                                     "holds: a load on a held component does nothing; remove one of them")
        for c in ld.held_components(d):
            if c >= d:
                raise ValueError(f"{desc}: component {_LETTERS[c]} does not exist in {d}D")
            claim(key, c, desc, True)
            if not isinstance(ld, DisplacementLoad) or c == ld.component:
                moving.add((key, c))     # a DisplacementLoad's held tangential components stay at 0
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"loads {dup} share a name: give each load its own name (name=...), it names its "
                         "history column force_<name>")
    scene.force_load  # a force_from that names no load raises here
    _check_shared_vertices(mesh, held, moving)


def _check_shared_vertices(mesh, held: dict, moving: set):
    """Conditions per vertex: where two boundaries meet (a corner), a load that moves a component
    and another condition on that component of the shared vertex (a support, a held tangential
    component, another load) cannot both hold; the last one set would win silently. ``held``:
    (("boundary", name) or ("vertex", nr), component) -> (description, is_load); ``moving``: the
    keys of ``held`` that a load moves (conditions that hold 0 agree with each other)."""
    on = {}       # boundary regex -> its vertex numbers
    per_vertex = {}
    for (key, c), (desc, is_load) in held.items():
        is_load = (key, c) in moving
        if key[0] == "vertex":
            vs = {key[1]}
        else:
            if key[1] not in on:
                on[key[1]] = vertices_of(mesh, key[1], ngs.BND)
                if not on[key[1]] and mesh.comm.size == 1:
                    raise ValueError(f"{desc}: boundary {key[1]!r} is named in the mesh but no boundary element "
                                     "carries it, so the condition would hold nothing")
            vs = on[key[1]]
        for v in vs:
            per_vertex.setdefault((v, c), []).append((desc, is_load))
    pts = None
    for (v, c), conds in sorted(per_vertex.items()):
        loads = [dsc for dsc, is_load in conds if is_load]
        if len(conds) > 1 and loads:
            if pts is None:
                pts = np.asarray(mesh.ngmesh.Coordinates())
            at = ", ".join(f"{x:g}" for x in pts[v, :mesh.dim])
            others = [dsc for dsc in (dsc for dsc, _ in conds) if dsc != loads[0]]
            raise ValueError(f"vertex {v} at ({at}) mm, where boundaries meet: component {_LETTERS[c]} is prescribed by "
                             f"{loads[0]} and also by {' and '.join(others)}; one of them would win silently. "
                             "Name the boundary without that corner, or hold the corner by a Point condition")


def _check_field(scene, ld, desc, key):
    """Shape and finiteness of a DisplacementField on its boundary or vertex, before any solve."""
    mesh, d = scene.mesh, scene.mesh.dim
    if key[0] == "vertex":
        pts = np.asarray(mesh.ngmesh.Coordinates())[[key[1]], :d]
    else:
        pts = _boundary_points(mesh, key[1])
    if ld.is_callable:
        for lam in (0.0, 1.0):
            ld.values(pts, lam, d)
        return
    if ld.field.dim != d:
        raise ValueError(f"{desc}: the field has {ld.field.dim} components; the mesh is {d}D (give one entry per "
                         "dimension; components= selects the prescribed ones)")
    vals = np.asarray(ld.field(mesh(*[pts[:, i] for i in range(d)]))).reshape(len(pts), d)
    if not np.all(np.isfinite(vals)):
        bad = int(np.argmax(~np.all(np.isfinite(vals), axis=1)))
        raise ValueError(f"{desc}: the field is not finite (NaN or inf) at {tuple(float(v) for v in pts[bad])} mm")


def _check_patterns(scene, regions):
    """Each mesh region matched by at most one pattern of ``materials`` and of ``density``; every
    pattern a valid regular expression."""
    maps = [("Scene.materials", scene.materials)]
    if isinstance(scene.density, Mapping):
        maps.append(("Scene.density", scene.density))
        for r, v in scene.density.items():
            check_number(f"Scene.density[{r!r}]", v, "dimensionless, in [0, 1]")
    for what, mapping in maps:
        for k in mapping:
            try:
                re.compile(k)
            except (re.error, TypeError) as e:
                raise ValueError(f"{what}: {k!r} is not a valid regular expression ({e}); region names are "
                                 "regular expressions matched against the whole region name") from None
        for r in sorted(regions):
            pats = [k for k in mapping if re.fullmatch(k, r)]
            if len(pats) > 1:
                raise ValueError(
                    f"{what}: region {r!r} is matched by several patterns {pats}. Region names are regular "
                    f"expressions matched against the whole region name ('.*' matches every region): give each "
                    f"region exactly one pattern, e.g. list the regions as 'a|b|c'")


def _check_resolution(scene, refine_to: float | None = None):
    mats = scene.mesh.GetMaterials()
    idx = np.array([el.index for el in scene.mesh.Elements(ngs.VOL)])
    h = scene.element_sizes() if refine_to is None else None   # with refine_to the mesh is not judged
    for r in scene.fracture_region_names:
        ids = [i for i, m in enumerate(mats) if re.fullmatch(r, m)]
        sel = np.isin(idx, ids)
        if not sel.any():
            continue
        l0 = min(scene.material_of(m).l0 for m in mats if re.fullmatch(r, m))
        if refine_to is not None:
            if refine_to > l0 / 2:
                warnings.warn(
                    f"fracture region {r!r}: the run refines the crack's path to h_crack = {refine_to:.4g} mm, "
                    f"larger than l0/2 = {l0 / 2:.4g} mm; the phase field is not resolved (h_crack <= l0/2, "
                    "ideally l0/4)", ResolutionWarning, stacklevel=4)
            continue
        h_min = float(h[sel].min())
        if h_min > l0 / 2:
            warnings.warn(
                f"fracture region {r!r}: smallest element {h_min:.4g} mm is larger than l0/2 = {l0 / 2:.4g} mm; "
                "the phase field is not resolved (refine to h <= l0/2, ideally l0/4, along the crack path)",
                ResolutionWarning, stacklevel=4)
