"""ngtmc.discrete.to_scipy: NGSolve's sparse matrices as scipy's, against what they must hold."""
from __future__ import annotations

import ngsolve as ngs
import numpy as np
import pytest
from netgen.occ import OCCGeometry, Rectangle

from ngtmc.discrete import to_scipy


@pytest.fixture(scope="module")
def mesh():
    return ngs.Mesh(OCCGeometry(Rectangle(2.0, 0.5).Face(), dim=2).GenerateMesh(maxh=0.2))


def test_a_mass_matrix_sums_to_the_area_and_acts_as_ngsolve_s(mesh):
    """P1 mass matrix: 1^T M 1 is the area (1 mm^2), symmetric, the shape of the space, and M x equals
    NGSolve's product for a random x."""
    fes = ngs.H1(mesh, order=1)
    u, v = fes.TnT()
    m = ngs.BilinearForm(u * v * ngs.dx).Assemble()
    M = to_scipy(m.mat)
    assert M.shape == (fes.ndof, fes.ndof)
    one = np.ones(fes.ndof)
    assert one @ (M @ one) == pytest.approx(1.0, rel=1e-12)
    assert abs(M - M.T).max() < 1e-15
    x = np.random.default_rng(0).standard_normal(fes.ndof)
    xv, y = m.mat.CreateColVector(), m.mat.CreateColVector()
    xv.FV().NumPy()[:] = x
    y.data = m.mat * xv
    assert np.allclose(M @ x, y.FV().NumPy(), rtol=1e-13, atol=1e-15)


def test_a_mixed_form_keeps_its_rectangular_shape(mesh):
    """P1 test functions against element-wise constants (the design filter's B): height the test
    space's dofs, width the trial space's; the entries of a column sum to its element's area."""
    h1, l2 = ngs.H1(mesh, order=1), ngs.L2(mesh, order=0)
    b = ngs.BilinearForm(trialspace=l2, testspace=h1)
    b += l2.TrialFunction() * h1.TestFunction() * ngs.dx
    b.Assemble()
    B = to_scipy(b.mat)
    assert B.shape == (h1.ndof, l2.ndof) == (h1.ndof, mesh.ne)
    areas = ngs.Integrate(ngs.CoefficientFunction(1.0), mesh, element_wise=True).NumPy()
    assert np.allclose(np.asarray(B.sum(axis=0)).ravel(), areas, rtol=1e-12)
    assert to_scipy(b.mat, (h1.ndof, mesh.ne)).shape == B.shape
