"""The bordered system of path following solved by one GMRES.

Each Newton step under dissipation control solves the linearised equations together with the
linearised constraint (:mod:`ngtmc.coupled.iteration`): on the free dofs, with p the negative
correction and dlambda the load change,

    [ A   -t ] [ p       ]   [ r ]        A   the tangent on the free dofs
    [ c^T  0 ] [ dlambda ] = [ h ]        t   the response of the equations to a unit load change
                                          c   the constraint's gradient (alpha dofs)

Solved as two systems (A a = r, A b = t, then dlambda from the constraint) it costs two GMRES
runs per Newton step. Here GMRES runs once, on the whole bordered matrix M, left-preconditioned
by the exact block inverse of M with A replaced by its preconditioner P (the block
Gauss-Seidel of :mod:`ngtmc.coupled.linear`):

    q = P t,  s = c^T q;   z = P v,  dl = (v_lambda - c^T z) / s,  z += dl q.

With P = A^-1 this is M^-1, so GMRES needs about the iterations of one solve with A, plus one
application of P for q. The solution is checked against M (the same GMRES_TRUE_RTOL as a single
solve); a failed check returns None and the caller solves the two systems instead.

Vectors are numpy arrays over all dofs of the coupled space; the entries of dofs that are not free
stay zero (the operator is the identity there, the preconditioner zero).
"""
from __future__ import annotations

import numpy as np

__all__ = ["bordered_gmres", "gmres", "numpy_operator"]


def gmres(apply, rhs: np.ndarray, rtol: float, maxiter: int):
    """Left-preconditioned GMRES from x0 = 0: ``apply(x)`` returns P M x (the preconditioned
    operator), ``rhs`` the preconditioned right-hand side P b. Stops when the preconditioned
    residual fell below ``rtol`` times that of x0 = 0, or after ``maxiter`` iterations.
    Modified Gram-Schmidt with one reorthogonalisation. Returns (x, iterations, converged)."""
    beta = float(np.linalg.norm(rhs))
    if not beta > 0.0:
        return np.zeros_like(rhs), 0, bool(beta == 0.0)
    V = [rhs / beta]
    H = np.zeros((maxiter + 1, maxiter))
    cs = np.zeros(maxiter)
    sn = np.zeros(maxiter)
    g = np.zeros(maxiter + 1)
    g[0] = beta
    k = 0
    converged = False
    for k in range(maxiter):
        w = apply(V[k])
        for _ in range(2):
            for i, v in enumerate(V):
                hij = float(v @ w)
                H[i, k] += hij
                w -= hij * v
        hk = float(np.linalg.norm(w))
        H[k + 1, k] = hk
        for i in range(k):   # earlier rotations on the new column
            a, b = H[i, k], H[i + 1, k]
            H[i, k], H[i + 1, k] = cs[i] * a + sn[i] * b, -sn[i] * a + cs[i] * b
        a, b = H[k, k], H[k + 1, k]
        rho = float(np.hypot(a, b))
        cs[k], sn[k] = (1.0, 0.0) if rho == 0.0 else (a / rho, b / rho)
        H[k, k], H[k + 1, k] = rho, 0.0
        g[k + 1] = -sn[k] * g[k]
        g[k] = cs[k] * g[k]
        if abs(g[k + 1]) <= rtol * beta:
            converged = True
            break
        if not hk > 1e-14 * beta:   # the Krylov space is exhausted: the solution is exact in it
            converged = True
            break
        V.append(w / hk)
    m = k + 1
    R = H[:m, :m]
    if not np.all(np.isfinite(R)) or np.any(np.diag(R) == 0.0):
        return np.full_like(rhs, np.nan), m, False
    y = np.zeros(m)
    for i in range(m - 1, -1, -1):   # back substitution
        y[i] = (g[i] - R[i, i + 1:m] @ y[i + 1:m]) / R[i, i]
    x = np.zeros_like(rhs)
    for yi, v in zip(y, V):
        x += yi * v
    return x, m, converged


def bordered_gmres(matvec, precondition, r: np.ndarray, t: np.ndarray, c: np.ndarray, h: float,
                   rtol: float, maxiter: int, true_rtol: float):
    """Solve the bordered system of the module docstring. ``matvec(x)``: A x (identity on the
    dofs that are not free), ``precondition(v)``: P v (zero there); ``r``, ``t``, ``c``: arrays
    over all dofs, zero where not free; ``h``: the constraint's right-hand side. Returns
    (p, dlambda, iterations), or None where the constraint does not respond to the
    preconditioned load response (s = 0), GMRES did not converge, or the solution fails the
    check ||A p - dlambda t - r|| <= true_rtol ||r + dlambda t|| and
    |c^T p - h| <= true_rtol sum |c p|."""
    q = precondition(t)
    s = float(c @ q)
    if not (np.isfinite(s) and s != 0.0):
        return None

    def pre(v, v_lam):
        z = precondition(v)
        dl = (v_lam - float(c @ z)) / s
        z += dl * q
        return z, dl

    n = r.size

    def apply(x):
        z, dl = pre(matvec(x[:n]) - x[n] * t, float(c @ x[:n]))
        return np.append(z, dl)

    z0, dl0 = pre(r, h)
    x, its, converged = gmres(apply, np.append(z0, dl0), rtol, maxiter)
    if not converged or not np.all(np.isfinite(x)):
        return None
    p, dlam = x[:n], float(x[n])
    rhs = r + dlam * t
    if np.linalg.norm(matvec(p) - dlam * t - r) > true_rtol * np.linalg.norm(rhs):
        return None
    miss = abs(float(c @ p) - h)
    if miss > true_rtol * max(float(np.abs(c * p).sum()), abs(h)):
        return None
    return p, dlam, its


def numpy_operator(op):
    """x -> op x on numpy arrays, for an NGSolve operator ``op`` (a matrix or a BaseMatrix)."""
    x, y = op.CreateColVector(), op.CreateColVector()
    xN, yN = x.FV().NumPy(), y.FV().NumPy()

    def apply(v):
        xN[:] = v
        y.data = op * x
        return yN.copy()
    return apply
