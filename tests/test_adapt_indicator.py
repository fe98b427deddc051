"""The refinement indicator's lookahead (ngtmc.Adaptivity.buffer_length), a hysteresis: when the
indicator marks an element still to refine, marked are exactly the elements larger than their
target whose centroid lies within the given distance of an element the indicator marks by itself;
when it marks none, nothing is marked."""
import numpy as np
import pytest

from ngtmc import adapt
from ngtmc.adapt import Adaptivity
from test_adapt import _damaged_notched_plate


def _centroids(mesh):
    nodes = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    return np.asarray(mesh.ngmesh.Coordinates())[:, :2][nodes].mean(axis=1)


def test_lookahead_marks_every_element_within_its_distance():
    s = _damaged_notched_plate()
    base = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0))
    assert 0 < base.sum()
    ahead = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, buffer_length=0.15))
    c = _centroids(s.mesh)
    dist = np.min(np.linalg.norm(c[:, None, :] - c[base][None, :, :], axis=-1), axis=1)
    expected = (dist <= 0.15) & (s.h > 0.03 * (1 + 1e-9))
    np.testing.assert_array_equal(ahead, expected)
    assert ahead.sum() > base.sum()
    # after the refinement of what the indicator alone marks, the lookahead is not triggered
    adapt.refine(s, base)
    for _ in range(5):
        base = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0))
        if not base.any():
            break
        adapt.refine(s, base)
    assert not base.any()
    assert not adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, buffer_length=0.15)).any()


def test_lookahead_must_be_a_length():
    with pytest.raises(ValueError, match="buffer_length"):
        Adaptivity(h_crack=0.01, buffer_length=-1.0)
