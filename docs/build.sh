#!/usr/bin/env bash
# Build the documentation site into docs/_build/html (open docs/_build/html/index.html; nothing
# loads from the web). Needs pip install -e ".[docs]". The gallery executes every examples/*.py
# (NGTMC_EXAMPLE_SHORT=1 in the environment runs their short modes). Warnings are errors.
set -euo pipefail
cd "$(dirname "$0")/.."
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
# -E: every page read again, so that the pages generated from the package and the records are current
python -m sphinx -E -W --keep-going -b html docs docs/_build/html "$@"
