"""Scenes: what is simulated, independent of how it is solved.

A :class:`Scene` names a mesh with regions and boundaries, the material and pseudo-density of each
region, where fracture may happen, where the third-medium regulariser acts, the supports and the
loads (:class:`DisplacementLoad`, :class:`DisplacementField`, :class:`Traction`; on boundaries or
at :class:`Point` vertices; defined in :mod:`ngtmc.conditions`), all driven by one load parameter
lambda. The solver builds only
what a scene needs: order-1 displacement when no regulariser acts, no phase-field unknowns when
no region may break, no contact medium when no region has density below one.

Units: mm, N, MPa. A 2D mesh is plane strain with out-of-plane ``thickness`` (mm); forces and
energies are reported for that thickness.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import re
import warnings
from typing import Mapping, Sequence

import numpy as np
import ngsolve as ngs

from .conditions import (LOAD_KINDS, DisplacementField, DisplacementLoad, Point, Support, Traction,  # noqa: F401
                         _LETTERS, _where)
from .materials import Material, check_number
from .splits import DEFAULT_FORMULATION, DEFAULT_SPLIT, check_split

__all__ = ["Support", "DisplacementLoad", "DisplacementField", "Traction", "Point", "Regulariser", "Scene",
           "ResolutionWarning"]

class ResolutionWarning(UserWarning):
    """The mesh does not resolve the phase-field length scale where fracture may happen."""


@dataclass(frozen=True)
class Regulariser:
    """Hessian regularisation of the third medium (Eq. 3) on the named regions.

    regions: region names where it acts (normally the void), joined by "|" or as a list;
    kbar_r: dimensionless factor (1e-6 in the literature), > 0; length: characteristic length L of
    the structure, mm, > 0; damping: "none" or "exp" (energy density times exp(-5 J), see
    :mod:`ngtmc.contact_regularisation`). k_r = kbar_r L^2 K0 with K0 the bulk modulus of the
    region's base material. It multiplies the void indicator 1 - rho.
    """

    regions: str | Sequence[str]
    length: float
    kbar_r: float = 1e-6
    damping: str = "none"

    def __post_init__(self):
        for name, v in (("kbar_r", self.kbar_r), ("length", self.length)):
            check_number(f"Regulariser {name}", v, "mm" if name == "length" else "dimensionless")
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"Regulariser {name} = {v!r} is outside the allowed range: finite and > 0")
        if self.damping not in ("none", "exp"):
            raise ValueError(f"Regulariser damping = {self.damping!r} is not one of 'none', 'exp'")


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


def _names(spec) -> list[str]:
    if spec is None:
        return []
    if isinstance(spec, str):
        return [s for s in spec.split("|") if s]
    return [s for item in spec for s in _names(item)]


@dataclass
class Scene:
    """A structure to simulate (see the module docstring).

    Parameters
    ----------
    mesh : ngsolve.Mesh
        2D (plane strain) or 3D mesh with named regions and boundaries (not empty).
    materials : mapping region name -> Material
        Base (fully dense) material of every region of the mesh. A void region has the material it is
        interpolated from (its stiffness is gamma(rho) times this one).

        **Region names are regular expressions**, here and in ``density``, ``fracture_regions`` and
        ``Regulariser.regions``, matched against the whole name of each mesh region (``re.fullmatch``):
        ``".*"`` matches every region, ``"beam|band"`` two of them. Within ``materials`` (and within
        ``density``) each region must be matched by exactly one pattern: overlapping patterns such as
        ``{".*": steel, "void": soft}`` are refused. Boundary names of ``Support`` and
        ``DisplacementLoad`` are regular expressions too.
    supports : list of Support
        On boundaries or at :class:`Point` vertices.
    load : a load or a list of loads
        :class:`DisplacementLoad` (uniform, axis-aligned), :class:`DisplacementField` (a field of the
        position and lambda, mm), :class:`Traction` (force control, MPa per unit lambda), or a list
        of them, each on its own boundary or point; the one load parameter lambda of the schedule
        drives them all. With several loads the history gains a ``force_<name>`` column (N) per load
        (see :func:`ngtmc.runfiles.history_units`).
    force_from : str or None
        Name of the load whose force is the ``force`` column of the history (the force of the
        report and of the adjoint's reaction objectives); default the first load.
    density : mapping region name -> rho in [0, 1], or array of one rho per element, optional
        Pseudo-density (1 solid, 0 void). Regions not named are solid (rho = 1).
    fracture_regions : region names where the phase field lives (empty: nothing may break)
    regulariser : Regulariser or None
    gamma0 : float
        Void stiffness ratio of Eq. 17, in (0, 1). Only matters where rho < 1.
    gc_a, gc_b : float
        Parameters a (> 0) and b (> 0) of the toughness interpolation of Eq. 18.
    residual_stiffness : float
        Added to g(alpha), >= 0 (default 1e-6; keep it at least about gamma0).
    thickness : float or None
        Out-of-plane thickness of a 2D (plane strain) mesh, mm (> 0; None means 1 mm). A 3D mesh has
        its own depth: giving a thickness there is refused (it stays None).
    order : int or None
        Polynomial order of the displacement; None chooses 2 with a regulariser and 1 without.
    variable_order : bool
        With ``order=None`` and a regulariser: order 2 only on the elements where the regulariser
        acts (and on all their edges), order 1 everywhere else (default True). False: order 2 on
        every element.
    name : str
        Free label used in messages and reports.
    split : str
        Tension/compression split of the elastic energy in the fracture regions, one of
        :data:`ngtmc.splits.SPLITS`: "vol-dev-J" (default, the paper's Eq. 6), "vol-dev-small"
        (Amor et al. 2009 on the small strain), "vol-dev-log" (Amor et al. 2009 on the Hencky
        strain; 2D), "spectral" (Miehe et al. 2010; 2D), "none" (see :mod:`ngtmc.splits`).
    formulation : str
        Where the split acts, one of :data:`ngtmc.splits.FORMULATIONS`: "hybrid" (default, the
        paper's: in the history only) or "anisotropic" (also in the displacement equation: only
        Psi_plus is degraded). The single-pass, staggered and monolithic schemes and the adjoint
        of :mod:`ngtmc.sensitivities` all use the chosen pair.
    """

    mesh: ngs.Mesh
    materials: Mapping[str, Material]
    supports: Sequence[Support]
    load: DisplacementLoad
    density: Mapping[str, float] | np.ndarray | None = None
    fracture_regions: str | Sequence[str] = ()
    regulariser: Regulariser | None = None
    gamma0: float = 1e-6
    gc_a: float = 10.0
    gc_b: float = 100.0
    residual_stiffness: float = 1e-6
    thickness: float | None = None
    order: int | None = None
    variable_order: bool = True
    name: str = "scene"
    split: str = DEFAULT_SPLIT
    formulation: str = DEFAULT_FORMULATION
    force_from: str | None = None

    def __post_init__(self):
        if self.thickness is None and getattr(self.mesh, "dim", 2) == 2:
            self.thickness = 1.0
        check_split(self.split, self.formulation)

    # ---------------------------------------------------------------- derived properties
    @property
    def dim(self) -> int:
        return self.mesh.dim

    @property
    def loads(self) -> list:
        """The loads of the scene as a list (``load`` may be one load or a list)."""
        if isinstance(self.load, (list, tuple)):
            return list(self.load)
        return [self.load]

    @property
    def force_load(self):
        """The load whose force is the history's ``force`` column (``force_from``, default the first)."""
        if self.force_from is None:
            return self.loads[0]
        for ld in self.loads:
            if getattr(ld, "label", None) == self.force_from:
                return ld
        raise ValueError(f"Scene.force_from = {self.force_from!r} names no load; the loads are "
                         f"{[getattr(ld, 'label', None) for ld in self.loads]}")

    @property
    def force_controlled(self) -> bool:
        """True when every load is a :class:`Traction` (no prescribed displacement moves)."""
        return all(isinstance(ld, Traction) for ld in self.loads)

    @property
    def fracture_region_names(self) -> list[str]:
        return _names(self.fracture_regions)

    @property
    def has_fracture(self) -> bool:
        return len(self.fracture_region_names) > 0

    @property
    def displacement_order(self) -> int:
        if self.order is not None:
            return int(self.order)
        return 2 if self.regulariser is not None else 1

    def element_density(self) -> np.ndarray:
        """Pseudo-density per element (array of length mesh.ne), dimensionless."""
        ne = self.mesh.ne
        if self.density is None:
            return np.ones(ne)
        if isinstance(self.density, Mapping):
            rho = np.ones(ne)
            mats = self.mesh.GetMaterials()
            idx = np.array([el.index for el in self.mesh.Elements(ngs.VOL)])
            for region, value in self.density.items():
                ids = [i for i, m in enumerate(mats) if re.fullmatch(region, m)]
                rho[np.isin(idx, ids)] = float(value)
            return rho
        rho = np.asarray(self.density, dtype=float).ravel()
        if rho.shape != (ne,):
            raise ValueError(f"density array has {rho.size} entries; the mesh has {ne} elements (one rho per element expected)")
        return rho

    @property
    def has_void(self) -> bool:
        from .distributed import Ranks
        return Ranks(self.mesh).any(bool(np.any(self.element_density() < 1.0)))

    # ---------------------------------------------------------------- validation
    def check(self, refine_to: float | None = None) -> "Scene":
        """Validate every input; raise ValueError naming the parameter and the allowed range.

        Warns (:class:`ResolutionWarning`) when the smallest element in a fracture region is larger
        than l0/2, or, for a run that refines the crack's path as it goes (``refine_to``, mm: its
        :attr:`ngtmc.Adaptivity.h_crack`), when that size is. Returns the scene."""
        mesh = self.mesh
        if not isinstance(mesh, ngs.Mesh):
            raise TypeError(f"Scene.mesh must be an ngsolve.Mesh, got {type(mesh).__name__}")
        if mesh.dim not in (2, 3):
            raise ValueError(f"mesh dimension {mesh.dim} is not supported (2 or 3)")
        if (mesh.ne if mesh.comm.size == 1 else mesh.comm.Sum(mesh.ne)) == 0:  # rank 0 of an MPI run holds none
            raise ValueError("Scene.mesh is empty (0 elements): generate it from a geometry with faces (2D) or "
                             "solids (3D), e.g. ngsolve.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=...))")
        if mesh.dim == 3 and self.thickness is not None:
            raise ValueError(f"Scene.thickness = {self.thickness!r} mm is given for a 3D mesh: thickness applies to "
                             "2D (plane strain) meshes only; leave it unset (None) in 3D")
        for name, unit in (("gamma0", "dimensionless"), ("gc_a", "dimensionless"), ("gc_b", "dimensionless"),
                           ("residual_stiffness", "dimensionless"), ("thickness", "mm")):
            if getattr(self, name) is not None:
                check_number(f"Scene.{name}", getattr(self, name), unit)
        if self.order is not None and (isinstance(self.order, bool) or not isinstance(self.order, (int, np.integer))):
            raise TypeError(f"Scene.order must be an integer 1..4 or None, got {type(self.order).__name__} {self.order!r}")
        regions = set(mesh.GetMaterials())
        boundaries = set(mesh.GetBoundaries())
        self._check_patterns(regions)

        def need_region(name, what):
            if not any(re.fullmatch(name, r) for r in regions):
                raise ValueError(f"{what}: unknown region {name!r}; the mesh has regions {sorted(regions)}")

        def need_boundary(name, what):
            if not any(re.fullmatch(name, b) for b in boundaries):
                raise ValueError(f"{what}: unknown boundary {name!r}; the mesh has boundaries {sorted(boundaries)}")

        if not self.materials:
            raise ValueError("Scene.materials is empty: give a Material for every region")
        for r in self.materials:
            need_region(r, "Scene.materials")
            if not isinstance(self.materials[r], Material):
                raise TypeError(f"Scene.materials[{r!r}] must be a Material")
        missing = [r for r in regions if not any(re.fullmatch(k, r) for k in self.materials)]
        if missing:
            raise ValueError(f"Scene.materials: regions {sorted(missing)} have no material")
        if isinstance(self.density, Mapping):
            for r, v in self.density.items():
                need_region(r, "Scene.density")
        rho = self.element_density()
        if rho.size and (not np.all(np.isfinite(rho)) or rho.min() < 0.0 or rho.max() > 1.0):
            raise ValueError(f"Scene.density: rho must lie in [0, 1]; got values in [{rho.min():g}, {rho.max():g}]")
        for r in self.fracture_region_names:
            need_region(r, "Scene.fracture_regions")
        if self.regulariser is not None:
            for r in _names(self.regulariser.regions):
                need_region(r, "Scene.regulariser.regions")
            if self.displacement_order < 2:
                raise ValueError(
                    f"Scene.order = {self.order}: the Hessian regulariser needs displacement order >= 2 "
                    "(it is identically zero on linear elements); use order=2 or None")
        if self.displacement_order < 1 or self.displacement_order > 4:
            raise ValueError(f"Scene.order = {self.order} is outside the allowed range 1..4")
        self._check_conditions(need_boundary)
        if not (0.0 < float(self.gamma0) < 1.0):
            raise ValueError(f"Scene.gamma0 = {self.gamma0!r} is outside the allowed range (0, 1)")
        for name in ("gc_a", "gc_b") + (("thickness",) if mesh.dim == 2 else ()):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"Scene.{name} = {v!r} is outside the allowed range: finite and > 0")
        if not (math.isfinite(self.residual_stiffness) and 0.0 <= self.residual_stiffness < 1.0):
            raise ValueError(f"Scene.residual_stiffness = {self.residual_stiffness!r} is outside the allowed range [0, 1)")
        check_split(self.split, self.formulation, mesh.dim)
        if self.has_fracture:
            self._check_resolution(refine_to)
        return self

    def _check_conditions(self, need_boundary):
        """Supports and loads: names, shapes, values, and no two conditions on one component."""
        mesh, d = self.mesh, self.mesh.dim
        if not self.supports and not any(isinstance(ld, (DisplacementLoad, DisplacementField)) and
                                         not isinstance(ld.boundary, Point) for ld in self.loads):
            raise ValueError("Scene.supports is empty: a scene needs supports (or a displacement load on a boundary)")
        if not self.loads:
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

        for s in self.supports:
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
        for ld in self.loads:
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
                self._check_field(ld, desc, key)
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
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"loads {dup} share a name: give each load its own name (name=...), it names its "
                             "history column force_<name>")
        self.force_load  # a force_from that names no load raises here

    def _check_field(self, ld, desc, key):
        """Shape and finiteness of a DisplacementField on its boundary or vertex, before any solve."""
        mesh, d = self.mesh, self.mesh.dim
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

    def _check_patterns(self, regions):
        """Each mesh region matched by at most one pattern of ``materials`` and of ``density``; every
        pattern a valid regular expression."""
        maps = [("Scene.materials", self.materials)]
        if isinstance(self.density, Mapping):
            maps.append(("Scene.density", self.density))
            for r, v in self.density.items():
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

    def material_of(self, region: str) -> Material:
        for k, m in self.materials.items():
            if re.fullmatch(k, region):
                return m
        raise KeyError(region)

    def element_vertices(self) -> np.ndarray:
        """Vertex numbers (0-based, NGSolve's) of every element: array (mesh.ne, 3) in 2D,
        (mesh.ne, 4) in 3D."""
        ng = self.mesh.ngmesh
        if self.mesh.dim == 2:
            return ng.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
        return ng.Elements3D().NumPy()["nodes"][:, :4].astype(int) - 1

    def element_sizes(self) -> np.ndarray:
        """Longest edge of every element, mm (array of length mesh.ne)."""
        pts = np.asarray(self.mesh.ngmesh.Coordinates())
        nodes = self.element_vertices()
        h = np.zeros(len(nodes))
        k = nodes.shape[1]
        for i in range(k):
            for j in range(i + 1, k):
                h = np.maximum(h, np.linalg.norm(pts[nodes[:, i]] - pts[nodes[:, j]], axis=1))
        return h

    def _check_resolution(self, refine_to: float | None = None):
        mats = self.mesh.GetMaterials()
        idx = np.array([el.index for el in self.mesh.Elements(ngs.VOL)])
        h = self.element_sizes() if refine_to is None else None   # with refine_to the mesh is not judged
        for r in self.fracture_region_names:
            ids = [i for i, m in enumerate(mats) if re.fullmatch(r, m)]
            sel = np.isin(idx, ids)
            if not sel.any():
                continue
            l0 = min(self.material_of(m).l0 for m in mats if re.fullmatch(r, m))
            if refine_to is not None:
                if refine_to > l0 / 2:
                    warnings.warn(
                        f"fracture region {r!r}: the run refines the crack's path to h_crack = {refine_to:.4g} mm, "
                        f"larger than l0/2 = {l0 / 2:.4g} mm; the phase field is not resolved (h_crack <= l0/2, "
                        "ideally l0/4)", ResolutionWarning, stacklevel=3)
                continue
            h_min = float(h[sel].min())
            if h_min > l0 / 2:
                warnings.warn(
                    f"fracture region {r!r}: smallest element {h_min:.4g} mm is larger than l0/2 = {l0 / 2:.4g} mm; "
                    "the phase field is not resolved (refine to h <= l0/2, ideally l0/4, along the crack path)",
                    ResolutionWarning, stacklevel=3)
