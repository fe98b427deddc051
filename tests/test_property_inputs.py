"""Property-based test of scene inputs (issue 58): random good and bad values of a scene's
parameters are each either accepted and solvable, or refused with a ValueError / TypeError whose
message names the parameter; never a foreign exception (AttributeError, KeyError, netgen's or
NGSolve's own errors)."""
import math
import warnings

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings, strategies as st  # noqa: E402

import ngtmc  # noqa: E402
from scenes import bar_mesh  # noqa: E402

MESH = bar_mesh(maxh=0.2)

NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64), st.integers(-5, 5),
                    st.sampled_from([0, -1.0, 1e-300, 1e300, "20.8e3", None, True, [1.0]]))
GOOD = {"E": st.floats(10.0, 1e5), "nu": st.floats(0.0, 0.45), "Gc": st.floats(1e-3, 10.0),
        "l0": st.floats(0.02, 0.4), "gamma0": st.floats(1e-6, 0.5), "thickness": st.floats(0.1, 10.0)}
#: the words a message must contain for each parameter
WORDS = {"E": ["E"], "nu": ["nu"], "Gc": ["Gc"], "l0": ["l0"], "gamma0": ["gamma0"], "thickness": ["thickness"],
         "order": ["order"], "support": ["Support", "boundary", "supports"], "direction": ["direction"],
         "final": ["schedule", "final load", "load"]}


@st.composite
def scenes(draw):
    """(kwargs, the names of the parameters drawn from outside their good range)."""
    values, bad = {}, []
    for key, good in GOOD.items():
        if draw(st.booleans()) and draw(st.integers(0, 4)) == 0:
            values[key] = draw(NUMBERS)
            bad.append(key)
        else:
            values[key] = draw(good)
    values["order"] = draw(st.one_of(st.sampled_from([None, 1, 2]), st.sampled_from([0, 5, "2", 2.0, True])))
    if not (values["order"] is None or (type(values["order"]) is int and values["order"] in (1, 2))):
        bad.append("order")
    values["support"] = draw(st.sampled_from(["left", "left", "Left", "nowhere", 3]))
    if values["support"] != "left":
        bad.append("support")
    values["direction"] = draw(st.sampled_from(["x", "x", "-x", "z", "q", ""]))
    if values["direction"] not in ("x", "-x"):
        bad.append("direction")
    values["final"] = draw(st.one_of(st.floats(1e-4, 2e-3), st.sampled_from([0.0, float("nan"), "0.001", -1e-3])))
    if values["final"] == -1e-3:
        values["final"] = -1e-3          # a compression: a good input
    if not (isinstance(values["final"], float) and math.isfinite(values["final"]) and values["final"] != 0.0):
        bad.append("final")
    return values, bad


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenes())
def test_every_input_is_accepted_and_solvable_or_named(drawn):
    v, bad = drawn
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            mat = ngtmc.Material(E=v["E"], nu=v["nu"], Gc=v["Gc"], l0=v["l0"])
            scene = ngtmc.Scene(MESH, {"bar": mat}, supports=[ngtmc.Support(v["support"], x=True, y=True)],
                                load=ngtmc.DisplacementLoad("right", v["direction"]), fracture_regions="bar",
                                gamma0=v["gamma0"], thickness=v["thickness"], order=v["order"])
            res = ngtmc.simulate(scene, v["final"], ngtmc.AdaptiveStepControl(du_max=abs(v["final"]) / 2
                                                                               if isinstance(v["final"], float)
                                                                               and math.isfinite(v["final"])
                                                                               and v["final"] != 0 else 1e-3))
        except (ValueError, TypeError) as e:
            msg = str(e)
            assert bad, f"good input refused: {v}: {msg}"
            assert any(w.lower() in msg.lower() for b in bad for w in WORDS[b]), \
                f"{type(e).__name__} names none of {bad}: {msg}"
            return
    # a number drawn at random may be a good one (E = 3 MPa); a wrong name or kind never is
    assert not [b for b in bad if b in ("order", "support", "direction", "final")], (v, bad)
    assert math.isfinite(res.history["force"].iloc[-1])
