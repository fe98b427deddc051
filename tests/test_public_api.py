"""The package's public names: every name a module lists in ``__all__`` exists, so that
``from ngtmc.<module> import *`` works (it raised AttributeError for ``ngtmc.study.run_files``, whose
``__all__`` named a class that had moved to ``ngtmc.runner.checkpoints``)."""
import importlib
import pkgutil

import pytest

import ngtmc

MODULES = sorted(m.name for m in pkgutil.walk_packages(ngtmc.__path__, "ngtmc.")
                 if not m.name.endswith("__main__"))


def test_the_package_has_modules_to_check():
    assert len(MODULES) > 30 and "ngtmc.study.run_files" in MODULES


@pytest.mark.parametrize("name", MODULES)
def test_every_name_in_all_exists(name):
    mod = importlib.import_module(name)
    missing = [n for n in getattr(mod, "__all__", []) if not hasattr(mod, n)]
    assert not missing, f"{name}.__all__ names {missing}, which the module does not define"


def test_one_version_everywhere():
    """ngtmc/version.py owns the version: the installed metadata (pyproject.toml reads it) and
    CITATION.cff state the same."""
    import importlib.metadata
    import pathlib
    import re
    import ngtmc
    root = pathlib.Path(__file__).resolve().parents[1]
    cff = re.search(r"^version:\s*(\S+)", (root / "CITATION.cff").read_text(), re.M).group(1)
    assert cff == ngtmc.__version__
    toml = (root / "pyproject.toml").read_text()
    assert 'dynamic = ["version"]' in toml and 'attr = "ngtmc.version.__version__"' in toml
    try:
        installed = importlib.metadata.version("ngtmc")
    except importlib.metadata.PackageNotFoundError:
        return
    assert installed == ngtmc.__version__, "reinstall (pip install -e .): the installed metadata is older"
