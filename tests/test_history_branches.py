"""The history-branch count of the coupled Newton's debug line (``NGTMC_DEBUG_COUPLED``) and its
reader ``benchmarks.history_branches``: which history points take H_n = Psi_plus in Eq. 7, and how
many change branch from one residual evaluation to the next."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import ngtmc
import ngtmc.coupled.settings as coupled_settings
from scenes import notched_plate

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks.history_branches import bins, solves  # noqa: E402


def _line(it, branch, changed):
    return (f"    [    0.1s] coupled it {it} lam 0.005 res_u 1.0e-03 (ref 1.0e+00) res_a 0.0e+00 (tol 1.0e-09) "
            f"g 0.0e+00 held 0/0 branch {branch} changed {changed} gmres [3, 3]")


def test_solves_and_bins_of_a_log():
    """Solves start at ``coupled it 1``; other lines are skipped; the long solves' evaluations after
    their first are binned by the number of points that changed."""
    log = "\n".join([_line(1, 5, -1), _line(2, 7, 2), "    levenberg mu 1e-3: accepted True",
                     _line(1, 7, -1), *[_line(i, 7, c) for i, c in zip(range(2, 12), [0, 3, 3, 0, 12, 4, 9, 1, 0, 40])]])
    counts = solves(log)
    assert counts == [[-1, 2], [-1, 0, 3, 3, 0, 12, 4, 9, 1, 0, 40]]
    b = bins(counts, min_evaluations=10)
    assert (b["solves"], b["evaluations"], b["long_solves"], b["long_evaluations"]) == (2, 13, 1, 11)
    assert b["by_changed_points"] == {"none": 3, "1 to 3": 3, "4 to 9": 2, "10 or more": 2}
    assert b["largest_change"] == 40
    assert bins(counts, min_evaluations=2)["by_changed_points"]["1 to 3"] == 4


def test_the_debug_line_counts_the_points_where_psi_plus_wins(monkeypatch, capsys):
    """A dissipation step of the notched plate before its crack runs (the damage grows at the notch):
    the debug line of its last evaluation names as many points on the Psi_plus branch as the
    converged state has (Psi_plus > H_{n-1} at the history points, counted here), at least one,
    fewer than all."""
    sim = ngtmc.Simulation(notched_plate(maxh=0.2, h_band=0.05, l0=0.1), 0.005,
                           ngtmc.AdaptiveStepControl(du_max=1e-3, du_min=1e-7), scheme="monolithic")
    sim.run()
    s, c = sim.solver, sim.coupled
    assert s.solve_displacement(0.0051).converged
    capsys.readouterr()
    monkeypatch.setattr(coupled_settings, "DEBUG", True)
    res = c.solve(0.0051, dissipation=0.05, load_bounds=(0.0, 0.012))
    out = capsys.readouterr().out
    assert res.converged, res.message
    counts = solves(out)
    assert len(counts) >= 1 and counts[0][0] == -1 and all(k >= 0 for k in counts[-1][1:])
    on_psi_plus = int(np.sum(s.psi_plus_values() > s.H_committed))
    last = [line for line in out.splitlines() if "coupled it" in line][-1]
    assert f"branch {on_psi_plus} changed" in last
    assert 0 < on_psi_plus < s.H_committed.size
