"""Checkpoints of the cases of a run: two generations per case, written atomically, read back with
a fall-back to the older generation when the newer cannot be read; on MPI ranks one file per rank
(the format: ``docs/run-directory.md``, "checkpoint/")."""
from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np

from ngtmc.study import CheckpointWarning, write_npz

__all__ = ["CheckpointStore"]


class CheckpointStore:
    """Checkpoints of the cases of one run, two generations each, in ``folder``.

    ``save`` moves ``<case>.npz`` to ``<case>.prev.npz`` and writes the new ``<case>.npz``;
    ``load`` returns the newest generation that ``decode`` accepts. ``rank`` = (rank, size): the
    checkpoints of one MPI rank of a run on ``size`` ranks, ``<case>.rank<r>of<size>.npz`` (each
    rank holds its own part of the fields).
    """

    def __init__(self, folder: Path, rank: tuple[int, int] | None = None):
        self.folder = Path(folder)
        self.rank = rank

    def stem(self, case: str) -> str:
        return case if self.rank is None else f"{case}.rank{self.rank[0]}of{self.rank[1]}"

    def files(self, case: str) -> list[Path]:
        """Newest first: ``<case>.npz``, ``<case>.prev.npz`` (with the rank's tag on MPI ranks)."""
        stem = self.stem(case)
        return [self.folder / f"{stem}.npz", self.folder / f"{stem}.prev.npz"]

    def other_layouts(self, case: str) -> set[int]:
        """Numbers of MPI ranks (0: a serial run) of the checkpoints of ``case`` in the folder that
        this store does not read: a run is resumed on the layout it was written on."""
        found = set()
        for f in self.folder.glob(f"{case}.*npz"):
            m = re.fullmatch(re.escape(case) + r"\.rank\d+of(\d+)(\.prev)?\.npz", f.name)
            n = int(m.group(1)) if m else (0 if f.name in (f"{case}.npz", f"{case}.prev.npz") else None)
            if n is not None and n != (0 if self.rank is None else self.rank[1]):
                found.add(n)
        return found

    def save(self, case: str, arrays: dict):
        """Write a new generation of the checkpoint of ``case`` (the previous one is kept)."""
        cur, prev = self.files(case)
        self.folder.mkdir(parents=True, exist_ok=True)
        if cur.exists():
            os.replace(cur, prev)
        write_npz(cur, arrays)

    def load(self, case: str, decode) -> dict | None:
        """``decode(arrays)`` of the newest readable generation of ``case``, or None if there is none.

        A file that ``np.load`` or ``decode`` rejects (truncated, garbage, missing keys) is named in
        a :class:`CheckpointWarning` and moved aside to ``<file>.corrupt``; the older generation is
        tried next."""
        return next(iter(self.readable(case, decode)), None)

    def readable(self, case: str, decode):
        """``decode(arrays)`` of the readable generations of ``case``, newest first, one by one (a
        generator: unreadable files are moved aside, as in :meth:`load`, when they are reached)."""
        for f in self.files(case):
            if not f.exists():
                continue
            try:
                with np.load(f, allow_pickle=False) as z:
                    arrays = {k: z[k] for k in z.files}
                ck = decode(arrays)
            except Exception as e:
                bad = f.with_name(f.name + ".corrupt")
                try:
                    os.replace(f, bad)
                    where = f"moved to {bad.name}"
                except OSError:
                    where = "left in place"
                warnings.warn(f"checkpoint {f} cannot be read ({type(e).__name__}: {e}); {where}, "
                              "using the older generation or re-running the case", CheckpointWarning, stacklevel=3)
                continue
            yield ck
