"""The cache of compiled expression code (ngtmc/cxx_cache.py): a second process reuses the object
files of the first, and the compiled expression gives the uncompiled one's numbers."""
import os
import subprocess
import sys
import textwrap

import pytest

from ngtmc import cxx_cache

SCRIPT = textwrap.dedent("""
    import ngsolve as ngs
    from netgen.geom2d import unit_square
    from ngtmc.discretisation import real_compile
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    F = ngs.CF((1 + 0.1 * ngs.x, 0.2 * ngs.y, 0.05 * ngs.x * ngs.y, 1 - 0.1 * ngs.y), dims=(2, 2))
    J = ngs.Det(F)
    psi = 0.5 * (ngs.Trace(F.trans * F) - 2) - ngs.log(J) + 0.3 * ngs.log(J) ** 2
    compiled = real_compile(psi)
    assert compiled is not None
    print(repr(ngs.Integrate(compiled, mesh, order=4)), repr(ngs.Integrate(psi, mesh, order=4)))
""")


def _compile_in_a_new_process(cache):
    env = dict(os.environ, NGTMC_CXX_CACHE=str(cache))
    out = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    compiled, symbolic = (float(v) for v in out.stdout.split())
    entries = {p.name: p.stat().st_mtime_ns for p in (cache / "objects").iterdir()}
    return compiled, symbolic, entries


def test_a_second_process_reuses_the_compiled_code(tmp_path):
    from ngtmc import discretisation
    if discretisation._REAL_COMPILE_FAILED:
        pytest.skip("no C++ compiler here")
    first = _compile_in_a_new_process(tmp_path)
    second = _compile_in_a_new_process(tmp_path)
    assert len(first[2]) == 1 and not any(n.endswith(".tmp") for n in first[2])
    assert second[2] == first[2]  # the same entry, not rewritten: a hit
    for compiled, symbolic, _ in (first, second):
        assert compiled == pytest.approx(symbolic, rel=1e-13)
    assert second[0] == first[0]


def test_the_cache_can_be_turned_off(monkeypatch, tmp_path):
    monkeypatch.setenv("NGTMC_CXX_CACHE", "off")
    assert cxx_cache.cache_dir() is None
    path = [str(tmp_path), "/usr/bin"]
    assert cxx_cache.activate(path) == path
    monkeypatch.setenv("NGTMC_CXX_CACHE", str(tmp_path / "c"))
    assert cxx_cache.cache_dir() == tmp_path / "c"
