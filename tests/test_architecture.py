"""The architecture guard: ngtmc is subpackages by layer (``[tool.importlinter]`` in pyproject.toml
orders them); a module imports from its own subpackage and the layers below only, with no import
cycle, no private name taken from another subpackage, and no module past about 400 lines; the
package face is imported by none of its modules; a built wheel holds every module. None of
these has an exception."""
from __future__ import annotations

from pathlib import Path
import inspect
import subprocess
import sys
import zipfile

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: The subpackages of ngtmc, from the bottom layer to the top (pyproject.toml's layers contract
#: orders them); the package's top level holds only its face, the command line and the version.
SUBPACKAGES = ["model", "scene", "discrete", "coupled", "stepping", "adapt", "classical", "simulation",
               "sensitivities", "design", "study", "report", "runner"]
TOP_LEVEL = {"__init__.py", "__main__.py", "cli.py", "version.py"}
MAX_LINES = 400


def _graph():
    grimp = pytest.importorskip("grimp")
    return grimp.build_graph("ngtmc")


def _cycles(graph) -> list[set]:
    """The strongly connected components of more than one module (Tarjan)."""
    edges = {m: {i for i in graph.find_modules_directly_imported_by(m) if i.split(".")[0] == "ngtmc"}
             for m in graph.modules}
    index, low, stack, on, out, count = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(max(10000, sys.getrecursionlimit()))

    def visit(v):
        index[v] = low[v] = count[0]
        count[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(comp)

    for m in sorted(edges):
        if m not in index:
            visit(m)
    return out


def test_layers_hold():
    """import-linter's layers contract of pyproject.toml holds, with no exception listed."""
    pytest.importorskip("importlinter")
    exe = Path(sys.executable).with_name("lint-imports")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "importlinter.cli"]
    res = subprocess.run(cmd + ["--config", str(ROOT / "pyproject.toml")], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-2000:]
    assert "0 broken" in res.stdout
    import tomllib
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    (contract,) = cfg["contracts"]
    assert not contract.get("ignore_imports")
    layers = [name for layer in contract["layers"] for part in layer.split("|") for name in part.split(":")]
    listed = {name.strip().removeprefix("ngtmc.") for name in layers}
    assert set(SUBPACKAGES) <= listed, f"subpackages missing from the layers: {set(SUBPACKAGES) - listed}"


def test_no_import_cycle():
    cycles = _cycles(_graph())
    assert not cycles, f"import cycles: {[sorted(c) for c in cycles]}"


def test_every_folder_is_a_layer_and_the_top_level_is_the_face_only():
    folders = {p.parent.name for p in (ROOT / "ngtmc").glob("*/__init__.py")} - {"data", "templates"}
    assert folders == set(SUBPACKAGES)
    loose = {p.name for p in (ROOT / "ngtmc").glob("*.py")} - TOP_LEVEL
    assert not loose, f"modules outside the subpackages: {sorted(loose)}"


def test_the_package_face_is_imported_by_no_module_of_the_package():
    graph = _graph()
    assert not set(graph.find_modules_that_directly_import("ngtmc"))


def _imports(path: Path):
    """(module, imported names) of every ``from ngtmc... import ...`` in a file."""
    import ast
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("ngtmc"):
            yield node.module, [a.name for a in node.names]


def test_no_private_name_is_imported_across_subpackages():
    """A name with a leading underscore is its subpackage's own; another subpackage, a study or a
    benchmark imports only public names (tests may reach inside)."""
    bad = []
    files = list((ROOT / "ngtmc").rglob("*.py")) + list((ROOT / "studies").glob("*.py")) + \
        list((ROOT / "benchmarks").glob("*.py"))
    for path in files:
        rel = path.relative_to(ROOT).parts
        home = rel[1] if rel[0] == "ngtmc" and len(rel) > 2 else ("studies" if rel[0] == "studies" else None)
        for module, names in _imports(path):
            parts = module.split(".")
            there = parts[1] if len(parts) > 1 else None
            if there == home and home is not None:
                continue
            private = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if private:
                bad.append(f"{'/'.join(rel)}: from {module} import {', '.join(private)}")
    assert not bad, "\n".join(bad)


def test_no_module_is_longer_than_about_400_lines():
    long = {}
    for path in sorted((ROOT / "ngtmc").rglob("*.py")) + sorted((ROOT / "studies").glob("*.py")):
        n = len(path.read_text().splitlines())
        if n > MAX_LINES:
            long[path.relative_to(ROOT).as_posix()] = n
    assert not long, f"modules over {MAX_LINES} lines: {long}"


@pytest.mark.slow
def test_a_built_wheel_holds_every_module_and_no_other(tmp_path):
    """setup.py finds the packages (the studies live in studies/ and install as ngtmc.studies,
    with their records): a wheel built from the tracked files holds every module and record of
    the tree, and none that the tree lacks (a stale ``build/`` folder once shipped a renamed
    module)."""
    pytest.importorskip("build")
    src = tmp_path / "src"
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, capture_output=True,
                           text=True).stdout.split()
    if not files:
        pytest.skip("not a git checkout")
    for f in files:
        if (ROOT / f).is_file():
            (src / f).parent.mkdir(parents=True, exist_ok=True)
            (src / f).write_bytes((ROOT / f).read_bytes())
    res = subprocess.run([sys.executable, "-m", "build", "--wheel", "--no-isolation", "--skip-dependency-check",
                          "--outdir", str(tmp_path / "dist"), str(src)], capture_output=True, text=True)
    if res.returncode != 0 and "No module named" in res.stderr:
        pytest.skip(res.stderr[-300:])
    assert res.returncode == 0, res.stderr[-3000:]
    wheel = next((tmp_path / "dist").glob("ngtmc-*.whl"))
    names = {n for n in zipfile.ZipFile(wheel).namelist() if n.endswith((".py", ".json"))}
    want = {p.relative_to(src).as_posix() for p in (src / "ngtmc").rglob("*.py")}
    want |= {"ngtmc/studies/" + p.relative_to(src / "studies").as_posix()
             for p in (src / "studies").rglob("*") if p.suffix in (".py", ".json")}
    assert not sorted(want - names), f"missing from the wheel: {sorted(want - names)}"
    assert not sorted(names - want), f"in the wheel but not in the tree: {sorted(names - want)}"


def test_a_subpackage_is_imported_through_its_face():
    """A module of ngtmc imports another subpackage through that subpackage's face (its
    ``__init__``), never from the modules behind it; inside its own subpackage it imports modules."""
    bad = []
    for path in (ROOT / "ngtmc").rglob("*.py"):
        rel = path.relative_to(ROOT).parts
        home = rel[1] if len(rel) > 2 else None
        for module, names in _imports(path):
            parts = module.split(".")
            if len(parts) > 2 and parts[1] != home:
                bad.append(f"{'/'.join(rel)}: from {module} import {', '.join(names)}")
    assert not bad, "\n".join(sorted(bad))


def test_no_face_hides_a_module_behind_a_name():
    """A name a face exports is never the name of one of its subpackage's modules: ``from
    ngtmc.scene import extrude`` would give the function and ``ngtmc.scene.extrude`` the module."""
    import importlib
    clashes = []
    for sub in SUBPACKAGES:
        face = importlib.import_module(f"ngtmc.{sub}")
        for path in (ROOT / "ngtmc" / sub).glob("*.py"):
            name = path.stem
            if name != "__init__" and hasattr(face, name) and not inspect.ismodule(getattr(face, name)):
                clashes.append(f"ngtmc.{sub}.{name}")
    assert not clashes, clashes
