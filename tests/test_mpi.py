"""One scene on several MPI ranks (ngtmc.scene.distributed): the history at 3 ranks equals the serial one,
and the NGSolve traps that make this need explicit reductions are pinned.

Needs mpi4py and an MPI launcher (``pip install ngtmc[mpi]``: the mpi4py and mpich wheels, which
the test extra installs); skips with the reason otherwise, except under ``CI=true``, where a
missing MPI is a failure. 3 ranks because NGSolve gives rank 0 no elements: 3 ranks
compute on 2, so dofs are shared between ranks.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import ngtmc
from ngtmc.scene.distributed import Ranks, unsupported
from ngtmc.study import StudyError

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from benchmarks import mpi_scene  # noqa: E402


def _launcher():
    for name in ("mpiexec", "mpirun"):
        exe = Path(sys.executable).parent / name
        if exe.exists():
            return str(exe)
        found = shutil.which(name)
        if found:
            return found
    return None


def _missing(reason: str):
    if os.environ.get("CI") == "true":
        pytest.fail(f"CI=true but {reason}")
    pytest.skip(reason)


def _mpi_launcher() -> str:
    """The MPI launcher; skips (fails under CI=true) without mpi4py or a launcher."""
    try:
        import mpi4py  # noqa: F401
    except ImportError:
        _missing("mpi4py is not installed (pip install ngtmc[mpi])")
    launcher = _launcher()
    if launcher is None:
        _missing("no mpiexec or mpirun found (pip install ngtmc[mpi] installs MPICH's)")
    return launcher


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    launcher = _mpi_launcher()
    out = tmp_path_factory.mktemp("mpi") / "history.json"
    env = dict(os.environ, OMP_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run([launcher, "-n", "3", sys.executable, "-m", "mpi4py", str(ROOT / "benchmarks" / "mpi_scene.py"), str(out)],
                          capture_output=True, text=True, timeout=600, env=env)
    assert proc.returncode == 0, f"mpiexec failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
        serial = mpi_scene.run(mpi_scene.scene())
    return json.loads(out.read_text()), serial


def test_three_ranks_reproduce_the_serial_history_through_contact_and_a_crack(runs):
    par, serial = runs
    h, s = par["history"], serial.history
    assert par["ranks"] == 3
    # the scene goes through contact (min J < 0.05), a peak and a crack that cuts the block
    assert s["min_J"].min() < 0.05 and s["max_alpha"].iloc[-1] == 1.0
    assert s["force"].iloc[-1] < 0.1 * s["force"].max()
    assert len(h["step"]) == len(s), "a different number of steps: some decision differed between ranks"
    for col in ("newton_iterations", "cutbacks", "alpha_projected"):
        assert h[col] == s[col].tolist(), col
    for col in ("load", "force", "elastic_energy", "regularisation_energy", "fracture_energy", "max_alpha", "min_J"):
        ref = s[col].to_numpy()
        err = np.max(np.abs(np.asarray(h[col]) - ref))
        assert err <= 1e-9 * max(np.max(np.abs(ref)), 1e-300), (col, err)


def test_ngsolve_energies_and_integrals_are_rank_local_on_a_distributed_mesh(runs):
    """The traps ngtmc.scene.distributed.Ranks exists for: BilinearForm.Energy and Integrate(cf * dx)
    return each rank's part (a wrong total, no error); Integrate(cf, mesh) is summed."""
    par, serial = runs
    local = par["ranks_local"]
    assert local[0]["elements"] == 0 and all(r["elements"] > 0 for r in local[1:])
    energies = [r["form_energy"] for r in local]
    assert all(0.0 < e < 0.99 * par["summed_energy"] for e in energies[1:])  # each a part only
    assert sum(energies) == pytest.approx(par["summed_energy"], rel=1e-12)
    s = serial.solver
    assert par["summed_energy"] == pytest.approx(s._energy(s.u.vec), rel=1e-8)
    integrals = [r["integral"] for r in local]
    total = integrals[0] + integrals[1] + integrals[2]
    assert integrals[0] == 0.0 and all(0.0 < i < 0.99 * total for i in integrals[1:])
    assert all(r["integrate_cf"] == pytest.approx(total, rel=1e-12) for r in local)


def test_adaptive_refinement_is_refused_clearly_on_a_distributed_mesh(runs):
    par, _ = runs
    assert "adaptive refinement" in par["refused"] and "docs/parallel.md" in par["refused"]


def test_serial_reductions_are_the_plain_values_and_unsupported_inputs_are_named():
    sc = mpi_scene.scene()
    r = Ranks(sc.mesh)
    assert not r.parallel and r.sum(2.5) == 2.5 and r.min(np.array([3.0, 1.0])) == 1.0
    assert r.max(np.zeros(0)) == -np.inf and r.any(True) and not r.all(False)
    assert ngtmc.scene.distributed.distribute(sc, comm=_SingleRank()) is sc
    msgs = unsupported(sc, adapt=object(), out_dir="x")
    assert len(msgs) == 2 and "adaptive refinement" in msgs[0]


class _SingleRank:
    size, rank = 1, 0


STUDY = ROOT / "benchmarks" / "mpi_study.py"


def _mpi_run(launcher, out, *extra):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    return subprocess.run([launcher, "-n", "3", sys.executable, "-m", "mpi4py", "-m", "ngtmc", "run", str(STUDY),
                           "--mpi", "-o", str(out), *extra],
                          capture_output=True, text=True, timeout=600, env=env)


@pytest.fixture(scope="module")
def run_folders(tmp_path_factory):
    """The MPI test scene as a study file, run by ``ngtmc run`` serially (in this process) and
    with ``--mpi`` on 3 ranks."""
    launcher = _mpi_launcher()
    base = tmp_path_factory.mktemp("mpi_run")
    serial = ngtmc.run_study(str(STUDY), output=base / "serial", report=False, progress=False)
    scratch_before = _scratch_folders()
    proc = _mpi_run(launcher, base / "mpi")
    assert proc.returncode == 0, f"mpiexec failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return serial, base / "mpi", proc, launcher, _scratch_folders() - scratch_before


#: The coupled Newton with dissipation control (the studies' default scheme) on the MPI test scene,
#: to where the damage grows before the peak (benchmarks/mpi_study.py says why not further).
PATH_FOLLOWING = {"scheme": "path-following", "final_load": "0.053"}


@pytest.fixture(scope="module")
def path_following_folders(tmp_path_factory):
    """The MPI test scene with path following, serially and with ``--mpi`` on 3 ranks."""
    launcher = _mpi_launcher()
    base = tmp_path_factory.mktemp("mpi_path")
    serial = ngtmc.run_study(str(STUDY), output=base / "serial", overrides=PATH_FOLLOWING, report=False, vtk=False,
                             progress=False)
    sets = [a for k, v in PATH_FOLLOWING.items() for a in ("--set", f"{k}={v}")]
    proc = _mpi_run(launcher, base / "mpi", *sets)
    assert proc.returncode == 0, f"mpiexec failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return serial, base / "mpi"


def _same_history(serial: Path, par: Path):
    """The history of the run folder ``par`` is that of ``serial``: the same steps, Newton
    iterations, cut-backs and projected dofs; loads, forces, energies, max alpha and min J within
    1e-9 of each column's scale. Returns the serial history."""
    import pandas as pd
    a, b = pd.read_csv(serial / "history.csv"), pd.read_csv(par / "history.csv")
    assert len(a) == len(b), "a different number of steps: some decision differed between ranks"
    for col in ("newton_iterations", "cutbacks", "alpha_projected"):
        assert (a[col] == b[col]).all(), col
    for col in ("load", "force", "elastic_energy", "regularisation_energy", "fracture_energy", "max_alpha", "min_J"):
        ref = a[col].to_numpy()
        assert np.max(np.abs(b[col].to_numpy() - ref)) <= 1e-9 * max(np.max(np.abs(ref)), 1e-300), col
    return a


def _scratch_folders() -> set:
    """The scratch folders of the ranks other than 0 in the temporary directory."""
    import tempfile
    return set(Path(tempfile.gettempdir()).glob("ngtmc-rank*"))


def test_ngtmc_run_mpi_writes_the_run_folder_of_the_serial_run(run_folders):
    """``mpiexec -n 3 python -m mpi4py -m ngtmc run STUDY --mpi``: rank 0 writes history, metadata
    and report; the history is the serial run's (same steps and iteration counts, values within
    1e-9 of their scale) through contact, the peak and the crack; the mesh is counted once; the
    snapshots and the ParaView file, gathered from the ranks on rank 0, are the serial run's to
    1e-9 of each field's scale (same vertices, elements and numbering); the report says where the
    fields come from. Each rank writes its own checkpoint. The other ranks print nothing and leave
    no scratch folder."""
    import json
    serial, par, proc, _, left = run_folders
    a = _same_history(serial, par)
    assert a["min_J"].min() < 0.05 and a["max_alpha"].iloc[-1] == 1.0
    assert a["force"].iloc[-1] < 0.1 * a["force"].max()
    ms, mp = (json.loads((d / "metadata.json").read_text()) for d in (serial, par))
    assert mp["status"] == "completed" and mp["mpi"] == {"ranks": 3} and "mpi" not in ms
    for key in ("n_elements", "n_vertices", "ndof_u", "ndof_alpha", "h_min", "h_max", "displacement_order"):
        assert mp["mesh"][key] == ms["mesh"][key], key
    names = {f.name for f in (par / "checkpoint").iterdir()}
    assert {f"main.rank{r}of3.npz" for r in range(3)} <= names and "main.npz" not in names
    # the fields gathered on rank 0 in the serial mesh's numbering: the serial run's snapshots and VTK
    zs, zp = np.load(serial / "snapshots.npz"), np.load(par / "snapshots.npz")
    assert sorted(zs.files) == sorted(zp.files)
    for k in zs.files:
        assert zp[k].shape == zs[k].shape, k
        assert np.max(np.abs(zp[k] - zs[k]), initial=0.0) <= 1e-9 * max(np.max(np.abs(zs[k]), initial=0.0), 1.0), k
    import meshio
    vs, vp = (meshio.read(d / "vtk" / "main_0000.vtu") for d in (serial, par))
    assert np.array_equal(vs.points, vp.points) and np.array_equal(vs.cells[0].data, vp.cells[0].data)
    for k in vs.point_data:
        assert np.max(np.abs(vp.point_data[k] - vs.point_data[k])) <= 1e-9 * max(np.max(np.abs(vs.point_data[k])), 1.0), k
    for k in vs.cell_data:
        ref = vs.cell_data[k][0]
        assert np.max(np.abs(vp.cell_data[k][0] - ref)) <= 1e-9 * max(np.max(np.abs(ref)), 1.0), k
    assert "computed on 3 MPI ranks" in (par / "report.html").read_text()
    assert proc.stdout.count("report:") == 1
    assert not left


def test_path_following_on_three_ranks_reproduces_the_serial_history(path_following_folders):
    """The coupled Newton on a distributed mesh (its systems gathered on rank 0, its norms, dot
    products, active sets and decisions reduced over the ranks): the serial history of path
    following through contact and dissipation-controlled damage growth, to 1e-9."""
    serial, par = path_following_folders
    a = _same_history(serial, par)
    assert a["min_J"].min() < 0.02 and a["max_alpha"].iloc[-1] > 0.2
    du = np.diff(a["load"].to_numpy())
    assert np.sum((du > 0) & (du < 0.001)) >= 3  # steps the dissipation control shortened (du_max 0.004 mm)


def test_ngtmc_run_mpi_refuses_what_it_cannot_do(run_folders, tmp_path):
    """What MPI runs do not support (here adaptive refinement) is refused by every rank before
    anything is solved (exit 2, one message, no run folder); without several ranks run_study
    refuses at once."""
    _, _, _, launcher, _ = run_folders
    before = _scratch_folders()
    proc = _mpi_run(launcher, tmp_path / "amr", "--set", "h_crack=0.0125")
    assert not _scratch_folders() - before
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert proc.stderr.count("ngtmc: error:") == 1 and "adaptive refinement" in proc.stderr
    assert not (tmp_path / "amr" / "history.csv").exists()
    with pytest.raises(StudyError, match="only MPI rank"):
        ngtmc.run_study(str(STUDY), output=tmp_path / "one", mpi=True, report=False, progress=False)


_STOP_DRIVER = """
import sys
import ngtmc

def halt(sim, row):
    if row["step"] == int(sys.argv[2]):
        raise KeyboardInterrupt

try:
    ngtmc.run_study(sys.argv[3], output=sys.argv[1], mpi=True, progress=False, report=False, vtk=False,
                    overrides=dict(a.split("=") for a in sys.argv[4:]), callbacks=[halt])
except KeyboardInterrupt:
    print("interrupted", flush=True)
"""


def test_an_interrupted_mpi_run_resumes_from_the_checkpoints_of_its_ranks(path_following_folders, tmp_path):
    """Each rank checkpoints its own part of the fields (``checkpoint/<case>.rank<r>of<n>.npz``, at
    the steps rank 0's clock chooses). Path following on 3 ranks, interrupted after step 13
    (damage growing, max alpha 0.12), resumed with ``ngtmc run --mpi --resume``: the history of the
    uninterrupted run on 3 ranks, step for step. A resume on 2 ranks, or serially, is refused
    with the command that works."""
    _, full = path_following_folders
    launcher = _mpi_launcher()
    driver = tmp_path / "stop.py"
    driver.write_text(_STOP_DRIVER)
    out = tmp_path / "run"
    env = dict(os.environ, OMP_NUM_THREADS="1")
    sets = [f"{k}={v}" for k, v in PATH_FOLLOWING.items()]
    proc = subprocess.run([launcher, "-n", "3", sys.executable, "-m", "mpi4py", str(driver), str(out), "13", str(STUDY),
                           *sets], capture_output=True, text=True, timeout=600, env=env)
    assert proc.returncode == 0 and proc.stdout.count("interrupted") == 3, proc.stderr[-3000:]
    assert json.loads((out / "metadata.json").read_text())["status"] == "interrupted"
    names = {f.name for f in (out / "checkpoint").iterdir()}
    assert {f"main.rank{r}of3.npz" for r in range(3)} <= names and "main.npz" not in names
    with pytest.raises(StudyError, match="written by 3 MPI ranks: resume it with mpiexec -n 3"):
        ngtmc.run_study(str(STUDY), output=out, resume=True, report=False, progress=False)
    two = subprocess.run([launcher, "-n", "2", sys.executable, "-m", "mpi4py", "-m", "ngtmc", "run", str(STUDY),
                          "--mpi", "--resume", "-o", str(out)], capture_output=True, text=True, timeout=600, env=env)
    assert two.returncode == 2 and "written by 3 MPI ranks" in two.stderr, two.stderr[-3000:]
    resumed = _mpi_run(launcher, out, "--resume")
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    assert "resuming from step 13" in resumed.stderr
    import pandas as pd
    h = pd.read_csv(out / "history.csv")
    assert h["max_alpha"].iloc[13] > 0.1
    _same_history(full, out)
    assert json.loads((out / "metadata.json").read_text())["status"] == "completed"


def test_3d_snapshots_gathered_from_the_ranks_are_the_serial_ones(tmp_path):
    """3D: the surface of the solid, u and alpha at its vertices, the alpha section at x = 0.5 mm
    and the VTK cell fields, gathered from 3 ranks, are the serial run's. The section's blank
    points differ only on the face z = 0.4 mm between the fracture region and the void, where a
    point lies in elements of both and a rank may find the fracture region's one."""
    launcher = _mpi_launcher()
    study = ROOT / "tests" / "mpi_study3d.py"
    serial = tmp_path / "serial"
    ngtmc.run_study(str(study), output=serial, report=False, progress=False)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.run([launcher, "-n", "3", sys.executable, "-m", "mpi4py", "-m", "ngtmc", "run", str(study),
                           "--mpi", "-o", str(tmp_path / "mpi"), "-q"], capture_output=True, text=True, timeout=600,
                          env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    zs, zp = np.load(serial / "snapshots.npz"), np.load(tmp_path / "mpi" / "snapshots.npz")
    assert sorted(zs.files) == sorted(zp.files) and zs["main__loads"].size == 2
    for k in zs.files:
        if k != "main__section_alpha":
            assert np.max(np.abs(zp[k] - zs[k]), initial=0.0) <= 1e-9 * max(np.max(np.abs(zs[k]), initial=0.0), 1.0), k
    a_s, a_p = zs["main__section_alpha"], zp["main__section_alpha"]
    both = ~np.isnan(a_s) & ~np.isnan(a_p)
    assert np.max(np.abs(a_p[both] - a_s[both])) <= 1e-9 and np.nanmax(a_s) > 0
    _, _, iz = np.nonzero(np.isnan(a_s) != np.isnan(a_p))
    assert np.allclose(zs["main__section_c2"][iz], 0.4)
    import meshio
    vs, vp = (meshio.read(d / "vtk" / "main_0001.vtu") for d in (serial, tmp_path / "mpi"))
    for k in vs.cell_data:
        ref = vs.cell_data[k][0]
        assert np.max(np.abs(vp.cell_data[k][0] - ref)) <= 1e-9 * max(np.max(np.abs(ref)), 1.0), k
