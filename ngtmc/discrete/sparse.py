"""NGSolve's sparse matrices as scipy's: the one conversion the filters of :mod:`ngtmc.design` and
the diagnostics of ``benchmarks/`` share."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["to_scipy"]


def to_scipy(mat, shape: tuple[int, int] | None = None) -> sp.csr_matrix:
    """The NGSolve sparse matrix ``mat`` (``BilinearForm.mat``) as a scipy CSR matrix of ``shape``
    (default: the matrix's height and width), duplicate entries summed. Its entries are the
    stored ones, constrained (Dirichlet) rows and columns included: restrict to the free dofs
    where that matters."""
    rows, cols, vals = mat.COO()
    shape = (mat.height, mat.width) if shape is None else shape
    return sp.csr_matrix((np.asarray(vals), (np.asarray(rows), np.asarray(cols))), shape=shape)
