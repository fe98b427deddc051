"""The version of ngtmc (one owner: pyproject.toml reads the same number through tests/test_public_api.py)."""
__version__ = "0.1.0"
