"""Adaptive refinement against a pre-refined band or a uniformly fine mesh, on two scenes of
tests/scenes.py: the single-edge-notched plate in tension (``--scene notched``, the default; its
crack runs straight along the notch's line) and in shear (``--scene shear``; its crack curves
down towards a corner, where nobody would place a band beforehand).

    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py amr        # coarse mesh + Adaptivity
    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py band       # band pre-refined to h_crack
    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py uniform    # whole plate at h_crack
    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py uniform --scene shear
    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py amr --scene shear
    PYTHONPATH=. python benchmarks/adaptivity.py compare --scene shear         # the path of amr against uniform
    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/adaptivity.py amr --scene shear --scheme single-pass

Shear: the same plate with its slit to the centre (0.5, 0.5), the top moved in x (y held) to
0.016 mm, path-following scheme (the three-point bending's default), same step control. Each run
of ``amr`` and ``uniform`` saves the vertices with alpha > 0.9 at the end (the crack) in
``benchmarks/results/adaptivity-<scene>-<kind>-crack.npy``; ``compare`` prints, for every crack
vertex of the adaptive run, the distance to the nearest crack vertex of the uniform run (mean, 95th
percentile and largest, mm, and the largest in units of h_crack), and the other way round.

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
from scenes import notched_plate, sheared_plate  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"

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


def crack_points(solver) -> np.ndarray:
    """Coordinates (mm) of the vertices with alpha > 0.9."""
    import ngsolve as ngs
    mesh = solver.mesh
    pts = np.asarray(mesh.ngmesh.Coordinates())[:, :2]
    a = solver.alpha.vec.FV().NumPy()
    out = []
    for v in range(mesh.nv):
        d = solver.fes_a.GetDofNrs(ngs.NodeId(ngs.VERTEX, v))
        if d and d[0] >= 0 and a[d[0]] > 0.9:
            out.append(pts[v])
    return np.array(out).reshape(-1, 2)


def _tag(scheme: str | None, default: str | None = None) -> str:
    """File-name tag of a run with a scheme other than its scene's default ('' otherwise)."""
    return "" if scheme is None or scheme == default else f"-{scheme}"


def compare(scene_name: str, scheme: str | None = None):
    """Distances between the crack vertices of the adaptive and the uniform run (mm)."""
    from benchmarks.crack_paths import distances
    a = np.load(RESULTS / f"adaptivity-{scene_name}-amr{_tag(scheme)}-crack.npy")
    u = np.load(RESULTS / f"adaptivity-{scene_name}-uniform{_tag(scheme)}-crack.npy")
    out = {"scene": scene_name, "h_crack": H_CRACK, "points_amr": len(a), "points_uniform": len(u)}
    for name, p, q in (("amr_to_uniform", a, u), ("uniform_to_amr", u, a)):
        out[name] = distances(p, q, H_CRACK)
    print(json.dumps(out), flush=True)
    return out


def main(kind: str, scene_name: str = "notched", scheme: str | None = None, **adapt_kw):
    if kind == "compare":
        return compare(scene_name, scheme)
    make, stop, default = {"notched": (notched_plate, 0.009, "single-pass"),
                           "shear": (sheared_plate, 0.016, "path-following")}[scene_name]
    scheme = scheme or default
    if kind == "amr":
        scene = make(maxh=COARSE, **({"h_band": COARSE} if scene_name == "notched" else {}), l0=L0)
        adapt = ngtmc.Adaptivity(h_crack=H_CRACK, **adapt_kw)
    elif kind == "band" and scene_name == "notched":
        scene = notched_plate(maxh=COARSE, h_band=H_CRACK, l0=L0)
        adapt = None
    elif kind == "uniform":
        scene = make(maxh=H_CRACK, **({"h_band": H_CRACK} if scene_name == "notched" else {}), l0=L0)
        adapt = None
    else:
        raise SystemExit(f"unknown kind {kind!r} for scene {scene_name!r}: amr, uniform, compare (band: notched only)")
    ctrl = ngtmc.AdaptiveStepControl(du_max=5e-4, k_u=100.0, du_min=1e-7)
    t0 = time.perf_counter()
    sim = ngtmc.Simulation(scene, stop, ctrl, adapt=adapt, compile=True, scheme=scheme)
    failure = None
    try:
        sim.run()
    except ngtmc.StepFailure as e:   # report how far it came
        failure = str(e)
    wall = time.perf_counter() - t0
    h = sim.history
    i = int(np.argmax(h["force"].to_numpy()))
    s = sim.solver
    dofs = lambda: s.fes_u.ndof + s.fes_a.ndof
    out = {"scene": scene_name, "kind": kind, "scheme": scheme, "peak_force": float(h["force"].iloc[i]),
           "peak_load": float(h["load"].iloc[i]),
           "steps": int(len(h) - 1), "newton_iterations": int(h["newton_iterations"].sum()),
           "dofs_at_peak": int(h["dofs"].iloc[i]) if "dofs" in h else dofs(),
           "elements_at_peak": int(h["elements"].iloc[i]) if "elements" in h else s.mesh.ne,
           "dofs_end": dofs(), "elements_end": s.mesh.ne, "wall_time_s": round(wall, 1),
           "final_force": float(h["force"].iloc[-1]),
           "refinements": len(sim.refinements), "adapt": adapt_kw,
           "final_load": float(h["load"].iloc[-1]), "failed": failure}
    if scene_name == "notched":
        out["crack_y"] = crack_height(s)
    if kind in ("amr", "uniform"):
        np.save(RESULTS / f"adaptivity-{scene_name}-{kind}{_tag(scheme, default)}-crack.npy", crack_points(s))
    print(json.dumps(out), flush=True)
    return out


if __name__ == "__main__":
    args = sys.argv[2:]
    scene_name = "notched"
    scheme = None
    if "--scene" in args:
        k = args.index("--scene")
        scene_name = args[k + 1]
        del args[k:k + 2]
    if "--scheme" in args:
        k = args.index("--scheme")
        scheme = args[k + 1]
        del args[k:k + 2]
    kw = {}
    for arg in args:
        k, v = arg.split("=")
        kw[k] = float(v) if "." in v or "e" in v else int(v)
    main(sys.argv[1], scene_name, scheme, **kw)
