"""Supports and loads of a scene: where the displacement is held or imposed, and where a traction
acts, on named boundaries or at single mesh vertices (:class:`Point`), all driven by the scene's
one load parameter lambda.

:class:`Support` holds components; :class:`DisplacementLoad` imposes lambda times a direction;
:class:`DisplacementField` imposes a field of x and lambda; :class:`Traction` applies lambda times
a traction. :class:`ngtmc.scene.scene.Scene` takes them; :mod:`ngtmc.discrete.boundary_conditions` turns them
into dofs, values and reactions.

Units: mm (displacements, coordinates), MPa (tractions), lambda in mm (or the scene's load unit).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import re

import numpy as np
import ngsolve as ngs


__all__ = ["Point", "Support", "DisplacementLoad", "DisplacementField", "Traction", "LOAD_KINDS"]

_DIRECTIONS = {"x": (0, 1.0), "-x": (0, -1.0), "y": (1, 1.0), "-y": (1, -1.0), "z": (2, 1.0), "-z": (2, -1.0)}


@dataclass(frozen=True)
class Point:
    """One vertex of the mesh, where a support or a displacement load may act instead of a boundary.

    name: a named point of the geometry (netgen names vertices: in OCC, ``shape.vertices...name =
    "tip"``; a 2D mesh lists them in ``mesh.GetBBoundaries()``, a 3D mesh in
    ``mesh.GetBBBoundaries()``); or near: a coordinate (mm, one number per mesh dimension), the
    vertex nearest to it is taken. Give exactly one of the two.
    """

    name: str | None = None
    near: tuple | None = None

    def __post_init__(self):
        if (self.name is None) == (self.near is None):
            raise ValueError(f"Point(name={self.name!r}, near={self.near!r}): give exactly one of name or near")
        if self.near is not None:
            try:
                near = tuple(float(v) for v in self.near)
            except (TypeError, ValueError):
                raise ValueError(f"Point near = {self.near!r} must be a coordinate (numbers, mm)") from None
            if not all(math.isfinite(v) for v in near):
                raise ValueError(f"Point near = {self.near!r} must be finite")
            object.__setattr__(self, "near", near)

    @property
    def label(self) -> str:
        """Short name used in messages and default load names."""
        if self.name is not None:
            return self.name
        return "point_" + "_".join(f"{v:g}" for v in self.near)

    def __str__(self):
        return f"Point({self.name!r})" if self.name is not None else f"Point(near={self.near})"

    def vertex(self, mesh: ngs.Mesh) -> int:
        """Vertex number of this point in ``mesh``; ValueError naming the point if there is none."""
        d = mesh.dim
        if self.near is not None:
            if len(self.near) != d:
                raise ValueError(f"{self}: the coordinate has {len(self.near)} entries; the mesh is {d}D")
            pts = np.asarray(mesh.ngmesh.Coordinates())[:, :d]
            return int(np.argmin(np.linalg.norm(pts - np.asarray(self.near), axis=1)))
        vb = ngs.BBND if d == 2 else ngs.BBBND
        names = mesh.GetBBoundaries() if d == 2 else mesh.GetBBBoundaries()
        for el in mesh.Elements(vb):
            if el.mat == self.name:
                return int(el.vertices[0].nr)
        named = sorted({n for n in names if n and n != "default"})
        raise ValueError(f"{self}: unknown point name {self.name!r}; the mesh has named points {named}")


def _where(b) -> str:
    return str(b) if isinstance(b, Point) else repr(b)


_LETTERS = "xyz"


@dataclass(frozen=True)
class Support:
    """Zero displacement of the chosen components on a named boundary or at one vertex.

    boundary: boundary name (a regular expression, several joined by "|"), or a :class:`Point`;
    x, y, z: which components are held.
    """

    boundary: str | Point
    x: bool = False
    y: bool = False
    z: bool = False

    def __post_init__(self):
        for c in "xyz":
            if not isinstance(getattr(self, c), (bool, np.bool_)):
                raise TypeError(f"Support on {_where(self.boundary)}: {c} = {getattr(self, c)!r} must be True or False")

    def components(self) -> list[int]:
        return [i for i, held in enumerate((self.x, self.y, self.z)) if held]


def _default_name(boundary) -> str:
    label = boundary.label if isinstance(boundary, Point) else str(boundary)
    return re.sub(r"\W+", "_", label).strip("_") or "load"


@dataclass(frozen=True)
class DisplacementLoad:
    """Displacement imposed uniformly on a named boundary (or a :class:`Point`) in a coordinate direction.

    boundary: boundary name or Point; direction: one of "x", "-x", "y", "-y", "z", "-z" (the load
    value, mm, is the displacement along this direction, and the recorded force is the reaction in
    this direction, N, positive when it resists the imposed motion); hold_tangential: also hold the
    other components of that boundary at zero (needed for a rigid indenter floating in a soft void,
    whose tangential motion is otherwise a near-singular mode); name: label of the load in the
    history (column ``force_<name>`` when a scene has several loads), default the boundary name.
    The simple case of :class:`DisplacementField` (field = sign e_direction, one component).
    """

    boundary: str | Point
    direction: str = "-y"
    hold_tangential: bool = False
    name: str | None = None

    def __post_init__(self):
        if not isinstance(self.direction, str) or self.direction not in _DIRECTIONS:
            raise ValueError(f"DisplacementLoad direction = {self.direction!r} is not one of {sorted(_DIRECTIONS)}")
        if not isinstance(self.hold_tangential, (bool, np.bool_)):
            raise TypeError(f"DisplacementLoad on {_where(self.boundary)}: hold_tangential = {self.hold_tangential!r} "
                            "must be True or False")

    @property
    def component(self) -> int:
        return _DIRECTIONS[self.direction][0]

    @property
    def sign(self) -> float:
        return _DIRECTIONS[self.direction][1]

    @property
    def label(self) -> str:
        """The load's name in the history (``name``, default from the boundary)."""
        return self.name if self.name is not None else _default_name(self.boundary)

    def held_components(self, dim: int) -> list[int]:
        """Components this load prescribes (the loaded one, and the others with hold_tangential)."""
        return list(range(dim)) if self.hold_tangential else [self.component]


@dataclass(frozen=True)
class DisplacementField:
    """Displacement prescribed as a field of the position and the load parameter lambda (mm).

    boundary: boundary name (regular expression) or a :class:`Point`.
    field: either an NGSolve CoefficientFunction of ``ngsolve.x, y(, z)`` with one entry per mesh
    dimension, the displacement (mm) per unit lambda: u_D = lambda * field; or a Python callable
    ``f(x, y, lam)`` (2D) / ``f(x, y, z, lam)`` (3D) returning the displacement (mm) as a sequence
    of one entry per mesh dimension; it is called with numpy arrays of coordinates (mm) and a float
    lambda and must accept them (use ``np.cos``, not ``math.cos``). A callable may depend on lambda
    in any way (a rigid rotation by theta = c lambda: ``(R(theta) - I) X``); it is interpolated at
    the vertices and edge midpoints of the boundary (exact for fields quadratic in the position,
    an approximation for displacement order 3 and 4). A CoefficientFunction is projected on the
    boundary at the displacement order.
    components: which components are prescribed, e.g. "xy", "x" (default every component of the
    mesh); the others stay free and the field's entries there are ignored.
    name: label in the history (``force_<name>``), default from the boundary.

    The recorded force of the load is the reaction conjugate to lambda: sum over the prescribed
    dofs of the residual (N) times d u_D / d lambda, the rate of the external work per unit
    lambda. Its unit is N times that of d u_D / d lambda: N where lambda is a displacement in mm
    and the field a dimensionless direction (a CoefficientFunction field such as ``CF((1, 0))``,
    or a callable whose entries grow like lambda mm), N mm where lambda is dimensionless and the
    field in mm (a rotation by theta = c lambda: the force is then the moment about the axis
    times c, N mm per unit lambda). For the uniform case, the reaction along the direction, N.
    (In 2D, per the scene's thickness as every force.)
    """

    boundary: str | Point
    field: object
    components: str | None = None
    name: str | None = None

    def __post_init__(self):
        if self.components is not None:
            c = self.components
            if not isinstance(c, str) or not c or any(ch not in _LETTERS for ch in c) or len(set(c)) != len(c):
                raise ValueError(f"DisplacementField on {_where(self.boundary)}: components = {c!r} must be letters "
                                 "out of 'xyz', each at most once, e.g. 'xy'")
        if not (isinstance(self.field, ngs.CoefficientFunction) or callable(self.field)):
            raise TypeError(f"DisplacementField on {_where(self.boundary)}: field must be an ngsolve "
                            f"CoefficientFunction or a callable (x, y[, z], lam), got {type(self.field).__name__}")

    @property
    def label(self) -> str:
        return self.name if self.name is not None else _default_name(self.boundary)

    @property
    def is_callable(self) -> bool:
        """True for a Python callable (evaluated at each load), False for a CoefficientFunction."""
        return not isinstance(self.field, ngs.CoefficientFunction)

    def held_components(self, dim: int) -> list[int]:
        if self.components is None:
            return list(range(dim))
        return sorted(_LETTERS.index(ch) for ch in self.components)

    def values(self, points: np.ndarray, lam: float, dim: int) -> np.ndarray:
        """Displacement (mm) of the field at ``points`` (n x dim, mm) and load ``lam``, shape (dim, n).
        ValueError naming the load for a wrong shape or a value that is not finite."""
        pts = np.asarray(points, dtype=float).reshape(-1, dim)
        where = f"DisplacementField {self.label!r} on {_where(self.boundary)}"
        if self.is_callable:
            try:
                out = self.field(*[pts[:, i].copy() for i in range(dim)], float(lam))
            except Exception as e:
                raise ValueError(f"{where}: calling the field with {dim} coordinate arrays and lam failed ({e})") from e
            n = len(pts)
            try:
                comps = list(out)
            except TypeError:
                comps = None
            if comps is None or len(comps) != dim:
                shape = np.shape(out) if comps is not None else type(out).__name__
                raise ValueError(f"{where}: the callable returned {shape}; expected {dim} components "
                                 f"(a sequence of {dim} numbers or arrays for a {dim}D mesh)")
            try:
                out = np.stack([np.broadcast_to(np.asarray(c, dtype=float), (n,)) for c in comps])
            except (TypeError, ValueError):
                raise ValueError(f"{where}: each of the {dim} components returned must be a number or an array "
                                 f"of one value per point ({n} points), got shapes {[np.shape(c) for c in comps]}") from None
        else:
            raise TypeError("values() is for callable fields")
        if not np.all(np.isfinite(out)):
            bad = int(np.argmax(~np.all(np.isfinite(out), axis=0)))
            raise ValueError(f"{where}: the field is not finite (NaN or inf) at {tuple(float(v) for v in pts[bad])} mm, lam = {lam:g}")
        return out


@dataclass(frozen=True)
class Traction:
    """Prescribed traction (Neumann) on a named boundary, scaled by the load parameter: force control.

    boundary: boundary name (regular expression); traction: the traction vector per unit lambda,
    MPa (a sequence of one number per mesh dimension, or a vector CoefficientFunction of
    ``ngsolve.x, y(, z)``), acting on the reference surface (a dead load); name: label in the
    history, default from the boundary.

    The recorded force of a traction load is the applied force lambda |int t ds| (N, for the scene
    thickness in 2D) and ``displacement_<name>`` its work-conjugate displacement int t.u ds /
    |int t ds| (mm; the mean displacement along a uniform traction). With only tractions the
    schedule's load parameter is this multiplier (the ``load`` column then holds lambda, not a
    length). Force control cannot pass a limit point: a run stops there with a StepFailure that
    says so.
    """

    boundary: str
    traction: object
    name: str | None = None

    @property
    def label(self) -> str:
        return self.name if self.name is not None else _default_name(self.boundary)

    def held_components(self, dim: int) -> list[int]:
        return []

    def vector(self, dim: int) -> ngs.CoefficientFunction:
        """The traction per unit lambda as a CoefficientFunction (MPa); ValueError naming the load if
        it has the wrong shape or is not finite."""
        t = self.traction
        where = f"Traction {self.label!r} on {_where(self.boundary)}"
        if isinstance(t, ngs.CoefficientFunction):
            if t.dim != dim:
                raise ValueError(f"{where}: the traction has {t.dim} components; the mesh is {dim}D")
            return t
        import numbers
        seq = t if isinstance(t, (list, tuple, np.ndarray)) else None
        if seq is None or not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in np.ravel(seq)):
            raise ValueError(f"{where}: traction = {t!r} must be {dim} numbers (MPa) or a CoefficientFunction")
        arr = np.asarray(t, dtype=float)
        if arr.shape != (dim,):
            raise ValueError(f"{where}: traction has shape {arr.shape}; expected ({dim},) for a {dim}D mesh")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{where}: traction = {t!r} is not finite")
        return ngs.CF(tuple(float(v) for v in arr))


#: The load kinds a scene accepts.
LOAD_KINDS = (DisplacementLoad, DisplacementField, Traction)
