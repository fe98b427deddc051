"""The Heaviside projection of filtered densities (Wang, Lazarov and Sigmund 2011):

    project(x) = (tanh(beta eta) + tanh(beta (x - eta))) / (tanh(beta eta) + tanh(beta (1 - eta)))

maps [0, 1] onto [0, 1], pushes densities below the threshold ``eta`` towards 0 and above it
towards 1, sharper as ``beta`` grows (beta -> 0: the identity). Dimensionless."""
from __future__ import annotations

import numpy as np

__all__ = ["project", "project_derivative"]


def _check(beta: float, eta: float):
    if not (np.isfinite(beta) and beta > 0.0):
        raise ValueError(f"projection: beta = {beta!r} must be a finite number > 0")
    if not (0.0 < eta < 1.0):
        raise ValueError(f"projection: eta = {eta!r} must lie strictly between 0 and 1")


def project(x, beta: float, eta: float = 0.5) -> np.ndarray:
    """The projected densities of ``x`` (array)."""
    _check(beta, eta)
    x = np.asarray(x, dtype=float)
    a, b = np.tanh(beta * eta), np.tanh(beta * (1.0 - eta))
    return (a + np.tanh(beta * (x - eta))) / (a + b)


def project_derivative(x, beta: float, eta: float = 0.5) -> np.ndarray:
    """d project / d x, element by element."""
    _check(beta, eta)
    x = np.asarray(x, dtype=float)
    a, b = np.tanh(beta * eta), np.tanh(beta * (1.0 - eta))
    return beta * (1.0 - np.tanh(beta * (x - eta)) ** 2) / (a + b)
