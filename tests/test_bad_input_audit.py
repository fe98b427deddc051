"""The bad-input audit as a test (issue 58): every one of the 248 wrong inputs of
benchmarks/bad_inputs.py is refused or warned about with a message naming its parameter; none is
accepted silently, none crashes with a foreign exception."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import bad_inputs  # noqa: E402


def test_every_bad_input_is_named():
    cases = bad_inputs.cases()
    assert len(cases) >= 240
    outcomes = [(label, *bad_inputs.classify(f, words)) for label, f, words in cases]
    unclear = [(label, kind, msg) for label, kind, msg in outcomes if kind != "clear"]
    assert not unclear, "\n".join(f"{label}: {kind}: {msg}" for label, kind, msg in unclear)
