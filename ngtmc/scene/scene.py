"""Scenes: what is simulated, independent of how it is solved.

A :class:`Scene` names a mesh with regions and boundaries, the material and pseudo-density of each
region, where fracture may happen, where the third-medium regulariser acts, the supports and the
loads (:class:`DisplacementLoad`, :class:`DisplacementField`, :class:`Traction`; on boundaries or
at :class:`Point` vertices; defined in :mod:`ngtmc.scene.conditions`), all driven by one load parameter
lambda. The solver builds only
what a scene needs: order-1 displacement when no regulariser acts, no phase-field unknowns when
no region may break, no contact medium when no region has density below one.

Units: mm, N, MPa. A 2D mesh is plane strain with out-of-plane ``thickness`` (mm); forces and
energies are reported for that thickness.

The validation of a scene (:meth:`Scene.check`) lives in :mod:`ngtmc.scene.checks`.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Mapping, Sequence

import numpy as np
import ngsolve as ngs

from ngtmc.scene.regions import Regions, element_sizes, element_vertices, matches, regex, region_names
from ngtmc.scene.warnings import ElementWarning, ResolutionWarning  # noqa: F401  (re-exported)
from ngtmc.scene.conditions import DisplacementField, DisplacementLoad, Point, Support, Traction  # noqa: F401
from ngtmc.model import Material, check_number
from ngtmc.model import DEFAULT_FORMULATION, DEFAULT_SPLIT, check_split
from ngtmc.scene.checks import check_scene
from ngtmc.scene.distributed import Ranks

__all__ = ["Support", "DisplacementLoad", "DisplacementField", "Traction", "Point", "Regulariser", "Scene",
           "ResolutionWarning", "ElementWarning"]

@dataclass(frozen=True)
class Regulariser:
    """Hessian regularisation of the third medium (Eq. 3) on the named regions.

    regions: region names where it acts (normally the void), joined by "|" or as a list;
    kbar_r: dimensionless factor (1e-6 in the literature), > 0; length: characteristic length L of
    the structure, mm, > 0; damping: "none" or "exp" (energy density times exp(-5 J), see
    :mod:`ngtmc.model.regularisation`). k_r = kbar_r L^2 K0 with K0 the bulk modulus of the
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
        (see :func:`ngtmc.simulation.history.history_units`).
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
        With ``order=None`` and a regulariser: True puts order 2 only on the elements where the
        regulariser acts (and on all their edges), order 1 everywhere else: fewer dofs, but a
        coarser model of the bodies. Default False (order 2 on every element, the full model):
        on a self-contact of one body (a C-shape closed through its slot, quad-dominated mesh,
        h = 0.1 mm) order 1 in the body moved the final force by 2.7 % and failed before the last
        load at h = 0.05 mm, where order 2 everywhere finished (``benchmarks/results/variable_order.json``);
        on the quick three-point bending it lowers the peak by 1.6 %. Opt in where that is measured
        to be acceptable (the three-point-bending studies do).
    name : str
        Free label used in messages and reports.
    split : str
        Tension/compression split of the elastic energy in the fracture regions, one of
        :data:`ngtmc.model.splits.SPLITS`: "vol-dev-J" (default, the paper's Eq. 6), "vol-dev-small"
        (Amor et al. 2009 on the small strain), "vol-dev-log" (Amor et al. 2009 on the Hencky
        strain; 2D), "spectral" (Miehe et al. 2010; 2D), "none" (see :mod:`ngtmc.model.splits`).
    formulation : str
        Where the split acts, one of :data:`ngtmc.model.splits.FORMULATIONS`: "hybrid" (default, the
        paper's: in the history only) or "anisotropic" (also in the displacement equation: only
        Psi_plus is degraded). The single-pass, staggered and monolithic schemes and the adjoint
        of :mod:`ngtmc.sensitivities` all use the chosen pair.
    scale_check : bool
        Warn (:class:`ngtmc.ScaleWarning`) where E, Gc, l0, the body's size or a point lie outside
        what is plausible in mm, N, MPa (:mod:`ngtmc.scene.scale`; default True). False when the
        numbers are meant.
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
    variable_order: bool = False
    name: str = "scene"
    split: str = DEFAULT_SPLIT
    formulation: str = DEFAULT_FORMULATION
    force_from: str | None = None
    scale_check: bool = True

    def __post_init__(self):
        if isinstance(self.supports, Support):      # one support given without a list
            self.supports = [self.supports]
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
        return region_names(self.fracture_regions)

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
                ids = [i for i, m in enumerate(mats) if matches(region, m)]
                rho[np.isin(idx, ids)] = float(value)
            return rho
        rho = np.asarray(self.density, dtype=float).ravel()
        if rho.shape != (ne,):
            raise ValueError(f"density array has {rho.size} entries; the mesh has {ne} elements (one rho per element expected)")
        return rho

    @property
    def has_void(self) -> bool:
        return Ranks(self.mesh).any(bool(np.any(self.element_density() < 1.0)))

    # ---------------------------------------------------------------- validation
    def check(self, refine_to: float | None = None) -> "Scene":
        """Validate every input; raise ValueError naming the parameter and the allowed range.

        Warns (:class:`ResolutionWarning`) when the smallest element in a fracture region is larger
        than l0/2, or, for a run that refines the crack's path as it goes (``refine_to``, mm: its
        :attr:`ngtmc.Adaptivity.h_crack`), when that size is. Returns the scene."""
        return check_scene(self, refine_to)

    def material_of(self, region: str) -> Material:
        for k, m in self.materials.items():
            if matches(k, region):
                return m
        raise KeyError(region)

    def element_vertices(self) -> np.ndarray:
        """Vertex numbers (0-based, NGSolve's) of every element (:func:`element_vertices`)."""
        return element_vertices(self.mesh)

    def element_sizes(self) -> np.ndarray:
        """Longest edge of every element, mm (array of length mesh.ne; :func:`ngtmc.scene.regions.element_sizes`)."""
        return element_sizes(self.mesh)

    def regions(self) -> Regions:
        """The scene's regions on its mesh as it is now (:class:`~ngtmc.scene.regions.Regions`):
        built again after each refinement of the mesh."""
        mesh = self.mesh
        names = tuple(mesh.GetMaterials())
        index = np.array([el.index for el in mesh.Elements(ngs.VOL)], dtype=int)
        frac = tuple(self.fracture_region_names)
        frac_re = regex(frac)
        materials = {r: self.material_of(r) for r in names}
        reg_re = regex(region_names(self.regulariser.regions)) if self.regulariser is not None else ""
        fracture = np.isin(index, [i for i, m in enumerate(names) if frac_re and matches(frac_re, m)])
        return Regions(names=names, index=index, density=self.element_density(), materials=materials,
                       fracture_names=frac, fracture_regex=frac_re, fracture=fracture, regulariser_regex=reg_re,
                       sizes=element_sizes(mesh))
