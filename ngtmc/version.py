"""The version of ngtmc: its one owner (pyproject.toml reads it; CITATION.cff states the same, tests/test_public_api.py)."""
__version__ = "0.2.0"
