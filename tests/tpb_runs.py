"""Quick runs of the three-point-bending study for the fidelity tests (``tests/test_tpb_fidelity.py``,
``tests/test_tpb_miehe.py``): one helper, so that every variant is run and read the same way."""
from __future__ import annotations

import json

import pandas as pd

import ngtmc
from ngtmc.study import study_parameters
from ngtmc.studies import three_point_bending as tpb


def solve_quick(tmp_path_factory, name: str, overrides: dict):
    """Run the study at quick with ``overrides`` (the study's default scheme, one thread, no report,
    no VTK) and check that it completed: (results of case main, its history, the parameters)."""
    out = ngtmc.run_study("three_point_bending", resolution="quick", output=tmp_path_factory.mktemp(name),
                          overrides=overrides, report=False, progress=False, threads=1, vtk=False)
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "completed"
    _, p = study_parameters(tpb, "quick", overrides)
    r = meta["results"]["main"]
    print(f"\n{name}, quick: peak {r['peak_force']:.3f} N/mm at {r['peak_load']:.5f} mm, "
          f"{r['steps']} steps, {r['newton_iterations']} Newton")
    return r, pd.read_csv(out / "history.csv"), p
