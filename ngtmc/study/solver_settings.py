"""The solver settings every named study exposes next to its physics (:data:`SOLVER_PARAMETERS`:
scheme, compiled energies, adaptive refinement, early stop) and the keywords of
:class:`ngtmc.Simulation` they make (:func:`simulation_options`). Units: mm."""
from __future__ import annotations

from ngtmc.adapt import Adaptivity
from ngtmc.simulation import SCHEMES, check_stop_after_drop
from ngtmc.study.contract import StudyError

__all__ = ["SOLVER_PARAMETERS", "simulation_options"]

#: Solver settings a study exposes next to its physics (``**SOLVER_PARAMETERS`` in PARAMETERS):
#: name -> (default, unit, description). They change cost and, for ``scheme``, the time
#: discretisation, never the model.
SOLVER_PARAMETERS = {
    "scheme": ("single-pass", "-", "solution scheme of a load step: 'single-pass' (paper), 'staggered', 'monolithic' or "
                                   "'path-following' (monolithic with dissipation control where the crack grows)"),
    "compile": ("auto", "-", "energy expressions: 'real' (generated C++, about 3x faster assembly, about 3.4 s to compile per expression; "
                             "falls back to 'symbolic' without a C++ compiler), 'symbolic', 'none', or 'auto' "
                             "('real' on meshes of 5000 elements or 10000 displacement dofs or more)"),
    "h_crack": (0.0, "mm", "adaptive refinement during the run (ngtmc.Adaptivity): target element size where the crack "
                           "is or is about to be, for example l0/4; 0: none (the mesh as the resolution gives it)"),
    "amr_lookahead": ("auto", "mm", "with h_crack: elements within this distance of those the indicator marks are refined "
                                    "too (Adaptivity.buffer_length), so that a running crack tip stays on the fine mesh "
                                    "for several steps; 'auto': the larger of 2 l0 and 3 h_crack in 2D (ngtmc.adapt.LOOKAHEAD_L0, LOOKAHEAD_H), none in 3D; 0: none"),
    "amr_corridor": ("auto", "mm", "with h_crack: half width of a corridor refined along the crack's path ahead of "
                                   "its front at the first refinement after the crack starts to run (the force below 0.95 of its peak; "
                                   "Adaptivity.corridor), so that the crack runs with fewer refinements; 'auto': 4 l0 "
                                   "(ngtmc.adapt.CORRIDOR_L0) in 2D, none in 3D; 0: none"),
    "amr_h_void": (0.0, "mm", "with h_crack: target element size in the void where it is squeezed (J < 0.5; "
                              "Adaptivity.h_void); 0: the void is not refined"),
    "amr_size_tolerance": (1.0, "-", "with h_crack: elements are refined while their longest edge exceeds this times "
                                     "their target (Adaptivity.size_tolerance; 1: the target is a strict bound, and "
                                     "sizes end between half the target and the target; 1.41: centred on it)"),
    "amr_remesh_maxh": ("auto", "mm", "with h_crack: refine by generating a new mesh from the geometry (ngtmc.adapt.remesh) "
                                      "instead of NGSolve's bisection; the global maxh the study's mesh is generated with "
                                      "(checked: the geometry meshed with it must give the study's mesh again); 'auto': "
                                      "remeshing with the maxh the study states for its 2D mesh (the three-point bending, "
                                      "the L-panel), else bisection; 0: bisection"),
    "amr_history_fraction": (1.0, "-", "with h_crack: elements whose history H reaches this fraction of H_c = Gc / (6 l0) "
                                       "(the level at which AT-2 peaks; Adaptivity.history_fraction) are refined, in "
                                       "(0, 1]; lower refines earlier, before the crack starts"),
    "amr_buffer": (1, "-", "with h_crack: layers of neighbours (sharing a vertex) refined with each element the "
                           "indicator marks (Adaptivity.buffer, an integer >= 0)"),
    "stop_after_drop": (0.0, "-", "stop each case once its force has fallen below this fraction of its peak, after "
                                  "the peak (the crack has run; Simulation.stop_after_drop); 0: the whole schedule"),
}
_COMPILE = {"real": "real", "symbolic": True, "none": False, "auto": "auto"}


def simulation_options(p: dict, mesh_maxh: float | None = None) -> dict:
    """Keyword arguments of :class:`ngtmc.Simulation` from the solver settings in ``p``
    (see SOLVER_PARAMETERS); raises StudyError on an unknown value. ``mesh_maxh`` (mm): the
    global maxh the study generates its 2D mesh with, which ``amr_remesh_maxh = "auto"`` remeshes
    with (None: the study's mesh cannot be remeshed, "auto" bisects)."""
    scheme = p.get("scheme", SOLVER_PARAMETERS["scheme"][0])
    compile_ = p.get("compile", SOLVER_PARAMETERS["compile"][0])
    if scheme not in SCHEMES:
        raise StudyError(f"scheme = {scheme!r} is not one of {', '.join(SCHEMES)}")
    if compile_ not in _COMPILE:
        raise StudyError(f"compile = {compile_!r} is not one of {', '.join(_COMPILE)}")
    out = {"scheme": scheme, "compile": _COMPILE[compile_]}
    drop = p.get("stop_after_drop", SOLVER_PARAMETERS["stop_after_drop"][0])
    if not (isinstance(drop, (int, float)) and not isinstance(drop, bool) and drop == 0):
        try:
            check_stop_after_drop(drop)
        except (TypeError, ValueError) as e:
            raise StudyError(f"{e}; as a study setting, 0 runs the whole schedule") from None
        out["stop_after_drop"] = float(drop)
    h_crack = p.get("h_crack", SOLVER_PARAMETERS["h_crack"][0])
    try:
        h_crack = float(h_crack)
    except (TypeError, ValueError):
        raise StudyError(f"h_crack = {h_crack!r} must be a length in mm (0: no adaptive refinement)") from None
    if h_crack < 0 or h_crack != h_crack:
        raise StudyError(f"h_crack = {h_crack!r} mm must be >= 0 (0: no adaptive refinement)")
    corridor = _auto_or_length(p, "amr_corridor", "a half width in mm (0: none)")   # checked whether refinement is on or not
    if h_crack > 0:
        maxh = _auto_or_length(p, "amr_remesh_maxh", "a global maxh in mm (0: bisection)")
        if maxh == "auto":
            maxh = float(mesh_maxh) if mesh_maxh is not None else 0.0
        lookahead = _auto_or_length(p, "amr_lookahead", "a distance in mm (0: none)")
        try:
            h_void = float(p.get("amr_h_void", 0.0))
            out["adapt"] = Adaptivity(h_crack=h_crack, buffer_length=lookahead, corridor=corridor,
                                      h_void=h_void if h_void > 0 else None,
                                      size_tolerance=float(p.get("amr_size_tolerance", 1.0)),
                                      history_fraction=float(p.get("amr_history_fraction", 1.0)),
                                      buffer=p.get("amr_buffer", 1),
                                      remesh_maxh=maxh if maxh > 0 else None)
        except (TypeError, ValueError) as e:
            raise StudyError(str(e)) from None
    return out


def _auto_or_length(p: dict, key: str, what: str):
    """The setting ``key`` of ``p`` (default: SOLVER_PARAMETERS): "auto", or a number as a float;
    StudyError naming ``what`` it must be otherwise."""
    value = p.get(key, SOLVER_PARAMETERS[key][0])
    if value == "auto":
        return value
    try:
        return float(value)
    except (TypeError, ValueError):
        raise StudyError(f"{key} = {value!r} must be 'auto' or {what}") from None
