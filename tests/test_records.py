"""The measured records of the studies (ngtmc.study.measured): the files studies/records/<study>.json
parse and have one uniform shape, records() reads them, record_from_run builds a record from a run
folder, add_record writes it, and a missing file is named in the error."""
from __future__ import annotations

import json
import math
from pathlib import Path
import subprocess
import sys

import pytest

import ngtmc
from ngtmc.study import records
from ngtmc.study.measured import FIELDS, add_record, record_file, record_from_run

ROOT = Path(__file__).resolve().parents[1]
FILES = sorted((ROOT / "studies" / "records").glob("*.json"))


def _numbers(x):
    if isinstance(x, dict):
        for v in x.values():
            yield from _numbers(v)
    elif isinstance(x, list):
        for v in x:
            yield from _numbers(v)
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        yield x


def test_the_record_files_parse_and_have_the_uniform_fields():
    assert {f.stem for f in FILES} >= {"l_panel", "three_point_bending", "contact_gamma0", "three_point_bending_3d"}
    for f in FILES:
        data = json.loads(f.read_text())
        assert set(data) == {"study", "units", "records"}, f
        assert data["study"] == f.stem and data["study"] in ngtmc.list_studies(), f
        assert isinstance(data["units"], dict) and data["units"], f
        assert data["records"], f
        for key, rec in data["records"].items():
            assert set(rec) == set(FIELDS), (f.name, key)
            assert isinstance(rec["figures"], dict) and rec["figures"], (f.name, key)
            assert isinstance(rec["note"], str), (f.name, key)
            for field in ("command", "date", "commit", "machine"):
                assert rec[field] is None or isinstance(rec[field], str), (f.name, key, field)
            if rec["date"] is not None:
                assert len(rec["date"]) == 10 and rec["date"][4] == rec["date"][7] == "-", (f.name, key)
            assert all(math.isfinite(v) for v in _numbers(rec["figures"])), (f.name, key)
        # written as add_record writes: sorted keys, indent 1
        assert f.read_text() == json.dumps(data, sort_keys=True, indent=1, allow_nan=False) + "\n", f


def test_records_reads_the_files_of_the_package():
    lp = records("l_panel")
    assert records("l-panel") == lp                      # a study name with dashes too
    assert records("l_panel") is not lp                  # a new dict every call: callers may change it
    assert lp["quick_monotonic"]["figures"]["peak_force"] == 22962
    assert lp["quick_monotonic"]["figures"]["peak_load"] == 6.451
    tpb = records("three_point_bending")
    assert tpb["quick_path_following"]["figures"]["peak_force"] == 37.429
    assert tpb["quick_path_following"]["date"] == "2026-11-25"
    g = records("contact_gamma0")["paper"]["figures"]
    assert g["parasitic"]["gamma0_1e-06"] == 0.002452 and g["post"]["gamma0_1e-04"] == 0.3445
    # the studies read their keys from there
    S = ngtmc.load_study("l_panel")
    assert all(k in lp for k in (*S.L0_SWEEP_KEYS, *S.WHOLE_WIDTH_KEYS, *S.MEDIUM_PAPER_SCHEDULE_BY_L0.values()))
    assert Path(str(record_file("l_panel"))).resolve() == ROOT / "studies" / "records" / "l_panel.json"


def test_a_missing_record_file_is_named():
    with pytest.raises(FileNotFoundError, match=r"no measured records of study 'no_such_study'.*no_such_study\.json"):
        records("no_such_study")


def _fake_run(tmp_path) -> Path:
    run = tmp_path / "run"
    run.mkdir()
    meta = {"study": "three_point_bending", "resolution": "quick", "overrides": {"h_band": 0.02, "scheme": "single-pass"},
            "git_revision": "0123456789ab", "created": "2026-12-06T18:07:12+00:00", "status": "completed",
            "wall_time_s": 12.5, "host": {"platform": "Linux-x86_64", "cpu_count": 2, "threads": 1},
            "process": {"pid": 1, "host": "vm"},
            "mesh": {"n_elements": 100, "ndof_u": 300, "ndof_alpha": 60},
            "cases": [{"name": "main", "threads": 1}, {"name": "other", "threads": 2}],
            "results": {"main": {"peak_force": 3.0, "peak_load": 0.2, "status": "completed"},
                        "other": {"status": "failed"}}}
    (run / "metadata.json").write_text(json.dumps(meta))
    rows = ["case,step,load,force,newton_iterations,cutbacks,wall_time",
            "main,0,0.0,0.0,0,0,0.0", "main,1,0.1,2.0,3,0,1.0", "main,2,0.2,3.0,4,1,2.5", "main,3,0.3,1.0,5,0,4.0",
            "other,0,0.0,0.0,0,0,0.0", "other,1,-0.1,-2.0,2,0,0.5", "other,2,-0.2,-1.5,6,2,1.5"]
    (run / "history.csv").write_text("\n".join(rows) + "\n")
    return run


def test_record_from_run_gives_the_run_figures(tmp_path):
    rec = record_from_run(_fake_run(tmp_path), note="a fake run")
    assert set(rec) == set(FIELDS)
    assert rec["command"] == "ngtmc run three-point-bending --resolution quick --set h_band=0.02 --set scheme=single-pass"
    assert rec["date"] == "2026-12-06" and rec["commit"] == "0123456789ab" and rec["note"] == "a fake run"
    assert "2 CPUs" in rec["machine"] and "host vm" in rec["machine"]
    fig = rec["figures"]
    assert fig["status"] == "completed" and fig["wall_time_s"] == 12.5
    assert (fig["n_elements"], fig["ndof_u"], fig["ndof_alpha"]) == (100, 300, 60)
    assert fig["cases"]["main"] == {"steps": 3, "newton_iterations": 12, "cutbacks": 1, "peak_force": 3.0,
                                    "peak_load": 0.2, "final_load": 0.3, "final_force": 1.0, "wall_time_s": 4.0,
                                    "status": "completed", "threads": 1}
    other = fig["cases"]["other"]      # no recorded peak: the history's, loaded in the negative direction
    assert (other["peak_force"], other["peak_load"]) == (-2.0, -0.1)
    assert (other["steps"], other["newton_iterations"], other["cutbacks"], other["threads"]) == (2, 8, 2, 2)
    assert other["status"] == "failed"
    json.dumps(rec, allow_nan=False)


def test_record_from_a_folder_that_is_no_run_is_refused(tmp_path):
    with pytest.raises(FileNotFoundError, match="metadata.json"):
        record_from_run(tmp_path)


def test_add_record_round_trips(tmp_path):
    path = tmp_path / "records" / "three_point_bending.json"
    rec = record_from_run(_fake_run(tmp_path))
    assert add_record("three_point_bending", "quick_fake", rec, path=path) == path
    data = json.loads(path.read_text())
    assert data["study"] == "three_point_bending" and data["units"]["length"] == "mm"
    assert data["records"] == {"quick_fake": rec}
    assert path.read_text() == json.dumps(data, sort_keys=True, indent=1) + "\n"
    # a second record is added beside it; the same key replaces its record
    add_record("three_point_bending", "other", {**rec, "note": "b"}, path=path)
    add_record("three_point_bending", "quick_fake", {**rec, "note": "c"}, path=path)
    data = json.loads(path.read_text())
    assert sorted(data["records"]) == ["other", "quick_fake"] and data["records"]["quick_fake"]["note"] == "c"
    assert not list(path.parent.glob(".*.tmp"))          # written atomically, no temporary file left
    with pytest.raises(ValueError, match="lacks figures"):
        add_record("three_point_bending", "bad", {k: rec[k] for k in FIELDS if k != "figures"}, path=path)


def test_the_command_adds_a_run_to_its_study_file(tmp_path, monkeypatch):
    """``python -m ngtmc.study.measured RUN_DIR KEY --note TEXT`` writes into the study's file (here
    redirected to a copy, so that the package's files stay as they are)."""
    mod = sys.modules["ngtmc.study.measured"]   # the module (ngtmc.study.measured is the function records)
    target = tmp_path / "three_point_bending.json"
    monkeypatch.setattr(mod, "record_file", lambda study: target)
    run = _fake_run(tmp_path)
    assert mod.main([str(run), "quick_cli", "--note", "from the command"]) == 0
    data = json.loads(target.read_text())
    assert data["records"]["quick_cli"]["note"] == "from the command"
    assert mod.main([str(tmp_path / "nothing"), "k"]) == 2
    # the module runs as a command (help only: a real run would write into the package)
    r = subprocess.run([sys.executable, "-m", "ngtmc.study.measured", "--help"], capture_output=True, text=True,
                       cwd=ROOT, timeout=120)
    assert r.returncode == 0 and "RUN_DIR" in r.stdout.upper()
    # and without runpy's warning that the package had loaded the module before it ran
    assert "RuntimeWarning" not in r.stderr, r.stderr
