"""Discrete adjoint of the load path (ngtmc.sensitivities) against finite differences.

Scene: the design_for_contact geometry on a coarse mesh (notched beam, a 0.1 mm pad of third medium
under an indenter). On the monotonic path 0 -> 0.2 mm in 8 fixed steps of 0.025 mm the pad is
squeezed and contact closes at about 0.075-0.1 mm (knee of the force curve), then a crack grows from
the notch (max alpha 0.16 -> 0.37 -> 0.64 over the last three steps, force drops after 0.175 mm).
The second path unloads to 0.1 mm after cracking.

Every check compares the adjoint directional derivative with central finite differences of
:func:`replay` runs (same load steps). The V-shaped error curve over the finite-difference step is
printed (run pytest with -s to see it).
"""
from __future__ import annotations

import time

import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from ngtmc import sensitivities as S
from ngtmc.studies import design_for_contact as D

OVERRIDES = {"h_band": 0.2, "h_pad": 0.1, "h": 0.5, "du": 0.025, "l0": 0.3, "Gc": 0.1}
TOL = 1e-4
EPS_REL = 1e-5


def _params():
    return D._params("quick", **OVERRIDES)


@pytest.fixture(scope="module")
def path():
    p = _params()
    sc = D.build_scene(p)
    return S.record_path(sc, D.schedule(p), D.control(p), newton=ngtmc.NewtonOptions(rtol=1e-12))


def _user_density():
    cache = {}

    def density(s, n):
        if "cf" not in cache:
            cache["cf"] = s.Gc * s.alpha**2 + 1e-3 * s.K * ngs.InnerProduct(ngs.Grad(s.u), ngs.Grad(s.u))
        return cache["cf"]

    return density


def _objectives(path):
    N = path.n_steps
    return {
        "reaction_last": S.ReactionAtStep(-1),
        "reaction_contact": S.ReactionAtStep(4),
        "external_work": S.ExternalWork(),
        "fracture_energy": S.FinalFractureEnergy(),
        "compliance": S.ComplianceAtStep(N - 2),
        "user_cf": S.UserObjective(_user_density(), region="beam"),
        "curve_misfit": S.ForceCurveObjective.least_squares(path.loads, 0.8 * path.forces),
        "combination": S.ExternalWork() - 2.0 * S.FinalFractureEnergy(),
    }


def _direction(path, seed=1):
    rng = np.random.default_rng(seed)
    pad = S.design_mask(path, "pad")
    d = rng.standard_normal(path.rho.size)
    # the pad is void (rho = 0, gamma0 = 1e-4): keep rho +- eps d away from negative stiffness
    d[pad] = 5e-3 * rng.uniform(-1.0, 1.0, int(pad.sum()))
    return {"rho": d}


@pytest.fixture(scope="module")
def gradients(path):
    out = {}
    for name, obj in _objectives(path).items():
        out[name] = S.gradient(path, obj, wrt=("rho", "E", "nu", "Gc", "l0", "gamma0"))
    return out


def test_path_has_contact_and_crack(path):
    h = path.history
    f = h["force"].to_numpy()
    assert path.n_steps == 8
    # contact: almost no force while the pad is open, then a steep rise
    assert f[1] < 0.05 * f.max() and f[4] > 10 * f[1]
    # crack grows over several steps and the force drops at the end
    a = h["max_alpha"].to_numpy()
    assert a[-3] > 0.1 and a[-1] > 0.5 and np.all(np.diff(a[-3:]) > 0.1)
    assert f[-1] < f.max()


def test_replay_reproduces_the_path(path):
    r = S.replay(path)
    assert np.allclose(r.forces, path.forces, rtol=1e-9, atol=1e-12)
    assert np.allclose(r.states[-1]["alpha"], path.states[-1]["alpha"], atol=1e-10)
    assert np.allclose(r.states[-1]["H"], path.states[-1]["H"], rtol=1e-8, atol=0)
    path.activate()


def test_rho_gradients_v_curve(path, gradients):
    """All objectives in one random design direction; eps swept 1e-2 .. 1e-8: the error falls like
    eps^2 (truncation), then rises again (solver round-off): the V. The best relative error must be
    below 1e-4 for every objective."""
    objs = _objectives(path)
    d = _direction(path)
    names = list(objs)
    adj = np.array([S.directional_derivative(gradients[k], d) for k in names])
    rows = []
    for eps in (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
        fd, paths = S.directional_fd(path, [objs[k] for k in names], d, eps, return_paths=True)
        sw = S.active_set_changes(*paths)
        rows.append((eps, np.abs(fd - adj) / np.abs(adj), sw))
    print("\nrelative |FD - adjoint| / |adjoint| in a random rho direction (V-curve):")
    print("   eps   " + " ".join(f"{k[:14]:>15s}" for k in names) + "   active-set switches between +eps and -eps")
    for eps, err, sw in rows:
        print(f"{eps:8.0e} " + " ".join(f"{e:15.2e}" for e in err) + f"   {sw}")
    errs = np.array([r[1] for r in rows])
    best = errs.min(axis=0)
    for k, b in zip(names, best):
        assert b <= TOL, f"{k}: best relative FD error {b:.2e}"
    # V shape, on the geometric mean over the objectives (a single objective's round-off error is
    # a random number and can, by chance, be smallest at eps = 1e-8): truncation error decreases
    # at least 100x from eps = 1e-2 to the best eps, and the smallest eps is worse than the best
    # (round-off side of the V)
    gm = np.exp(np.log(errs).mean(axis=1))
    assert gm[0] > 100 * gm.min()
    assert gm[-1] > gm.min()


@pytest.mark.parametrize("name", ["E", "Gc", "l0", "gamma0", "nu"])
def test_parameter_gradients(path, gradients, name):
    objs = _objectives(path)
    names = list(objs)
    g = gradients
    value = S.parameter_value(path, name)
    fd = S.directional_fd(path, [objs[k] for k in names], {name: value}, EPS_REL)
    adj = np.array([g[k][name] * value for k in names])
    rel = np.abs(fd - adj) / np.maximum(np.abs(adj), 1e-12 * np.max(np.abs(adj)))
    print(f"\n{name} = {value:g}: relative FD errors (eps = {EPS_REL:g} relative):",
          {k: f"{r:.1e}" for k, r in zip(names, rel)})
    for k, r, a in zip(names, rel, adj):
        if name == "gamma0" and abs(a) < 1e-9 * np.max(np.abs(adj)):
            continue
        assert r <= TOL, f"d {k} / d {name}: FD {fd[names.index(k)]:.6e}, adjoint {a:.6e}"


def test_taylor_remainder_is_quadratic(path, gradients):
    d = _direction(path, seed=2)
    d.update({"E": 0.3 * S.parameter_value(path, "E"), "Gc": -0.2 * S.parameter_value(path, "Gc"),
              "l0": 0.1 * S.parameter_value(path, "l0"), "gamma0": 0.5 * S.parameter_value(path, "gamma0")})
    obj = S.ExternalWork()
    g = S.gradient(path, obj)
    t = S.taylor_test(path, obj, d, g, eps_list=(4e-3, 2e-3, 1e-3, 5e-4))
    print("\nTaylor test (ExternalWork, rho + E + Gc + l0 + gamma0): eps", t["eps"], "remainder",
          [f"{r:.2e}" for r in t["remainder"]], "orders", [f"{o:.2f}" for o in t["order"]])
    assert all(1.8 <= o <= 2.3 for o in t["order"])


def test_unloading_after_cracking():
    p = _params()
    sc = D.build_scene(p)
    up = S.record_path(sc, ngtmc.Schedule([0.0, 0.2, 0.1]), D.control(p), newton=ngtmc.NewtonOptions(rtol=1e-12))
    lam = up.loads
    unload = np.nonzero(np.diff(lam) < 0)[0] + 1
    assert len(unload) >= 3
    sets = S.active_sets(up)
    from ngtmc.sensitivities.adjoint import _engine
    eng = _engine(up)
    ind = ngs.GridFunction(up.solver.irs)
    ind.Interpolate(eng.frac_ind)
    in_beam = ind.vec.FV().NumPy() > 0.5
    # while unloading, the history freezes: the inactive branches of the max carry the adjoint. In
    # the first unloading steps the damage lagged by one step (single pass) still grows near the
    # crack tip, so some points stay active; by the end of the unloading none is.
    active = [int(np.count_nonzero(sets[n - 1]["history"][in_beam])) for n in unload]
    held = [int(np.count_nonzero(sets[n - 1]["alpha_held"])) for n in unload]
    print(f"\nunloading steps {unload.tolist()}: history points still growing {active} of {int(in_beam.sum())}; "
          f"phase-field dofs held by irreversibility {held} of {up.solver.fes_a.ndof}")
    assert active[-1] == 0 and active[-1] < active[0]
    objs = [S.ExternalWork(), S.ReactionAtStep(-1), S.FinalFractureEnergy(), S.ReactionAtStep(int(unload[0]))]
    d = _direction(up, seed=3)
    d["Gc"] = S.parameter_value(up, "Gc")
    grads = [S.gradient(up, o) for o in objs]
    adj = np.array([S.directional_derivative(g, d) for g in grads])
    fd = S.directional_fd(up, objs, d, EPS_REL)
    rel = np.abs(fd - adj) / np.abs(adj)
    print("\nunloading path: loads", np.round(lam, 4).tolist(), "relative FD errors", [f"{r:.1e}" for r in rel])
    assert np.all(rel <= TOL)


def test_cost_and_memory(path):
    r = S.replay(path)
    t0 = time.perf_counter()
    g = S.gradient(r, S.ExternalWork(), wrt=("rho", "E", "Gc", "l0", "gamma0"))
    tg = time.perf_counter() - t0
    assert abs(g["time"] - tg) < 0.1 * tg + 0.05
    s = path.solver
    per_step = 8 * (s.fes_u.ndof + s.fes_a.ndof + s.irs.ndof)
    print(f"\ncost: forward (record, adaptive) {path.forward_time:.2f} s, replay {r.forward_time:.2f} s, "
          f"gradient (rho + 4 parameters) {tg:.2f} s = {tg / r.forward_time:.2f} x replay; "
          f"stored states {path.memory_bytes} bytes = {path.n_steps + 1} x {per_step} bytes")
    assert path.memory_bytes == (path.n_steps + 1) * per_step
    assert tg <= 1.5 * r.forward_time


def test_errors(path):
    p = _params()
    with pytest.raises(ValueError, match="scheme"):
        S.record_path(D.build_scene(p), 0.05, scheme="staggered")
    with pytest.raises(ValueError, match="unknown parameter"):
        S.gradient(path, S.ExternalWork(), wrt=("K",))
    with pytest.raises(ValueError, match="outside the recorded steps"):
        S.ReactionAtStep(99).value(path)


def test_checkpointing_gives_the_same_gradient(path, gradients):
    """Store every third state only: the reverse sweep recomputes the others, same gradient."""
    p = _params()
    cp = S.record_path(D.build_scene(p), D.schedule(p), D.control(p), newton=ngtmc.NewtonOptions(rtol=1e-12),
                       checkpoint_every=3)
    stored = [n for n, st in enumerate(cp.states) if st is not None]
    assert stored == [0, 3, 6, cp.n_steps]
    assert cp.memory_bytes == len(stored) * cp.state_bytes < path.memory_bytes
    t0 = time.perf_counter()
    for name, obj in (("external_work", S.ExternalWork()), ("user_cf", S.UserObjective(_user_density(), region="beam"))):
        g = S.gradient(cp, obj, wrt=("rho", "E", "Gc", "l0", "gamma0", "nu"))
        ref = gradients[name]
        assert abs(g["value"] - ref["value"]) <= 1e-9 * abs(ref["value"])
        assert np.linalg.norm(g["rho"] - ref["rho"]) <= 1e-7 * np.linalg.norm(ref["rho"])
        for k in ("E", "Gc", "l0", "gamma0", "nu"):
            assert abs(g[k] - ref[k]) <= 1e-7 * abs(ref[k]) + 1e-12
    print(f"\ncheckpointing every 3 steps: {cp.memory_bytes} bytes stored (peak {cp.peak_memory_bytes}) "
          f"instead of {path.memory_bytes}; two gradients in {time.perf_counter() - t0:.2f} s")


def test_contact_only_scene():
    """Without a phase field (nothing may break) the sweep is the displacement adjoint alone."""
    p = _params()
    base = D.build_scene(p)
    sc = ngtmc.Scene(base.mesh, base.materials, base.supports, base.load, density={"pad": 0.0},
                     regulariser=base.regulariser, gamma0=p["gamma0"], order=2)
    objs = [S.ExternalWork(), S.ReactionAtStep(-1), S.FinalFractureEnergy()]
    g0, cp = S.differentiate(sc, 0.15, objs[0], ngtmc.AdaptiveStepControl(du_max=0.025), wrt=("rho", "E:pad", "gamma0"))
    assert cp.solver.alpha is None and cp.n_steps == 6
    d = _direction(cp, seed=5)
    d["E:pad"] = S.parameter_value(cp, "E:pad")
    grads = [g0] + [S.gradient(cp, o, wrt=("rho", "E:pad", "gamma0")) for o in objs[1:]]
    assert grads[2]["value"] == 0.0 and not np.any(grads[2]["rho"])
    adj = np.array([S.directional_derivative(g, d) for g in grads[:2]])
    fd = S.directional_fd(cp, objs[:2], d, EPS_REL)
    rel = np.abs(fd - adj) / np.abs(adj)
    print("\ncontact only: relative FD errors", [f"{r:.1e}" for r in rel])
    assert np.all(rel <= TOL)


@pytest.mark.parametrize("split,formulation", [("spectral", "anisotropic"), ("vol-dev-small", "hybrid")])
def test_adjoint_follows_the_split(split, formulation):
    """The adjoint differentiates the scene's split (history) and formulation (energy): coarse
    notched plate, 8 steps to 0.008 mm (damage up to about 0.6), against central differences."""
    from scenes import notched_plate
    sc = notched_plate(maxh=0.2, h_band=0.05, l0=0.1, split=split, formulation=formulation)
    path = S.record_path(sc, 0.008, ngtmc.AdaptiveStepControl(du_max=1e-3), newton=ngtmc.NewtonOptions(rtol=1e-12))
    assert path.solver.max_alpha() > 0.3
    rng = np.random.default_rng(1)
    d = {"rho": 0.1 * rng.standard_normal(path.rho.size), "E": 2100.0, "Gc": 0.03}
    objs = [S.ExternalWork(), S.ReactionAtStep(-1)]
    adj = np.array([S.directional_derivative(S.gradient(path, o, wrt=("rho", "E", "Gc")), d) for o in objs])
    fd = S.directional_fd(path, objs, d, EPS_REL)
    rel = np.abs(fd - adj) / np.abs(adj)
    print(f"\n{split} {formulation}: relative FD errors", [f"{r:.1e}" for r in rel])
    assert np.all(rel <= TOL)
