"""Run a named study into a run folder (the format of ``docs/run-directory.md``).

    >>> import ngtmc
    >>> run_dir = ngtmc.run_study("three_point_bending", resolution="quick")   # doctest: +SKIP

One folder per run holds ``metadata.json``, ``history.csv`` (one row per accepted step, per case),
``snapshots.npz`` (u, alpha at the vertices and rho per triangle at chosen loads), ``vtk/``
(ParaView series), ``checkpoint/`` (to resume) and, if the report module is available,
``report.html``.

Every file is written to a temporary file and moved into place with ``os.replace``, so a crash never
leaves a truncated history or metadata behind. Checkpoints (``checkpoint/<case>.npz``: the
Simulation state, the history rows and the snapshots of that case) are written every
``checkpoint_every`` accepted steps or ``checkpoint_seconds`` seconds, whichever comes first, and
when a run is interrupted or fails; each case keeps two generations. ``run_study(...,
resume=True)`` continues from them and gives the same history as an uninterrupted run (wall and
solve times aside). A resume takes the recorded overrides and refuses other ones, skips an
unreadable checkpoint (named in a warning) for the older generation, and never rewrites the rows
of a completed case (see :mod:`ngtmc.study.run_files`).

The outputs (snapshots and VTK, checkpoints, progress, user callbacks, the report) are the plugins
of :mod:`ngtmc.runner.outputs` and :mod:`ngtmc.simulation.plugins`, on the accepted steps that ``Simulation.steps()`` yields. A user's own
scene goes through the same run: :func:`run_scene` (``ngtmc.simulate(..., out_dir=...)``) wraps it in a
one-case study (:func:`scene_study`).

A failed run (:class:`ngtmc.StepFailure`) still writes its history and metadata, with status
``"failed"`` and the error message, and then re-raises. An interrupted run (KeyboardInterrupt)
gets status ``"interrupted"``.

This package: :func:`run_study` and the checks before a run (:mod:`ngtmc.runner.study_run`); the folder of a run, its
files, metadata and checkpoints (:mod:`ngtmc.runner.folder`); the case loop and resume
(:mod:`ngtmc.runner.cases`); the cases on a Dask cluster (:mod:`ngtmc.runner.parallel`, optional);
a user's own scene (:mod:`ngtmc.runner.user_scene`).
"""
from ngtmc.runner.folder import case_results
from ngtmc.runner.study_run import default_output, execute, run_study
from ngtmc.runner.user_scene import run_scene, scene_study, simulate
from ngtmc.simulation import HISTORY_COLUMNS
from ngtmc.study import write_atomic

__all__ = ["run_study", "run_scene", "scene_study", "simulate", "default_output", "HISTORY_COLUMNS", "case_results",
           "write_atomic"]
