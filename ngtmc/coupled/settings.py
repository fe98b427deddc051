"""The tuned settings of the coupled Newton (:mod:`ngtmc.coupled.monolithic`, :mod:`ngtmc.coupled.iteration`),
each with the measurement it rests on."""
import os

__all__ = ["DEBUG", "STALL_WINDOW", "STALL_FACTOR", "LEVENBERG_SHIFTS", "WEAK_STEP", "WEAK_STOP", "COUPLED_RTOL", "FACTOR_REUSE",
           "BORDERED", "RELAX_DISSIPATION"]

#: print the merits and steps of each iteration (environment variable NGTMC_DEBUG_COUPLED set)
DEBUG = bool(os.environ.get("NGTMC_DEBUG_COUPLED"))



#: A solve stops as stalled when its merit function fell less than STALL_FACTOR over the last
#: STALL_WINDOW iterations (checked from iteration STALL_WINDOW + 3 on): a Newton iteration that
#: converges falls far faster, one that creeps along the line search does not reach the tolerance.
STALL_WINDOW = 3
STALL_FACTOR = 0.25

#: FLOOR_RTOL (the residual floor at which a solve is accepted) is :data:`ngtmc.discrete.newton.FLOOR_RTOL`.

#: Levenberg shifts mu tried in turn when the line search along the Newton direction fails: the
#: free diagonal of the tangent is scaled by (1 + mu), which shortens the step in near-singular
#: modes most (the squeezed-void vertex of FLOOR_RTOL).
LEVENBERG_SHIFTS = (1e-4, 1e-2, 1.0)

#: A Newton step accepted at a step length below WEAK_STEP is compared with Levenberg steps.
WEAK_STEP = 1.0 / 16

#: Default of ``CoupledNewton(weak_stop=...)``: an iteration that kept a weak Newton step (below
#: WEAK_STEP) because no Levenberg step did better is treated as a stall (a displacement relaxation
#: once, else acceptance at the residual floor, else the attempt fails and the caller cuts back).
#: Without it, the paper L-panel's crack run spent most of a failed attempt there: from iteration
#: 11 on, steps of 1/128-1/512 that lowered the merit by 1 % each, every one after a failed line
#: search and three failed Levenberg factorizations, until the iteration limit (15). With it, two
#: such steps took 76 and 74 s instead of 100 and 107 s (the same states); the quick L-panel's
#: monotonic case 121 steps and 610 iterations instead of 129 and 654 (docs/performance.md).
WEAK_STOP = True

#: Relative residual of the coupled Newton where ``NewtonOptions.rtol`` is None (the default), and
#: its complementarity tolerance where ``alpha_tol`` is None. The coupled Newton converges
#: quadratically near a solution (the merit falls 1e-2, 1e-6, 1e-11, 1e-23), so 1e-6 instead of the
#: displacement Newton's 1e-8 saves its last iteration in most steps. Measured on the quick
#: three-point bending, path following, side by side with 1e-8 for both: the same 78 steps, 459
#: instead of 515 Newton iterations, every recorded force the same to 7e-5 N/mm (2e-6 of the peak),
#: the peak to 1e-8 N/mm (docs/performance.md). The adjoint's recordings pass 1e-12.
COUPLED_RTOL = 1e-6

#: Reuse of the u-u factor of block-GMRES across Newton directions ("rent or buy"): GMRES always
#: solves the current tangent, so an older factor is only a poorer preconditioner. With reuse on,
#: a direction keeps the factor if the GMRES time spent with it beyond the iterations of its first
#: solve (those extra iterations times the measured time per iteration), plus what the next
#: direction is expected to add, stays below the measured time of its factorization. The next
#: direction is expected to add what the last reused one did, or, for the first reuse of a
#: factor, what the first reuse of the factors before it did (learned during the run: where one
#: reuse already costs more than a factorization, as in 2D, factors are not reused). A Levenberg
#: (shifted) direction always makes a new factor, and a solve that fails with an older factor is
#: repeated with a new one before UMFPACK. The choice is per run: ``coupled={"factor_reuse": ...}``
#: (True, False or "auto"). "auto", the default, reuses on 3D meshes only, as measured
#: (docs/performance.md, "Reusing the u-u factor while it pays"): in 3D a factorization costs
#: 35 to 68 triangular solves (medium and paper hemisphere), in 2D a reused factor's extra GMRES
#: iterations cost more than the factorization they save.
FACTOR_REUSE = "auto"

#: Block-GMRES solves the bordered system of path following (the Newton correction and the load
#: change together) in one GMRES run instead of two (:mod:`ngtmc.coupled.bordered`);
#: ``coupled={"bordered": False}`` makes the two solves (docs/performance.md).
BORDERED = True

#: Default of ``coupled={"relax_dissipation": ...}``: whether a solve under dissipation control
#: (path following's dissipation steps) relaxes the displacement at fixed alpha where it stalls,
#: as a solve at a fixed load does (:meth:`ngtmc.coupled.iteration.Iteration.relax_u`). The
#: relaxation leaves an unstable equilibrium of a squeezed void at contact onset, a displacement
#: step; in a dissipation step that stalls it mostly adds its iterations to an attempt that then
#: fails and is cut back. Measured without it, side by side on one machine (docs/performance.md):
#: the paper three-point bending 185 steps and 871 Newton iterations, the most in a step 18,
#: against 178/952 and 183/964 for two runs with it (an earlier run: three steps above 20); the quick one 82 steps
#: and 389 against 398; the quick L-panel with path following, case main 614 against 671, but
#: case monotonic 818 against 686 (34 against 14 cut-backs). So it stays on by default and the
#: three-point-bending studies switch it off (the 2D study, and the 3D study's hemisphere: 291 against
#: 376 iterations at quick).
RELAX_DISSIPATION = True
