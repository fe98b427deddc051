"""One scene on several MPI ranks (ngtmc.distributed): the history at 3 ranks equals the serial one,
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
from ngtmc.distributed import Ranks, _unsupported

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


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    try:
        import mpi4py  # noqa: F401
    except ImportError:
        _missing("mpi4py is not installed (pip install ngtmc[mpi])")
    launcher = _launcher()
    if launcher is None:
        _missing("no mpiexec or mpirun found (pip install ngtmc[mpi] installs MPICH's)")
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
    """The traps ngtmc.distributed.Ranks exists for: BilinearForm.Energy and Integrate(cf * dx)
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


def test_the_coupled_schemes_are_refused_clearly_on_a_distributed_mesh(runs):
    par, _ = runs
    assert "scheme='monolithic'" in par["refused"] and "docs/parallel.md" in par["refused"]


def test_serial_reductions_are_the_plain_values_and_unsupported_inputs_are_named():
    sc = mpi_scene.scene()
    r = Ranks(sc.mesh)
    assert not r.parallel and r.sum(2.5) == 2.5 and r.min(np.array([3.0, 1.0])) == 1.0
    assert r.max(np.zeros(0)) == -np.inf and r.any(True) and not r.all(False)
    assert ngtmc.distributed.distribute(sc, comm=_SingleRank()) is sc
    msgs = _unsupported(sc, scheme="path-following", adapt=object(), out_dir="x")
    assert len(msgs) == 3 and "path-following" in msgs[0]


class _SingleRank:
    size, rank = 1, 0
