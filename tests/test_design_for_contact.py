"""The design_for_contact study: filtered design gradient and a short optimisation run."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import ngsolve as ngs

from ngtmc import sensitivities as S
from ngtmc.studies import design_for_contact as D

# coarse mesh and steps (the tests of ngtmc.sensitivities use the same scene)
OVERRIDES = {"h_band": 0.2, "h_pad": 0.1, "h": 0.5, "du": 0.025, "l0": 0.3, "Gc": 0.1}


def test_study_interface():
    assert D.NAME == "design_for_contact"
    assert {"quick", "medium", "paper"} <= set(D.RESOLUTIONS)
    p = D._params("quick")
    (case,) = D.cases(p)
    assert case.name == "initial"
    assert D.references(p) == [] and D.targets(p) == []
    W = D.density_filter(np.random.default_rng(0).random((20, 2)), np.ones(20), 0.3)
    assert np.allclose(W.sum(axis=1), 1.0) and np.all(W >= 0)


def test_filtered_design_gradient_matches_fd():
    """dW/dx through the density filter and the adjoint sweep, against a central difference."""
    p = D._params("quick", **OVERRIDES)
    prob = D.DesignProblem(p)
    n = int(prob.mask.sum())
    x = np.full(n, p["initial_fill"])
    W, dW, path = prob.evaluate(x)
    d = np.random.default_rng(4).uniform(-1, 1, n) * p["initial_fill"]
    eps = 1e-4
    Wp = S.ExternalWork().value(S.replay(path, rho=prob.rho(x + eps * d)))
    Wm = S.ExternalWork().value(S.replay(path, rho=prob.rho(x - eps * d)))
    fd = (Wp - Wm) / (2 * eps)
    adj = float(dW @ d)
    print(f"\ndesign gradient: FD {fd:.8e}, adjoint {adj:.8e}, relative difference {abs(fd - adj) / abs(adj):.1e}")
    assert abs(fd - adj) <= 1e-4 * abs(adj)
    assert np.isclose(prob.volume(x), p["initial_fill"])


def test_h_crack_refines_by_a_forward_run_and_the_gradient_holds_on_that_mesh():
    """``--set h_crack``: the beam is meshed without the band and refined during a forward run of
    the initial design (issue 12: "record the path on the final mesh"); the design problem then
    lives on that fixed mesh, its pad elements are the design variables, and the adjoint gradient
    agrees with central differences there."""
    p = D._params("quick", **OVERRIDES, h_crack=0.15)
    coarse = D._generated_mesh(p, p["h"])
    mesh = D.build_mesh(p)
    assert D.build_mesh(dict(p)) is mesh  # one refining run per parameter set
    assert mesh.ne > coarse.ne
    beam = np.array([mesh.GetMaterials()[el.index] == "beam" for el in mesh.Elements(ngs.VOL)])
    pts = np.asarray(mesh.ngmesh.Coordinates())
    tri = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    edge = np.linalg.norm(pts[tri] - np.roll(pts[tri], 1, axis=1), axis=2).max(axis=1)
    centre = pts[tri].mean(axis=1)
    assert edge[beam].max() > 0.3  # coarse far from the crack ...
    above_notch = beam & (np.abs(centre[:, 0] - 2.0) < 0.1) & (centre[:, 1] < 0.5)
    assert above_notch.any() and edge[above_notch].max() <= 0.15 + 1e-9  # ... fine where it ran
    prob = D.DesignProblem(p)
    assert prob.mesh is mesh and prob.mask.sum() == D._pad_mask(mesh).sum()
    x = np.full(int(prob.mask.sum()), p["initial_fill"])
    W, dW, path = prob.evaluate(x)
    d = np.random.default_rng(4).uniform(-1, 1, x.size) * p["initial_fill"]
    eps = 1e-4
    fd = (S.ExternalWork().value(S.replay(path, rho=prob.rho(x + eps * d)))
          - S.ExternalWork().value(S.replay(path, rho=prob.rho(x - eps * d)))) / (2 * eps)
    adj = float(dW @ d)
    print(f"\nrefined mesh: {coarse.ne} -> {mesh.ne} elements; FD {fd:.8e}, adjoint {adj:.8e}")
    assert abs(fd - adj) <= 1e-4 * abs(adj)


@pytest.mark.parametrize("bad", [-0.1, float("nan"), float("inf")])
def test_h_crack_must_be_a_size(bad):
    from ngtmc.study import StudyError
    with pytest.raises(StudyError, match="h_crack"):
        D.cases(D._params("quick", h_crack=bad))


@pytest.mark.slow
def test_short_optimisation_improves_the_objective(tmp_path):
    out = D.run(tmp_path / "run", "quick", overrides={**OVERRIDES, "iterations": 2}, report=False)
    for f in ("metadata.json", "history.csv", "optimisation.csv", "designs.npz", "snapshots.npz", "optimisation.html"):
        assert (out / f).exists(), f
    meta = json.loads((out / "metadata.json").read_text())
    opt = pd.read_csv(out / "optimisation.csv")
    hist = pd.read_csv(out / "history.csv")
    assert set(hist["case"]) == {"initial", "final"}
    res = meta["results"]["optimisation"]
    print("\noptimisation:", opt.to_dict("list"), res)
    assert res["W_final"] > res["W_initial"]
    assert opt["volume_fraction"].max() <= D.PARAMETERS["volume_fraction"][0] + 1e-6
    des = np.load(out / "designs.npz")
    assert des["rho"].shape[1] == des["pad_mask"].size


def test_run_metadata_follows_the_run_folder_schema(tmp_path):
    """The optimisation's metadata.json is built from ngtmc.study.parameters.run_description (no copy of
    its own): schema version, every parameter with its unit, the overrides and both hashes."""
    from ngtmc.study.run_files import SCHEMA_VERSION, UNITS, read_metadata, write_json
    from ngtmc.study import parameters_hash, run_description

    p = D._params("quick", iterations=2)
    cases = [{"name": "initial", "label": "initial design", "parameters": {}}]
    meta = D.run_metadata(p, "quick", {"iterations": 2}, {"n_elements": 10, "n_vertices": 8, "n_design": 3},
                          cases, {"initial": {"peak_force": float("nan")}}, 1.5)
    write_json(tmp_path / "metadata.json", meta)
    back = read_metadata(tmp_path)
    assert set(run_description(D, p, "quick", {"iterations": 2})) <= set(back)
    assert back["study"] == "design_for_contact" and back["schema_version"] == SCHEMA_VERSION
    assert back["units"] == UNITS and back["force_unit"] == "N/mm" and back["thickness_mm"] == p["thickness"]
    assert back["overrides"] == {"iterations": 2} and back["parameters_hash"] == parameters_hash(p)
    assert back["parameters"]["E"] == {"value": 1000.0, "unit": "MPa", "description": D.PARAMETERS["E"][2]}
    assert back["parameters"]["iterations"]["value"] == 2
    assert back["results"]["initial"]["peak_force"] is None  # NaN is written as null, the file stays JSON
    assert back["status"] == "completed" and back["wall_time_s"] == 1.5


def test_gradient_check_runs_its_finite_differences_as_cases_on_dask_workers(tmp_path):
    """``ngtmc run design-for-contact --set gradient_check=2 --workers 2``: the initial design with
    its adjoint sweep and the four forward runs of the central differences are cases of one run,
    computed on 2 Dask workers; post_results compares dW/dx . d_j of the adjoint with (W(x0 + eps
    d_j) - W(x0 - eps d_j)) / (2 eps) of the forward cases (same load steps): within 1e-6
    (measured 4e-9 and 2e-8), and W of the initial case's history is the adjoint's objective."""
    from ngtmc.runner import run_study

    pytest.importorskip("dask.distributed")
    out = run_study("design_for_contact", output=tmp_path / "check", overrides={**OVERRIDES, "gradient_check": 2},
                    workers=2, report=False, progress=False, vtk=False)
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "completed" and meta["parallel"]["workers"] == 2
    check = meta["results"]["gradient_check"]
    assert [c["direction"] for c in check["directions"]] == [0, 1]
    for c in check["directions"]:
        print(f"\ndirection {c['direction']}: FD {c['finite_difference']:.10e}, adjoint {c['adjoint']:.10e}, "
              f"relative difference {c['relative_difference']:.1e}")
        assert c["same_load_steps"] and abs(c["adjoint"]) > 0
        assert c["relative_difference"] <= 1e-6
    p = D._params("quick", **{**OVERRIDES, "gradient_check": 2})
    prob = D.DesignProblem(p)
    W, dW, _ = prob.evaluate(np.full(int(prob.mask.sum()), p["initial_fill"]))
    assert check["W_initial"] == pytest.approx(W, rel=1e-12)
    assert [c["adjoint"] for c in check["directions"]] == pytest.approx(list(D.check_directions(p, dW.size) @ dW),
                                                                        rel=1e-12)
    hist = pd.read_csv(out / "history.csv")
    assert set(hist["case"]) == {"initial", "d0_plus", "d0_minus", "d1_plus", "d1_minus"}
    # the report's "Study tables" shows the check, units in the heads
    from ngtmc.report import render_report
    html = render_report(out).read_text()
    assert "Adjoint gradient against central differences" in html and "central difference [N mm]" in html
