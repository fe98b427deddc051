"""Penalised interpolation of the physical (projected) density xbar in [0, 1] into the model's
pseudo-density rho, which the model turns into stiffness gamma(rho) and toughness Gc(rho)
(Eqs. 17-18 of :mod:`ngtmc.model.materials`):

* ``"simp"`` (Bendsoe 1989): rho = xbar^p, p >= 1 (p = 3 the usual choice);
* ``"ramp"`` (Stolpe and Svanberg 2001): rho = xbar / (1 + q (1 - xbar)), q >= 0;
* ``"linear"``: rho = xbar (the model's own interpolation, unpenalised).

Intermediate densities then carry less stiffness than their share of material, which pushes an
optimum towards solid and void. Dimensionless."""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

__all__ = ["Interpolation"]

KINDS = ("simp", "ramp", "linear")


@dataclass(frozen=True)
class Interpolation:
    """rho(xbar) and its derivative (see :mod:`ngtmc.design.interpolation`). ``kind``: one of
    "simp", "ramp", "linear"; ``exponent``: p of SIMP (>= 1) or q of RAMP (>= 0); ignored by
    "linear"."""

    kind: str = "simp"
    exponent: float = 3.0

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"Interpolation kind = {self.kind!r} is not one of {', '.join(KINDS)}")
        e = float(self.exponent)
        low = 1.0 if self.kind == "simp" else 0.0
        if not (math.isfinite(e) and e >= low):
            raise ValueError(f"Interpolation exponent = {self.exponent!r} must be a finite number >= {low:g} "
                             f"for {self.kind}")

    def __call__(self, xbar) -> np.ndarray:
        x = np.asarray(xbar, dtype=float)
        if self.kind == "simp":
            return np.sign(x) * np.abs(x) ** self.exponent
        if self.kind == "ramp":
            return x / (1.0 + self.exponent * (1.0 - x))
        return x.copy()

    def derivative(self, xbar) -> np.ndarray:
        """d rho / d xbar, element by element."""
        x = np.asarray(xbar, dtype=float)
        if self.kind == "simp":
            return self.exponent * np.abs(x) ** (self.exponent - 1.0)
        if self.kind == "ramp":
            q = self.exponent
            return (1.0 + q) / (1.0 + q * (1.0 - x)) ** 2
        return np.ones_like(x)
