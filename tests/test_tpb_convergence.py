"""The mesh-convergence extrapolation of the three-point bending's peak (studies/_tpb_convergence.py)
recovers known limits and orders from exact data, and refuses what is not a convergence."""
import numpy as np
import pytest

from ngtmc.studies._tpb_convergence import extrapolate, observed_order

H = np.array([0.015, 0.01, 0.0075])  # the study's h_band at quick, medium, paper (mm)


@pytest.mark.parametrize("q", [0.7, 1.0, 2.0])
def test_richardson_recovers_the_limit_and_the_order_of_a_power_law(q):
    F = 30.0 + 500.0 * H ** q
    out = extrapolate(H, F)
    assert out["order"] == pytest.approx(q, rel=1e-9)
    assert out["richardson"] == pytest.approx(30.0, rel=1e-9)
    assert out["richardson_coefficient"] == pytest.approx(500.0, rel=1e-9)


def test_the_linear_extrapolation_is_exact_for_linear_data_and_the_order_is_one():
    F = 35.0 + 120.0 * H
    out = extrapolate(H, F)
    assert out["linear"] == pytest.approx(35.0, rel=1e-12)
    assert out["linear_slope"] == pytest.approx(120.0, rel=1e-10)
    assert out["order"] == pytest.approx(1.0, rel=1e-9)


def test_no_order_without_monotone_convergence():
    assert observed_order(H, [37.0, 36.0, 36.5]) is None
    out = extrapolate(H[:2], [37.0, 36.0])  # two points: linear only
    assert out["order"] is None and out["richardson"] is None
    assert out["linear"] == pytest.approx(37.0 - 1.0 / 0.005 * 0.015)
    with pytest.raises(ValueError):
        extrapolate([0.01], [36.0])
