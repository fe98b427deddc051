"""The cases of a run on a Dask cluster (ngtmc.runner.parallel), on the tiny two-case study of
test_runner.py (seconds each, two worker processes at most).

A parallel run writes the files of the serial run (same history, snapshots and results); a case
that raises in its worker, or whose worker dies, fails alone and a resume completes it; the
cases can go to an existing scheduler, also from a study file; without Dask the error names the
extra to install.
"""
from __future__ import annotations

import json
import os
import sys

import numpy as np
import pandas as pd
import pytest

from ngtmc.runner import run_study
from ngtmc.study import StudyError

from test_runner import _physics, tiny_study  # noqa: E402

QUIET = dict(report=False, progress=False, vtk=False)
CASES = ("a", "b")


def _distributed():
    return pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "run"
    run_study(tiny_study(names=CASES), output=out, threads=1, **QUIET)
    return out


def _strip_times(x):
    """``x`` without the measurements of the process that ran it: times, the peak memory (the
    largest resident set of that process so far, which depends on what else it ran: a case run
    in the test process counts every earlier test of it), and the solver's safeguard counters
    (``counters``: they count from the process's start, a resumed run from the resume, as
    :meth:`ngtmc.simulation.records.RunRecords.counters` says)."""
    if isinstance(x, dict):
        return {k: _strip_times(v) for k, v in x.items()
                if not (k.endswith("time_s") or k in ("time_split_s", "peak_memory_mb", "counters"))}
    if isinstance(x, list):
        return [_strip_times(v) for v in x]
    return x


def _same_as_serial(serial, out):
    pd.testing.assert_frame_equal(_physics(pd.read_csv(serial / "history.csv")),
                                  _physics(pd.read_csv(out / "history.csv")))     # the same numbers
    za, zb = np.load(serial / "snapshots.npz"), np.load(out / "snapshots.npz")
    assert za.files == zb.files
    for k in za.files:
        np.testing.assert_array_equal(za[k], zb[k], err_msg=k)
    ma, mb = (json.loads((d / "metadata.json").read_text()) for d in (serial, out))
    assert mb["status"] == "completed"
    for key in ("cases", "results", "mesh", "features", "force_unit", "thickness_mm"):
        assert _strip_times(ma[key]) == _strip_times(mb[key]), key
    return mb


def test_two_workers_give_the_serial_files(serial, tmp_path):
    _distributed()
    out = tmp_path / "par"
    run_study(tiny_study(names=CASES), output=out, workers=2, checkpoint_every=4, **{**QUIET, "vtk": True})
    meta = _same_as_serial(serial, out)
    assert meta["parallel"] == {"workers": 2, "scheduler": "local", "threads_per_worker": 1}
    assert sorted(p.name for p in (out / "checkpoint").iterdir()) == ["a.npz", "a.prev.npz", "b.npz", "b.prev.npz"]
    assert {"a.pvd", "b.pvd"} <= {p.name for p in (out / "vtk").iterdir()}
    assert not [p for p in out.rglob("*.tmp")]      # every file moved into place


def _fail_b(how):
    def callback(sim, row):   # runs in the worker of case b
        if row["case"] == "b" and row["step"] == 6:
            if how == "raise":
                raise RuntimeError("synthetic failure of b")
            os._exit(3)       # the worker process dies
    return callback


@pytest.mark.parametrize("how", ["raise", "die"])
def test_failed_case_fails_alone_and_resume_completes_it(serial, tmp_path, how):
    from ngtmc.runner.parallel import CaseFailure
    _distributed()
    out = tmp_path / how
    with pytest.raises(CaseFailure, match="case 'b' failed") as err:
        run_study(tiny_study(names=CASES), output=out, workers=2, callbacks=[_fail_b(how)], checkpoint_every=4,
                  checkpoint_seconds=1e9, **QUIET)
    assert list(err.value.failures) == ["b"]
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "failed" and "case 'b' failed" in meta["error"]
    res = meta["results"]
    assert list(res) == ["a", "b"]
    assert res["a"]["status"] == "completed" and res["b"]["status"] == "failed"
    assert res["b"]["error"] == ("RuntimeError: synthetic failure of b" if how == "raise"
                                 else "its worker process died (KilledWorker)")
    hist = pd.read_csv(out / "history.csv")
    steps = hist.groupby("case")["step"].max().to_dict()
    assert steps["a"] == res["a"]["steps"]
    # raised: every accepted step is recorded; died: the steps of its last checkpoint (every 4 steps)
    assert steps["b"] == (6 if how == "raise" else 4)
    run_study(tiny_study(names=CASES), output=out, resume=True, workers=2, **QUIET)
    _same_as_serial(serial, out)


def test_interrupt_keeps_the_cases_and_resume_completes_them(serial, tmp_path):
    """SIGTERM in the main process (as Ctrl-C) while case b is running: the cluster stops, b keeps
    the steps of its last checkpoint with status interrupted, and a resume completes the run."""
    import signal
    import threading
    import time
    _distributed()
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("SIGTERM becomes KeyboardInterrupt only in the main thread")
    marker = tmp_path / "b-at-step-6"

    def hold_b(sim, row):     # in the worker of case b
        if row["case"] == "b" and row["step"] == 6:
            marker.touch()
            time.sleep(120)

    def terminate():
        deadline = time.monotonic() + 120
        while not marker.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        if marker.exists():
            os.kill(os.getpid(), signal.SIGTERM)

    killer = threading.Thread(target=terminate, daemon=True)
    killer.start()
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        run_study(tiny_study(names=CASES), output=out, workers=2, callbacks=[hold_b], checkpoint_every=4,
                  checkpoint_seconds=1e9, **QUIET)
    killer.join(5)
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "interrupted"
    assert meta["results"]["b"]["status"] == "interrupted" and meta["results"]["b"]["steps"] == 4
    run_study(tiny_study(names=CASES), output=out, resume=True, workers=2, **QUIET)
    _same_as_serial(serial, out)


def test_existing_scheduler_and_a_study_file(serial, tmp_path):
    distributed = _distributed()
    study = tmp_path / "two_cases.py"
    study.write_text("from test_runner import tiny_study as _tiny\n_m = _tiny(names=('a', 'b'))\n"
                     "NAME, TITLE, SUMMARY, PARAMETERS, RESOLUTIONS = _m.NAME, _m.TITLE, _m.SUMMARY, "
                     "_m.PARAMETERS, _m.RESOLUTIONS\nDEFAULT_RESOLUTION = 'quick'\n"
                     "cases, references, targets = _m.cases, _m.references, _m.targets\n")
    out = tmp_path / "sched"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cl:
        run_study(str(study), output=out, scheduler=cl.scheduler_address, **QUIET)
    meta = _same_as_serial(serial, out)
    assert meta["parallel"]["scheduler"] == cl.scheduler_address


def test_without_dask_the_error_names_the_extra(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)     # import distributed raises ImportError
    with pytest.raises(StudyError, match=r"pip install ngtmc\[parallel\]"):
        run_study(tiny_study(names=CASES), output=tmp_path / "x", workers=2, **QUIET)
    assert not (tmp_path / "x").exists()
    from ngtmc.cli import main
    assert main(["run", "three-point-bending", "--workers", "2", "-o", str(tmp_path / "y")]) == 2
    assert "pip install ngtmc[parallel]" in capsys.readouterr().err
    assert not (tmp_path / "y").exists()
    # without workers nothing changes
    run_study(tiny_study(final_load=0.004), output=tmp_path / "serial", threads=1, **QUIET)


@pytest.mark.parametrize("kw, msg", [(dict(workers=0), "workers = 0"), (dict(workers=True), "workers = True"),
                                     (dict(workers=2, scheduler="tcp://x:1"), "not both"),
                                     (dict(scheduler=""), "scheduler = ''")])
def test_bad_settings_are_refused(tmp_path, kw, msg):
    with pytest.raises(StudyError, match=msg):
        run_study(tiny_study(), output=tmp_path / "x", **kw, **QUIET)
    assert not (tmp_path / "x").exists()


def test_cli_forwards_workers_scheduler_and_threads(tmp_path, monkeypatch):
    import ngtmc.runner
    from ngtmc.cli import main
    seen = {}

    def fake_run_study(name, **kw):
        seen.update(kw)
        return tmp_path

    monkeypatch.setattr(ngtmc.runner, "run_study", fake_run_study)
    assert main(["run", "step-control", "--workers", "3"]) == 0
    assert seen["workers"] == 3 and seen["scheduler"] is None and seen["threads"] == "auto"
    assert main(["run", "step-control", "--scheduler", "tcp://h:8786", "--threads", "2"]) == 0
    assert seen["workers"] is None and seen["scheduler"] == "tcp://h:8786" and seen["threads"] == 2
    assert main(["run", "step-control"]) == 0
    assert seen["workers"] is None and seen["threads"] == "auto"



def test_costliest_cases_start_first():
    """On a cluster the cases start in descending Case.cost (the study's order among equal costs);
    step_control gives its k_u = 1000 cases, the longest of its recorded runs, the highest cost."""
    from ngtmc.runner.parallel import costliest_first
    from ngtmc.study import load_study
    from ngtmc.study import Case
    from ngtmc.study import study_parameters
    todo = [(0, Case("a")), (1, Case("b", cost=5.0)), (2, Case("c")), (3, Case("d", cost=2.5))]
    assert [c.name for _, c in costliest_first(todo)] == ["b", "d", "a", "c"]
    with pytest.raises(ValueError, match="cost"):
        Case("e", cost=0.0)
    mod = load_study("step_control")
    for resolution in ("quick", "medium"):
        _, p = study_parameters(mod, resolution)
        order = [c.name for _, c in costliest_first(list(enumerate(mod.cases(p))))]
        assert all(name.startswith("ku1000") for name in order[:len(order) // 3]), order
