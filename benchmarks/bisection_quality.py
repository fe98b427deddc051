"""Shape of bisected elements, and what netgen's 2D mesh optimisation makes of them.

The quick three-point-bending mesh with its band generated at ``--h-band`` (mm), the band's
elements bisected ``--levels`` times by NGSolve (``mesh.Refine()`` with marks), then the whole
mesh optimised by netgen (``ngmesh.OptimizeMesh2d``) with each strategy of ``--strategies``
(netgen's letters: ``m`` moves nodes, ``s`` swaps edges; the counts of vertices and elements stay).
Prints the band's median and 5th-percentile shape quality (4 sqrt(3) area / sum of squared edges,
1 for an equilateral triangle) and the largest vertex move (mm). docs/adaptivity.md.

    python -m benchmarks.bisection_quality --h-band 0.048 --levels 2 --strategies m smsmsm
"""
from __future__ import annotations

import argparse

import numpy as np


def band_quality(mesh, region: str = "band") -> tuple[float, float, int]:
    """(median, 5th percentile, count) of the shape quality of the triangles of ``region``."""
    import ngsolve as ngs
    X = np.asarray(mesh.ngmesh.Coordinates())[:, :2]
    P = np.array([X[[v.nr for v in el.vertices]] for el in mesh.Elements(ngs.VOL) if el.mat == region])
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    edges = sum(np.sum((P[:, i] - P[:, j]) ** 2, axis=1) for i, j in ((0, 1), (1, 2), (0, 2)))
    q = 4 * np.sqrt(3) * area / edges
    return float(np.median(q)), float(np.percentile(q, 5)), len(q)


def main(argv=None):
    import netgen.meshing as nm
    import ngsolve as ngs
    from ngtmc.studies import three_point_bending as tpb
    from ngtmc.study import study_parameters
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h-band", type=float, default=0.048, help="band element size before bisection, mm")
    ap.add_argument("--levels", type=int, default=2, help="bisections of the band's elements")
    ap.add_argument("--strategies", nargs="+", default=["m", "smsmsm"], help="netgen optimize2d strings")
    a = ap.parse_args(argv)
    _, p = study_parameters(tpb, "quick", {"h_band": a.h_band})
    print(f"{'mesh':<34} {'median':>7} {'5th pct':>7} {'band elements':>13} {'max move mm':>11}")
    mesh = tpb.build_mesh(p)
    print(f"{'generated at h_band':<34} {band_quality(mesh)[0]:7.3f} {band_quality(mesh)[1]:7.3f} {band_quality(mesh)[2]:13d}")
    for _ in range(a.levels):
        for el in mesh.Elements(ngs.VOL):
            mesh.SetRefinementFlag(el, el.mat == "band")
        mesh.Refine()
    med, p5, n = band_quality(mesh)
    print(f"{f'bisected {a.levels} times':<34} {med:7.3f} {p5:7.3f} {n:13d}")
    saved = mesh.ngmesh.Copy() if hasattr(mesh.ngmesh, "Copy") else None
    for strategy in a.strategies:
        ngm = saved.Copy() if saved is not None else mesh.ngmesh
        X0 = np.asarray(ngm.Coordinates()).copy()
        ngm.OptimizeMesh2d(nm.MeshingParameters(optimize2d=strategy, optsteps2d=3))
        m2 = ngs.Mesh(ngm)
        med, p5, n = band_quality(m2)
        move = float(np.abs(np.asarray(ngm.Coordinates()) - X0).max())
        print(f"{f'then optimize2d={strategy!r}':<34} {med:7.3f} {p5:7.3f} {n:13d} {move:11.4f}")


if __name__ == "__main__":
    main()
