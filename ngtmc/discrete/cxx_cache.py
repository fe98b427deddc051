"""A persistent cache of the object files that NGSolve compiles for ``Compile(realcompile=True)``.

NGSolve generates C++ code for a compiled expression and compiles it with its ``ngscxx`` script
(next to the Python executable), then links it with ``ngsld``. It caches the libraries within one
process only, so every new process pays about 5 s of compiler time per expression again: 23 of
the 25 s set-up of the 3D hemisphere study (five expressions), measured.

The code of an expression is the same in every process (the process-specific addresses go to a
second, small source file with no ``#include``, which compiles in about 0.6 s and is not cached). So :func:`activate` puts a small
``ngscxx`` wrapper first on ``PATH``: it looks the object file up by a SHA-256 of the source, the
arguments, the real ``ngscxx`` script and the NGSolve and Python versions, copies it on a hit,
and otherwise runs the real ``ngscxx`` and stores its output (written to a temporary name and
renamed, so that concurrent processes never see half a file).

Where: ``$NGTMC_CXX_CACHE`` if set, else ``$XDG_CACHE_HOME/ngtmc/cxx`` (default
``~/.cache/ngtmc/cxx``). ``NGTMC_CXX_CACHE=off`` turns the cache off. Each entry is one object
file of 1-200 kB after a line of the names of its pointers, written at once (a process never
reads the names of one compilation with the object of another); delete the folder to empty the
cache.

NGSolve names the pointers of an expression's code with a counter of the process (``_POINTER``),
so the same expression compiled again within a run has another text: a remeshed run builds a
new solver, and compiles its five expressions, after every remesh. The key therefore numbers
the pointers by first appearance, and a hit stored under other numbers is renamed
(``objcopy --redefine-sym``). Measured on the quick three-point bending with remeshing, from an
empty cache: a remesh took 45-48 s before (every expression a miss), 5 s after.
"""
from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

__all__ = ["cache_dir", "activate"]

#: the name NGSolve gives the pointers of a compiled expression, followed by a counter of the
#: process: the same expression compiled again in a run (a new solver after each remesh) or in
#: another order has other numbers, so the key numbers them by first appearance, and a hit
#: compiled with other numbers gets its symbols renamed (``objcopy --redefine-sym``, binutils,
#: which the C++ compiler needs anyway); without objcopy such a hit is compiled again
_POINTER = "compiled_code_pointer"

#: the wrapper script's file name, which also marks a folder as a wrapper folder
_SCRIPT = "ngscxx_cache.py"

_SHELL = '''#!/bin/sh
exec "{python}" -I "{script}" "$@"
'''

_WRAPPER = '''# ngtmc's cache of compiled expression code (ngtmc/discrete/cxx_cache.py); runs the real ngscxx on a miss.
import hashlib, json, os, re, shutil, subprocess, sys
real = os.environ.get("NGTMC_REAL_NGSCXX") or {real!r}
args = sys.argv[1:]
if os.path.isfile(os.path.join(os.path.dirname(os.path.abspath(real)), {script_name!r})):
    sys.exit("ngtmc cxx cache: the compiler it would call is a cache wrapper itself (%s)" % real)
try:
    src = args[args.index("-c") + 1]
    obj = args[args.index("-o") + 1]
except (ValueError, IndexError):
    os.execv(real, [real] + args)
with open(src, "rb") as f:
    code = f.read()
if b"#include" not in code:  # the small file of process-specific addresses: never the same twice
    os.execv(real, [real] + args)
# the pointers' names carry a counter of the process: numbered by first appearance for the key
names = []
def number(m):
    if m.group(1) not in names:
        names.append(m.group(1))
    return b"%s#%d" % ({prefix!r}, names.index(m.group(1)))
code = re.sub({prefix!r} + rb"(\\d+)", number, code)
names = [n.decode() for n in names]
key = hashlib.sha256()
with open(real, "rb") as f:
    key.update(f.read())
key.update(os.environ.get("NGTMC_CXX_KEY", "").encode())
key.update(" ".join(a for a in args if a not in (src, obj)).encode())
key.update(code)
# one file per entry, written at once: the pointer names (a JSON line), then the object file
entry = os.path.join({objects!r}, key.hexdigest() + ".entry")
try:
    with open(entry, "rb") as f:
        stored, blob = f.read().split(b"\\n", 1)
    stored = json.loads(stored)
except (OSError, ValueError):
    stored = None
if stored is not None and len(stored) == len(names):
    if stored == names:
        with open(obj, "wb") as f:
            f.write(blob)
        sys.exit(0)
    objcopy = shutil.which("objcopy")
    if objcopy is not None:
        p = {prefix!r}.decode()
        renames = ["--redefine-sym=%s%s=%s%s" % (p, a, p, b) for a, b in zip(stored, names)]
        with open(obj + ".stored", "wb") as f:
            f.write(blob)
        rc = subprocess.call([objcopy] + renames + [obj + ".stored", obj])
        os.remove(obj + ".stored")
        if rc == 0:
            sys.exit(0)
rc = subprocess.call([real] + args)
if rc == 0:
    try:
        tmp = "%s.%d.tmp" % (entry, os.getpid())
        with open(obj, "rb") as f, open(tmp, "wb") as g:
            g.write(json.dumps(names).encode() + b"\\n" + f.read())
        os.replace(tmp, entry)
    except OSError:
        pass
sys.exit(rc)
'''


def cache_dir() -> Path | None:
    """The cache folder, or None when ``NGTMC_CXX_CACHE`` is ``off`` (or ``0``, ``false``, ``no``)."""
    setting = os.environ.get("NGTMC_CXX_CACHE")
    if setting is not None and setting.strip().lower() in ("off", "0", "false", "no", ""):
        return None
    if setting:
        return Path(setting).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "ngtmc" / "cxx"


def activate(path: list[str]) -> list[str]:
    """``path`` (the folders of ``PATH``, NGSolve's scripts folder already in it) with the caching
    ``ngscxx`` wrapper first. Unchanged when the cache is off, the real ``ngscxx`` is not on
    ``path``, or the cache folder cannot be written (the compilation then runs uncached)."""
    folder = cache_dir()
    if folder is None or os.name == "nt":  # on Windows NGSolve calls ngscxx.bat
        return path
    # the real ngscxx: never a wrapper of this or of another cache folder (a process started
    # with NGTMC_CXX_CACHE set elsewhere inherits its parent's PATH, wrapper first)
    kept = [p for p in path if not _is_wrapper_folder(p)]
    real = shutil.which("ngscxx", path=os.pathsep.join(kept))
    if real is None:
        return path
    import hashlib
    import ngsolve
    # one wrapper per interpreter, so that two environments sharing the cache never rewrite it
    bin_dir = folder / "bin" / hashlib.sha256(f"{sys.executable}|{real}".encode()).hexdigest()[:12]
    try:
        (folder / "objects").mkdir(parents=True, exist_ok=True)
        bin_dir.mkdir(parents=True, exist_ok=True)
        script = bin_dir / _SCRIPT
        files = {script: _WRAPPER.format(real=real, objects=str(folder / "objects"), script_name=_SCRIPT,
                                         prefix=_POINTER.encode()),
                 bin_dir / "ngscxx": _SHELL.format(python=sys.executable, script=script)}
        for file, text in files.items():
            if not file.is_file() or file.read_text() != text:
                tmp = file.with_name(f"{file.name}.{os.getpid()}.tmp")
                tmp.write_text(text)
                tmp.chmod(0o755)
                os.replace(tmp, file)
    except OSError:
        return path
    os.environ["NGTMC_REAL_NGSCXX"] = real
    os.environ["NGTMC_CXX_KEY"] = f"ngsolve {ngsolve.__version__}; python {sys.version}"
    return [str(bin_dir)] + kept


def _is_wrapper_folder(folder: str) -> bool:
    """Whether ``folder`` holds a cache wrapper (of any cache folder)."""
    return os.path.isfile(os.path.join(folder, _SCRIPT))
