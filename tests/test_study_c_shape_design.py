"""The C-shape topology optimisation study, run end to end on a coarse mesh with few evaluations:
both optimisations, their gradient checks (EXPECTED: 1e-4), no failed design, the comparison with
fracture on, the snapshots of both cases and the report's figures and tables. The quick run
(3282 design variables, 100 evaluations per design) is a benchmark record
(studies/records/c_shape_design.json), too long for the suite."""
from __future__ import annotations

import json

import numpy as np
import pytest

from ngtmc.study import load_study
from study_expected import expected_test

S = load_study("c_shape_design")
OVERRIDES = {"h": 0.1, "evaluations": 8, "check_directions": 1}


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    from ngtmc.runner import run_study
    return run_study("c_shape_design", resolution="quick", overrides=OVERRIDES,
                     output=tmp_path_factory.mktemp("cs") / "run", vtk=False, progress=False)


test_expected = expected_test(S)


@pytest.fixture(scope="module")
def meta(run_dir):
    return json.loads((run_dir / "metadata.json").read_text())


def test_both_designs_ran_and_were_compared_with_fracture_on(meta):
    r = meta["results"]
    assert meta["status"] == "completed"
    for case in ("fracture", "contact_only"):
        c = r[case]
        assert c["evaluations"] == OVERRIDES["evaluations"] + 1            # and the final design's run
        assert c["objective_final"] > c["objective_initial"]
        assert c["volume_final"] <= S.PARAMETERS["volume_fraction"][0] + 2e-3
        assert len(c["gradient_checks"]) == 3                              # initial, gray, final
        assert c["adjoint_per_forward"] < 1.5
    assert r["fracture"]["W_as_designed"] == pytest.approx(r["fracture"]["W_fracture_on"], rel=1e-9)
    # contact only: fracture on takes energy away from the design made without it
    assert r["contact_only"]["W_fracture_on"] < r["contact_only"]["W_as_designed"]
    assert meta["mesh"]["n_elements"] > 0 and meta["features"]["fracture"]


def test_the_report_shows_designs_checks_and_snapshots(run_dir, meta):
    html = (run_dir / "report.html").read_text()
    for text in ("Designs, designed with fracture", "Gradient checks", "Objective against evaluation",
                 "The two designs, run with fracture on", "Optimisation size and cost"):
        assert text in html
    with np.load(run_dir / "snapshots.npz") as z:
        for case in ("fracture", "contact_only"):
            # the last frame is the final state, whose largest phase field the comparison table gives
            assert z[f"{case}__alpha"][-1].max() == pytest.approx(meta["results"][case]["alpha_max"], abs=1e-12)
            assert z[f"{case}__rho"].size == z[f"{case}__triangles"].shape[0]
        with np.load(run_dir / f"optimisation_{case}.npz") as d:      # the design, for a rerun
            assert np.allclose(d["rho"], z[f"{case}__rho"]) and d["x"].size == d["design_mask"].sum()
