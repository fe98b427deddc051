"""Resume that cannot mix physics, on the tiny notched-bar study of test_runner.py (seconds).

Overrides are recorded and compared, checkpoints keep two generations and a corrupted one is
named and skipped, completed cases are never overwritten, a stale "running" status is recognised,
and a refused run leaves no folder behind.
"""
from __future__ import annotations

import json
import os
import socket
import subprocess
import sys

import pandas as pd
import pytest

from ngtmc.study import CheckpointWarning, effective_status
from ngtmc.study import parameters_hash
from ngtmc.runner import run_study
from ngtmc.study import StudyError
from ngtmc.study.parameters import ADDED_AT_DEFAULT, INERT_WITHOUT_REFINEMENT

from test_runner import _physics, tiny_study  # noqa: E402

QUIET = dict(report=False, progress=False, threads=1, vtk=False)


def _stop_at(case, step):
    def stop(sim, row):
        if row["case"] == case and row["step"] == step:
            raise KeyboardInterrupt
    return stop


@pytest.fixture(scope="module")
def stiff_reference(tmp_path_factory):
    """An uninterrupted run with E = 2000 MPa (by override)."""
    out = tmp_path_factory.mktemp("ref") / "stiff"
    run_study(tiny_study(), output=out, overrides={"E": "2000"}, **QUIET)
    return out


@pytest.fixture(scope="module")
def two_case_reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "two"
    run_study(tiny_study(names=("a", "b")), output=out, **QUIET)
    return out


def _files(out):
    return {f.name: f.read_bytes() for f in out.iterdir() if f.is_file()}


def test_metadata_records_overrides_hash_and_process(stiff_reference):
    meta = json.loads((stiff_reference / "metadata.json").read_text())
    assert meta["schema_version"] == 2
    assert meta["overrides"] == {"E": 2000.0}            # the value it resolved to, not the string
    assert meta["parameters"]["E"]["value"] == 2000.0
    p = {k: v["value"] for k, v in meta["parameters"].items()}
    assert meta["parameters_hash"] == parameters_hash(p) and meta["parameters_hash"].startswith("sha256:")
    assert meta["process"] == {"pid": os.getpid(), "host": socket.gethostname()}


def test_resume_takes_recorded_overrides_and_refuses_others(stiff_reference, tmp_path):
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        run_study(tiny_study(), output=out, overrides={"E": "2000"}, callbacks=[_stop_at("main", 6)],
                  checkpoint_every=4, **QUIET)
    before = _files(out)
    for given, diff in [({"E": "1000"}, "E: 2000.0 -> 1000.0"),
                        ({"E": "2000", "k_u": "30"}, "k_u: (not set) -> 30.0"),
                        ({"h": "0.04"}, "E: 2000.0 -> (not set); h: (not set) -> 0.04")]:
        with pytest.raises(StudyError, match="differences \\(key: recorded -> given\\): " + diff.replace("(", "\\(")
                           .replace(")", "\\)")):
            run_study(tiny_study(), output=out, overrides=given, resume=True, **QUIET)
        assert _files(out) == before                      # refused before anything was written
    with pytest.raises(StudyError, match="resolution: 'quick' -> 'medium'"):
        run_study(tiny_study(), output=out, resolution="medium", resume=True, **QUIET)
    # the same overrides, or none at all: continues with E = 2000 and matches the uninterrupted run
    run_study(tiny_study(), output=out, resume=True, **QUIET)
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "completed" and meta["overrides"] == {"E": 2000.0}
    assert meta["parameters_hash"] == json.loads((stiff_reference / "metadata.json").read_text())["parameters_hash"]
    pd.testing.assert_frame_equal(_physics(pd.read_csv(stiff_reference / "history.csv")),
                                  _physics(pd.read_csv(out / "history.csv")), rtol=1e-9, atol=1e-12)


def _interrupted_two_case_run(out):
    """Case a completed, case b interrupted at step 9 (checkpoints of b at steps 8 and 9)."""
    with pytest.raises(KeyboardInterrupt):
        run_study(tiny_study(names=("a", "b")), output=out, callbacks=[_stop_at("b", 9)], checkpoint_every=4,
                  checkpoint_seconds=1e9, **QUIET)
    ck = out / "checkpoint"
    assert sorted(f.name for f in ck.iterdir()) == ["a.npz", "a.prev.npz", "b.npz", "b.prev.npz"]
    return ck


def _damage(f, how):
    data = f.read_bytes()
    f.write_bytes(data[: len(data) // 2] if how == "truncate" else b"garbage, not a zip file" * 10)


@pytest.mark.parametrize("files, how, recomputed", [
    (["b.npz"], "truncate", {"a": 0, "b": "from step 9"}),       # b goes on from its older generation (step 8)
    (["b.npz"], "garbage", {"a": 0, "b": "from step 9"}),
    (["b.npz", "b.prev.npz"], "garbage", {"a": 0, "b": "all"}),  # nothing left of b: b alone is re-run
    (["a.npz"], "truncate", {"a": "some", "b": "from step 10"}),  # a goes on from its older generation
    (["a.npz", "a.prev.npz"], "garbage", {"a": 0, "b": "from step 10"}),  # a comes from history.csv
])
def test_corrupted_checkpoint_is_named_and_skipped(two_case_reference, tmp_path, files, how, recomputed):
    out = tmp_path / "run"
    ck = _interrupted_two_case_run(out)
    a_rows = pd.read_csv(out / "history.csv").query("case == 'a'").reset_index(drop=True)
    for name in files:
        _damage(ck / name, how)
    seen = []
    with pytest.warns(CheckpointWarning, match=f"checkpoint .*{files[0]} cannot be read") as rec:
        run_study(tiny_study(names=("a", "b")), output=out, callbacks=[lambda s, row: seen.append(row)],
                  resume=True, **QUIET)
    named = " ".join(str(w.message) for w in rec)
    assert all(name in named for name in files)
    assert all((ck / (name + ".corrupt")).exists() for name in files)
    steps = {c: [r["step"] for r in seen if r["case"] == c] for c in "ab"}
    assert len(steps["a"]) == 0 if recomputed["a"] == 0 else 0 < len(steps["a"]) and min(steps["a"]) > 1
    if recomputed["b"] == "all":
        assert min(steps["b"]) == 1
    else:
        assert min(steps["b"]) == int(recomputed["b"].split()[-1])
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "completed" and set(meta["results"]) == {"a", "b"}
    h = pd.read_csv(out / "history.csv")
    pd.testing.assert_frame_equal(_physics(pd.read_csv(two_case_reference / "history.csv")), _physics(h),
                                  rtol=1e-9, atol=1e-12)
    # the completed case is intact, to the last digit written
    pd.testing.assert_frame_equal(_physics(a_rows), _physics(h.query("case == 'a'").reset_index(drop=True)))


def test_failure_during_resume_keeps_completed_cases(tmp_path):
    """A resume that fails early still writes every case it had (it used to wipe them)."""
    out = tmp_path / "run"
    ck = _interrupted_two_case_run(out)
    before = pd.read_csv(out / "history.csv")
    _damage(ck / "b.npz", "garbage")

    def boom(sim, row):
        raise RuntimeError("synthetic failure")

    with pytest.warns(CheckpointWarning), pytest.raises(RuntimeError, match="synthetic"):
        run_study(tiny_study(names=("a", "b")), output=out, callbacks=[boom], resume=True, **QUIET)
    after = pd.read_csv(out / "history.csv")
    pd.testing.assert_frame_equal(before.query("case == 'a'"), after.query("case == 'a'"))
    assert after.query("case == 'b'")["step"].max() >= 8        # b's rows up to its older checkpoint
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "failed" and meta["results"]["a"]["status"] == "completed"


def _dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_stale_running_status_is_recognised(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        run_study(tiny_study(), output=out, callbacks=[_stop_at("main", 5)], **QUIET)
    meta_f = out / "metadata.json"
    meta = json.loads(meta_f.read_text())
    # as a SIGKILL leaves it: status "running", written by a process that is gone
    meta["status"] = "running"
    meta["process"] = {"pid": _dead_pid(), "host": socket.gethostname()}
    meta_f.write_text(json.dumps(meta))
    status, note = effective_status(meta)
    assert status == "interrupted" and "is gone" in note
    with pytest.raises(StudyError, match="status interrupted: .*is gone"):
        run_study(tiny_study(), output=out, **QUIET)
    from ngtmc.report import load_run
    assert load_run(out)[0]["status"] == "interrupted"
    # a live process: resuming is refused
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        meta["process"]["pid"] = live.pid
        meta_f.write_text(json.dumps(meta))
        assert effective_status(meta)[0] == "running"
        with pytest.raises(StudyError, match="still running"):
            run_study(tiny_study(), output=out, resume=True, **QUIET)
    finally:
        live.kill()
        live.wait()
    run_study(tiny_study(), output=out, resume=True, **QUIET)
    assert json.loads(meta_f.read_text())["status"] == "completed"


def test_refused_run_leaves_no_folder(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(StudyError, match="case 'main': parameter E = -5.0 MPa is outside the allowed range"):
        run_study(tiny_study(), output=out, overrides={"E": "-5"}, **QUIET)
    assert not out.exists()
    with pytest.raises(StudyError, match="E expects a number"):
        run_study(tiny_study(), output=out, overrides={"E": "stiff"}, **QUIET)
    assert not out.exists()
    run_study(tiny_study(), output=out, overrides={"E": "1500"}, **QUIET)   # the same command, corrected
    assert json.loads((out / "metadata.json").read_text())["status"] == "completed"


def test_a_refined_run_recorded_before_the_default_corridor_resumes_without_one(tmp_path):
    """amr_corridor's default changed from 0 (none) to "auto" (4 l0) on 2026-12-06
    (ngtmc.study.registry.DEFAULT_CHANGED): a refined run recorded before, with amr_corridor at 0 or not
    named at all, resumes with no corridor; one recorded after resumes with "auto"; one recorded
    with a width given resumes with it."""
    from ngtmc.study import resume_parameters, run_description
    from ngtmc.study import load_study
    from ngtmc.study.parameters import DEFAULT_CHANGED, simulation_options, study_parameters
    assert DEFAULT_CHANGED["amr_corridor"] == 0.0
    mod = load_study("three_point_bending")
    res, p = study_parameters(mod, "quick", {"h_crack": 0.015})
    assert p["amr_corridor"] == "auto"
    old = dict(p, amr_corridor=0.0)
    meta = run_description(mod, old, res, {"h_crack": 0.015})
    got = resume_parameters(meta, mod, None, None, tmp_path)[2]
    assert got["amr_corridor"] == 0.0 and simulation_options(got)["adapt"].corridor == 0.0
    meta["parameters"].pop("amr_corridor")     # recorded before the setting existed
    assert resume_parameters(meta, mod, None, None, tmp_path)[2]["amr_corridor"] == 0.0
    meta.pop("parameters")                      # only its hash recorded: the hash decides
    assert resume_parameters(meta, mod, None, None, tmp_path)[2]["amr_corridor"] == 0.0
    meta_new = run_description(mod, p, res, {"h_crack": 0.015})
    assert resume_parameters(meta_new, mod, None, None, tmp_path)[2]["amr_corridor"] == "auto"
    meta_new.pop("parameters")
    assert resume_parameters(meta_new, mod, None, None, tmp_path)[2]["amr_corridor"] == "auto"
    _, p_w = study_parameters(mod, "quick", {"h_crack": 0.015, "amr_corridor": 0.1})
    meta_w = run_description(mod, p_w, res, {"h_crack": 0.015, "amr_corridor": 0.1})
    assert resume_parameters(meta_w, mod, None, None, tmp_path)[2]["amr_corridor"] == 0.1


def test_a_refined_run_recorded_before_remeshing_by_default_resumes_bisecting(tmp_path):
    """amr_remesh_maxh's default changed from 0 (bisection) to "auto" (remeshing where the study
    states its mesh's maxh; DEFAULT_CHANGED): a refined run recorded before, with the setting at 0
    or not named, resumes bisecting; one recorded after resumes remeshing with the study's maxh."""
    from ngtmc.study import resume_parameters, run_description
    from ngtmc.study import load_study
    from ngtmc.study.parameters import DEFAULT_CHANGED
    assert DEFAULT_CHANGED["amr_remesh_maxh"] == 0.0
    mod = load_study("three_point_bending")
    res, p = study_parameters_of(mod, {"h_crack": 0.015})
    assert p["amr_remesh_maxh"] == "auto"
    assert mod.cases(dict(p))[0].options["adapt"].remesh_maxh == float(p["h_beam"]) == 0.25
    old = dict(p, amr_remesh_maxh=0.0)
    meta = run_description(mod, old, res, {"h_crack": 0.015})
    got = resume_parameters(meta, mod, None, None, tmp_path)[2]
    assert got["amr_remesh_maxh"] == 0.0 and mod.cases(got)[0].options["adapt"].remesh_maxh is None
    meta["parameters"].pop("amr_remesh_maxh")   # recorded before the setting existed
    assert resume_parameters(meta, mod, None, None, tmp_path)[2]["amr_remesh_maxh"] == 0.0
    meta_h = run_description(mod, old, res, {"h_crack": 0.015})
    meta_h.pop("parameters")                    # only its hash: recorded between the two changes
    got = resume_parameters(meta_h, mod, None, None, tmp_path)[2]
    assert got["amr_remesh_maxh"] == 0.0 and got["amr_corridor"] == "auto"
    meta_new = run_description(mod, p, res, {"h_crack": 0.015})
    assert resume_parameters(meta_new, mod, None, None, tmp_path)[2]["amr_remesh_maxh"] == "auto"


def study_parameters_of(mod, overrides):
    from ngtmc.study.parameters import study_parameters
    return study_parameters(mod, "quick", overrides)


def test_settings_without_effect_do_not_block_a_resume(tmp_path):
    """The adaptivity settings (h_crack, amr_lookahead, amr_h_void) have no effect while h_crack is
    0: they are not in the parameter hash, and a run recorded before they existed resumes; a run
    recorded with refinement on does not resume without it."""
    from ngtmc.study import resume_parameters, run_description
    from ngtmc.study import load_study
    from ngtmc.study import study_parameters
    mod = load_study("l_panel")
    res, p = study_parameters(mod, "quick", {})
    assert p["h_crack"] == 0.0
    old = {k: v for k, v in p.items() if k not in ("h_crack", "amr_lookahead", "amr_h_void")}
    assert parameters_hash(old) == parameters_hash(p)
    assert parameters_hash(dict(p, h_crack=2.0)) != parameters_hash(p)
    meta = run_description(mod, old, res, {})
    meta["parameters"] = {k: v for k, v in meta["parameters"].items() if k in old}
    assert resume_parameters(meta, mod, None, None, tmp_path)[2] == p
    meta_amr = run_description(mod, dict(p, h_crack=2.0), res, {"h_crack": 2.0})
    with pytest.raises(StudyError, match="h_crack"):
        resume_parameters(meta_amr, mod, None, {"h_crack": 0}, tmp_path)
    # a refined run recorded before amr_size_tolerance existed resumes at its value then (1)
    old_amr = {k: v for k, v in dict(p, h_crack=2.0).items() if k != "amr_size_tolerance"}
    assert parameters_hash(old_amr) == parameters_hash(dict(p, h_crack=2.0))
    assert parameters_hash(dict(p, h_crack=2.0, amr_size_tolerance=1.41)) != parameters_hash(dict(p, h_crack=2.0))
    # an L-panel run recorded before band_left existed (the band from x = 150 mm) resumes: the
    # study names it in its ADDED_AT_DEFAULT, and its default is the one of its PARAMETERS
    assert p["band_left"] == 150.0 == mod.PARAMETERS["band_left"][0] and "band_left" in mod.ADDED_AT_DEFAULT
    assert parameters_hash({k: v for k, v in p.items() if k != "band_left"}, mod) == parameters_hash(p, mod)
    assert parameters_hash(dict(p, band_left=100.0), mod) != parameters_hash(p, mod)
    meta_old = run_description(mod, p, res, {})
    meta_old["parameters"].pop("band_left")
    meta_old["parameters_hash"] = parameters_hash({k: v for k, v in p.items() if k != "band_left"}, mod)
    assert resume_parameters(meta_old, mod, None, None, tmp_path)[2] == p
    meta_old.pop("parameters")    # only the hash recorded: it guards the resume alone
    assert resume_parameters(meta_old, mod, None, None, tmp_path)[2] == p
    meta_old["parameters_hash"] = parameters_hash(dict(p, band_left=100.0), mod)
    with pytest.raises(StudyError, match="hash differs"):
        resume_parameters(meta_old, mod, None, None, tmp_path)
    # a study that does not name it keeps it in the hash (another study's setting)
    assert parameters_hash({k: v for k, v in p.items() if k != "band_left"}) != parameters_hash(p)
    # and before amr_history_fraction (1) and amr_buffer (one layer of neighbours) existed: each left
    # out of the hash at its default, in it at another value, and passed on to Adaptivity (checked there)
    from ngtmc.study import simulation_options
    for name, other, attribute, bad in (("amr_history_fraction", 0.5, "history_fraction", 0.0),
                                        ("amr_buffer", 0, "buffer", -1)):
        assert p[name] == INERT_WITHOUT_REFINEMENT[name] == ADDED_AT_DEFAULT[name]
        old_amr = {k: v for k, v in dict(p, h_crack=2.0).items() if k != name}
        assert parameters_hash(old_amr) == parameters_hash(dict(p, h_crack=2.0))
        assert parameters_hash(dict(p, h_crack=2.0, **{name: other})) != parameters_hash(dict(p, h_crack=2.0))
        assert getattr(simulation_options(dict(p, h_crack=2.0, **{name: other}))["adapt"], attribute) == other
        with pytest.raises(StudyError, match=attribute):
            simulation_options(dict(p, h_crack=2.0, **{name: bad}))
    # so does a run recorded before stop_after_drop existed (the whole schedule, 0)
    assert p["stop_after_drop"] == 0.0
    assert parameters_hash({k: v for k, v in p.items() if k != "stop_after_drop"}) == parameters_hash(p)
    assert parameters_hash(dict(p, stop_after_drop=0.5)) != parameters_hash(p)


def test_stop_after_drop_setting():
    """The study setting ``stop_after_drop`` becomes the Simulation option, 0 none; bad values are
    refused with the setting's name."""
    from ngtmc.study import simulation_options
    assert "stop_after_drop" not in simulation_options({"stop_after_drop": 0.0})
    assert simulation_options({"stop_after_drop": 0.5})["stop_after_drop"] == 0.5
    for bad in (1.0, -0.5, "half"):
        with pytest.raises(StudyError, match="stop_after_drop"):
            simulation_options({"stop_after_drop": bad})
