"""The library finds named studies through its registry (ngtmc.study.STUDIES and the entry points
of the group "ngtmc.studies"), never by scanning or importing the top-level studies package."""
import importlib.metadata
from pathlib import Path
import subprocess
import sys

import pytest

from ngtmc.study import ENTRY_POINT_GROUP, STUDIES, StudyError, list_studies, load_study, registered_studies

ROOT = Path(__file__).resolve().parents[1]


def test_registry_names_every_study_file_of_ngtmc():
    files = sorted(f.stem for f in (ROOT / "studies").glob("*.py") if not f.stem.startswith("_"))
    assert sorted(STUDIES) == files
    assert all(STUDIES[n] == f"studies.{n}" for n in files)
    assert set(files) <= set(list_studies())


def test_listing_studies_imports_no_study():
    code = ("import sys, ngtmc; names = ngtmc.list_studies(); "
            "assert 'three_point_bending' in names, names; "
            "assert not [m for m in sys.modules if m == 'studies' or m.startswith('studies.')], "
            "[m for m in sys.modules if m.startswith('studies')]")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT / "tests")


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
    assert reg["three_point_bending"] == "studies.three_point_bending"  # ngtmc's own name is not taken over
    assert "plugged_study" in list_studies()
    assert load_study("plugged-study").NAME == "plugged_study"
    with pytest.raises(StudyError, match="'broken' is registered as module 'ngtmc_no_such_module_xyz'"):
        load_study("broken")
    with pytest.raises(StudyError, match="valid studies: .*plugged_study"):
        load_study("no-such-study")
