"""Linear solves of the coupled (u, alpha) tangent of :class:`ngtmc.coupled.monolithic.CoupledNewton`.

One object per coupled solver holds the factorizations of its assembled tangent (the form's
``mat``): ``factorize(free)`` (block-GMRES with block Cholesky factors, or a direct solver on the
whole non-symmetric matrix), ``shifted(free, mu)`` (the Levenberg copy, UMFPACK) and
``diagonal_scale()`` (the complementarity scale of the alpha bounds). Each factorization returns
``solve(rhs, out)``, out = A^-1 rhs on the free dofs, for any number of right-hand sides.

On a mesh distributed over MPI ranks (:mod:`ngtmc.scene.distributed`) every factorization is NGSolve's
"masterinverse" (the matrix gathered and factorized on rank 0; it solves the non-symmetric
tangent, a residual of 4e-15 measured on a compound space over 3 ranks), whatever
``linear_solver`` says: the block solver works on the whole matrix's arrays. The diagonal the
Levenberg shift and the complementarity scale read is then each rank's part of it: the scale
sums the parts over the ranks, the shift scales each part (so the sum of the shifts is mu times
the sum of the parts' magnitudes, at least mu times the magnitude of the diagonal).

Units: those of the tangent (N/mm for u-u entries, N mm for alpha-alpha, per thickness in 2D).
"""
from __future__ import annotations

import contextlib
import math
import time

import numpy as np
import ngsolve as ngs

from ngtmc.coupled.bordered import bordered_gmres, numpy_operator
from ngtmc.coupled.settings import BORDERED, FACTOR_REUSE

__all__ = ["CoupledLinearSolver", "LINEAR_SOLVERS"]

#: Linear solvers of the coupled tangent: "block-gmres" (GMRES preconditioned by the block lower
#: triangle, with sparse Cholesky factors of the symmetric u-u and alpha-alpha blocks; the u-u
#: factor reuses its symbolic step), "umfpack" or "pardiso" (direct, whole matrix).
LINEAR_SOLVERS = ("block-gmres", "umfpack", "pardiso")

#: A block-GMRES solution is checked against the matrix: where its true residual on the free dofs
#: exceeds GMRES_TRUE_RTOL times the right-hand side, the factorization's solves fall back to
#: UMFPACK. GMRES stops on the preconditioned residual, and where elements are almost broken the
#: block preconditioner is so poor that a solution "converged" to 1e-8 in 5 iterations had a true
#: residual larger than the right-hand side (the MPI test scene's stall, docs/performance.md).
GMRES_TRUE_RTOL = 1e-4


class CoupledLinearSolver:
    """Factorizations of the assembled coupled tangent ``form.mat`` (u dofs first, ``nu`` of
    them). ``linear_solver``: one of LINEAR_SOLVERS; ``gmres_rtol``, ``gmres_maxsteps``: of
    block-GMRES; ``factor_reuse``: keep block-GMRES's u-u factor while it pays
    (:data:`FACTOR_REUSE`; :class:`~ngtmc.coupled.monolithic.CoupledNewton` resolves its "auto").
    ``bordered``: one GMRES for the bordered system of path following (:data:`BORDERED`).
    :attr:`gmres_iterations` lists the GMRES iterations of each solve."""

    @staticmethod
    def check(linear_solver: str, gmres_rtol: float):
        """Raise ValueError for an unknown ``linear_solver`` or a ``gmres_rtol`` outside (0, 1)."""
        if linear_solver not in LINEAR_SOLVERS:
            raise ValueError(f"linear_solver = {linear_solver!r} is not one of {', '.join(map(repr, LINEAR_SOLVERS))} "
                             "(the coupled tangent is not symmetric: no 'sparsecholesky' on the whole matrix)")
        if not 0.0 < gmres_rtol < 1.0:
            raise ValueError(f"gmres_rtol = {gmres_rtol!r} must be in (0, 1)")

    def __init__(self, form, nu: int, linear_solver: str = "block-gmres", gmres_rtol: float = 1e-8,
                 gmres_maxsteps: int = 100, ranks=None, factor_reuse: bool = False, bordered: bool = True):
        self.check(linear_solver, gmres_rtol)
        if not isinstance(factor_reuse, bool):
            raise ValueError(f"factor_reuse = {factor_reuse!r} must be True or False")
        if not isinstance(bordered, bool):
            raise ValueError(f"bordered = {bordered!r} must be True or False")
        #: block-GMRES solves the bordered system of path following in one run (BORDERED); the
        #: solves so made, and those that failed their check and were made as two systems
        self.bordered = bordered
        self.bordered_solves = 0
        self.bordered_fallbacks = 0
        self.form = form
        #: reductions over MPI ranks (:class:`ngtmc.scene.distributed.Ranks`; None or serial: one process)
        self.ranks = ranks
        self.parallel = bool(ranks is not None and ranks.parallel)
        self.nu = int(nu)
        self.linear_solver = linear_solver
        self.gmres_rtol = float(gmres_rtol)
        self.gmres_maxsteps = int(gmres_maxsteps)
        self.gmres_iterations: list[int] = []
        #: block-GMRES solves solved by UMFPACK instead: their true residual failed GMRES_TRUE_RTOL,
        #: or GMRES did not converge in ``gmres_maxsteps`` (with a new u-u factor, when reused)
        self.inexact_solves = 0
        self._inv_u = None
        self._inv_a = None
        self._inv_a_key = (None, np.zeros(0, dtype=bool))
        self._diag = None  # (positions in the matrix values, rows) of the diagonal entries
        #: keep the u-u factor while it pays (FACTOR_REUSE); counts of the factors made and reused
        self.factor_reuse = factor_reuse
        self.u_factorizations = 0
        self.u_factor_reuses = 0
        self._u_stale = True     # the stored factor is of a shifted matrix, or none was made yet
        self._u_cost = 0.0       # s, the last u-u factorization
        self._u_extra = 0.0      # s of GMRES beyond the first solve's iterations since that factorization
        self._u_base = None      # GMRES iterations of the first solve with that factor
        self._u_last = 0.0       # s of extra GMRES of the last direction that reused it
        self._u_first = 0.0      # s of extra GMRES of the first reuse of a factor (learned)
        self._u_pending = None   # (extra before it, first reuse?) of the direction in progress, if reused
        self._u_count = 0        # directions that reused the current factor

    def _diagonal(self):
        """Positions of the diagonal entries in the values of ``form.mat`` and their rows (from
        the matrix graph, found again when its size changes)."""
        mat = self.form.mat.local_mat if self.parallel else self.form.mat
        vals = mat.AsVector().FV().NumPy()
        if self._diag is None or self._diag[2] != vals.size:
            _, cols, rowptr = mat.CSR()
            cols = np.asarray(cols).astype(np.int64)
            rowptr = np.asarray(rowptr).astype(np.int64)
            rows = np.repeat(np.arange(rowptr.size - 1), np.diff(rowptr))
            on = cols == rows
            self._diag = (np.nonzero(on)[0], rows[on], vals.size)
        return vals, self._diag[0], self._diag[1]

    @contextlib.contextmanager
    def _diagonal_added(self, shift: np.ndarray):
        """Within the block, the assembled matrix's diagonal entries hold ``shift`` (per dof) more;
        restored afterwards."""
        vals, pos, row = self._diagonal()
        keep = vals[pos].copy()
        vals[pos] = keep + shift[row]
        try:
            yield
        finally:
            vals[pos] = keep

    def shifted(self, free: np.ndarray, mu: float):
        """Factorization of the tangent with its diagonal on the ``free`` dofs increased by mu
        times its magnitude (Levenberg); the assembled matrix is restored. Block-GMRES keeps its
        preconditioner's symbolic factorization and applies the shift in its operator; the direct
        solvers factorize the shifted matrix. Returns solve(rhs, out)."""
        A = self.form.mat
        vals, pos, row = self._diagonal()
        shift = np.zeros(A.height)
        shift[row] = np.where(free[row], mu * np.abs(vals[pos]), 0.0)
        with self._diagonal_added(shift):
            if self.parallel:
                return self._gathered(free)
            if self.linear_solver == "block-gmres":
                return self._block_solver(free, diagonal_shift=shift)
            return _applying(A.Inverse(ngs.BitArray(free.tolist()), inverse=self.linear_solver))

    def diagonal_scale(self) -> np.ndarray:
        """1 / diagonal of the assembled tangent's alpha-alpha block (per unit of R_alpha)."""
        vals, pos, row = self._diagonal()
        if self.parallel:
            # each rank holds its part of a shared dof's entry: summed over the ranks
            v = self.form.mat.CreateColVector()
            v.SetParallelStatus(ngs.PARALLEL_STATUS.DISTRIBUTED)
            v.FV().NumPy()[:] = 0.0
            v.FV().NumPy()[row] = vals[pos]
            v.Cumulate()
            d = v.FV().NumPy().copy()
        else:
            d = np.zeros(self.form.mat.height)
            d[row] = vals[pos]
        d = d[self.nu:]
        d = np.where(d > 0, d, np.nan)
        fin = np.isfinite(d)
        if self.parallel:
            top = self.ranks.max(d[fin])  # -inf where no rank has a positive entry
            floor = 1e-12 * top if math.isfinite(top) else 1.0
        else:
            floor = 1e-12 * np.nanmax(d) if np.any(fin) else 1.0
        return 1.0 / np.where(fin, np.maximum(d, floor), floor)

    def factorize(self, free: np.ndarray):
        """Factorize the assembled tangent on the ``free`` dofs; returns solve(rhs, out), out = A^-1
        rhs on the free dofs (any number of right-hand sides with one factorization)."""
        if self.parallel:
            return self._gathered(free)
        if self.linear_solver == "block-gmres":
            return self._block_solver(free)
        return _applying(self.form.mat.Inverse(ngs.BitArray(free.tolist()), inverse=self.linear_solver))

    def _gathered(self, free: np.ndarray):
        """MPI: the matrix gathered and factorized on rank 0 (``free`` the same on every rank that
        shares a dof)."""
        return _applying(self.form.mat.Inverse(ngs.BitArray(free.tolist()), inverse="masterinverse"))

    def _block_solver(self, free: np.ndarray, diagonal_shift: np.ndarray | None = None):
        """GMRES with the block lower-triangular preconditioner [K_uu 0; K_au K_aa], with sparse
        Cholesky factors of the symmetric u-u and alpha-alpha blocks (the u-u factor reuses its
        symbolic step). GMRES stops when the preconditioned residual fell by ``gmres_rtol``
        (relative: ngsolve's ``GMRes(tol=)`` is an absolute tolerance, which left the Newton
        corrections of a nearly converged step inexact, see tests/test_traps.py). Falls back to
        UMFPACK when GMRES does not converge in ``gmres_maxsteps``, or when its solution's true
        residual exceeds GMRES_TRUE_RTOL of the right-hand side (counted in
        :attr:`inexact_solves`). With :attr:`factor_reuse` the u-u factor of an earlier matrix may
        precondition (:data:`FACTOR_REUSE`); a solve that fails with it is repeated with a new one
        before UMFPACK.

        ``diagonal_shift`` (per dof, Levenberg): the matrix's values hold the shifted diagonal
        while the factors are made (:meth:`shifted`); the solves apply the restored matrix plus
        this diagonal."""
        from ngsolve.krylovspace import GMResSolver
        A = self.form.mat
        nu = self.nu
        shifted = diagonal_shift is not None
        if self._u_pending is not None:   # the last direction reused the factor: what it cost
            before, first = self._u_pending
            self._u_last = self._u_extra - before
            if first:
                self._u_first = self._u_last
            self._u_pending = None
        reuses = self._u_count > 0          # the factor was reused already: the last reuse's price is the estimate
        expected = self._u_last if reuses else self._u_first
        reused = not (shifted or self._u_stale or not self.factor_reuse or self._u_extra + expected >= self._u_cost)
        if reused:
            self.u_factor_reuses += 1
            self._u_pending = (self._u_extra, not reuses)
            self._u_count += 1
        else:
            self._new_u_factor(free, shifted)
        inv_a = self._alpha_factor(free)
        op = Masked(A, free, diagonal_shift)
        pre = _BlockLower(A, self._inv_u, inv_a)
        direct = []
        check = A.CreateColVector()

        def direct_inverse():
            """UMFPACK of the matrix (with the diagonal shift)."""
            with self._diagonal_added(diagonal_shift) if diagonal_shift is not None else contextlib.nullcontext():
                return A.Inverse(ngs.BitArray(free.tolist()), inverse="umfpack")

        def book(its, t0):
            """Count a GMRES run of ``its`` iterations begun at ``t0`` (the reuse rule's prices)."""
            self.gmres_iterations.append(its)
            if self._u_base is None:
                self._u_base = its
            elif its > self._u_base:   # the older factor's price: its extra iterations
                self._u_extra += (its - self._u_base) * (time.perf_counter() - t0) / its

        def gmres(rhs):
            """GMRES on the current factors: (solution, whether it failed)."""
            t0 = time.perf_counter()
            gm = GMResSolver(mat=op, pre=pre, tol=self.gmres_rtol, atol=1e-300, maxiter=self.gmres_maxsteps,
                             printrates=False)
            sol = gm.Solve(rhs=rhs)
            its = gm.iterations
            book(its, t0)
            bad = its >= self.gmres_maxsteps or not np.all(np.isfinite(sol.FV().NumPy()))
            if not bad:
                check.data = op * sol
                check.data -= rhs
                bad = check.Norm() > GMRES_TRUE_RTOL * rhs.Norm()
            return sol, bad

        def renew():
            """A new u-u factor after a failed solve with an older one (reusing did not pay)."""
            nonlocal reused
            self._u_first = max(self._u_first, self._u_cost)
            self._u_pending = None
            self._new_u_factor(free, shifted)
            reused = False

        def solve(rhs, out):
            rhsN = rhs.FV().NumPy()
            rhsN[~free] = 0.0
            if direct:
                out.data = direct[0] * rhs
                return
            sol, bad = gmres(rhs)
            if bad and reused:         # an older factor: try again with a new one
                renew()
                sol, bad = gmres(rhs)
            if bad:
                self.inexact_solves += 1
                direct.append(direct_inverse())
                sol.data = direct[0] * rhs
            out.data = sol

        def bordered(r, t, c, h):
            """(p, dlambda) of the bordered system of path following in one GMRES
            (:func:`ngtmc.coupled.bordered.bordered_gmres`; arrays over all dofs, zero where not
            free), or None: then the caller solves the two systems with ``solve``. A failure
            with an older u-u factor is tried again with a new one."""
            while not direct:
                t0 = time.perf_counter()
                out = bordered_gmres(numpy_operator(op), numpy_operator(pre), r, t, c, h,
                                     self.gmres_rtol, self.gmres_maxsteps, GMRES_TRUE_RTOL)
                if out is not None:
                    book(out[2], t0)
                    self.bordered_solves += 1
                    return out[0], out[1]
                if not reused:
                    break
                renew()                     # an older factor: try again with a new one
            self.bordered_fallbacks += 1
            return None
        if self.bordered:
            solve.bordered = bordered
        return solve

    def _alpha_factor(self, free: np.ndarray):
        """The sparse Cholesky factor of the alpha-alpha block on the free alpha dofs of ``free``:
        the last one updated where the free set and the matrix are the same (its symbolic step
        kept: 6 against 21 ms at the paper three-point bending), else a new one."""
        A = self.form.mat
        fa = free.copy()
        fa[:self.nu] = False
        matrix, kept = self._inv_a_key
        if self._inv_a is not None and matrix is A and np.array_equal(kept, fa):
            self._inv_a.Update()
        else:
            self._inv_a = A.Inverse(ngs.BitArray(fa.tolist()), inverse="sparsecholesky")
            self._inv_a_key = (A, fa)
        return self._inv_a

    def _new_u_factor(self, free: np.ndarray, shifted: bool):
        """A new sparse Cholesky factor of the u-u block of the matrix's current values (its
        symbolic step made once); its time is the price :data:`FACTOR_REUSE` weighs."""
        A = self.form.mat
        t0 = time.perf_counter()
        if self._inv_u is None:
            fu = free.copy()
            fu[self.nu:] = False
            self._inv_u = A.Inverse(ngs.BitArray(fu.tolist()), inverse="sparsecholesky")
        else:
            self._inv_u.Update()
        self._u_cost = time.perf_counter() - t0
        self._u_extra = 0.0
        self._u_base = None
        self._u_count = 0
        self._u_stale = shifted
        self.u_factorizations += 1


def _applying(inv):
    """solve(rhs, out), out = inv rhs, of a factorization ``inv``."""
    def solve(rhs, out):
        out.data = inv * rhs
    return solve


class SquareOperator(ngs.BaseMatrix):
    """An operator with the shape and vectors of the square matrix A."""

    def __init__(self, A):
        super().__init__()
        self.A = A

    def Height(self):
        return self.A.height

    def Width(self):
        return self.A.width

    def CreateColVector(self):
        return self.A.CreateColVector()

    def CreateRowVector(self):
        return self.A.CreateRowVector()


class Masked(SquareOperator):
    """The matrix (plus a diagonal ``shift`` per dof, if given) restricted to the free dofs,
    identity on the others."""

    def __init__(self, A, free, shift: np.ndarray | None = None):
        super().__init__(A)
        self.free = free
        self.shift = shift
        self.t = A.CreateColVector()

    def Mult(self, x, y):
        xN = x.FV().NumPy()
        tN = self.t.FV().NumPy()
        tN[:] = np.where(self.free, xN, 0.0)
        y.data = self.A * self.t
        yN = y.FV().NumPy()
        if self.shift is not None:
            yN += self.shift * tN
        yN[:] = np.where(self.free, yN, xN)


class _BlockLower(SquareOperator):
    """Block Gauss-Seidel preconditioner: z_u = K_uu^-1 r_u, z_a = K_aa^-1 (r_a - K_au z_u)."""

    def __init__(self, A, inv_u, inv_a):
        super().__init__(A)
        self.inv_u, self.inv_a = inv_u, inv_a
        self.z = A.CreateColVector()
        self.t = A.CreateColVector()

    def Mult(self, r, z):
        self.z.data = self.inv_u * r
        self.t.data = r - self.A * self.z
        z.data = self.z + self.inv_a * self.t
