"""One run per run folder (issue 58): a run claims its folder before it writes anything; a second
run into it is refused with a message naming the first, and nothing of the two is mixed."""
import json
import os
from pathlib import Path
import socket
import subprocess
import sys
import time

import pytest

from ngtmc.runner.claim import CLAIM_FILE, FolderClaim, FolderInUse
from ngtmc.study import StudyError
from test_user_scene import STUDY_FILE


def _claim_of(folder: Path, pid: int):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / CLAIM_FILE).write_text(json.dumps({"pid": pid, "host": socket.gethostname(), "started": time.time()}))


def test_a_live_claim_refuses_a_second_run_and_names_it(tmp_path):
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        _claim_of(tmp_path / "run", other.pid)
        with pytest.raises(FolderInUse, match=f"in use by another run: process {other.pid}") as err:
            FolderClaim(tmp_path / "run").acquire()
        assert isinstance(err.value, StudyError)          # the command line prints it as a clear error
        assert json.loads((tmp_path / "run" / CLAIM_FILE).read_text())["pid"] == other.pid   # left alone
    finally:
        other.kill()
        other.wait()


def test_a_stale_claim_is_taken_over_and_said_and_released_at_the_end(tmp_path):
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    _claim_of(tmp_path / "run", gone.pid)
    said = []
    with FolderClaim(tmp_path / "run", note=said.append):
        assert json.loads((tmp_path / "run" / CLAIM_FILE).read_text())["pid"] == os.getpid()
    assert said and "took over" in said[0] and str(gone.pid) in said[0]
    assert not (tmp_path / "run" / CLAIM_FILE).exists()


def test_a_refused_new_folder_is_not_left_behind(tmp_path):
    with FolderClaim(tmp_path / "new"):
        assert (tmp_path / "new").is_dir()
    assert not (tmp_path / "new").exists()


def test_two_runs_into_one_folder_the_second_is_refused(tmp_path):
    """Two ``ngtmc run`` of a study file started 0.3 s apart into the same folder: the first
    finishes, the second exits 2 naming the first's process; the folder holds one run."""
    f = tmp_path / "my_study.py"
    f.write_text(STUDY_FILE.format(tests=str(Path(__file__).parent)))
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "ngtmc", "run", str(f), "-o", str(out), "--threads", "1", "--no-vtk"]
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[1]))
    first = subprocess.Popen(cmd + ["--set", "final_load=1.0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True, env=env)
    for _ in range(200):                     # until the first run has claimed the folder
        if (out / CLAIM_FILE).exists():
            break
        time.sleep(0.05)
    time.sleep(0.3)
    second = subprocess.run(cmd + ["--set", "E=2000"], capture_output=True, text=True, env=env)
    first_out, first_err = first.communicate(timeout=300)
    assert first.returncode == 0, first_err
    assert second.returncode == 2, second.stderr
    assert f"in use by another run: process {first.pid}" in second.stderr
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "completed" and meta["overrides"] == {"final_load": 1.0}
    assert not (out / CLAIM_FILE).exists()


# ----------------------------------------------------------------- a study file's contract
@pytest.mark.parametrize("body, words", [
    ('NAME = "three_point_bending"\nPARAMETERS = {"E": (1.0, "MPa", "x")}\nRESOLUTIONS = {"quick": {}}\n'
     'def cases(p): return []\n', "is the name of a study of ngtmc"),
    ('NAME = "my_empty"\nPARAMETERS = {"E": (1.0, "MPa", "x")}\nRESOLUTIONS = {"quick": {}}\n'
     'def cases(p): return []\n', "cases() returned no case"),
    ('NAME = "my_badpar"\nPARAMETERS = {"E": 1.0}\nRESOLUTIONS = {"quick": {}}\ndef cases(p): return []\n',
     "PARAMETERS['E'] = 1.0 must be a tuple (default, unit, description)"),
    ('NAME = ""\nPARAMETERS = {}\nRESOLUTIONS = {"quick": {}}\ndef cases(p): return []\n',
     "NAME must be a non-empty string"),
    ('NAME = "my_res"\nPARAMETERS = {}\nRESOLUTIONS = {"quick": 1}\ndef cases(p): return []\n',
     "RESOLUTIONS must be a non-empty dict"),
])
def test_a_study_file_that_breaks_its_contract_is_refused_and_leaves_no_folder(tmp_path, body, words):
    from ngtmc.runner import run_study
    f = tmp_path / "s.py"
    f.write_text(body)
    with pytest.raises(StudyError) as err:
        run_study(str(f), output=tmp_path / "out", progress=False)
    assert words in str(err.value)
    assert not (tmp_path / "out").exists()


def test_a_closed_pipe_ends_the_printing_not_the_run(tmp_path):
    """``ngtmc run ... 2>&1 | head -2``: the reader goes away after two lines; the run completes
    (it used to be recorded as failed on the BrokenPipeError)."""
    f = tmp_path / "my_study.py"
    f.write_text(STUDY_FILE.format(tests=str(Path(__file__).parent)))
    out = tmp_path / "run"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[1]))
    proc = subprocess.Popen([sys.executable, "-m", "ngtmc", "run", str(f), "-o", str(out), "--threads", "1",
                             "--no-vtk", "--set", "final_load=0.05"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, env=env)
    proc.stderr.readline()
    proc.stderr.readline()
    proc.stderr.close()
    proc.wait(timeout=300)
    assert json.loads((out / "metadata.json").read_text())["status"] == "completed"


@pytest.mark.parametrize("override, words", [({"h_band": 0}, "the mesh size h_band = 0"),
                                              ({"amr_corridor": "wide"}, "amr_corridor = 'wide' must be 'auto'"),
                                              ({"stop_load": 0.5}, r"stop_load = 0.5 mm must lie in \(0, final_load")])
def test_study_settings_are_checked_whether_or_not_they_act(tmp_path, override, words):
    """A mesh size of 0 (netgen's CalcLU failed), a corridor word while refinement is off and a
    stop_load past the final load (clamped without a word) are refused, naming the setting, before
    any folder exists."""
    from ngtmc.runner import run_study
    with pytest.raises(StudyError, match=words):
        run_study("three-point-bending", "quick", tmp_path / "out", overrides=override, progress=False)
    assert not (tmp_path / "out").exists()


def test_a_resume_names_a_missing_paraview_file_and_a_missing_metadata(tmp_path):
    """A completed run whose ParaView file and metadata.json were lost (a full disk, a hand): the
    resume says so, naming each, instead of going on silently, and its wall time carries over
    from the checkpoints."""
    from ngtmc.runner import run_study
    f = tmp_path / "my_study.py"
    f.write_text(STUDY_FILE.format(tests=str(Path(__file__).parent)))
    out = tmp_path / "run"
    run_study(str(f), output=out, progress=False, report=False, overrides={"final_load": 0.05})
    import pandas as pd
    solved = float(pd.read_csv(out / "history.csv")["wall_time"].max())   # s, the case's own time
    vtus = sorted((out / "vtk").glob("*.vtu"))
    assert vtus
    vtus[0].unlink()
    (out / "metadata.json").unlink()
    with pytest.warns(UserWarning) as rec:
        run_study(str(f), output=out, progress=False, report=False, resume=True, overrides={"final_load": 0.05})
    text = " ".join(str(w.message) for w in rec)
    assert "metadata.json is missing" in text
    assert vtus[0].name in text and "lists files that are not there" in text
    # the wall time carries over from the checkpoints' latest row (it restarted from 0 before)
    assert json.loads((out / "metadata.json").read_text())["wall_time_s"] >= solved


def test_a_scheduler_that_does_not_answer_is_refused_at_once(tmp_path):
    """A Dask scheduler address where nothing listens (a loopback port) is refused in seconds,
    before any folder exists (it hung 60 s, printed a traceback and left a failed folder)."""
    pytest.importorskip("distributed")
    from ngtmc.runner import run_study
    f = tmp_path / "my_study.py"
    f.write_text(STUDY_FILE.format(tests=str(Path(__file__).parent)))
    t0 = time.perf_counter()
    with pytest.raises(StudyError, match="no Dask scheduler answers at tcp://127.0.0.1:1"):
        run_study(str(f), output=tmp_path / "out", progress=False, scheduler="tcp://127.0.0.1:1")
    assert time.perf_counter() - t0 < 30
    assert not (tmp_path / "out").exists()
    with pytest.raises(StudyError, match="is not an address host:port"):
        run_study(str(f), output=tmp_path / "out", progress=False, scheduler="tcp://localhost")
