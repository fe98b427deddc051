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


def test_size_tolerance_refines_while_the_longest_edge_exceeds_it_times_the_target():
    """Adaptivity.size_tolerance: marked are the elements the indicator marks whose longest edge
    exceeds size_tolerance times the target; refined until none is, the crack's elements end
    between about half that bound and the bound, so with sqrt(2) the target lies inside, not at
    the top of, the range of sizes."""
    s = _damaged_notched_plate()
    strict = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0))
    loose = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, size_tolerance=2 ** 0.5))
    np.testing.assert_array_equal(loose, strict & (s.h > 0.03 * 2 ** 0.5 * (1 + 1e-9)))
    assert strict.sum() > loose.sum() > 0
    for _ in range(6):
        marked = adapt.mark(s, Adaptivity(h_crack=0.03, alpha_threshold=0.5, buffer=0, size_tolerance=2 ** 0.5))
        if not marked.any():
            break
        adapt.refine(s, marked)
    assert not marked.any()
    indicated = adapt.mark(s, Adaptivity(h_crack=1e-9, alpha_threshold=0.5, buffer=0))  # every indicated element
    assert indicated.any() and s.h[indicated].max() <= 0.03 * 2 ** 0.5 * (1 + 1e-9)
    with pytest.raises(ValueError, match="size_tolerance"):
        Adaptivity(h_crack=0.01, size_tolerance=0.9)
