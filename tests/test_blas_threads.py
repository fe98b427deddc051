"""numpy's and scipy's BLAS run on one thread during a step (ngtmc.discrete.blas_threads): the limit
is set inside a step and the adjoint sweep, restored after them, leaves NGSolve's own BLAS alone,
follows NGTMC_BLAS_THREADS, and refuses a bad value with a message that names the variable."""
from __future__ import annotations

import pytest
from threadpoolctl import ThreadpoolController, threadpool_limits

import ngtmc
from ngtmc.discrete import blas_threads

from scenes import tension_bar


def _counts() -> dict:
    """filepath -> threads of every BLAS library threadpoolctl finds."""
    return {lib.filepath: lib.num_threads for lib in ThreadpoolController().lib_controllers if lib.user_api == "blas"}


def _numpy_side(counts: dict) -> dict:
    return {p: n for p, n in counts.items() if "ngsolve" not in p.lower()}


@pytest.fixture
def two_threads():
    """numpy's BLAS on two threads for the test (skipped where it cannot have two)."""
    with threadpool_limits(limits=2, user_api="blas"):
        side = _numpy_side(_counts())
        if not side or min(side.values()) < 2:
            pytest.skip("numpy's BLAS cannot run two threads here")
        yield


@pytest.mark.parametrize("text, expected", [("", 1), ("3", 3), (" 2 ", 2), ("keep", None), ("KEEP", None)])
def test_setting(monkeypatch, text, expected):
    monkeypatch.setenv(blas_threads.ENV, text)
    assert blas_threads.setting() == expected


@pytest.mark.parametrize("text", ["0", "-1", "two", "1.5"])
def test_bad_setting_is_refused(monkeypatch, text):
    monkeypatch.setenv(blas_threads.ENV, text)
    with pytest.raises(ValueError, match="NGTMC_BLAS_THREADS"):
        blas_threads.setting()


def test_limited_sets_numpy_side_and_restores(monkeypatch, two_threads):
    monkeypatch.delenv(blas_threads.ENV, raising=False)
    before = _counts()
    with blas_threads.limited():
        inside = _counts()
    assert set(_numpy_side(inside).values()) == {1}
    for path, n in before.items():
        if "ngsolve" in path.lower():
            assert inside[path] == n, "NGSolve's own BLAS is left to NGSolve"
    assert _counts() == before


def test_keep_leaves_the_counts(monkeypatch, two_threads):
    monkeypatch.setenv(blas_threads.ENV, "keep")
    before = _counts()
    with blas_threads.limited():
        assert _counts() == before


def test_a_step_runs_with_one_blas_thread_and_restores(monkeypatch, two_threads):
    """Inside Simulation.advance (seen from the displacement solve) numpy's BLAS has one thread;
    after the step it has two again."""
    monkeypatch.delenv(blas_threads.ENV, raising=False)
    seen = []
    original = ngtmc.Solver.solve_displacement

    def spy(self, *args, **kwargs):
        seen.append(set(_numpy_side(_counts()).values()))
        return original(self, *args, **kwargs)

    monkeypatch.setattr(ngtmc.Solver, "solve_displacement", spy)
    sim = ngtmc.Simulation(tension_bar(), 1e-3, scheme="single-pass", progress=False)
    sim.advance()
    assert seen and all(s == {1} for s in seen)
    assert set(_numpy_side(_counts()).values()) == {2}
