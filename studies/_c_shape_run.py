"""The cases and the report of the C-shape topology optimisation (``studies/c_shape_design.py``,
whose docstring states the problem): one optimisation per case with its gradient checks, its final
design run with fracture on, and the tables and figures of the report.

The file name starts with an underscore: it is a helper, not a study. Units: mm, N, MPa; energies
in N mm and forces in N per mm of thickness."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import ngsolve as ngs

from ngtmc import sensitivities as sens
from ngtmc.studies._design_optimisation import path_snapshot

#: pixels of a design image along the box's length (its height gets half)
IMAGE_COLUMNS = 80


def _study():
    from ngtmc.studies import c_shape_design
    return c_shape_design


def _full_run(scene, rho, opt):
    """The forward run of density ``rho`` on ``scene`` with the optimisation's load steps, as a
    recorded path with its whole history."""
    ev = opt.evaluation
    return sens.record_path(dataclasses.replace(scene, density=rho), ev.schedule, ev.control, newton=ev.newton)


def _crack(snapshot: dict) -> dict:
    """Largest phase field of the last frame of a snapshot (the final state) and where it is (mm)."""
    a = snapshot["alpha"][-1]
    k = int(np.argmax(a))
    x, y = snapshot["vertices"][k][:2]
    return {"alpha_max": float(a[k]), "crack_x": float(x), "crack_y": float(y)}


def _image(mesh, values, p) -> list:
    """Element values sampled on a grid over the box (rows bottom to top), NaN outside the mesh."""
    q = ngs.GridFunction(ngs.L2(mesh, order=0))
    q.vec.FV().NumPy()[:] = values
    nx = IMAGE_COLUMNS
    ny = max(2, int(round(nx * p["height"] / p["length"])))
    xs = (np.arange(nx) + 0.5) * p["length"] / nx
    ys = (np.arange(ny) + 0.5) * p["height"] / ny
    X, Y = np.meshgrid(xs, ys)
    z = np.asarray(q(mesh(X.ravel(), Y.ravel()))).reshape(ny, nx)
    return np.round(z, 3).tolist()


def _curve(path) -> dict:
    return {"load": [float(v) for v in path.loads], "force": [float(v) for v in path.forces]}


def optimise_case(p: dict, fracture: bool, case, out_dir) -> pd.DataFrame:
    """Optimise with (``fracture``) or without fracture; check the gradient at the initial, gray and
    final designs; run the final design with fracture on. Writes the final design variables, its
    physical and pseudo-densities and the design at the end of each stage to
    ``optimisation_<case>.npz`` in the run folder; returns that run's history, with the results
    and snapshots in ``attrs`` (docs/study-interface.md)."""
    S = _study()
    opt = S.optimisation(p, fracture)
    dens, ev = opt.density, opt.evaluation
    k, eps = int(p["check_directions"]), float(p["check_eps"])
    x0 = np.full(dens.n, float(p["volume_fraction"]))
    checks = [dict(c, design="initial", beta=opt.betas[0]) for c in ev.gradient_check(x0, k, eps, seed=1)]
    res = opt.run(evaluations=int(p["evaluations"]))
    dens.beta = opt.betas[0]
    checks += [dict(c, design="gray (end of stage 1)", beta=dens.beta)
               for c in ev.gradient_check(res.stage_x[0], k, eps, seed=2)]
    dens.beta = opt.betas[-1]
    checks += [dict(c, design="final", beta=dens.beta) for c in ev.gradient_check(res.x, k, eps, seed=3)]
    mesh = dens.scene.mesh
    as_designed = _full_run(dens.scene, res.rho, opt)
    on = as_designed if fracture else _full_run(S.build_scene(p, True, mesh=mesh), res.rho, opt)
    W = sens.ExternalWork()
    split = res.time_split()
    hist = res.history
    full = dens.fixed.copy()
    designs = {}   # the initial design and those at the end of each stage
    ends = [0] + [max(r["evaluation"] for r in hist if r["stage"] == k) for k in range(1, len(opt.betas) + 1)]
    for e in ends:
        if e in res.designs:
            full[dens.mask] = res.designs[e]
            designs[str(e)] = _image(mesh, full, p)
    snapshot = path_snapshot(on, res.rho, frames=5)
    results = {
        "design_variables": dens.n, "evaluations": res.evaluations, "optimisation_s": res.seconds,
        "forward_s": split["forward_s"], "adjoint_s": split["adjoint_s"],
        "adjoint_per_forward": split["adjoint_per_forward"],
        "newton_iterations_total": int(sum(r["newton_iterations"] or 0 for r in hist)),
        "objective_initial": hist[0]["objective"], "objective_final": res.objective, "volume_final": res.volume,
        "W_as_designed": W.value(as_designed), "W_fracture_on": W.value(on),
        "failed_designs": res.shortened, "failed_attempts": len(res.failures),
        "worst_gradient_check": max(c["relative_difference"] for c in checks), "gradient_checks": checks,
        "optimisation": {key: [r[key] for r in hist] for key in ("evaluation", "beta", "objective", "volume",
                                                                 "forward_s", "adjoint_s")},
        "curve_as_designed": _curve(as_designed), "designs": designs, "status": res.status,
        **_crack(snapshot),
    }
    # the design variables, for a rerun or a check of one design (``optimisation_<case>.npz``)
    np.savez_compressed(Path(out_dir) / f"optimisation_{case.name}.npz", x=res.x, xbar=res.xbar, rho=res.rho,
                        stage_x=np.array(res.stage_x), design_mask=dens.mask)
    df = on.history.copy()
    df.attrs["results"] = results
    df.attrs["snapshots"] = snapshot
    df.attrs["solver"] = on.solver
    return df


def report_entries(p: dict, results: dict) -> dict:
    """The study's tables and figures from the two cases' results (those present)."""
    from ngtmc.studies._c_shape_report import entries
    return entries(p, results)
