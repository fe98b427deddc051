"""The entry points of the adjoint: :func:`record_path` records a run for it, by scheme (the
single-pass scheme in :mod:`ngtmc.sensitivities.path`, the monolithic ones in
:mod:`ngtmc.sensitivities.coupled`), and :func:`differentiate` records and differentiates in one
call."""
from __future__ import annotations

from typing import Iterable

from ngtmc.discrete import NewtonOptions
from ngtmc.scene import Scene
from ngtmc.sensitivities.adjoint import gradient
from ngtmc.sensitivities.coupled import record_coupled_path
from ngtmc.sensitivities.objectives import Objective
from ngtmc.sensitivities.path import Path, check_recordable, record_single_pass
from ngtmc.stepping import AdaptiveStepControl, Schedule

__all__ = ["record_path", "differentiate"]


def record_path(scene: Scene, schedule: Schedule | float, control: AdaptiveStepControl | None = None,
                newton: NewtonOptions | None = None, checkpoint_every: int | None = None, **options) -> Path:
    """Run ``scene`` through ``schedule`` (adaptive steps as in :class:`~ngtmc.simulation.loop.Simulation`)
    and store every accepted state for :func:`gradient`.

    ``options`` go to :class:`~ngtmc.simulation.loop.Simulation`; ``scheme="single-pass"`` (the paper's
    scheme, the default), ``"monolithic"`` and ``"path-following"`` can be differentiated (the two
    monolithic ones by :mod:`ngtmc.sensitivities.coupled`, which returns a
    :class:`~ngtmc.sensitivities.coupled.CoupledPath`; no checkpointing there). For gradients that
    agree with finite differences to 1e-4, converge Newton tightly, e.g.
    ``newton=NewtonOptions(rtol=1e-12)``, and for the monolithic schemes also the phase field,
    ``coupled={"alpha_tol": 1e-12}``. ``checkpoint_every``: store only every k-th state (see
    :class:`Path`). Returns a :class:`Path`."""
    scheme = check_recordable(scene, checkpoint_every, options)
    if scheme != "single-pass":
        return record_coupled_path(scene, schedule, control, newton=newton, checkpoint_every=checkpoint_every,
                                   **options)
    return record_single_pass(scene, schedule, control, newton=newton, checkpoint_every=checkpoint_every, **options)


def differentiate(scene: Scene, schedule: Schedule | float, objective: Objective,
                  control: AdaptiveStepControl | None = None,
                  wrt: Iterable[str] = ("rho", "E", "Gc", "l0", "gamma0"), **options) -> tuple[dict, Path]:
    """One call: run ``scene`` through ``schedule`` (:func:`record_path`, ``options`` as there) and
    return (``gradient(path, objective, wrt)``, path). Newton defaults to ``rtol=1e-12`` here, and
    for the monolithic schemes the coupled solver's ``alpha_tol`` to 1e-12."""
    options.setdefault("newton", NewtonOptions(rtol=1e-12))
    if options.get("scheme") in ("monolithic", "path-following"):
        options["coupled"] = {"alpha_tol": 1e-12, **(options.get("coupled") or {})}
    path = record_path(scene, schedule, control, **options)
    return gradient(path, objective, wrt), path

