"""The study runner and the command line, on a tiny custom study (seconds, not minutes).

The tiny study is a notched bar pulled apart (order-1 displacement, no void, a few hundred
triangles): enough to exercise history, metadata, snapshots, checkpoints, resume and failure.
"""
from __future__ import annotations

import json
import types

import numpy as np
import pandas as pd
import pytest

import ngtmc
from ngtmc.runner import HISTORY_COLUMNS, run_study, write_atomic
from ngtmc.study import list_studies, load_study
from ngtmc.study import StudyError
from ngtmc.study import Case
from ngtmc.study import study_parameters

TIMING_COLUMNS = ["wall_time", "solve_time", "assembly_time"]


def _tiny_scene(p):
    from netgen.occ import MoveTo, OCCGeometry, Rectangle, X, Y
    import ngsolve as ngs
    bar = Rectangle(1.0, 0.4).Face() - MoveTo(0.48, 0).Rectangle(0.04, 0.1).Face()
    bar.faces.name = "bar"
    for e in bar.edges:
        if abs(e.center.y) < 1e-9:
            e.name = "bottom"      # both sides of the notch
    bar.edges.Max(Y).name = "top"
    mesh = ngs.Mesh(OCCGeometry(bar, dim=2).GenerateMesh(maxh=float(p["h"])))
    mat = ngtmc.Material(E=float(p["E"]), nu=0.3, Gc=float(p["Gc"]), l0=float(p["l0"]))
    return ngtmc.Scene(mesh=mesh, materials={"bar": mat},
                       supports=[ngtmc.Support("bottom", x=True, y=True)],
                       load=ngtmc.DisplacementLoad("top", direction="y", hold_tangential=True),
                       fracture_regions="bar", gamma0=1e-6, name="tiny")


def tiny_study(final_load=0.02, du_min=1e-5, options=None, names=("main",)):
    mod = types.ModuleType("tiny_study")
    mod.NAME = "tiny"
    mod.TITLE = "Tiny notched bar"
    mod.SUMMARY = "test study"
    mod.PARAMETERS = {"E": (1000.0, "MPa", "Young's modulus"), "Gc": (0.05, "N/mm", "toughness"),
                      "l0": (0.1, "mm", "length scale"), "k_u": (20.0, "1/N", "step control"),
                      "final_load": (final_load, "mm", "final load")}
    mod.RESOLUTIONS = {"quick": {"h": 0.05, "du_max": 1e-3}, "medium": {"h": 0.04, "du_max": 1e-3},
                       "paper": {"h": 0.03, "du_max": 1e-3}}
    mod.DEFAULT_RESOLUTION = "quick"

    def cases(p):
        return [Case(name=name, label="tiny", scene=lambda: _tiny_scene(p),
                     schedule=ngtmc.Schedule.monotonic(float(p["final_load"])),
                     control=ngtmc.AdaptiveStepControl(du_max=float(p["du_max"]), k_u=float(p["k_u"]), du_min=du_min),
                     snapshot_loads=[0.005, 0.01], parameters={"k_u": p["k_u"]}, options=dict(options or {}))
                for name in names]

    mod.cases = cases
    mod.references = lambda p: [{"label": "line", "source": "none", "kind": "curve", "x": [0, 1], "y": [0, 1],
                                 "x_unit": "mm", "y_unit": "N/mm"}]
    mod.targets = lambda p: [{"case": "main", "quantity": "peak_force", "value": 1.0, "unit": "N/mm",
                              "source": "none", "tolerance": 0.5}]
    return mod


def _physics(df):
    return df.drop(columns=[c for c in TIMING_COLUMNS if c in df.columns])


@pytest.fixture(scope="module")
def full_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "full"
    run_study(tiny_study(), output=out, report=False, progress=False, threads=1, vtk=True)
    return out


def test_registry_names_and_errors():
    names = list_studies()
    assert "three_point_bending" in names and "step_control" in names
    assert load_study("three-point-bending").NAME == "three_point_bending"
    with pytest.raises(StudyError, match="valid studies: .*three_point_bending"):
        load_study("no-such-study")
    mod = load_study("three_point_bending")
    with pytest.raises(StudyError, match="valid keys: .*k_u"):
        study_parameters(mod, "quick", {"k_uu": 1})
    with pytest.raises(StudyError, match="valid: quick, medium, paper"):
        study_parameters(mod, "fine")
    res, p = study_parameters(mod, "quick", {"k_u": "50", "du_max": "2e-3"})
    assert p["k_u"] == 50.0 and p["du_max"] == 2e-3 and isinstance(p["k_u"], float)
    for name in names:
        m = load_study(name)
        assert {"quick", "medium", "paper"} <= set(m.RESOLUTIONS), name


def test_resolution_changes_mesh_and_steps_only():
    for name in list_studies():
        m = load_study(name)
        for r in m.RESOLUTIONS.values():
            clash = set(r) & set(m.PARAMETERS)
            assert not clash, f"{name}: resolution keys {clash} are physics parameters"


def test_run_folder_contents(full_run):
    meta = json.loads((full_run / "metadata.json").read_text())
    assert meta["status"] == "completed" and meta["study"] == "tiny" and meta["resolution"] == "quick"
    for key in ("versions", "git_revision", "units", "parameters", "mesh", "wall_time_s", "cases", "results",
                "references", "targets", "created", "thickness_mm", "force_unit"):
        assert key in meta, key
    assert meta["parameters"]["E"] == {"value": 1000.0, "unit": "MPa", "description": "Young's modulus"}
    assert meta["parameters"]["h"]["unit"] == "mm"
    assert meta["mesh"]["n_elements"] > 0 and meta["mesh"]["ndof_u"] > 0 and meta["mesh"]["ndof_alpha"] > 0
    res = meta["results"]["main"]
    for key in ("peak_force", "peak_load", "steps", "newton_iterations", "wall_time_s", "solve_time_s"):
        assert key in res, key
    # the solver's safeguard counters (Simulation.counters): non-negative integer counts
    assert set(res["counters"]) >= {"floor_accepts", "energy_noise_switches"}
    assert all(isinstance(res["counters"][k], int) and res["counters"][k] >= 0
               for k in ("floor_accepts", "energy_noise_switches"))
    h = pd.read_csv(full_run / "history.csv")
    assert list(h.columns[:len(HISTORY_COLUMNS)]) == HISTORY_COLUMNS
    assert h["step"].tolist() == list(range(len(h)))
    assert h["load"].iloc[-1] == pytest.approx(0.02)
    assert res["steps"] == len(h) - 1
    assert res["peak_force"] == pytest.approx(h["force"].max())
    # the bar breaks: the force drops after the peak
    assert h["max_alpha"].iloc[-1] > 0.9 and h["force"].iloc[-1] < 0.5 * h["force"].max()

    z = np.load(full_run / "snapshots.npz")
    nv = meta["mesh"]["n_vertices"]
    V, T = z["main__vertices"], z["main__triangles"]
    assert V.shape == (nv, 2) and T.shape == (meta["mesh"]["n_elements"], 3) and T.min() == 0 and T.max() == nv - 1
    loads = z["main__loads"]
    assert loads[0] >= 0.005 and loads[1] >= 0.01 and loads[-1] == pytest.approx(0.02)
    assert z["main__u"].shape == (len(loads), nv, 2) and z["main__alpha"].shape == (len(loads), nv)
    assert np.all(z["main__rho"] == 1.0)
    # u at the vertices: the top edge moves by the load, the bottom stays
    top = V[:, 1] > 0.4 - 1e-9
    assert np.allclose(z["main__u"][-1][top, 1], loads[-1])
    assert np.allclose(z["main__u"][-1][V[:, 1] < 1e-9], 0.0)
    assert (full_run / "vtk" / "main.pvd").exists() and len(list((full_run / "vtk").glob("main_*.vtu"))) == len(loads)


class _Crash(BaseException):
    """Stands for a kill: not caught as an error by the runner's case handler."""


@pytest.mark.parametrize("how", ["interrupt", "crash"])
def test_resume_gives_same_history(full_run, tmp_path, how):
    out = tmp_path / how

    def stop(sim, row):
        if row["step"] == 9:
            raise KeyboardInterrupt if how == "interrupt" else _Crash()

    with pytest.raises(KeyboardInterrupt if how == "interrupt" else _Crash):
        run_study(tiny_study(), output=out, report=False, progress=False, threads=1, callbacks=[stop], checkpoint_every=4,
                  checkpoint_seconds=1e9)
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == ("interrupted" if how == "interrupt" else "failed")
    part = pd.read_csv(out / "history.csv")
    assert part["step"].max() == 9          # every accepted step is in the history
    # interrupt: the checkpoint is the last accepted step; a crash leaves the last periodic one (step 8)
    ck = np.load(out / "checkpoint" / "main.npz")
    assert json.loads(str(ck["simulation"]))["step"] == (9 if how == "interrupt" else 8)
    with pytest.raises(StudyError, match="holds a run already"):
        run_study(tiny_study(), output=out, report=False, progress=False, threads=1)
    run_study(tiny_study(), output=out, report=False, progress=False, threads=1, resume=True)
    a = _physics(pd.read_csv(full_run / "history.csv"))
    b = _physics(pd.read_csv(out / "history.csv"))
    pd.testing.assert_frame_equal(a, b, rtol=1e-9, atol=1e-12)
    za, zb = np.load(full_run / "snapshots.npz"), np.load(out / "snapshots.npz")
    assert sorted(za.files) == sorted(zb.files)
    for k in za.files:
        np.testing.assert_allclose(za[k], zb[k], rtol=1e-9, atol=1e-12, err_msg=k)
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "completed"


def test_failed_run_writes_history_and_status(tmp_path):
    out = tmp_path / "fail"

    def boom(sim, row):
        if row["step"] == 3:
            raise ngtmc.StepFailure("synthetic failure", sim.history, None)

    with pytest.raises(ngtmc.StepFailure):
        run_study(tiny_study(), output=out, report=False, progress=False, threads=1, callbacks=[boom])
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "failed" and "synthetic failure" in meta["error"]
    assert meta["results"]["main"]["status"] == "failed"
    h = pd.read_csv(out / "history.csv")
    assert h["step"].tolist() == [0, 1, 2, 3]


def test_real_step_failure(tmp_path):
    """A StepFailure raised by the Simulation itself (here: its max_steps limit) is recorded as failed."""
    out = tmp_path / "realfail"
    with pytest.raises(ngtmc.StepFailure, match="max_steps"):
        run_study(tiny_study(options={"max_steps": 3}), output=out, report=False, progress=False, threads=1, vtk=False)
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "failed" and "max_steps" in meta["error"]
    assert "max_steps" in meta["results"]["main"]["error"]
    assert pd.read_csv(out / "history.csv")["step"].tolist() == [0, 1, 2, 3]


def test_write_atomic_leaves_no_temp_files(tmp_path):
    f = tmp_path / "a.csv"
    write_atomic(f, "x\n1\n")
    write_atomic(f, "x\n2\n")
    assert f.read_text() == "x\n2\n" and [p.name for p in tmp_path.iterdir()] == ["a.csv"]


def test_cli(tmp_path, capsys, monkeypatch):
    from ngtmc.cli import main, parse_overrides
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "three-point-bending" in out and "step-control" in out
    assert main(["run", "no-such-study"]) == 2
    assert "valid studies" in capsys.readouterr().err
    assert main(["run", "three-point-bending", "--set", "not_a_knob=1", "--output", str(tmp_path / "x")]) == 2
    assert "valid keys" in capsys.readouterr().err
    assert main(["run", "three-point-bending", "--set", "k_u"]) == 2
    assert parse_overrides(["k_u=50", "du_max=1e-3"]) == {"k_u": "50", "du_max": "1e-3"}
    # the run command forwards everything to run_study
    seen = {}

    def fake_run_study(name, **kw):
        seen.update(kw, name=name)
        return tmp_path

    import ngtmc.runner
    monkeypatch.setattr(ngtmc.runner, "run_study", fake_run_study)
    assert main(["run", "three-point-bending", "-r", "medium", "-o", "o", "--set", "k_u=50", "--resume",
                 "--no-report"]) == 0
    assert seen["name"] == "three-point-bending" and seen["resolution"] == "medium" and seen["output"] == "o"
    assert seen["overrides"] == {"k_u": "50"} and seen["resume"] is True and seen["report"] is False


def test_cli_report_missing_function(tmp_path, capsys, monkeypatch):
    from ngtmc.cli import main
    import ngtmc.report as report
    monkeypatch.delattr(report, "render_index", raising=False)
    assert main(["report", "--index", str(tmp_path)]) == 1
    assert "render_index" in capsys.readouterr().err
    assert main(["report"]) == 2


def test_top_level_exports():
    assert ngtmc.run_study is run_study
    assert ngtmc.list_studies() == list_studies()


def test_sigterm_is_recorded_as_interrupted_and_resumable(full_run, tmp_path):
    import os
    import signal
    out = tmp_path / "term"

    def term(sim, row):
        if row["step"] == 5:
            os.kill(os.getpid(), signal.SIGTERM)

    with pytest.raises(KeyboardInterrupt):
        run_study(tiny_study(), output=out, report=False, progress=False, threads=1, callbacks=[term], vtk=False)
    assert json.loads((out / "metadata.json").read_text())["status"] == "interrupted"
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL or callable(signal.getsignal(signal.SIGTERM))
    run_study(tiny_study(), output=out, report=False, progress=False, threads=1, resume=True, vtk=False)
    pd.testing.assert_frame_equal(_physics(pd.read_csv(full_run / "history.csv")),
                                  _physics(pd.read_csv(out / "history.csv")), rtol=1e-9, atol=1e-12)


def test_cli_version_and_show(capsys):
    from ngtmc.cli import main
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"ngtmc {ngtmc.__version__}"
    assert main(["show", "three-point-bending"]) == 0
    out = capsys.readouterr().out
    mod = load_study("three_point_bending")
    assert "Three-point bending" in out and "default quick" in out
    lines = out.splitlines()
    e_line = next(line for line in lines if line.split()[:1] == ["E"])
    assert e_line.split()[1:3] == ["20800", "MPa"]                 # default and unit
    header = next(line for line in lines if line.split()[:2] == ["key", "unit"])
    assert header.split()[2:5] == ["quick", "medium", "paper"]
    h_band = next(line for line in lines if line.split()[:1] == ["h_band"]).split()
    assert h_band[1] == "mm" and [float(x) for x in h_band[2:5]] == [mod.RESOLUTIONS[r]["h_band"]
                                                                      for r in ("quick", "medium", "paper")]
    assert main(["show", "no-such-study"]) == 2
    assert "valid studies" in capsys.readouterr().err


def test_history_columns_defined_once():
    """simulation, runner, report and docs/run-directory.md agree on the history columns and units."""
    import pathlib
    import re
    from ngtmc import report, runner
    from ngtmc.simulation import history as runfiles      # the history schema's one owner
    assert ngtmc.HISTORY_UNITS is runfiles.HISTORY_UNITS
    assert runner.HISTORY_COLUMNS == ["case", *runfiles.HISTORY_UNITS]
    assert list(report.HISTORY_COLUMNS) == runner.HISTORY_COLUMNS
    assert all(report.HISTORY_COLUMNS[k] == u for k, u in runfiles.HISTORY_UNITS.items() if k != "force")
    doc = (pathlib.Path(__file__).parents[1] / "docs" / "run-directory.md").read_text()
    section = doc.split("## `history.csv`")[1].split("## ")[0]
    documented = re.findall(r"^\| `(\w+)` \|", section, flags=re.M)
    assert documented == runner.HISTORY_COLUMNS


def test_checkpoint_state_by_name_and_the_positional_form_still_loads():
    """The Simulation state is stored by name (JSON, floats exact); a checkpoint in the older
    positional form (``scalars``, ``control``) decodes to the same state."""
    from ngtmc.runner.cases import _Run
    state = {"t": 0.0123456789012345, "step": 7, "last_delta_wf": 1.5e-7, "wf_prev": 0.25, "elapsed": 3.5,
             "control": {"scale": 0.5, "successes": 2}}
    common = {"done": np.array(False), "rows": np.array("[]"), "results": np.array("{}"),
              "case_meta": np.array("{}"), "solver__u": np.arange(3.0)}
    new = dict(common, simulation=np.array(json.dumps(state)))
    old = dict(common, scalars=np.array([state[k] for k in ("t", "step", "last_delta_wf", "wf_prev", "elapsed")]),
               control=np.array(json.dumps(state["control"])))
    a, b = _Run._decode_checkpoint(new)["state"], _Run._decode_checkpoint(old)["state"]
    assert np.array_equal(a.pop("solver")["u"], b.pop("solver")["u"])
    assert a == b and a["t"] == state["t"] and a["step"] == 7


def test_auto_threads_follow_the_mesh_size(monkeypatch):
    """threads="auto" of a serial run: per case, one NGSolve thread below AUTO_TWO_THREADS_ELEMENTS
    elements (AUTO_TWO_THREADS_ELEMENTS_3D in 3D) in its built scene (two runs side by side on two
    threads each were more than ten times slower than on one each), two from there; a case whose
    scene is not built gets one."""
    import ngtmc.runner.study_run as runner
    from ngtmc.study import study_parameters
    mod = tiny_study()
    _, p = study_parameters(mod, "quick")
    case, unbuilt = mod.cases(p)[0], mod.cases(p)[0]
    ne = case.build_scene().mesh.ne
    assert case.scene.mesh.dim == 2 and ne < runner.AUTO_TWO_THREADS_ELEMENTS
    assert runner.case_threads(case) == 1 and runner.case_threads(unbuilt) == 1
    monkeypatch.setattr(runner, "AUTO_TWO_THREADS_ELEMENTS", ne)
    assert runner.case_threads(case) == 2 and runner.case_threads(unbuilt) == 1
    monkeypatch.setattr(runner, "AUTO_TWO_THREADS_ELEMENTS_3D", 1)   # a 2D mesh ignores the 3D threshold
    monkeypatch.setattr(runner, "AUTO_TWO_THREADS_ELEMENTS", ne + 1)
    assert runner.case_threads(case) == 1


def test_auto_threads_are_chosen_and_recorded_per_case(tmp_path, monkeypatch):
    """A serial run with threads="auto" runs each case in its own TaskManager with the count
    case_threads gives it, and records the count that was active in the case's metadata."""
    import ngtmc.runner.study_run as runner
    mod = tiny_study(names=("a", "b"))
    monkeypatch.setattr(runner, "case_threads", lambda c: {"a": 2, "b": 1}[c.name])
    out = run_study(mod, output=tmp_path / "run", report=False, progress=False)
    meta = json.loads((out / "metadata.json").read_text())
    assert {c["name"]: c["threads"] for c in meta["cases"]} == {"a": 2, "b": 1}
    out = run_study(mod, output=tmp_path / "one", report=False, progress=False, threads=1)   # explicit: every case
    meta = json.loads((out / "metadata.json").read_text())
    assert {c["name"]: c["threads"] for c in meta["cases"]} == {"a": 1, "b": 1}


def test_a_coarse_case_warns_once(tmp_path):
    """A case whose fracture mesh is coarser than l0/2 gets one ResolutionWarning, from its solver:
    the runner's check of every case before the run refuses bad input but leaves the warning to it."""
    import warnings
    mod = tiny_study(final_load=0.001)
    mod.RESOLUTIONS["quick"]["h"] = 0.08          # l0/2 = 0.05 mm
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        run_study(mod, output=tmp_path / "run", report=False, progress=False, threads=1, vtk=False)
    res = [w for w in seen if issubclass(w.category, ngtmc.ResolutionWarning)]
    assert len(res) == 1, [str(w.message) for w in res]
    assert "l0/2" in str(res[0].message)
