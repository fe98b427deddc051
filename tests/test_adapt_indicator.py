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


def test_lead_sweeps_the_front_ahead_along_the_crack_not_behind_it():
    """Adaptivity.lead_length: the zone within buffer_length of the crack's front (the marked
    crack elements still to refine) swept up to lead_length along the direction from the nearby
    refined crack to the front. A straight crack along +x, refined up to x = 0.4 mm, front at 0.4
    to 0.5 mm: the swept zone reaches about x = 0.5 + lead, stays within the width of the crack's
    line, and does not extend behind the front; without refined crack elements there is no
    direction and nothing is swept."""
    import ngsolve as ngs
    from netgen.geom2d import unit_square

    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.02))
    c = _centroids(mesh)
    crack = (np.abs(c[:, 1] - 0.5) < 0.03) & (c[:, 0] < 0.5)
    coarse = c[:, 0] > 0.4
    lead, width = 0.2, 0.05
    zone = adapt._ahead(mesh, crack, coarse, lead, width)
    assert zone.any()
    front_x = c[crack & coarse, 0]
    assert c[zone, 0].min() >= front_x.min() - width - 1e-9            # nothing behind the front
    assert c[zone, 0].max() <= front_x.max() + lead + width + 1e-9     # at most lead ahead
    assert c[zone, 0].max() >= front_x.max() + lead - 0.02             # ... and that far
    assert np.abs(c[zone, 1] - 0.5).max() <= 0.03 + width + 1e-9       # the crack's line, widened
    assert not adapt._ahead(mesh, crack, np.ones(mesh.ne, dtype=bool), lead, width).any()
    with pytest.raises(ValueError, match="lead_length"):
        Adaptivity(h_crack=0.01, lead_length=0.1)                      # needs a buffer_length
    with pytest.raises(ValueError, match="lead_length"):
        Adaptivity(h_crack=0.01, buffer_length=0.05, lead_length=-1.0)
