"""Adaptive mesh refinement during a run: the settings (:class:`Adaptivity`, :mod:`ngtmc.adapt.settings`),
which elements to refine (:func:`mark`, :mod:`ngtmc.adapt.marking`), the crack corridor
(:mod:`ngtmc.adapt.corridor`), newest-vertex bisection with the transfer of the state
(:func:`refine`, :mod:`ngtmc.adapt.bisection`), remeshing (:mod:`ngtmc.adapt.remesh`), the state
carried across non-nested meshes (:mod:`ngtmc.adapt.carried_state`) and the record of a refinement
(:class:`RefinementRecord`). docs/adaptivity.md explains when each pays. Units: mm."""
from ngtmc.adapt.bisection import refine, replay, transfer_history
from ngtmc.adapt.marking import mark, targets
from ngtmc.adapt.record import RefinementRecord
from ngtmc.adapt.settings import CORRIDOR_L0, HISTORY_TRANSFERS, LOOKAHEAD_H, LOOKAHEAD_L0, Adaptivity, check_solver, private_scene
from ngtmc.scene import centroids, coordinates

from ngtmc.adapt.corridor import corridor_due, corridor_elements, strip
from ngtmc.adapt.remesh import Remesher, move, remesh_step

__all__ = ["Adaptivity", "CORRIDOR_L0", "HISTORY_TRANSFERS", "LOOKAHEAD_H", "LOOKAHEAD_L0", "mark", "targets", "refine", "replay", "transfer_history",
           "RefinementRecord", "private_scene", "check_solver", "centroids", "coordinates"]
__all__ += ['Remesher', 'corridor_due', 'corridor_elements', 'move', 'remesh_step', 'strip']
