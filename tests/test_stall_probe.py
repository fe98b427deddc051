"""benchmarks.stall_probe.analyse: the region shares of a residual and a correction, and the tangent's
eigenvalues nearest below zero, on a small scene whose answers are known (two blocks and a void,
the tangent at rest)."""
from __future__ import annotations

import ngsolve as ngs
import numpy as np
import pytest

import ngtmc
from ngtmc.discrete import to_scipy
from benchmarks.stall_probe import analyse
from scenes import two_blocks


@pytest.fixture(scope="module")
def capture():
    s = ngtmc.Solver(two_blocks(gap=0.3, maxh=0.2, void_maxh=0.08, kbar_r=None, order=1), compile=False)
    s.a_u.AssembleLinearization(s.u.vec)
    n = s.fes_u.ndof
    K = to_scipy(s.a_u.mat, (n, n))
    free = np.asarray(s._free_np, dtype=bool)
    return {"K": K, "free": free, "u": np.zeros(n), "fes": s.fes_u, "solver": s}


def _void_only_vertex(c):
    mesh = c["fes"].mesh
    inside = {v.nr for el in mesh.Elements(ngs.VOL) if el.mat == "void" for v in el.vertices}
    solid = {v.nr for el in mesh.Elements(ngs.VOL) if el.mat != "void" for v in el.vertices}
    return sorted(inside - solid)[0]


def test_a_residual_on_one_void_vertex_is_all_void_and_the_eigenvalues_are_the_tangents(capture):
    c = dict(capture)
    fes = c["fes"]
    v = _void_only_vertex(c)
    dofs = fes.GetDofNrs(ngs.NodeId(ngs.VERTEX, v))
    r = np.zeros(fes.ndof)
    r[dofs[1]] = 1e-3            # N, on the vertex's y dof
    f = np.where(c["free"])[0]
    Kf = c["K"][f][:, f].toarray()
    du = np.zeros(fes.ndof)
    du[f] = -np.linalg.solve(Kf, r[f])
    c.update(r=r, du=du)
    res = analyse(c, eigenvalues=4)
    assert res["residual_shares"] == {"void": 1.0}
    assert res["residual_vertices"][0]["vertex"] == v
    assert res["residual_norm_N"] == pytest.approx(1e-3)
    assert res["linear_residual_N"] < 1e-12
    # the correction spreads, but most of it stays in the soft void
    assert res["correction_shares"]["void"] > 0.5
    # undeformed: det F = 1 everywhere
    for lo, hi in res["det_F_range"].values():
        assert lo == pytest.approx(1.0) and hi == pytest.approx(1.0)
    # the tangent at rest is positive definite: the four eigenvalues nearest -1 are its four lowest
    lowest = np.sort(np.linalg.eigvalsh(0.5 * (Kf + Kf.T)))[:4]
    assert [m["eigenvalue"] for m in res["modes"]] == pytest.approx(list(lowest), rel=1e-8)
    assert all(m["eigenvalue"] > 0 for m in res["modes"])
