"""A user's own scene gets the run folder and report of a named study; one progress printer.

``ngtmc.simulate(scene, schedule, control, out_dir=...)`` and ``ngtmc run path/to/my_study.py``
go through the runner (:mod:`ngtmc.runner`) and its per-step plugins (:mod:`ngtmc.simulation.plugins`):
the same files, the same metadata schema, the same report. Tiny scenes of tests/scenes.py (a few
dozen triangles, about a second each).
"""
from __future__ import annotations

import json
from pathlib import Path
import sys
import textwrap

import numpy as np
import pandas as pd
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import ngtmc  # noqa: E402
from ngtmc.simulation import Progress  # noqa: E402
from ngtmc.simulation import force_unit
from ngtmc.study.run_files import SCHEMA_VERSION  # noqa: E402
from ngtmc.simulation import HISTORY_UNITS
from ngtmc.study import StudyError  # noqa: E402
from scenes import tension_bar  # noqa: E402

PHYSICS = [c for c in HISTORY_UNITS if c not in ("wall_time", "solve_time", "assembly_time")]


def _bar(**kw):
    kw.setdefault("maxh", 0.1)
    kw.setdefault("Gc", 1e-3)
    kw.setdefault("l0", 0.25)
    return tension_bar(**kw)


def _control():
    return ngtmc.AdaptiveStepControl(du_max=2.5e-4)


@pytest.fixture(scope="module")
def scene_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("user") / "bar"
    res = ngtmc.simulate(_bar(), 0.002, _control(), out_dir=out, report=True)
    return out, res


def test_simulate_out_dir_writes_a_study_folder(scene_run):
    out, res = scene_run
    assert res.run_dir == out
    for f in ("history.csv", "metadata.json", "snapshots.npz", "report.html", "vtk/main.pvd"):
        assert (out / f).is_file(), f
    assert list((out / "checkpoint").glob("main*.npz"))
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["schema_version"] == SCHEMA_VERSION and meta["status"] == "completed"
    assert meta["parameters_hash"].startswith("sha256:")
    assert meta["force_unit"] == "N/mm" and meta["thickness_mm"] == 1.0
    assert meta["parameters"]["bar.E"] == {"value": 1000.0, "unit": "MPa",
                                           "description": "Young's modulus in region 'bar'"}
    assert meta["results"]["main"]["status"] == "completed"
    hist = pd.read_csv(out / "history.csv")
    assert list(hist.columns[:len(HISTORY_UNITS) + 1]) == ["case", *HISTORY_UNITS]
    # the same history as the in-memory run, and the result of simulate carries it with the solver
    mem = ngtmc.simulate(_bar(), 0.002, _control())
    np.testing.assert_allclose(hist[PHYSICS].to_numpy(float), mem.history[PHYSICS].to_numpy(float),
                               rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(res.history[PHYSICS].to_numpy(float), mem.history[PHYSICS].to_numpy(float),
                               rtol=1e-9, atol=1e-14)
    assert res.solver is not None and res.peak_force == pytest.approx(mem.peak_force)


def test_simulate_out_dir_resume_and_refusals(scene_run, tmp_path):
    out, _ = scene_run
    # the same scene: every case is complete, nothing is recomputed
    again = ngtmc.simulate(_bar(), 0.002, _control(), out_dir=out, resume=True, report=False)
    assert len(again.history) == len(pd.read_csv(out / "history.csv"))
    # another scene in the same folder: refused, the differences named
    with pytest.raises(StudyError, match=r"bar\.E: 1000\.0 -> 2000\.0"):
        ngtmc.simulate(_bar(E=2000.0), 0.002, _control(), out_dir=out, resume=True, report=False)
    with pytest.raises(StudyError, match="holds a run already"):
        ngtmc.simulate(_bar(), 0.002, _control(), out_dir=out, report=False)


def test_user_scene_report_renders_in_chromium(scene_run, tmp_path):
    from test_report_browser import _check_page, _chromium
    exe = _chromium()
    if exe is None:
        pytest.skip("no chromium binary (install the Debian package 'chromium')")
    out, _ = scene_run
    _check_page(exe, out / "report.html", tmp_path, min_plots=4)


STUDY_FILE = '''
"""A study of my own: a bar pulled in tension."""
import sys
sys.path.insert(0, {tests!r})
import ngtmc
from ngtmc.study import Case
from scenes import tension_bar

NAME = "my_bar"
TITLE = "My bar in tension"
SUMMARY = "a user's study file"
PARAMETERS = {{"E": (1000.0, "MPa", "Young's modulus"), "final_load": (0.002, "mm", "final load")}}
RESOLUTIONS = {{"quick": {{"maxh": 0.1}}, "medium": {{"maxh": 0.05}}, "paper": {{"maxh": 0.025}}}}


def cases(p):
    return [Case("main", "bar", scene=lambda: tension_bar(E=p["E"], Gc=1e-3, l0=0.25, maxh=p["maxh"]),
                 schedule=p["final_load"], control=ngtmc.AdaptiveStepControl(du_max=5e-4),
                 snapshot_loads=[0.001])]
'''


def test_cli_runs_a_study_file(tmp_path, capsys):
    from ngtmc.cli import main
    f = tmp_path / "my_study.py"
    f.write_text(STUDY_FILE.format(tests=str(Path(__file__).parent)))
    out = tmp_path / "run"
    assert main(["run", str(f), "-o", str(out), "--set", "E=2000", "--threads", "1", "-q", "--no-vtk"]) == 0
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["study"] == "my_bar" and meta["overrides"] == {"E": 2000.0}
    assert meta["parameters"]["E"]["value"] == 2000.0 and (out / "report.html").is_file()
    assert main(["run", str(tmp_path / "missing.py"), "-o", str(tmp_path / "x")]) == 2
    assert "does not exist" in capsys.readouterr().err


# ---------------------------------------------------------------------------------- progress
def test_force_unit():
    assert force_unit(2, 1.0) == "N/mm"
    assert force_unit(2, 2.0) == "N"
    assert force_unit(3, None) == "N"


def test_progress_lines_carry_the_unit_and_agree(tmp_path, capsys):
    ngtmc.simulate(_bar(), 0.001, _control(), progress=True)
    api = [ln for ln in capsys.readouterr().err.splitlines() if "step" in ln and "load" in ln]
    ngtmc.simulate(_bar(), 0.001, _control(), out_dir=tmp_path / "r", progress=True, report=False, vtk=False)
    run = [ln for ln in capsys.readouterr().err.splitlines() if " step " in ln and "load" in ln]
    assert api and run
    for ln in api + run:
        assert " N/mm " in ln, ln
    # one printer: the same words after the prefix
    strip = lambda ln: ln.split(" step ", 1)[1].split(" % of the load path")[0]  # noqa: E731
    assert [strip(a)[:30] for a in api[-1:]] == [strip(r)[:30] for r in run[-1:]]
    ngtmc.simulate(_bar(thickness=2.0), 0.001, _control(), progress=True)
    thick = [ln for ln in capsys.readouterr().err.splitlines() if "step" in ln and "load" in ln]
    assert thick and all(" N " in ln and "N/mm" not in ln for ln in thick)


class _FakeSim:
    def __init__(self, total):
        self.schedule = type("S", (), {"total_time": total})()
        self.t = 0.0
        self.finished = False
        self.solver = type("V", (), {"alpha": None})()


def test_time_left_follows_the_recent_pace():
    """Steps shrink after the peak: the estimate follows the recent pace, not the load fraction."""
    p = Progress(True, unit="N/mm", window=20.0)
    # 0.5 of the load path in 10 s, then the pace drops to 0.01 per 10 s
    for el, t in [(0.0, 0.0), (5.0, 0.25), (10.0, 0.5)]:
        p.time_left(el, t, 1.0)
    for k in range(1, 8):
        left = p.time_left(10.0 + 10 * k, 0.5 + 0.01 * k, 1.0)
    # load fraction alone would say about 1.5 x 80 s = 120 s; the recent pace says about 430 s
    assert left[0] > 300
    assert left[1] <= 30
    sim = _FakeSim(1.0)
    sim.t = 0.57
    line = p.line(sim, {"step": 9, "load": 0.57, "step_size": 0.01, "force": 1.5, "newton_iterations": 3,
                        "cutbacks": 0, "wall_time": 90.0})
    assert "force 1.5 N/mm" in line and "estimate from the pace of the last" in line


def test_result_units_carry_the_force_unit(scene_run):
    out, res = scene_run
    meta = json.loads((out / "metadata.json").read_text())
    assert res.units["force"] == meta["force_unit"] == "N/mm"
    assert ngtmc.Simulation(_bar(thickness=2.0), 0.001).units["force"] == "N"


def test_no_time_left_while_the_steps_are_tiny():
    """While a crack runs the steps are 1e-6 of the path: the recent pace would promise days; the
    line says there is no estimate instead."""
    p = Progress(True, unit="N/mm", window=20.0)
    for el, t in [(0.0, 0.0), (50.0, 0.5), (60.0, 0.5 + 1e-6), (70.0, 0.5 + 2e-6), (80.0, 0.5 + 3e-6)]:
        p.time_left(el, t, 1.0)
    sim = _FakeSim(1.0)
    sim.t = 0.5 + 4e-6
    line = p.line(sim, {"step": 9, "load": sim.t, "step_size": 1e-6, "force": 30.0, "newton_iterations": 3,
                        "cutbacks": 0, "wall_time": 90.0})
    assert "no estimate of the time left while the steps are this short" in line and "s left" not in line


# ---------------------------------------------------------------------------------- steps, plugins
def test_steps_yields_each_accepted_row_and_run_is_built_on_it():
    sim = ngtmc.Simulation(_bar(), 0.001, _control())
    it = sim.steps()
    first = next(it)                      # lazy: one step solved, the state is that of the step
    assert sim.step == 1 and first is sim.rows[-1] and first["step"] == 1 and not sim.finished
    rows = [first, *it]
    assert sim.finished and rows == sim.rows[1:] and [r["step"] for r in rows] == list(range(1, len(rows) + 1))
    seen = []
    res = ngtmc.Simulation(_bar(), 0.001, _control()).run(callbacks=[lambda s, row: seen.append(row["load"])])
    assert seen == [r["load"] for r in rows] == list(res.history["load"].iloc[1:])


def test_max_steps_ends_the_steps_with_a_step_failure():
    sim = ngtmc.Simulation(_bar(), 0.001, _control(), max_steps=2)
    got = []
    with pytest.raises(ngtmc.StepFailure, match="max_steps = 2") as e:
        for row in sim.steps():
            got.append(row["step"])
    assert got == [1, 2] and len(e.value.history) == 3


def test_report_output_plugin(tmp_path, capsys, monkeypatch):
    """The report is a plugin: rendered once, from the run folder, when the run ends; strict only
    for a completed run."""
    from ngtmc.runner.outputs import ReportOutput
    import ngtmc.report
    calls = []
    monkeypatch.setattr(ngtmc.report, "render_report", lambda out: calls.append(out) or Path(out) / "report.html")
    plugin = ReportOutput(tmp_path, strict=True)
    plugin(None, {})                      # nothing per step
    assert calls == []
    assert plugin.finish("completed") == tmp_path / "report.html" and calls == [tmp_path]

    def broken(out):
        raise ValueError("no history")

    monkeypatch.setattr(ngtmc.report, "render_report", broken)
    ReportOutput(tmp_path, strict=True).finish("failed")          # a failed run: warn only
    assert "report not rendered: ValueError: no history" in capsys.readouterr().err
    with pytest.raises(ValueError, match="no history"):
        ReportOutput(tmp_path, strict=True).finish("completed")
    ReportOutput(tmp_path, strict=False).finish("completed")
    assert "report not rendered" in capsys.readouterr().err


def test_no_time_left_while_the_crack_runs_and_the_share_never_goes_back():
    """The estimate is left out while the dissipated energy grows with a crack formed (the crack runs) and while path
    following turns the load back; the share of the load path is the furthest reached."""
    p = Progress(True, unit="N/mm", window=20.0)
    sim = _FakeSim(1.0)
    row = {"step": 1, "load": 0.0, "step_size": 0.01, "force": 1.0, "newton_iterations": 3, "cutbacks": 0,
           "max_alpha": 1.0}
    for k, (t, d) in enumerate([(0.1, 0.0), (0.2, 0.0), (0.3, 0.0), (0.4, 0.0)]):
        sim.t = t
        line = p.line(sim, dict(row, load=t, wall_time=5.0 * (k + 1), dissipated_energy=d))
    assert "s left" in line                       # no dissipation: the pace holds
    sim.t = 0.42                                  # diffuse damage (max alpha 0.5) growing: still estimated
    assert "s left" in p.line(sim, dict(row, load=0.42, wall_time=22.0, dissipated_energy=0.05, max_alpha=0.5))
    for k, (t, d) in enumerate([(0.45, 0.1), (0.5, 0.3), (0.55, 0.6)]):
        sim.t = t
        line = p.line(sim, dict(row, load=t, wall_time=25.0 + 5.0 * k, dissipated_energy=d))
    assert "no estimate of the time left while the crack runs" in line and "s left" not in line
    sim.t = 0.5                                   # a snap-back: the load turns back
    line = p.line(sim, dict(row, load=0.5, wall_time=45.0, dissipated_energy=0.7))
    assert "55.0 % of the load path" in line and "turns back" in line and "s left" not in line


def test_no_time_left_before_the_crack_has_run():
    """A scene that may crack: before a crack has formed the pace cannot foresee the crack run's
    steps (the quick three-point bending's pace said a tenth of the time left), so no estimate."""
    p = Progress(True, unit="N/mm", window=20.0)
    sim = _FakeSim(1.0)
    sim.solver = type("V", (), {"alpha": object()})()
    row = {"step": 1, "step_size": 0.01, "force": 1.0, "newton_iterations": 3, "cutbacks": 0, "dissipated_energy": 0.0}
    for k, t in enumerate([0.1, 0.2, 0.3]):
        sim.t = t
        line = p.line(sim, dict(row, load=t, wall_time=5.0 * (k + 1), max_alpha=0.3))
    assert "before the crack has run" in line and "s left" not in line
    sim.t = 0.5
    line = p.line(sim, dict(row, load=0.5, wall_time=40.0, max_alpha=1.0, dissipated_energy=0.0))
    assert "s left" in line
