"""Where a stalled step's displacement residual sits: resume a run (a copy of its folder) from its
checkpoint, take the displacement tangent K, the residual r and the Newton correction du of the
first (``--at relaxation``) or K-th (``--at relaxation:K``) Newton direction of the coupled Newton's
displacement relaxations (its fallback where the coupled iteration stalls), or of the N-th
displacement Newton direction after resuming (``--at N``: the single-pass and staggered schemes),
and report

* the share of |r|^2 and |du|^2 (free dofs) on each region, and the vertices that carry the most;
* the range of det F (element means) per region;
* the eigenvalues of K on the free dofs nearest below zero, and the regions their modes live in
  (a negative one is an unstable configuration; its mode says of what).

    python -m benchmarks.stall_probe RUN_FOLDER [--at relaxation[:K]|N] [--eigenvalues 6] [--threads 2]

The run folder is not touched (the copy goes to a temporary folder). The record
``stall-probe-<study>-<UTC time>.json`` / ``.md`` goes to ``--out`` (default ``benchmarks/results``).
Units: mm, N (per unit thickness in 2D, as the solver's residuals).
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path
import shutil
import sys
import tempfile

import numpy as np

from .study_process import RESULTS, git_state, git_text, stamp, write_record


class _Captured(BaseException):
    """Stops the resumed run once the tangent is taken (a BaseException: the runner's handlers of
    failed steps do not catch it)."""


def capture(folder: Path, at: str = "relaxation", threads: int = 2, study: str | None = None) -> dict:
    """Resume a copy of the run ``folder`` and return the arrays of the K-th displacement Newton
    direction in displacement relaxations (``at = 'relaxation[:K]'``, K = 1 by default) or of the
    ``at``-th displacement Newton direction: K (scipy CSR), r, du, u, the free mask and the space."""
    from ngtmc.discrete import to_scipy

    import ngtmc
    import ngtmc.coupled.iteration as iteration
    import ngtmc.discrete.newton as newton

    meta = json.loads((Path(folder) / "metadata.json").read_text())
    out: dict = {}
    state = {"relaxing": False, "solver": None, "count": 0}
    relax0, lifted0, solve0 = iteration.Iteration.relax_u, newton.lifted_direction, newton.DisplacementNewton.solve

    def relax_u(self):
        state["relaxing"] = True
        try:
            return relax0(self)
        finally:
            state["relaxing"] = False

    def solve(self, p, load):
        state["problem"] = p
        return solve0(self, p, load)

    relaxation = at.startswith("relaxation")
    nth = int(at.partition(":")[2] or 1) if relaxation else int(at)

    def lifted_direction(mat, inv, r, rem, dirichlet, w, tmp, du):
        lifted0(mat, inv, r, rem, dirichlet, w, tmp, du)
        if relaxation and not state["relaxing"]:
            return
        state["count"] += 1
        if state["count"] == nth:
            p = state["problem"]
            out.update(K=to_scipy(mat),
                       r=r.FV().NumPy().copy(), du=du.FV().NumPy().copy(), u=p.u.vec.FV().NumPy().copy(),
                       free=np.asarray(p.free, dtype=bool).copy(), fes=p.u.space)
            raise _Captured

    with tempfile.TemporaryDirectory(prefix="stall-probe-") as tmp:
        work = Path(tmp) / "run"
        shutil.copytree(folder, work, ignore=shutil.ignore_patterns("*.vtu", "*.pvd", "vtk", "report.html"))
        iteration.Iteration.relax_u, newton.lifted_direction, newton.DisplacementNewton.solve = (
            relax_u, lifted_direction, solve)
        try:
            ngtmc.run_study(study or meta["study"], meta["resolution"], work, report=False, resume=True, progress=False,
                            threads=threads, vtk=False)
        except _Captured:
            pass
        finally:
            iteration.Iteration.relax_u, newton.lifted_direction, newton.DisplacementNewton.solve = (
                relax0, lifted0, solve0)
    if not out:
        raise SystemExit(f"stall_probe: the resumed run ended without a displacement Newton direction at {at!r}")
    out["meta"] = meta
    return out


def analyse(c: dict, eigenvalues: int = 6) -> dict:
    """Shares, vertices, det F and the eigenvalues nearest below zero of a capture (:func:`capture`)."""
    import ngsolve as ngs
    import scipy.sparse.linalg as sla

    fes = c["fes"]
    mesh = fes.mesh
    free, r, du, u = c["free"], c["r"], c["du"], c["u"]
    # the regions of each dof: the materials of the elements it belongs to
    labels = [set() for _ in range(fes.ndof)]
    for el in mesh.Elements(ngs.VOL):
        for d in fes.GetDofNrs(el):
            if d >= 0:
                labels[d].add(el.mat)
    label = np.array(["+".join(sorted(s)) for s in labels], dtype=object)

    def shares(x, floor):
        """Each region's share of |x|^2 on the free dofs, to four digits, those of at least ``floor``."""
        x2 = np.where(free, x, 0.0) ** 2
        tot = x2.sum()
        if not tot > 0:
            return {}
        out = {k: x2[label == k].sum() / tot for k in sorted(set(label[free]))}
        return {k: round(float(v), 4) for k, v in out.items() if v >= floor}

    # vertices: the vertex dofs of each component
    dim = mesh.dim
    vdofs = np.array([fes.GetDofNrs(ngs.NodeId(ngs.VERTEX, i)) for i in range(mesh.nv)])   # nv x dim
    pts = np.array([mesh.vertices[i].point for i in range(mesh.nv)])

    def top(x, k=8):
        xv = np.sqrt((np.where(free, x, 0.0)[vdofs] ** 2).sum(axis=1))
        return [{"vertex": int(i), "x_mm": [round(float(t), 3) for t in pts[i]], "norm": float(xv[i]),
                 "u_mm": [round(float(t), 4) for t in u[vdofs[i]]], "regions": label[vdofs[i][0]]}
                for i in np.argsort(xv)[::-1][:k]]

    # det F, element means
    gu = ngs.GridFunction(fes)
    gu.vec.FV().NumPy()[:] = u
    J = ngs.GridFunction(ngs.L2(mesh, order=0))
    J.Set(ngs.Det(ngs.Id(dim) + ngs.Grad(gu)))
    Jv = J.vec.FV().NumPy()
    mats = np.array([el.mat for el in mesh.Elements(ngs.VOL)])
    dets = {m: [float(Jv[mats == m].min()), float(Jv[mats == m].max())] for m in sorted(set(mats))}

    f = np.where(free)[0]
    Kf = c["K"][f][:, f]
    Kf = (0.5 * (Kf + Kf.T)).tocsc()
    vals, vecs = sla.eigsh(Kf, k=eigenvalues, sigma=-1.0, which="LM")
    modes = []
    for j in np.argsort(vals):
        x = np.zeros(fes.ndof)
        x[f] = vecs[:, j]
        modes.append({"eigenvalue": float(vals[j]), "regions": shares(x, 1e-3),
                      "top_vertices": [t["vertex"] for t in top(x, 5)]})
    return {"residual_norm_N": float(np.linalg.norm(r[free])), "correction_norm_mm": float(np.linalg.norm(du[free])),
            "linear_residual_N": float(np.linalg.norm((c["K"] @ du + r)[free])),
            "residual_shares": shares(r, 1e-4), "correction_shares": shares(du, 1e-4),
            "residual_vertices": top(r), "correction_vertices": top(du), "det_F_range": dets, "modes": modes}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", help="a run folder with a checkpoint (ngtmc run ... -o FOLDER)")
    ap.add_argument("--at", default="relaxation",
                    help="'relaxation' or 'relaxation:K' (the first or K-th Newton direction in the coupled Newton's "
                         "displacement relaxations) or N (the N-th displacement Newton direction after resuming)")
    ap.add_argument("--eigenvalues", type=int, default=6)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--study", default=None,
                    help="the study file the run came from, where its name is not a registered study "
                         "(e.g. benchmarks/mpi_study.py)")
    ap.add_argument("--out", default=str(RESULTS))
    a = ap.parse_args(argv)
    c = capture(Path(a.folder), a.at, a.threads, a.study)
    res = analyse(c, a.eigenvalues)
    meta = c["meta"]
    record = {"command": "python -m benchmarks.stall_probe " + " ".join(sys.argv[1:] if argv is None else argv),
              "git": git_state(), "study": meta["study"], "resolution": meta["resolution"],
              "overrides": meta.get("overrides"), "at": a.at, **res}
    fmt = lambda d: ", ".join(f"{k} {v:.3g}" for k, v in d.items())
    when = stamp()

    def vertices(rows, what):
        return (["", f"| vertex | at (mm) | u (mm) | regions | {what} |", "|---:|:---|:---|:---|---:|"]
                + [f"| {t['vertex']} | {t['x_mm']} | {t['u_mm']} | {t['regions']} | {t['norm']:.3e} |" for t in rows])

    lines = [f"### Stall probe: {meta['study']}, {meta['resolution']} ({when})", "",
             f"`{record['command']}`", "", f"{git_text(record)}; run overrides {meta.get('overrides')}; at {a.at}.", "",
             f"Residual on the free dofs {res['residual_norm_N']:.3e} N; Newton correction {res['correction_norm_mm']:.3e} mm "
             f"(linear residual {res['linear_residual_N']:.1e} N).", "",
             f"* residual |r|^2 by region: {fmt(res['residual_shares'])}",
             f"* correction |du|^2 by region: {fmt(res['correction_shares'])}",
             "* det F (element means) by region: " + ", ".join(f"{k} {lo:.3g} to {hi:.3g}" for k, (lo, hi) in res["det_F_range"].items()),
             "", "| eigenvalue (N/mm) | mode's regions (share of its norm^2) | its largest vertices |", "|---:|:---|:---|"]
    lines += [f"| {m['eigenvalue']:.4g} | {fmt(m['regions'])} | {m['top_vertices']} |" for m in res["modes"]]
    lines += vertices(res["residual_vertices"], "residual (N)") + vertices(res["correction_vertices"], "correction (mm)")
    write_record(a.out, f"stall-probe-{meta['study']}-{when}", record, lines, shown=0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
