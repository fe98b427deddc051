"""Is the V-notch's higher peak a matter of the mesh at its apex? The three-point bending's window
variant (displacement on a window of the top edge, no indenter, no void; path following) with the
V-notch and with the flat notch, each with the elements within ``--radius`` (mm) of the notch tip
bisected 0, 1, 2, ... times (``--levels``) after meshing. If the V's peak fell towards the flat
notch's as its apex is refined, the discretisation of the apex would be the cause; if it stays,
the difference belongs to the model (a notch shape at the scale of l0). The flat notch refined
the same way is the control: what local refinement alone does to a peak.

    python -m benchmarks.notch_apex --resolution quick --levels 0 2 4 [--stop-load 0.06] [--set l0=0.06]

Prints one line per run (peak N/mm, load at peak mm, elements, steps, Newton iterations, wall
s) and writes them as JSON to ``--out`` (default benchmarks/results/notch_apex-<resolution>-<UTC>.json).
Timings depend on the machine; they are never pass/fail tests.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import time
from pathlib import Path

import ngsolve as ngs

import ngtmc
from ngtmc.study import load_study
from ngtmc.study import simulation_options, study_parameters


def refine_near(mesh, centre: tuple[float, float], radius: float, levels: int) -> None:
    """Bisect the elements whose centroid lies within ``radius`` (mm) of ``centre``, ``levels``
    times (each round marks the elements of the current mesh)."""
    cx, cy = centre
    for _ in range(levels):
        for el in mesh.Elements(ngs.VOL):
            pts = [mesh.ngmesh.Points()[v.nr + 1] for v in el.vertices]
            x = sum(p[0] for p in pts) / len(pts)
            y = sum(p[1] for p in pts) / len(pts)
            mesh.SetRefinementFlag(el, (x - cx) ** 2 + (y - cy) ** 2 <= radius ** 2)
        mesh.Refine()


def run(mod, p: dict, levels: int, radius: float) -> dict:
    """One run of the window variant of ``p`` with the notch tip refined ``levels`` times."""
    case = mod.cases(p)[0]
    scene = case.build_scene()
    refine_near(scene.mesh, (float(p["beam_length"]) / 2, float(p["notch_depth"])), radius, levels)
    opts = {**simulation_options(p), **case.options}
    sim = ngtmc.Simulation(scene, case.schedule, case.control, **opts)
    t0 = time.perf_counter()
    res = sim.run()
    h = res.history
    return {"notch_shape": p["notch_shape"], "levels": levels, "radius_mm": radius,
            "elements": scene.mesh.ne, "peak_N_per_mm": res.peak_force, "peak_load_mm": res.peak_load,
            "steps": int(len(h)), "newton_iterations": int(h["newton_iterations"].sum()),
            "wall_s": time.perf_counter() - t0}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resolution", default="quick")
    ap.add_argument("--levels", type=int, nargs="+", default=[0, 2, 4])
    ap.add_argument("--radius", type=float, default=None, help="mm (default 2 l0)")
    ap.add_argument("--shapes", nargs="+", default=["v", "flat"])
    ap.add_argument("--stop-load", type=float, default=0.06, help="mm (the window peak is at about 0.045 mm)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="a further study parameter (repeatable), e.g. --set l0=0.06")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    mod = load_study("three_point_bending")
    rows = []
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    out = Path(a.out) if a.out else Path(__file__).resolve().parent / "results" / f"notch_apex-{a.resolution}-{stamp}.json"
    for shape in a.shapes:
        for lv in a.levels:
            extra = dict(kv.split("=", 1) for kv in a.overrides)
            _, p = study_parameters(mod, a.resolution, {"loading": "window", "notch_shape": shape,
                                                        "scheme": "path-following", "stop_load": str(a.stop_load),
                                                        **extra})
            radius = a.radius if a.radius is not None else 2 * float(p["l0"])
            r = run(mod, p, lv, radius)
            r["overrides"] = extra
            rows.append(r)
            print(f"{shape:5s} levels {lv}  peak {r['peak_N_per_mm']:.3f} N/mm at {r['peak_load_mm']:.5f} mm  "
                  f"{r['elements']} elements  {r['steps']} steps  {r['newton_iterations']} Newton  "
                  f"{r['wall_s']:.1f} s", flush=True)
            out.write_text(json.dumps({"command": "python -m benchmarks.notch_apex", "resolution": a.resolution,
                                       "stop_load_mm": a.stop_load, "runs": rows}, indent=1))
    print(f"written {out}")


if __name__ == "__main__":
    main()
