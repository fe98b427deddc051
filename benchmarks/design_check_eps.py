"""The C-shape study's gradient check of one saved design at several finite-difference steps:
whether a miss is the step (truncation: the difference falls with the step) or the gradient.

    python -m benchmarks.design_check_eps RUN_FOLDER [--case contact_only] [--stage final]
        [--eps 1e-5 1e-4 1e-3] [--resolution medium]

Reads ``optimisation_<case>.npz`` of a ``ngtmc run c-shape-design`` folder, sets beta to that of
the design (``final``: the last stage's; ``gray``: the first stage's, with the design at the end
of stage 1), and runs :meth:`ngtmc.design.DesignEvaluation.gradient_check` with the study's
``check_directions`` and seed 3 (the study's seed of the final check) at each step. A direction
is shortened where x +- eps d would leave [0, 1], so its entries near the bounds depend on eps.
Writes ``c_shape_design-<resolution>-<UTC time>-check-eps.json`` / ``.md`` to ``--out``
(default ``benchmarks/results``).
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
from pathlib import Path
import shlex
import sys
import time

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.design_check_eps")
    ap.add_argument("run_folder")
    ap.add_argument("--case", default="contact_only", choices=("fracture", "contact_only"))
    ap.add_argument("--stage", default="final", choices=("final", "gray"))
    ap.add_argument("--eps", type=float, nargs="+", default=[1e-5, 1e-4, 1e-3])
    ap.add_argument("--resolution", default="medium")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    from ngtmc.study import load_study, study_parameters
    S = load_study("c_shape_design")
    _, p = study_parameters(S, args.resolution, {})
    opt = S.optimisation(p, args.case == "fracture", progress=False)
    saved = np.load(Path(args.run_folder) / f"optimisation_{args.case}.npz")
    if args.stage == "final":
        x, beta = saved["x"], opt.betas[-1]
    else:
        x, beta = saved["stage_x"][0], opt.betas[0]
    opt.density.beta = beta
    k = int(p["check_directions"])
    rows = []
    for eps in args.eps:
        t0 = time.perf_counter()
        for c in opt.evaluation.gradient_check(x, k, eps, seed=3):
            rows.append({"eps": eps, **{key: (float(v) if isinstance(v, (float, np.floating)) else v)
                                        for key, v in c.items() if not isinstance(v, np.ndarray)}})
            print(json.dumps(rows[-1]), flush=True)
        print(f"eps {eps:g}: {time.perf_counter() - t0:.1f} s", flush=True)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    name = f"c_shape_design-{args.resolution}-{stamp}-check-eps"
    cmd = "python -m benchmarks.design_check_eps " + shlex.join(list(sys.argv[1:] if argv is None else argv))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}.json").write_text(json.dumps({"command": cmd, "case": args.case, "stage": args.stage,
                                                  "beta": beta, "directions": k, "checks": rows}, indent=1))
    lines = [f"### c_shape_design, {args.resolution}: gradient check of the {args.stage} {args.case} design at "
             f"several steps ({stamp})", "", f"`{cmd}`", "", f"beta = {beta:g}, {k} random directions (seed 3)", "",
             "| eps | direction | adjoint | finite difference | relative difference | switches |",
             "|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['eps']:g} | {r['direction']} | {r['adjoint']:.10g} | {r['finite_difference']:.10g} | "
                     f"{r['relative_difference']:.2e} | {r['switches']} |")
    (out / f"{name}.md").write_text("\n".join(lines) + "\n")
    print(f"written {out / name}.json and .md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
