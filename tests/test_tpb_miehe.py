"""The three-point bending against the second published curve of the benchmark, Miehe et al. (2010),
in Miehe's set-up (``three_point_bending.MIEHE_SET_UP``: Gc = 0.5 N/mm, anisotropic spectral split,
a 0.5 mm loaded window on the beam top, no indenter, no void), solved at quick past its peak.

Measured 2026-12-03 (quick, path following, ``python -m benchmarks.tpb``): 36.92 N/mm at 0.0382 mm
with the study's l0 = 0.03 mm, 35.67 N/mm at 0.0378 mm with l0 = 0.06 mm, against Miehe's 34.75 N/mm
at 0.0390 mm (docs/fidelity.md). The schedule goes to 0.06 mm, as measured: to 0.045 mm (path steps
bounded by 1/50 of the load path, so a slightly different path) the run met an arrested crack at
22.2 N/mm and 0.0371 mm, where its displacement steps took 10-35 s each (peak 36.78 N/mm at
0.0380 mm; benchmarks record quick-20261203T071844Z, interrupted). The tests read the peak only,
so the run stops once the force has fallen below 0.9 of it (``stop_after_drop``): the same path to
there, and the peak is past. Measured 2026-12-03: the peak at step 32 after 97 s, the force below
0.8 of it at step 40 after 184 s, below half at step 56 after 327 s (the tail to 0.06 mm took most
of the run); later that day on one thread, the peak after 73 s, below 0.9 at step 36 after 98 s,
below 0.8 after 131 s.
"""
from __future__ import annotations

import pytest

from ngtmc.studies import three_point_bending as tpb
from tpb_runs import solve_quick


@pytest.fixture(scope="module")
def miehe_run(tmp_path_factory):
    r, _, p = solve_quick(tmp_path_factory, "miehe", {**tpb.MIEHE_SET_UP, "stop_load": 0.06, "stop_after_drop": 0.9})
    return r, p


@pytest.mark.slow
def test_miehes_set_up_peaks_where_miehe_does(miehe_run):
    """Peak force and its displacement against Miehe's digitised curve, within the tolerances the
    study sets for Ambati's (15 % and 10 %); measured +6.2 % and -2.1 %."""
    r, p = miehe_run
    assert p["Gc"] == 0.5 and p["split"] == "spectral" and p["formulation"] == "anisotropic"
    force, load = tpb.reference_peaks()["miehe"]
    tol = {t["quantity"]: t["tolerance"] for t in tpb.targets(p)}
    print(f"against Miehe's {force:.2f} N/mm at {load:.4f} mm: {100 * (r['peak_force'] / force - 1):+.1f} %, "
          f"{100 * (r['peak_load'] / load - 1):+.1f} %")
    assert r["peak_force"] == pytest.approx(force, rel=tol["peak_force"])
    assert r["peak_load"] == pytest.approx(load, rel=tol["peak_load"])


@pytest.mark.slow
def test_miehes_set_up_is_nearer_to_miehe_than_to_ambati(miehe_run):
    """With Miehe's parameters the model is nearer to Miehe's peak than to Ambati's: the two published
    curves of this benchmark differ by 21 % (34.75 and 42 N/mm)."""
    r, _ = miehe_run
    peaks = tpb.reference_peaks()
    miehe, ambati = peaks["miehe"][0], peaks["ambati"][0]
    assert abs(r["peak_force"] - miehe) < abs(r["peak_force"] - ambati)
