"""Adaptive refinement against a pre-refined band: the single-edge-notched plate of tests/scenes.py.

    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py amr        # coarse mesh + Adaptivity
    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py band       # band pre-refined to h_crack
    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py uniform    # whole plate at h_crack

Plate 1 x 1 mm, slit to x = 0.3 at y = 0.5, E = 210e3 MPa, nu = 0.3, Gc = 2.7 N/mm, l0 = 0.05 mm,
top pulled in y to 0.009 mm; single-pass scheme, AdaptiveStepControl(du_max=5e-4, k_u=100,
du_min=1e-7). Prints one JSON line: peak force (N/mm), load at the peak (mm), steps, dofs and
elements at the peak and at the end, wall time (s), and where the crack ran (mean y of the
vertices with alpha > 0.9 between x = 0.4 and 0.9, mm).
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import ngtmc  # noqa: E402
from scenes import notched_plate  # noqa: E402

L0 = 0.05
H_CRACK = L0 / 4
COARSE = 0.1


def crack_height(solver) -> float:
    """Mean y (mm) of the vertices with alpha > 0.9 and 0.4 < x < 0.9 (NaN if none)."""
    mesh = solver.mesh
    pts = np.asarray(mesh.ngmesh.Coordinates())
    import ngsolve as ngs
    ys = []
    a = solver.alpha.vec.FV().NumPy()
    for v in range(mesh.nv):
        x, y = pts[v, :2]
        if 0.4 < x < 0.9:
            d = solver.fes_a.GetDofNrs(ngs.NodeId(ngs.VERTEX, v))
            if d and d[0] >= 0 and a[d[0]] > 0.9:
                ys.append(y)
    return float(np.mean(ys)) if ys else float("nan")


def main(kind: str, **adapt_kw):
    if kind == "amr":
        scene = notched_plate(maxh=COARSE, h_band=COARSE, l0=L0)
        adapt = ngtmc.Adaptivity(h_crack=H_CRACK, **adapt_kw)
    elif kind == "band":
        scene = notched_plate(maxh=COARSE, h_band=H_CRACK, l0=L0)
        adapt = None
    elif kind == "uniform":
        scene = notched_plate(maxh=H_CRACK, h_band=H_CRACK, l0=L0)
        adapt = None
    else:
        raise SystemExit(f"unknown kind {kind!r}: amr, band or uniform")
    ctrl = ngtmc.AdaptiveStepControl(du_max=5e-4, k_u=100.0, du_min=1e-7)
    t0 = time.perf_counter()
    sim = ngtmc.Simulation(scene, 0.009, ctrl, adapt=adapt, compile=True)
    res = sim.run()
    wall = time.perf_counter() - t0
    h = res.history
    i = int(np.argmax(h["force"].to_numpy()))
    s = res.solver
    dofs = lambda: s.fes_u.ndof + s.fes_a.ndof
    out = {"kind": kind, "peak_force": float(h["force"].iloc[i]), "peak_load": float(h["load"].iloc[i]),
           "steps": int(len(h) - 1), "newton_iterations": int(h["newton_iterations"].sum()),
           "dofs_at_peak": int(h["dofs"].iloc[i]) if "dofs" in h else dofs(),
           "elements_at_peak": int(h["elements"].iloc[i]) if "elements" in h else s.mesh.ne,
           "dofs_end": dofs(), "elements_end": s.mesh.ne, "wall_time_s": round(wall, 1),
           "final_force": float(h["force"].iloc[-1]), "crack_y": crack_height(s),
           "refinements": len(sim.refinements), "adapt": adapt_kw}
    print(json.dumps(out), flush=True)
    return out


if __name__ == "__main__":
    kw = {}
    for arg in sys.argv[2:]:
        k, v = arg.split("=")
        kw[k] = float(v) if "." in v or "e" in v else int(v)
    main(sys.argv[1], **kw)
