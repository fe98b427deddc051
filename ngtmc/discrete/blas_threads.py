"""The threads of numpy's and scipy's BLAS while ngtmc computes.

The Newton loops call BLAS on vectors of the size of the mesh (norms of residuals, dot products
of the bordered system): tens of microseconds of work. A multi-threaded OpenBLAS hands each call
to its threads, which then wait for the cores that NGSolve's own threads hold inside a
``TaskManager`` (or that other processes use): the quick three-point bending on two NGSolve
threads took 129.5 s with numpy's OpenBLAS on two threads and 47.6 s on one, the same 82 steps
and 390 Newton iterations (benchmarks/blas_threads.py; docs/performance.md, "BLAS threads").
So a step runs with the BLAS libraries that numpy and scipy load limited to one thread, and
restored after it; NGSolve's own BLAS (a library under its package) is left to NGSolve's
thread count. The environment variable ``NGTMC_BLAS_THREADS`` sets the limit: a positive
integer, or ``keep`` for the libraries' own counts (default 1).
"""
from __future__ import annotations

from contextlib import nullcontext
import os

__all__ = ["limited", "setting", "ENV", "DEFAULT"]

#: the environment variable of the limit
ENV = "NGTMC_BLAS_THREADS"
#: threads of numpy's and scipy's BLAS during a step where ENV is unset
DEFAULT = 1


def setting() -> int | None:
    """The limit ENV asks for (threads), or None for ``keep``; ValueError for anything else."""
    text = os.environ.get(ENV, "").strip()
    if not text:
        return DEFAULT
    if text.lower() == "keep":
        return None
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise ValueError(f"{ENV}={text!r} must be a positive integer (threads of numpy's and scipy's BLAS "
                         "during a step) or 'keep'")
    return n


def limited():
    """A context manager within which the BLAS libraries loaded by numpy and scipy (not those of
    NGSolve's package) use at most :func:`setting` threads; their counts are restored on exit.
    Nothing is changed for ``keep`` or where threadpoolctl finds no such library."""
    n = setting()
    if n is None:
        return nullcontext()
    from threadpoolctl import ThreadpoolController
    ctl = ThreadpoolController()
    paths = [lib.filepath for lib in ctl.lib_controllers
             if lib.user_api == "blas" and "ngsolve" not in str(lib.filepath).lower()]
    if not paths:
        return nullcontext()
    return ctl.select(filepath=paths).limit(limits=n)
