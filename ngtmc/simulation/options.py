"""The keywords of a run (:class:`ngtmc.Simulation`, :func:`ngtmc.simulate`): which only a run
folder uses, which were removed and what replaced them, and the message for a keyword that is
not taken (naming the public function, the replacement or the nearest valid keyword)."""
from __future__ import annotations

import difflib
import inspect

__all__ = ["RUN_FOLDER_OPTIONS", "REMOVED_OPTIONS", "check_options", "simulation_keywords"]

#: Keywords of :func:`simulate` that only a run folder (``out_dir``) uses.
RUN_FOLDER_OPTIONS = frozenset({"resume", "report", "vtk", "threads", "checkpoint_every", "checkpoint_seconds",
                                "name", "title", "summary", "snapshot_loads", "references", "targets", "section"})

#: Keywords that :class:`Simulation` no longer takes, with what replaced them.
REMOVED_OPTIONS = {
    "staggered": "scheme='staggered' (and staggered_tol, max_staggered)",
    "monolithic": "scheme='monolithic'",
    "path_following": "scheme='path-following'",
    "newton_options": "newton=ngtmc.NewtonOptions(...)",
    "adaptivity": "adapt=ngtmc.Adaptivity(...)",
}


def simulation_keywords(cls) -> list:
    """The keywords of ``cls.__init__`` (a :class:`ngtmc.Simulation`) after the scene and schedule."""
    return [n for n, p in inspect.signature(cls.__init__).parameters.items()
            if n not in ("self", "scene", "schedule") and p.kind is not p.VAR_KEYWORD]


def check_options(options: dict, valid: list, where: str = "ngtmc.Simulation"):
    """Raise TypeError for a keyword of ``options`` not in ``valid``, naming ``where`` (the public
    function called), the replacement of a removed keyword, or the nearest valid one."""
    for key in options:
        if key in valid:
            continue
        if key in REMOVED_OPTIONS:
            raise TypeError(f"{where}: the keyword {key!r} was removed; use {REMOVED_OPTIONS[key]}")
        near = difflib.get_close_matches(key, valid + sorted(RUN_FOLDER_OPTIONS), n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise TypeError(f"{where}: unknown keyword {key!r}{hint} (it takes {', '.join(valid)}"
                        + (", and with out_dir: " + ", ".join(sorted(RUN_FOLDER_OPTIONS | {'callbacks'})) + ")"
                           if where == "ngtmc.simulate" else ")"))
