"""The library finds named studies through its registry (ngtmc.study.registry.STUDIES and the entry points
of the group "ngtmc.studies"), never by scanning or importing a package of studies. The studies of
ngtmc live in the folder studies/ at the top of the repository and import as ngtmc.studies
(pyproject package-dir; from a source tree, the finder of ngtmc/__init__.py): there is no top-level
package "studies"."""
import importlib.metadata
from pathlib import Path
import subprocess
import sys

import pytest

from ngtmc.study.registry import ENTRY_POINT_GROUP, STUDIES, list_studies, load_study, registered_studies
from ngtmc.study import StudyError

ROOT = Path(__file__).resolve().parents[1]


def test_registry_names_every_study_file_of_ngtmc():
    files = sorted(f.stem for f in (ROOT / "studies").glob("*.py") if not f.stem.startswith("_"))
    assert sorted(STUDIES) == files
    assert all(STUDIES[n] == f"ngtmc.studies.{n}" for n in files)
    assert set(files) <= set(list_studies())


def test_listing_studies_imports_no_study():
    code = ("import sys, ngtmc; names = ngtmc.list_studies(); "
            "assert 'three_point_bending' in names, names; "
            "assert not [m for m in sys.modules if 'studies' in m.split('.')], "
            "[m for m in sys.modules if 'studies' in m.split('.')]")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT / "tests")


def _python(code_or_args, cwd, **kw):
    """Run Python in a fresh process from ``cwd`` with this source tree first on the path."""
    import os
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    args = ["-c", code_or_args] if isinstance(code_or_args, str) else list(code_or_args)
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True, **kw)


def test_studies_import_as_ngtmc_studies_from_this_tree(tmp_path):
    code = ("import ngtmc, ngtmc.studies.three_point_bending as t, ngtmc.studies.step_control as s; "
            "print(ngtmc.__file__); print(ngtmc.studies.__file__); print(t.__file__); "
            "assert s.tpb is t")
    r = _python(code, tmp_path)
    assert r.returncode == 0, r.stderr
    pkg, init, tpb = (Path(line) for line in r.stdout.split())
    assert pkg == ROOT / "ngtmc" / "__init__.py"  # the ngtmc of this tree, and its studies/
    assert init == ROOT / "studies" / "__init__.py" and tpb == ROOT / "studies" / "three_point_bending.py"


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_study_file_runs_as_a_script_and_loads_from_its_path(name, tmp_path):
    """`python studies/NAME.py --help` from another folder (its imports of ngtmc.studies resolve),
    and `ngtmc run studies/NAME.py` imports the file by path (ngtmc.study.registry.load_study_file)."""
    r = _python([str(ROOT / "studies" / f"{name}.py"), "--help"], tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "usage:" in r.stdout and "--resolution" in r.stdout, r.stdout
    mod = load_study(str(ROOT / "studies" / f"{name}.py"))
    assert mod.NAME == name


_STUDY = '''"""A study registered by another package."""
NAME = "plugged_study"
PARAMETERS = {"E": (1000.0, "MPa", "Young's modulus")}
RESOLUTIONS = {"quick": {}, "medium": {}, "paper": {}}
DEFAULT_RESOLUTION = "quick"


def cases(p):
    return []
'''


def test_entry_points_register_other_packages_studies(tmp_path, monkeypatch):
    (tmp_path / "ngtmc_plugged_study_mod.py").write_text(_STUDY)
    monkeypatch.syspath_prepend(str(tmp_path))
    eps = [importlib.metadata.EntryPoint("plugged-study", "ngtmc_plugged_study_mod", ENTRY_POINT_GROUP),
           importlib.metadata.EntryPoint("broken", "ngtmc_no_such_module_xyz", ENTRY_POINT_GROUP),
           importlib.metadata.EntryPoint("three_point_bending", "ngtmc_plugged_study_mod", ENTRY_POINT_GROUP)]
    real = importlib.metadata.entry_points

    def fake(**kw):
        return eps if kw.get("group") == ENTRY_POINT_GROUP else real(**kw)

    monkeypatch.setattr(importlib.metadata, "entry_points", fake)
    reg = registered_studies()
    assert reg["plugged_study"] == "ngtmc_plugged_study_mod"
    assert reg["three_point_bending"] == "ngtmc.studies.three_point_bending"  # ngtmc's own name is not taken over
    assert "plugged_study" in list_studies()
    assert load_study("plugged-study").NAME == "plugged_study"
    with pytest.raises(StudyError, match="'broken' is registered as module 'ngtmc_no_such_module_xyz'"):
        load_study("broken")
    with pytest.raises(StudyError, match="valid studies: .*plugged_study"):
        load_study("no-such-study")


def test_list_into_a_closed_pipe_is_quiet():
    """``ngtmc list | head -1``: the reader stops early; no traceback, and no study reported as
    'cannot be loaded' because its line could not be written."""
    p = subprocess.run(f"{sys.executable} -m ngtmc list | head -1", shell=True, capture_output=True, text=True,
                       timeout=120)
    assert p.stdout.count("\n") == 1 and "cannot be loaded" not in p.stdout
    assert "Traceback" not in p.stderr and "BrokenPipe" not in p.stderr


@pytest.mark.parametrize("added, message", [(("E", "nosuch"), r"not parameters: \['nosuch'\]"),
                                            ("E", r"must be a tuple of names")])
def test_added_at_default_names_the_studys_parameters(tmp_path, added, message):
    """A study's ADDED_AT_DEFAULT (docs/study-interface.md) names parameters of its PARAMETERS;
    a misspelt name, or a string instead of a tuple, is refused when the study is loaded."""
    f = tmp_path / "bad_added.py"
    f.write_text(_STUDY + f"\nADDED_AT_DEFAULT = {added!r}\n")
    with pytest.raises(StudyError, match=message):
        load_study(str(f))
    f.write_text(_STUDY + "\nADDED_AT_DEFAULT = ('E',)\n")
    mod = load_study(str(f))
    from ngtmc.study.parameters import added_at_default
    assert added_at_default(mod)["E"] == 1000.0
