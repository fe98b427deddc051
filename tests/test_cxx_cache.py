"""The cache of compiled expression code (ngtmc/discrete/cxx_cache.py): a second process reuses the object
files of the first, and the compiled expression gives the uncompiled one's numbers."""
import os
import subprocess
import sys
import textwrap

import pytest

from ngtmc.discrete import cxx_cache
SCRIPT = textwrap.dedent("""
    import ngsolve as ngs
    from netgen.geom2d import unit_square
    from ngtmc.discrete.spaces import real_compile
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    F = ngs.CF((1 + 0.1 * ngs.x, 0.2 * ngs.y, 0.05 * ngs.x * ngs.y, 1 - 0.1 * ngs.y), dims=(2, 2))
    J = ngs.Det(F)
    psi = 0.5 * (ngs.Trace(F.trans * F) - 2) - ngs.log(J) + 0.3 * ngs.log(J) ** 2
    import sys
    if len(sys.argv) > 1:   # another expression first: psi's pointers get other numbers
        assert real_compile(ngs.sin(ngs.x) * F[0, 0] + ngs.exp(ngs.y)) is not None
    compiled = real_compile(psi)
    assert compiled is not None
    print(repr(ngs.Integrate(compiled, mesh, order=4)), repr(ngs.Integrate(psi, mesh, order=4)))
""")


def _compile_in_a_new_process(cache, *argv):
    env = dict(os.environ, NGTMC_CXX_CACHE=str(cache))
    out = subprocess.run([sys.executable, "-c", SCRIPT, *argv], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    compiled, symbolic = (float(v) for v in out.stdout.split())
    entries = {p.name: p.stat().st_mtime_ns for p in (cache / "objects").iterdir()}
    return compiled, symbolic, entries


def test_a_second_process_reuses_the_compiled_code(tmp_path):
    from ngtmc.discrete import spaces as discretisation
    if discretisation._REAL_COMPILE_FAILED:
        pytest.skip("no C++ compiler here")
    first = _compile_in_a_new_process(tmp_path)
    second = _compile_in_a_new_process(tmp_path)
    assert len(first[2]) == 1 and all(n.endswith(".entry") for n in first[2])   # one entry, no .tmp left
    assert second[2] == first[2]  # the same entry, not rewritten: a hit
    for compiled, symbolic, _ in (first, second):
        assert compiled == pytest.approx(symbolic, rel=1e-13)
    assert second[0] == first[0]


def test_the_same_expression_compiled_with_other_pointer_numbers_is_a_hit(tmp_path):
    """NGSolve numbers the pointers of a compiled expression with a counter of the process, so the
    same expression compiled after another one has another source text (every remesh compiled
    its solver's five expressions again: 30-45 s per remesh on the quick three-point bending,
    measured). The cache keys on the text with the pointers numbered by first appearance and
    renames the symbols of the stored object; the renamed object gives the same numbers."""
    from ngtmc.discrete import spaces as discretisation
    if discretisation._REAL_COMPILE_FAILED:
        pytest.skip("no C++ compiler here")
    import shutil
    if shutil.which("objcopy") is None:
        pytest.skip("no objcopy here (a hit with other numbers is then compiled again)")
    first = _compile_in_a_new_process(tmp_path)
    second = _compile_in_a_new_process(tmp_path, "other-first")
    added = set(second[2]) - set(first[2])
    assert len(added) == 1 and all(n.endswith(".entry") for n in added)   # the other expression only
    assert all(second[2][n] == first[2][n] for n in first[2])   # psi's entry: read, not written
    assert second[0] == first[0] and second[0] == pytest.approx(second[1], rel=1e-13)


def test_the_cache_can_be_turned_off(monkeypatch, tmp_path):
    monkeypatch.setenv("NGTMC_CXX_CACHE", "off")
    assert cxx_cache.cache_dir() is None
    path = [str(tmp_path), "/usr/bin"]
    assert cxx_cache.activate(path) == path
    monkeypatch.setenv("NGTMC_CXX_CACHE", str(tmp_path / "c"))
    assert cxx_cache.cache_dir() == tmp_path / "c"


def test_a_process_with_another_cache_never_calls_a_wrapper_as_its_compiler(tmp_path, monkeypatch):
    """A child process whose NGTMC_CXX_CACHE differs from its parent's inherits the parent's PATH,
    the parent's wrapper first. Its real ngscxx must still be NGSolve's, not that wrapper: a
    wrapper that calls a wrapper called itself without end (measured: processes until the
    machine ran out of memory)."""
    from ngtmc.discrete import spaces as discretisation
    if discretisation._REAL_COMPILE_FAILED:
        pytest.skip("no C++ compiler here")
    import sysconfig
    scripts = [sysconfig.get_path("scripts"), os.path.dirname(sys.executable)]
    monkeypatch.setenv("NGTMC_CXX_CACHE", str(tmp_path / "parent"))
    parent_path = cxx_cache.activate(list(scripts) + os.environ.get("PATH", "").split(os.pathsep))
    assert os.path.isfile(os.path.join(parent_path[0], "ngscxx_cache.py"))
    monkeypatch.setenv("NGTMC_CXX_CACHE", str(tmp_path / "child"))
    child_path = cxx_cache.activate(parent_path)
    real = os.environ["NGTMC_REAL_NGSCXX"]
    assert not os.path.isfile(os.path.join(os.path.dirname(real), "ngscxx_cache.py")), real
    assert child_path[0].startswith(str(tmp_path / "child")) and parent_path[0] not in child_path
    # and a compilation through the child's PATH terminates, with NGSolve's compiler
    monkeypatch.setenv("PATH", os.pathsep.join(parent_path))
    first = _compile_in_a_new_process(tmp_path / "third")
    assert first[0] == pytest.approx(first[1], rel=1e-13)
