"""One load path of a study run: :class:`Case`."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ngtmc.scene import Scene
from ngtmc.study.contract import StudyError

__all__ = ["Case"]


@dataclass
class Case:
    """One load path of a study run.

    name: case name used in ``history.csv`` and ``metadata.json`` (e.g. ``"main"``).
    label: human-readable label for the report legend.
    scene: an :class:`ngtmc.Scene`, or a zero-argument callable building it (built lazily by the
        runner, so listing the cases of a study is cheap).
    schedule: :class:`ngtmc.Schedule` or a final load in mm.
    control: :class:`ngtmc.AdaptiveStepControl` or None (the Simulation default).
    options: keyword arguments for :class:`ngtmc.Simulation` (e.g. ``scheme="monolithic"``).
    snapshot_loads: loads (mm) at which fields are saved; the runner saves the first accepted step
        at or past each load.
    parameters: case-specific values (e.g. ``{"gamma0": 1e-5}``) recorded in the metadata.
    run: optional ``run(case, out_dir) -> pandas.DataFrame`` for a case that is not an ngtmc
        simulation (e.g. a classical penalty-contact reference); the DataFrame has at least the
        columns ``load`` and ``force``.
    cost: expected cost relative to the study's other cases (dimensionless, default 1): on a
        cluster the costliest cases start first, so that the last one to finish is not a long one
        started late; a serial run keeps the study's order.
    section: 3D only, a plane ``(axis, coordinate)`` such as ``("x", 4.0)`` (mm) through which each
        snapshot also samples alpha on a grid (the crack plane: the report draws the crack front
        there; :mod:`ngtmc.runner.snapshots`). None: no section.
    """

    name: str
    label: str = ""
    scene: Any = None
    schedule: Any = None
    control: Any = None
    options: dict = field(default_factory=dict)
    snapshot_loads: list = field(default_factory=list)
    parameters: dict = field(default_factory=dict)
    run: Callable | None = None
    cost: float = 1.0
    section: tuple | None = None

    def __post_init__(self):
        if not self.label:
            self.label = self.name
        if self.section is not None:
            axis, at = self.section
            if axis not in ("x", "y", "z") or not np.isfinite(float(at)):
                raise StudyError(f"case {self.name!r}: section = {self.section!r} must be (axis, coordinate in mm) with "
                                 "axis 'x', 'y' or 'z'")
        if not (isinstance(self.cost, (int, float)) and not isinstance(self.cost, bool) and self.cost > 0
                and self.cost < float("inf")):
            raise ValueError(f"case {self.name!r}: cost = {self.cost!r} must be a finite number > 0")

    def build_scene(self):
        """The scene, building it if ``scene`` is a callable."""
        if self.scene is None:
            raise ValueError(f"case {self.name!r} has no scene")
        if isinstance(self.scene, Scene):
            return self.scene
        if callable(self.scene):
            self.scene = self.scene()
        return self.scene
