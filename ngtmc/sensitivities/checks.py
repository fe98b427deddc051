"""Finite-difference checks of the adjoint: directional differences by replay, Taylor tests and
the active sets they must not cross (``ngtmc.sensitivities``).
"""
from __future__ import annotations

import numpy as np

from ngtmc.sensitivities.objectives import Objective
from ngtmc.sensitivities.path import Path, parameter_value, replay


def _perturbed(path: Path, direction: dict, eps: float) -> Path:
    rho = path.rho + eps * np.asarray(direction["rho"]) if "rho" in direction else None
    pars = {k: parameter_value(path, k) + eps * v for k, v in direction.items() if k != "rho"}
    return replay(path, rho=rho, parameters=pars)


def directional_fd(path: Path, objective, direction: dict, eps: float, return_paths: bool = False):
    """Central finite difference (J(p + eps d) - J(p - eps d)) / (2 eps) by two :func:`replay` runs.

    objective: an Objective or a list of them (all evaluated on the same two replays; a list gives
    a numpy array). direction: {"rho": array, "E": dE, ...} (absent entries are zero). With
    ``return_paths`` also returns the two replayed paths (for :func:`active_set_changes`)."""
    objs = objective if isinstance(objective, (list, tuple)) else [objective]
    paths = [_perturbed(path, direction, sgn * eps) for sgn in (1.0, -1.0)]
    fd = np.array([(o.value(paths[0]) - o.value(paths[1])) / (2 * eps) for o in objs])
    path.activate()
    out = fd if isinstance(objective, (list, tuple)) else float(fd[0])
    return (out, paths) if return_paths else out


def active_sets(path: Path) -> list:
    """Per step n = 1..N the active branches of the scheme: ``"history"`` (bool per history point:
    H_n > H_{n-1}, i.e. the max took Psi_plus), ``"alpha_held"`` (bool per phase-field dof:
    alpha_n == alpha_{n-1}, irreversibility or the upper bound active) and ``"alpha_one"``
    (alpha_n == 1)."""
    out = []
    for n in range(1, path.n_steps + 1):
        a, b = path.state(n - 1), path.state(n)
        d = {"history": b["H"] > a["H"]}
        if "alpha" in b:
            d["alpha_held"] = b["alpha"] == a["alpha"]
            d["alpha_one"] = b["alpha"] >= 1.0
        out.append(d)
    return out


def active_set_changes(path_a: Path, path_b: Path) -> dict:
    """Number of history points and phase-field dofs whose active branch differs between two paths
    of the same load sequence (a finite difference across a switch is not a derivative)."""
    sa, sb = active_sets(path_a), active_sets(path_b)
    out = {"history": 0, "alpha_held": 0, "alpha_one": 0}
    for x, y in zip(sa, sb):
        for k in out:
            if k in x:
                out[k] += int(np.count_nonzero(x[k] != y[k]))
    return out


def directional_derivative(grad: dict, direction: dict) -> float:
    """<dJ/dp, d> for a gradient dict of :func:`gradient` and a direction as in :func:`directional_fd`."""
    total = 0.0
    for k, v in direction.items():
        total += float(np.dot(grad[k], v)) if k == "rho" else float(grad[k]) * float(v)
    return total


def taylor_test(path: Path, objective: Objective, direction: dict, grad: dict, eps_list=(4e-2, 2e-2, 1e-2, 5e-3)) -> dict:
    """Remainders |J(p + eps d) - J(p) - eps <dJ, d>| for decreasing eps; they shrink as eps^2 when
    the gradient is right. Returns {"eps": [...], "remainder": [...], "order": [...], "switches":
    [...]} (observed orders between consecutive eps; history points whose branch of the max differs
    from the path's at each eps: a remainder across a switch is not that of a derivative).

    The path's own states are read before the replays (which overwrite the solver's fields)."""
    J0 = grad["value"]
    dJ = directional_derivative(grad, direction)
    rem, switches = [], []
    for eps in eps_list:
        pert = _perturbed(path, direction, eps)
        J = objective.value(pert)
        rem.append(abs(J - J0 - eps * dJ))
        switches.append(active_set_changes(path, pert)["history"])
    path.activate()
    orders = [float(np.log(rem[i] / rem[i + 1]) / np.log(eps_list[i] / eps_list[i + 1])) for i in range(len(rem) - 1)]
    return {"eps": list(eps_list), "remainder": rem, "order": orders, "switches": switches}
