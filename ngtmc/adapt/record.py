"""The record of one refinement (counts and marked elements), from which a run folder's refinement
is replayed."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RefinementRecord"]


@dataclass
class RefinementRecord:
    """One refinement: elements marked, elements and displacement dofs before and after, and the
    numbers of the marked elements (in the mesh before the refinement), from which
    :func:`~ngtmc.adapt.bisection.replay` makes the same mesh again; ``equilibrium``: whether the state
    before the step is an equilibrium of the new mesh (False where a remesh's carried state found
    none, :func:`ngtmc.adapt.carried_state.equilibrate`; not recorded in the run folder)."""

    marked: int
    elements_before: int
    elements_after: int
    dofs_before: int
    dofs_after: int
    elements: np.ndarray | None = None
    equilibrium: bool = True

    _COUNTS = ("marked", "elements_before", "elements_after", "dofs_before", "dofs_after")

    def as_dict(self) -> dict:
        """The counts (JSON); the marked elements are :attr:`elements`."""
        return {k: int(getattr(self, k)) for k in self._COUNTS}

    @classmethod
    def from_dict(cls, counts: dict, elements: np.ndarray) -> "RefinementRecord":
        """The record of :meth:`as_dict` and its marked elements."""
        return cls(*(int(counts[k]) for k in cls._COUNTS), np.asarray(elements, dtype=np.int64))
