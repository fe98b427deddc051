"""Distance between the cracks of two run folders, for example an adaptive run and a run on a
pre-refined mesh of the same study (issue targets: "the crack path within one element").

    python -m benchmarks.crack_paths RUN_A RUN_B [--case NAME] [--threshold 0.9] [--h H]

The crack of a run is the set of vertices of its last snapshot where alpha exceeds
``threshold``. For every crack vertex of A the distance to the nearest crack vertex of B is
taken (mean, 95th percentile, largest, mm; in units of ``h`` when given, the target element
size), and the other way round. A run whose mesh changed keeps one snapshot group per mesh
(``case@k``); the last group holds the last snapshot. Units: mm.
"""
from __future__ import annotations

import argparse
import json

import numpy as np
from scipy.spatial import cKDTree

from ngtmc.report.loading import load_run


def crack_vertices(run_dir, case: str | None = None, threshold: float = 0.9) -> np.ndarray:
    """Coordinates (n, dim), mm, of the vertices of the last snapshot of ``case`` (default: the
    run's first case) in ``run_dir`` where alpha > ``threshold``."""
    meta, _, snaps = load_run(run_dir)
    if not snaps:
        raise SystemExit(f"{run_dir}: no snapshots.npz")
    name = case or meta["cases"][0]["name"]
    groups = [k for k in snaps if k == name or k.startswith(name + "@")]
    if not groups:
        raise SystemExit(f"{run_dir}: no snapshots of case {name!r} (it has {', '.join(sorted(snaps))})")
    last = max(groups, key=lambda k: int(k.partition("@")[2] or 0))
    g = snaps[last]
    alpha = np.asarray(g["alpha"])[-1]
    return np.asarray(g["vertices"])[alpha > threshold]


def distances(a: np.ndarray, b: np.ndarray, h: float | None = None) -> dict:
    """For every point of ``a`` the distance to the nearest of ``b`` (mm): mean, 95th
    percentile, largest (and the largest in units of ``h``)."""
    d, _ = cKDTree(b).query(a)
    out = {"points": len(a), "mean": float(d.mean()), "p95": float(np.percentile(d, 95)), "max": float(d.max())}
    if h:
        out.update({"mean_in_h": out["mean"] / h, "max_in_h": out["max"] / h})
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run_a")
    ap.add_argument("run_b")
    ap.add_argument("--case", default=None)
    ap.add_argument("--threshold", type=float, default=0.9)
    ap.add_argument("--h", type=float, default=None, help="target element size, mm (distances also in units of it)")
    args = ap.parse_args(argv)
    a = crack_vertices(args.run_a, args.case, args.threshold)
    b = crack_vertices(args.run_b, args.case, args.threshold)
    if not len(a) or not len(b):
        raise SystemExit(f"no crack (alpha > {args.threshold}) in {args.run_a if not len(a) else args.run_b}")
    out = {"a_to_b": distances(a, b, args.h), "b_to_a": distances(b, a, args.h)}
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
