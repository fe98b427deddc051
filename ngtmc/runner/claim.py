"""One run per run folder: a run claims its folder before it writes anything, so that a second run
into the same folder is refused with a message naming the first (two runs started 0.3 s apart
both used to finish, the folder keeping a mix of both).

The claim is the file ``.ngtmc-claim.json`` in the folder, created atomically (``O_CREAT |
O_EXCL``) with the claiming process's id, host and start time, and removed when the run ends,
whatever way it ends. A claim whose process is gone (a run killed with SIGKILL, a machine that
stopped) is stale: the next run takes it over, and says so.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import time

from ngtmc.study import process_alive, process_info
from ngtmc.study import StudyError

__all__ = ["CLAIM_FILE", "FolderInUse", "FolderClaim"]

#: The claim's file name inside a run folder.
CLAIM_FILE = ".ngtmc-claim.json"


class FolderInUse(StudyError):
    """The run folder is claimed by another run that is still alive."""


class FolderClaim:
    """``with FolderClaim(folder):`` the block runs with the folder claimed by this process.

    ``note``: called with one line when a stale claim was taken over (for the run's progress).
    Raises :class:`FolderInUse` naming the claiming run when another live process holds it."""

    def __init__(self, folder, note=None):
        self.folder = Path(folder)
        self.path = self.folder / CLAIM_FILE
        self.note = note
        self._held = False

    def _describe(self, info: dict) -> str:
        started = info.get("started")
        when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(started)) if isinstance(started, (int, float)) else "?"
        return f"process {info.get('pid')} on {info.get('host')}, started {when}"

    def _read(self) -> dict:
        try:
            info = json.loads(self.path.read_text())
            return info if isinstance(info, dict) else {}
        except (OSError, ValueError):
            return {}

    def acquire(self):
        self._created = not self.folder.exists()
        self.folder.mkdir(parents=True, exist_ok=True)
        me = dict(process_info(), started=time.time())
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                info = self._read()
                if not info:                      # being written this instant, or unreadable
                    time.sleep(0.05)
                    info = self._read()
                same_host = info.get("host") == me["host"]
                if info.get("pid") == me["pid"] and same_host:
                    self._held = False            # this process holds it already (a nested run): leave it
                    return self
                if info and (not same_host or process_alive(info.get("pid"))):
                    where = "" if same_host else " (another host: its process cannot be checked from here)"
                    raise FolderInUse(f"{self.folder} is in use by another run: {self._describe(info)}{where}. "
                                      f"Choose another output folder, or wait for that run to end (if it is "
                                      f"gone, delete {self.path})")
                if self.note is not None:
                    self.note(f"{self.folder}: took over the claim of a run that is gone"
                              + (f" ({self._describe(info)})" if info else ""))
                try:
                    self.path.unlink()
                except FileNotFoundError:
                    pass
                continue
            with os.fdopen(fd, "w") as f:
                json.dump(me, f)
            self._held = True
            return self
        raise FolderInUse(f"{self.folder}: could not claim the folder ({self.path} keeps reappearing)")

    def release(self):
        if self._held:
            info = self._read()
            if info.get("pid") == os.getpid():
                try:
                    self.path.unlink()
                except FileNotFoundError:
                    pass
            self._held = False
            if getattr(self, "_created", False):
                try:
                    self.folder.rmdir()           # a run refused before it wrote anything leaves no folder
                except OSError:
                    pass

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()
        return False
