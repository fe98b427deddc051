"""The bad-input audit (``python -m benchmarks.bad_inputs``; about a minute): several hundred
wrong inputs a user may bring, each run as a user would, and each outcome classified:

* **clear**: refused (ValueError, TypeError, StudyError) or warned (ScaleWarning,
  ElementWarning, ResolutionWarning) with a message naming the parameter;
* **unnamed**: refused or warned, but the message names none of the parameter's words;
* **crash**: another exception (AttributeError, KeyError, netgen's or NGSolve's own);
* **silent**: accepted without a word.

Writes ``benchmarks/results/bad_inputs-<UTC stamp>.json`` and ``.md`` (the counts and every input
that is not clear). Units: mm, N, MPa.
"""
from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
import subprocess
import sys
import tempfile
import warnings
from datetime import datetime, timezone

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
sys.path.insert(0, str(ROOT / "tests"))

import ngsolve as ngs  # noqa: E402
import ngtmc  # noqa: E402
from ngtmc.study import StudyError  # noqa: E402
from scenes import bar_mesh  # noqa: E402

MESH = bar_mesh(maxh=0.1)
MAT = {"bar": ngtmc.Material(1000.0, 0.3, 1.0, 0.3)}       # l0 resolved on this mesh: no ResolutionWarning
#: the warnings that name a bad input (a ResolutionWarning is about the mesh, not the input)
WARNINGS = (ngtmc.ScaleWarning, ngtmc.ElementWarning)
BAD_NUMBERS = [0, -1.0, float("nan"), float("inf"), "1.0", None, True, [1.0], 1e-300, 1e300, -1e-9, complex(1, 1)]


def scene(**kw):
    base = dict(mesh=MESH, materials=MAT, supports=[ngtmc.Support("left", x=True, y=True)],
                load=ngtmc.DisplacementLoad("right", "x"), fracture_regions="bar")
    base.update(kw)
    return ngtmc.Scene(**base)


def solve(sc, final=1e-3, **kw):
    return ngtmc.simulate(sc, final, ngtmc.AdaptiveStepControl(du_max=abs(final) / 2 if isinstance(final, float)
                                                               and math.isfinite(final) and final else 1e-3), **kw)


def cases():
    """(label, callable, words): the callable does what a user does; one of ``words`` must be in
    the message."""
    out = []
    add = lambda label, f, *words: out.append((label, f, words))   # noqa: E731
    # -------------------------------------------------------------- materials
    for key in ("E", "nu", "Gc", "l0"):
        for v in BAD_NUMBERS:
            def f(key=key, v=v):
                args = dict(E=1000.0, nu=0.3, Gc=1.0, l0=0.1)
                args[key] = v
                solve(scene(materials={"bar": ngtmc.Material(**args)}))
            if key == "nu" and v in (0, -1e-9, 1e-300):
                continue                   # a Poisson's ratio of 0 (or about 0) is a material
            add(f"Material({key}={v!r})", f, key)
    # -------------------------------------------------------------- scene numbers
    for key in ("gamma0", "gc_a", "gc_b", "residual_stiffness", "thickness"):
        for v in BAD_NUMBERS + [2.0]:
            if (key, v) in (("residual_stiffness", 0), ("thickness", None), ("gc_a", 2.0), ("gc_b", 2.0),
                            ("thickness", 2.0), ("gc_a", 1e300), ("gc_b", 1e300), ("thickness", 1e-300),
                            ("gc_a", 1e-300), ("gc_b", 1e-300), ("residual_stiffness", 1e-300)):
                continue                   # good values (the interpolation's parameters may be any positive number)
            add(f"Scene({key}={v!r})", lambda key=key, v=v: solve(scene(density={"bar": 0.5}, **{key: v})), key)
    # -------------------------------------------------------------- scene structure
    add("Scene(mesh=None)", lambda: solve(scene(mesh=None)), "mesh")
    add("Scene(mesh='bar.msh')", lambda: solve(scene(mesh="bar.msh")), "mesh")
    add("materials={}", lambda: solve(scene(materials={})), "materials")
    add("materials unknown region", lambda: solve(scene(materials={"beam": MAT["bar"]})), "materials", "region")
    add("materials overlapping", lambda: solve(scene(materials={".*": MAT["bar"], "bar": MAT["bar"]})), "materials", "region")
    add("materials not a Material", lambda: solve(scene(materials={"bar": {"E": 1000}})), "materials", "Material")
    add("density unknown region", lambda: solve(scene(density={"void": 0.0})), "density", "region")
    add("density 1.5", lambda: solve(scene(density={"bar": 1.5})), "density", "rho")
    add("density -0.1", lambda: solve(scene(density={"bar": -0.1})), "density", "rho")
    add("density array too short", lambda: solve(scene(density=np.zeros(3))), "density")
    add("density NaN", lambda: solve(scene(density={"bar": float("nan")})), "density", "rho")
    add("fracture_regions unknown", lambda: solve(scene(fracture_regions="beam")), "fracture_regions")
    add("regulariser unknown region", lambda: solve(scene(regulariser=ngtmc.Regulariser("void", length=1.0))), "regulariser")
    add("regulariser with order 1", lambda: solve(scene(regulariser=ngtmc.Regulariser("bar", length=1.0), order=1)), "order", "regulariser")
    add("regulariser length 0", lambda: solve(scene(regulariser=ngtmc.Regulariser("bar", length=0.0))), "length")
    add("regulariser damping", lambda: solve(scene(regulariser=ngtmc.Regulariser("bar", length=1.0, damping="log"))), "damping")
    for v in (0, 5, "2", 2.0, True, -1):
        add(f"Scene(order={v!r})", lambda v=v: solve(scene(order=v)), "order")
    add("supports unknown boundary", lambda: solve(scene(supports=[ngtmc.Support("nowhere", x=True)])), "boundary", "Support")
    add("supports a dict", lambda: solve(scene(supports=[{"left": "xy"}])), "supports", "Support")
    add("supports empty, no boundary load", lambda: solve(scene(supports=[], load=ngtmc.DisplacementLoad(ngtmc.Point(near=(1.0, 0.0)), "x"))), "supports")
    add("Support holding nothing", lambda: solve(scene(supports=[ngtmc.Support("left")])), "Support", "component")
    add("Support z in 2D", lambda: solve(scene(supports=[ngtmc.Support("left", x=True, y=True, z=True)])), "z")
    add("support and load on one boundary component", lambda: solve(scene(supports=[ngtmc.Support("left", x=True, y=True), ngtmc.Support("right", x=True)])), "component", "right")
    add("load and support at a corner", lambda: solve(scene(load=ngtmc.DisplacementLoad("top", "-y"))), "vertex", "corner", "boundaries meet")
    for d in ("z", "-z", "q", "", "xy", 1):
        add(f"DisplacementLoad direction {d!r}", lambda d=d: solve(scene(load=ngtmc.DisplacementLoad("right", d))), "direction")
    add("load unknown boundary", lambda: solve(scene(load=ngtmc.DisplacementLoad("nowhere", "x"))), "boundary")
    add("load not a load", lambda: solve(scene(load="right")), "load")
    add("load empty list", lambda: solve(scene(load=[])), "load")
    add("two loads one name", lambda: solve(scene(load=[ngtmc.DisplacementLoad("right", "x", name="a"), ngtmc.DisplacementLoad("top", "y", name="a")], supports=[ngtmc.Support("bottom", y=True), ngtmc.Support("left", x=True)])), "name")
    add("force_from unknown", lambda: solve(scene(force_from="nowhere")), "force_from")
    add("field with 3 entries in 2D", lambda: solve(scene(load=ngtmc.DisplacementField("right", ngs.CF((1.0, 0.0, 0.0))))), "field", "components")
    add("field NaN", lambda: solve(scene(load=ngtmc.DisplacementField("right", lambda x, y, lam: (np.nan * x, 0 * y)))), "field", "NaN", "finite")
    add("field not callable", lambda: solve(scene(load=ngtmc.DisplacementField("right", 3.0))), "field")
    add("field components 'w'", lambda: solve(scene(load=ngtmc.DisplacementField("right", ngs.CF((1.0, 0.0)), components="w"))), "components")
    add("traction on a Point", lambda: solve(scene(load=ngtmc.Traction(ngtmc.Point(near=(1.0, 0.0)), (1.0, 0.0)))), "Traction", "Point")
    add("Point unknown name", lambda: solve(scene(load=ngtmc.DisplacementLoad(ngtmc.Point("tip"), "x"))), "Point", "tip")
    add("Point near 3 entries", lambda: solve(scene(load=ngtmc.DisplacementLoad(ngtmc.Point(near=(1, 0, 0)), "x"))), "Point", "coordinate")
    add("Point near NaN", lambda: ngtmc.Point(near=(float("nan"), 0.0)), "near", "finite")
    add("Point both", lambda: ngtmc.Point("tip", near=(1, 0)), "name", "near")
    add("split unknown", lambda: solve(scene(split="cosine")), "split")
    add("formulation unknown", lambda: solve(scene(formulation="isotropic")), "formulation")
    add("thickness in 3D", lambda: ngtmc.Scene(ngtmc.extrude(MESH, 0.1), MAT, supports=[ngtmc.Support("left", x=True, y=True, z=True)], load=ngtmc.DisplacementLoad("right", "x"), thickness=1.0).check(), "thickness")
    add("scale_check 'no'", lambda: solve(scene(scale_check="no")), "scale_check")
    # -------------------------------------------------------------- units and scale (a warning)
    add("E in Pa", lambda: solve(scene(materials={"bar": ngtmc.Material(2.08e10, 0.3, 540.0, 0.1)})), "E")
    add("Gc in J/m^2 read as N/mm", lambda: solve(scene(materials={"bar": ngtmc.Material(1000.0, 0.3, 5400.0, 0.1)})), "Gc")
    add("l0 of 100 mm on a 1 mm bar", lambda: solve(scene(materials={"bar": ngtmc.Material(1000.0, 0.3, 1.0, 100.0)})), "l0")
    add("Point far off the body", lambda: solve(scene(supports=[ngtmc.Support("left", x=True), ngtmc.Support(ngtmc.Point(near=(1e6, 1e6)), y=True)])), "Point", "nearest vertex")

    def metres():
        face = __import__("netgen.occ", fromlist=["Rectangle"]).Rectangle(0.001, 0.0002).Face()
        face.faces.name = "bar"
        X = __import__("netgen.occ", fromlist=["X"]).X
        face.edges.Min(X).name, face.edges.Max(X).name = "left", "right"
        m = ngs.Mesh(__import__("netgen.occ", fromlist=["OCCGeometry"]).OCCGeometry(face, dim=2).GenerateMesh(maxh=1e-4))
        solve(scene(mesh=m, fracture_regions=()), 1e-6)
    add("body drawn in metres", metres, "metres", "size")
    add("final load of 5 mm on a 1 mm bar", lambda: ngtmc.Simulation(scene(), 5.0), "load", "size")
    # -------------------------------------------------------------- simulation options
    for v in (float("nan"), "0.001", 0.0, [0.0, 0.0], None, [0.001, float("inf")]):
        add(f"schedule {v!r}", lambda v=v: ngtmc.simulate(scene(), v), "schedule", "Schedule")
    for c in ({"du_max": 1e-3}, "adaptive", 1e-3):
        add(f"control {c!r}", lambda c=c: ngtmc.simulate(scene(), 1e-3, c), "control")
    for key, v in (("du_max", 0.0), ("du_max", -1.0), ("du_max", float("nan")), ("du_max", "x"), ("du_min", 0.0),
                   ("du_min", 1.0), ("k_u", -1.0), ("k_u", "x"), ("n_s", 0), ("n_s", "x")):
        def f(key=key, v=v):
            args = dict(du_max=1e-3)
            args[key] = v
            ngtmc.AdaptiveStepControl(**args)
        add(f"AdaptiveStepControl({key}={v!r})", f, key)
    for kw, words in (({"scheme": "implicit"}, ("scheme",)), ({"staggered_tol": -1.0}, ("staggered_tol",)),
                      ({"staggered_tol": "x"}, ("staggered_tol",)), ({"max_staggered": 0}, ("max_staggered", "pass")),
                      ({"newton": {"tol": 1e-8}}, ("newton", "tol")), ({"newton": 1e-8}, ("newton",)),
                      ({"compile": "fast"}, ("compile",)), ({"coupled": "yes"}, ("coupled",)),
                      ({"coupled": {"linear_solver": "lu"}}, ("linear_solver",)), ({"coupled": {"fallback": "x"}}, ("fallback",)),
                      ({"adapt": 0.01}, ("adapt",)), ({"stop_after_drop": 1.5}, ("stop_after_drop",)),
                      ({"stop_after_drop": "half"}, ("stop_after_drop",)), ({"max_steps": "many"}, ("max_steps",)),
                      ({"staggered": True}, ("staggered", "scheme")), ({"newtn": None}, ("newtn", "newton")),
                      ({"vtk": False}, ("vtk", "out_dir")), ({"resume": True}, ("resume", "out_dir"))):
        add(f"simulate({kw!r})", lambda kw=kw: solve(scene(), **kw), *words)
    for key, v in (("max_iterations", 0), ("max_iterations", -1), ("rtol", 0.0), ("rtol", 2.0), ("rtol", "x"),
                   ("atol", -1.0), ("atol", "x"), ("linear_solver", "lu"), ("floor_rtol", 2.0), ("floor_rtol", "x"),
                   ("levenberg_expansion", -1), ("levenberg_expansion", 0.5)):
        add(f"NewtonOptions({key}={v!r})", lambda key=key, v=v: ngtmc.NewtonOptions(**{key: v}), key)
    # -------------------------------------------------------------- a named study's settings
    tmp = Path(tempfile.mkdtemp())
    for k, (key, v) in enumerate((("h_band", 0), ("h_band", -1), ("h_band", "x"), ("amr_corridor", "wide"),
                                  ("stop_load", 0.5), ("stop_load", -1), ("scheme", "foo"), ("foo", 1), ("E", "abc"),
                                  ("split", "cosine"), ("loading", "hammer"), ("k_u", "x"), ("du_max", -1),
                                  ("h_crack", -1), ("stop_after_drop", 2))):
        add(f"ngtmc run three-point-bending --set {key}={v}",
            lambda key=key, v=v, k=k: ngtmc.run_study("three-point-bending", "quick", tmp / f"s{k}", overrides={key: v},
                                                      progress=False), key)
    add("resolution 'fast'", lambda: ngtmc.run_study("three-point-bending", "fast", tmp / "r", progress=False), "resolution", "fast")
    add("unknown study", lambda: ngtmc.run_study("four-point-bending", progress=False), "study", "four")
    add("threads 0", lambda: ngtmc.run_study("three-point-bending", output=tmp / "t", threads=0, progress=False), "threads")
    for k, body in enumerate((
            'NAME = "three_point_bending"\nPARAMETERS = {}\nRESOLUTIONS = {"quick": {}}\ndef cases(p): return []\n',
            'NAME = "x"\nPARAMETERS = {"E": 1.0}\nRESOLUTIONS = {"quick": {}}\ndef cases(p): return []\n',
            'NAME = "x"\nPARAMETERS = {}\nRESOLUTIONS = {"quick": {}}\ndef cases(p): return []\n',
            'NAME = "x"\nPARAMETERS = {}\nRESOLUTIONS = {"quick": {}}\ncases = 3\n',
            'NAME = "x"\nPARAMETERS = {}\nRESOLUTIONS = []\ndef cases(p): return []\n',
            'PARAMETERS = {}\nRESOLUTIONS = {"quick": {}}\ndef cases(p): return []\n',
            'NAME = "x"\nPARAMETERS = {}\nRESOLUTIONS = {"quick": {}}\ndef cases(p): raise ValueError("E must be > 0")\n',
            'import nonexistent_module\n')):
        f = tmp / f"study{k}.py"
        f.write_text(body)
        add(f"study file {k}", lambda f=f: ngtmc.run_study(str(f), output=tmp / f"o{k}", progress=False),
            "NAME", "PARAMETERS", "RESOLUTIONS", "cases", "study", "import")
    # -------------------------------------------------------------- more conditions and helpers
    for kw in ({"h_crack": 0.0}, {"h_crack": -1.0}, {"h_crack": "x"}, {"h_crack": 0.01, "corridor": "wide"}):
        add(f"Adaptivity({kw!r})", lambda kw=kw: solve(scene(), adapt=ngtmc.Adaptivity(**kw)), *kw)
    for t in ((float("nan"), 0.0), ("1", 0.0), (1.0,)):
        add(f"Traction {t!r}", lambda t=t: solve(scene(load=ngtmc.Traction("right", t))), "Traction", "traction")
    add("hold_tangential 'yes'", lambda: solve(scene(load=ngtmc.DisplacementLoad("right", "x", hold_tangential="yes"))), "hold_tangential")
    add("Support x='yes'", lambda: solve(scene(supports=[ngtmc.Support("left", x="yes", y=True)])), "Support", "x")
    for v in (-1.0, "x", 0.0):
        add(f"Regulariser kbar_r={v!r}", lambda v=v: solve(scene(regulariser=ngtmc.Regulariser("bar", length=1.0, kbar_r=v))), "kbar_r")
    add("Schedule equal points", lambda: ngtmc.Schedule([0.0, 0.01, 0.01]), "Schedule")
    add("Schedule empty", lambda: ngtmc.Schedule([]), "Schedule")
    add("extrude thickness 0", lambda: ngtmc.extrude(MESH, 0.0), "thickness")
    add("extrude layers 0", lambda: ngtmc.extrude(MESH, 0.1, layers=0), "layers")
    # -------------------------------------------------------------- gmsh files
    add("gmsh file missing", lambda: ngtmc.read_gmsh(tmp / "none.msh"), "does not exist")
    (tmp / "garbage.msh").write_text("not a mesh\n")
    add("gmsh file garbage", lambda: ngtmc.read_gmsh(tmp / "garbage.msh"), "gmsh")
    return out


def classify(f, words) -> tuple[str, str]:
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        try:
            f()
        except (ValueError, TypeError, StudyError, ngtmc.StepFailure) as e:
            msg = f"{type(e).__name__}: {e}"
            named = any(w.lower() in str(e).lower() for w in words)
            return ("clear" if named else "unnamed"), msg[:300]
        except BaseException as e:     # noqa: BLE001 - the audit's point is to see every kind
            if isinstance(e, KeyboardInterrupt):
                raise
            return "crash", f"{type(e).__name__}: {e}"[:300]
    ours = [r for r in rec if issubclass(r.category, WARNINGS)]
    if ours:
        text = " ".join(str(r.message) for r in ours)
        named = any(w.lower() in text.lower() for w in words)
        return ("clear" if named else "unnamed"), f"{ours[0].category.__name__}: {text}"[:300]
    return "silent", ""


def main():
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    rows = []
    for label, f, words in cases():
        kind, msg = classify(f, words)
        rows.append({"input": label, "outcome": kind, "message": msg})
    counts = {k: sum(r["outcome"] == k for r in rows) for k in ("clear", "unnamed", "crash", "silent")}
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT).stdout.strip()
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"bad_inputs-{stamp}.json"
    path.write_text(json.dumps({"benchmark": "bad_inputs", "date_utc": stamp, "commit": commit, "counts": counts,
                                "inputs": rows}, indent=1))
    n = len(rows)
    lines = [f"# bad-input audit ({stamp}, commit {commit})", "",
             f"{n} inputs: {counts['clear']} clear ({100 * counts['clear'] / n:.1f} %), {counts['unnamed']} refused "
             f"without naming the parameter, {counts['crash']} crashes, {counts['silent']} silent.", "",
             "| input | outcome | message |", "|---|---|---|"]
    lines += [f"| {r['input']} | {r['outcome']} | {r['message'][:160].replace('|', '/')} |" for r in rows
              if r["outcome"] != "clear"]
    path.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"record: {path}")


if __name__ == "__main__":
    main()
