"""
A gradient check: adjoint against finite differences
====================================================

:func:`ngtmc.sensitivities.differentiate` runs a scene and returns the derivative of an objective
with respect to the pseudo-density of every element and to material parameters, by one reverse
(adjoint) sweep over the recorded load path. Here the objective is the external work (N mm) of
pulling a coarse notched bar like that of the crack example (l0 = 0.1 mm) to 0.008 mm, where the
crack has begun.
The gradient is checked two ways along a random direction d: against a central finite
difference, and by a Taylor test, whose remainder ``abs(J(p + eps d) - J(p) - eps dJ.d)`` must
fall as eps^2 (observed order 2) when the gradient is right. Units: mm, N, MPa.
"""
import os

import numpy as np
import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, X, Y

import ngtmc
from ngtmc import sensitivities as sens

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"

bar = Rectangle(2.0, 0.5).Face() - MoveTo(0.995, -0.01).Rectangle(0.01, 0.11).Face()
band = MoveTo(0.9, 0.0).Rectangle(0.2, 0.5).Face()
ligament, rest = bar * band, bar - band
ligament.faces.name, rest.faces.name = "band", "bar"
ligament.faces.maxh = 0.05 if SHORT else 0.025
shape = Glue([rest, ligament])
shape.edges.Min(X).name, shape.edges.Max(X).name = "left", "right"
shape.vertices.Min(X + Y).name = "corner"
mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.2))
scene = ngtmc.Scene(mesh, {".*": ngtmc.Material(E=210e3, nu=0.3, Gc=2.7, l0=0.1)},   # MPa, -, N/mm, mm
                    supports=[ngtmc.Support("left", x=True), ngtmc.Support(ngtmc.Point("corner"), y=True)],
                    load=ngtmc.DisplacementLoad("right", "x"), fracture_regions="band")

# %%
# Record the path (8 steps of 1e-3 mm) and differentiate in one call.
objective = sens.ExternalWork()                                   # N mm
control = ngtmc.AdaptiveStepControl(du_max=1e-3)                  # mm
g, path = sens.differentiate(scene, 0.008, objective, control, wrt=("rho", "E", "Gc"))
print(f"J = {g['value']:.6g} N mm after {path.n_steps} steps, max alpha {path.history['max_alpha'].iloc[-1]:.2f}")
print(f"dJ/dE = {g['E']:.4g} N mm/MPa, dJ/dGc = {g['Gc']:.4g} mm^2, dJ/drho: {g['rho'].size} values")

# %%
# A random direction in the densities (kept within [0, 1]: rho = 1, so step down) and in E.
rng = np.random.default_rng(0)
d = {"rho": -rng.uniform(0.0, 1.0, path.rho.size), "E": 0.1 * sens.parameter_value(path, "E")}
adjoint = sens.directional_derivative(g, d)
fd = sens.directional_fd(path, objective, d, eps=1e-5)
print(f"directional derivative: adjoint {adjoint:.8g}, finite difference {fd:.8g}, "
      f"relative difference {abs(fd - adjoint) / abs(adjoint):.1e}")

# %%
# The Taylor test: remainders and the observed orders between successive eps.
t = sens.taylor_test(path, objective, d, g, eps_list=(4e-3, 2e-3, 1e-3, 5e-4))
print("remainders", ["%.2e" % r for r in t["remainder"]], "orders", ["%.2f" % o for o in t["order"]])
print(f"smallest observed order {min(t['order']):.2f} (expected 2)")
