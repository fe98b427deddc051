"""The parts of one Newton iteration of a named study's scene, side by side for discretisation
options: tangent assembly, residual, energy, re-factorization (symbolic step reused) and solve,
J guard and Psi_plus at the history points. Best of 3, ms.

    python -m benchmarks.iteration --study three_point_bending --resolution quick [--threads 1]

Timings depend on the machine and on what else runs on it; they are never pass/fail tests.
"""
from __future__ import annotations

import argparse
import dataclasses
import time

import ngsolve as ngs

import ngtmc
from ngtmc.study import load_study
from ngtmc.study import study_parameters

CONFIGURATIONS = [
    ("order 2 everywhere, symbolic compile", {"variable_order": False}, True),
    ("order 2 in the void only", {}, True),
    ("order 2 in the void only, C++ energies", {}, "real"),
]


def best(f, n=3) -> float:
    """Smallest wall time of n calls of f, s."""
    t = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return min(t)


def measure(scene, compile_mode) -> dict:
    """ms per operation at a non-trivial displacement state (a uniform compression)."""
    s = ngtmc.Solver(scene, compile=compile_mode)
    s.u.Set(ngs.CF(tuple([0.0] * (s.dim - 1) + [-1e-3 * (ngs.y if s.dim == 2 else ngs.z)])))
    r = s.u.vec.CreateVector()
    out = {"u dofs": s.ndof["u"], "history points": s.ndof["history_points"]}
    with ngs.TaskManager():
        out["assembly"] = best(lambda: s.a_u.AssembleLinearization(s.u.vec))
        out["residual"] = best(lambda: s.a_u.Apply(s.u.vec, r))
        out["energy"] = best(lambda: s.a_u.Energy(s.u.vec))
        inv = s.a_u.mat.Inverse(s.free, inverse="sparsecholesky")
        out["re-factorization"] = best(inv.Update)
        tmp = r.CreateVector()

        def solve():
            tmp.data = inv * r
        out["solve"] = best(solve)
        out["min J"] = best(s.min_J)
        out["Psi_plus"] = best(s.psi_plus_values)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--study", default="three_point_bending")
    ap.add_argument("--resolution", default="quick")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args(argv)
    ngs.SetNumThreads(args.threads)
    mod = load_study(args.study)
    _, p = study_parameters(mod, args.resolution)
    base = mod.cases(p)[0].build_scene()
    print(f"{args.study} {args.resolution}: {base.mesh.ne} elements, {args.threads} thread(s); ms, best of 3")
    for label, scene_change, compile_mode in CONFIGURATIONS:
        row = measure(dataclasses.replace(base, **scene_change), compile_mode)
        parts = ", ".join(f"{k} {1e3 * v:.1f}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items())
        print(f"{label}: {parts}", flush=True)


if __name__ == "__main__":
    main()
