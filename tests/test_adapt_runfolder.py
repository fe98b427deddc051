"""A run folder of an adaptive run (ngtmc.adapt): snapshots and the ParaView series keep the mesh
each snapshot was taken on, the history records dofs and elements, the metadata the mesh the
case ended on, the report shows one mesh per group of snapshots, and an interrupted run resumes on
its refined mesh (the refinements replayed) to the same history as a run that was not
interrupted."""
from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest

import ngtmc
from ngtmc.adapt import Adaptivity
from scenes import notched_plate

SCHEDULE = ngtmc.Schedule([0.0, 0.0065])
CONTROL = ngtmc.AdaptiveStepControl(du_max=5e-4, k_u=0.0, du_min=1e-7)
ADAPT = Adaptivity(h_crack=0.07)
QUIET = dict(report=False, progress=False, threads=1, checkpoint_every=1, compile=True,
             snapshot_loads=[0.002, 0.004, 0.005, 0.0055, 0.006, 0.0065])


def _scene():
    return notched_plate(maxh=0.2, h_band=0.2, l0=0.1)


def _run(out, **kw):
    return ngtmc.simulate(_scene(), SCHEDULE, CONTROL, out_dir=out, adapt=ADAPT, **{**QUIET, **kw})


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The adaptive run without interruption, with its report."""
    out = tmp_path_factory.mktemp("amr") / "ref"
    res = _run(out, report=True)
    return out, res


def test_snapshots_keep_the_mesh_they_were_taken_on(reference):
    out, res = reference
    h = res.history
    assert h["elements"].iloc[-1] > 2 * h["elements"].iloc[0]          # the mesh was refined
    z = np.load(out / "snapshots.npz")
    groups = sorted({k.split("__")[0] for k in z.files})
    assert len(groups) >= 2 and all(re.fullmatch(r"main@\d+", g) for g in groups)
    loads, meshes = [], []
    for g in sorted(groups, key=lambda g: int(g.split("@")[1])):
        V, T, rho, U, A = (z[f"{g}__{f}"] for f in ("vertices", "triangles", "rho", "u", "alpha"))
        k = len(z[f"{g}__loads"])
        assert U.shape == (k, len(V), 2) and A.shape == (k, len(V)) and rho.shape == (len(T),)
        assert T.min() == 0 and T.max() == len(V) - 1
        loads += list(z[f"{g}__loads"])
        meshes.append(len(T))
    assert np.all(np.diff(meshes) > 0)                                   # each group on a finer mesh
    assert len(loads) == len(QUIET["snapshot_loads"])
    # every snapshot on its own mesh in the ParaView series: points and cells of each file
    pvd = (out / "vtk" / "main.pvd").read_text()
    files = re.findall(r'file="([^"]+)"', pvd)
    assert len(files) == len(loads)
    n_points = [int(re.search(r'NumberOfPoints="(\d+)"', (out / "vtk" / f).read_text()).group(1)) for f in files]
    n_cells = [int(re.search(r'NumberOfCells="(\d+)"', (out / "vtk" / f).read_text()).group(1)) for f in files]
    per_snapshot = [len(z[f"{g}__vertices"]) for g in sorted(groups, key=lambda g: int(g.split("@")[1]))
                    for _ in z[f"{g}__loads"]]
    assert n_points == per_snapshot and n_cells[-1] == h["elements"].iloc[-1]


def test_history_metadata_and_report_of_a_refined_run(reference):
    out, res = reference
    hist = pd.read_csv(out / "history.csv")
    assert {"dofs", "elements"} <= set(hist.columns)
    meta = json.loads((out / "metadata.json").read_text())
    case = meta["cases"][0]
    assert case["mesh_final"]["n_elements"] == hist["elements"].iloc[-1] > meta["mesh"]["n_elements"]
    assert case["refinements"] >= 1
    assert meta["parameters"]["adapt.h_crack"]["value"] == 0.07
    html = (out / "report.html").read_text()
    n_groups = len({k.split("__")[0] for k in np.load(out / "snapshots.npz").files})
    assert len(set(re.findall(r"mesh \d+ \(\d+ elements\)", html))) == n_groups
    assert f"after {case['refinements']} refinements: elements" in html


def test_interrupted_adaptive_run_resumes_on_its_refined_mesh(reference, tmp_path):
    ref_out, ref = reference
    h_ref = ref.history
    # interrupt after the first step taken on a refined mesh (the mesh of step 0 refined at least once)
    stop_step = int(h_ref.index[h_ref["elements"] > h_ref["elements"].iloc[0]][0]) + 1
    out = tmp_path / "run"

    def stop(sim, row):
        if row["step"] == stop_step:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _run(out, callbacks=[stop])
    assert json.loads((out / "metadata.json").read_text())["status"] == "interrupted"
    seen = []
    res = _run(out, resume=True, callbacks=[lambda sim, row: seen.append(row["step"])])
    assert seen[0] == stop_step + 1          # continued from the checkpoint, not from the start
    h = res.history
    print(f"\nadaptive run: {len(h_ref) - 1} steps, {h_ref['elements'].iloc[0]} -> {h_ref['elements'].iloc[-1]} "
          f"elements; interrupted after step {stop_step}, resumed")
    assert len(h) == len(h_ref)
    for col in ("load", "force", "dissipated_energy", "elements", "dofs", "newton_iterations"):
        np.testing.assert_allclose(h[col].to_numpy(dtype=float), h_ref[col].to_numpy(dtype=float),
                                   rtol=1e-9, atol=1e-12, err_msg=col)
    z, z_ref = np.load(out / "snapshots.npz"), np.load(ref_out / "snapshots.npz")
    assert sorted(z.files) == sorted(z_ref.files)
    for k in z.files:
        np.testing.assert_allclose(z[k], z_ref[k], rtol=1e-9, atol=1e-12, err_msg=k)


def test_resume_after_a_refinement_with_the_snapshots_on_an_earlier_mesh(tmp_path):
    """A checkpoint written after a refinement, while every snapshot so far lies on the mesh before
    it, keeps that mesh: resuming used to read the snapshots onto the refined mesh and failed at
    the next checkpoint ("cannot reshape array"; a medium L-panel run with refinement, measured)."""
    one = {"snapshot_loads": [0.002]}
    ref = _run(tmp_path / "ref", **one).history
    refined = [int(i) for i in ref.index[1:] if ref["elements"][i] > ref["elements"][i - 1]]
    stop_step = next(i for i in refined if ref["load"][i - 1] >= 0.002)   # snapshot on an earlier mesh
    out = tmp_path / "run"

    def stop(sim, row):
        if row["step"] == stop_step:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _run(out, callbacks=[stop], **one)
    h = _run(out, resume=True, **one).history
    assert len(h) == len(ref)
    z, z_ref = np.load(out / "snapshots.npz"), np.load(tmp_path / "ref" / "snapshots.npz")
    assert sorted(z.files) == sorted(z_ref.files)
    for k in z.files:
        np.testing.assert_allclose(z[k], z_ref[k], rtol=1e-9, atol=1e-12, err_msg=k)


def _short_format(npz):
    """Rewrite a checkpoint's snapshots (on one mesh) in the short format of the versions before
    2026-12-05, which kept no mesh of theirs (the solver's was taken on resuming)."""
    d = dict(np.load(npz))
    k = len(d["snap__loads"])
    assert set(d["snap__mesh_of"]) == {0}
    d["snap__u"] = np.stack([d.pop(f"snap__u__{i}") for i in range(k)])
    d["snap__alpha"] = np.stack([d.pop(f"snap__alpha__{i}") for i in range(k)])
    for key in [key for key in d if key.startswith(("snap__mesh_of", "snap__vertices__", "snap__triangles__",
                                                    "snap__rho__"))]:
        del d[key]
    np.savez(npz, **d)


def test_resume_of_an_old_checkpoint_with_the_snapshots_on_an_earlier_mesh(tmp_path):
    """A checkpoint written before 2026-12-05 after a refinement, while every snapshot lay on the
    mesh before it, kept no mesh of the snapshots: resuming put them on the refined mesh and failed
    at the next checkpoint ("cannot reshape array", a medium L-panel run). The mesh is now taken
    from the checkpoint's copy of the snapshot arrays, and the run ends as the uninterrupted one;
    without that copy the resume stops at once with a clear message."""
    one = {"snapshot_loads": [0.002]}
    ref = _run(tmp_path / "ref", **one).history
    refined = [int(i) for i in ref.index[1:] if ref["elements"][i] > ref["elements"][i - 1]]
    stop_step = next(i for i in refined if ref["load"][i - 1] >= 0.002)

    def stop(sim, row):
        if row["step"] == stop_step:
            raise KeyboardInterrupt

    for name in ("run", "bare"):
        with pytest.raises(KeyboardInterrupt):
            _run(tmp_path / name, callbacks=[stop], **one)
        for f in (tmp_path / name / "checkpoint").glob("*.npz"):
            _short_format(f)
    h = _run(tmp_path / "run", resume=True, **one).history
    assert len(h) == len(ref)
    z, z_ref = np.load(tmp_path / "run" / "snapshots.npz"), np.load(tmp_path / "ref" / "snapshots.npz")
    assert sorted(z.files) == sorted(z_ref.files)
    for k in z.files:
        np.testing.assert_allclose(z[k], z_ref[k], rtol=1e-9, atol=1e-12, err_msg=k)
    for f in (tmp_path / "bare" / "checkpoint").glob("*.npz"):
        np.savez(f, **{k: v for k, v in np.load(f).items() if not k.startswith("snaparr__")})
    with pytest.raises(ValueError, match=r"snapshots lie on a mesh of \d+ vertices.*start a new run"):
        _run(tmp_path / "bare", resume=True, **one)


def test_state_of_a_refined_run_needs_adapt():
    """A state on a refined mesh, set on a simulation without adaptive refinement, is refused."""
    sim = ngtmc.Simulation(_scene(), SCHEDULE, CONTROL, compile=True, adapt=ADAPT)
    for _ in sim.steps():
        if sim.refinements:
            break
    st = sim.get_state()
    plain = ngtmc.Simulation(_scene(), SCHEDULE, CONTROL, compile=True)
    with pytest.raises(ValueError, match="adapt="):
        plain.set_state(st)
    # on a fresh adaptive simulation it is replayed: the same mesh, and the state is an equilibrium there
    fresh = ngtmc.Simulation(_scene(), SCHEDULE, CONTROL, compile=True, adapt=ADAPT)
    fresh.set_state(st)
    assert fresh.solver.mesh.ne == sim.solver.mesh.ne and fresh.solver.fes_u.ndof == sim.solver.fes_u.ndof
    np.testing.assert_array_equal(np.asarray(fresh.solver.mesh.ngmesh.Coordinates()),
                                  np.asarray(sim.solver.mesh.ngmesh.Coordinates()))
    assert fresh.solver.solve_displacement(fresh.solver.load).iterations == 0
