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
