"""Region and boundary names: a scene names them by regular expressions (``"beam|band"``, ``".*"``),
matched against the whole name of each mesh region or boundary. The one owner of how a name
specification splits and matches; the scene, its checks, the solver and the runner use it."""
from __future__ import annotations

import re

__all__ = ["region_names", "matches", "regex"]


def region_names(spec) -> list[str]:
    """The names (patterns) of a specification: a string with alternatives joined by "|", a
    sequence of such strings, or None (no name)."""
    if spec is None:
        return []
    if isinstance(spec, str):
        return [s for s in spec.split("|") if s]
    return [s for item in spec for s in region_names(item)]


def regex(names) -> str:
    """One pattern matching any of ``names``."""
    return "|".join(names)


def matches(pattern: str, name: str) -> bool:
    """True where the pattern matches the whole region or boundary name."""
    return re.fullmatch(pattern, name) is not None
