"""The gmsh example of docs/gmsh.md runs, keeps the physical names, and gives the hand force."""
import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[1] / "docs" / "gmsh.md"


def test_gmsh_example_reads_names_and_gives_the_hand_force():
    code = re.search(r"```python\n(.*?)```", DOC.read_text(), re.S).group(1)
    ns = {}
    exec(compile(code, str(DOC), "exec"), ns)
    mesh = ns["mesh"]
    assert set(mesh.GetMaterials()) == {"plate"}
    assert {"left", "right", "bottom"} <= set(mesh.GetBoundaries())
    assert mesh.ne == 8
    # homogeneous plane-strain uniaxial stress: F = E / (1 - nu^2) * strain * height * thickness
    assert ns["force"] == pytest.approx(1000.0 / (1 - 0.3**2) * 1e-4, rel=2e-4)
