"""The packages of the wheel, found rather than listed: every package under ngtmc/, and the studies
of studies/ as ngtmc.studies (the rest of the configuration is in pyproject.toml)."""
from setuptools import find_packages, setup

setup(packages=find_packages(include=["ngtmc", "ngtmc.*"]) + ["ngtmc.studies"],
      package_dir={"ngtmc.studies": "studies"})
