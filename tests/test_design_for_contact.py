"""The design_for_contact study: filtered design gradient and a short optimisation run."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from ngtmc import sensitivities as S
from studies import design_for_contact as D

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
