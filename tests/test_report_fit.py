"""Reports that fit the study: sections and captions follow what the run has (fracture, a third
medium, several cases, references); overrides are shown in the report and the index, and the
index compares only runs with the same physics.

Synthetic run folders of tests/report_fixtures.py, and one real fracture-free user scene
(tests/scenes.py, about a second).
"""
from __future__ import annotations

import json
from pathlib import Path
import re
import sys

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from report_fixtures import write_run  # noqa: E402

from ngtmc import report  # noqa: E402

FRACTURE_WORDS = ["the drop when the crack runs", "crack running", "W_f jumps", "final W_f",
                  "Phase-field snapshots", "Fracture toughness interpolation", "during crack growth"]


def _page(run) -> str:
    return report.render_report(run).read_text(encoding="utf-8")


def _figs(page: str) -> dict:
    m = re.search(r'<script type="application/json" id="fig-data">(.*?)</script>', page, re.S)
    return json.loads(m.group(1))


def _dofs_card(page: str) -> str:
    m = re.search(r"<dt>dofs</dt><dd>(.*?)</dd>", page)
    return m.group(1)


def test_no_fracture_report_has_no_fracture_parts(tmp_path):
    run = write_run(tmp_path / "nofrac", fracture=False, cases=[("main", "main", 2e-3, {})])
    page = _page(run)
    for words in FRACTURE_WORDS:
        assert words not in page, words
    figs = _figs(page)
    assert "fig-wf-alpha" not in figs and 'id="fig-wf-alpha"' not in page
    assert not any("W_f" in (t.get("name") or "") for t in figs["fig-energies"]["data"])
    assert "α" not in _dofs_card(page) and "(u)" in _dofs_card(page)
    # a single case without time split: no empty speed section, no link to it
    assert 'id="speed-error"' not in page and 'href="#speed-error"' not in page
    # this scene has a void (the fixture's rho < 1 strip): the gap caption stays
    assert "near-zero force until the gap closes" in page


def test_fracture_report_keeps_fracture_parts(tmp_path):
    page = _page(write_run(tmp_path / "frac"))
    assert "the drop when the crack runs" in page and "fig-wf-alpha" in _figs(page)
    assert "u + α" in _dofs_card(page)
    assert 'id="speed-error"' in page     # two cases: speed against error within the run


def test_contact_gamma0_without_fracture_has_no_gc_plot(tmp_path):
    page = _page(write_run(tmp_path / "cg", study="contact_gamma0"))
    figs = _figs(page)
    assert "fig-gamma" in figs and "fig-gc" not in figs and 'id="fig-gc"' not in page
    assert "Fracture toughness interpolation" not in page


def test_features_recorded_win_over_inference(tmp_path):
    run = write_run(tmp_path / "rec")
    meta = json.loads((run / "metadata.json").read_text())
    meta["features"] = {"fracture": False, "void": False, "regulariser": False}
    (run / "metadata.json").write_text(json.dumps(meta))
    m, h, sn = report.load_run(run)
    f = report.run_features(m, h, sn)
    assert f["fracture"] is False and f["void"] is False and f["several_cases"] is True
    page = _page(run)
    assert "near-zero force until the gap closes" not in page and "the initial slope" in page


def _comparisons(index_page: str) -> list[tuple[str, str]]:
    """(physics, table body) of each comparison of the index's speed-against-error section."""
    sec = index_page[index_page.index('<section id="speed-error">'):]
    return re.findall(r"<h3><code>[^<]*</code> · (.*?)</h3>.*?<tbody>(.*?)</tbody>", sec, re.S)


def test_overrides_in_report_and_index(tmp_path):
    reports = tmp_path / "reports"
    plain = write_run(reports / "tpb-quick", cases=[("main", "main", 2e-3, {})], n_elements=100)
    write_run(reports / "tpb-medium", cases=[("main", "main", 1e-3, {})], n_elements=400,
              resolution="medium")
    stiff = write_run(reports / "tpb-quick-E", cases=[("main", "main", 2e-3, {})], n_elements=100,
                      overrides={"E": 41600.0}, force_scale=2.0)
    write_run(reports / "tpb-medium-E", cases=[("main", "main", 1e-3, {})], n_elements=400,
              resolution="medium", overrides={"E": 41600.0}, force_scale=2.0)
    page = _page(stiff)
    assert 'id="overrides-card"' in page and "E = 41600 MPa" in page
    assert "No overrides" in _page(plain)
    idx = report.render_index(reports).read_text(encoding="utf-8")
    assert "E = 41600 MPa" in idx
    figs = _figs(idx)
    assert len(figs) == 2          # one comparison per physics, never across
    for fig in figs.values():
        title = fig["layout"]["title"]["text"]
        assert ("E = 41600" in title) == ("own parameters" not in title)
    # the rows of each comparison: both runs of the same physics and no other
    tables = _comparisons(idx)
    assert len(tables) == 2
    for physics, body in tables:
        runs = set(re.findall(r"<tr><td>(tpb-[a-zE-]+)", body))
        if "41600" in physics:
            assert runs == {"tpb-quick-E", "tpb-medium-E"}
        else:
            assert runs == {"tpb-quick", "tpb-medium"}


def test_index_groups_by_physics_hash(tmp_path):
    reports = tmp_path / "reports"
    write_run(reports / "a", cases=[("main", "main", 2e-3, {})], physics_hash="sha256:one", n_elements=100)
    write_run(reports / "b", cases=[("main", "main", 1e-3, {})], physics_hash="sha256:one", n_elements=400)
    write_run(reports / "c", cases=[("main", "main", 1e-3, {})], physics_hash="sha256:two", n_elements=800)
    idx = report.render_index(reports).read_text(encoding="utf-8")
    figs = _figs(idx)
    assert len(figs) == 1
    body = _comparisons(idx)[0][1]
    assert set(re.findall(r"<tr><td>([abc])", body)) == {"a", "b"}


# ------------------------------------------------------------------ a real scene without fracture
@pytest.fixture(scope="module")
def plain_bar(tmp_path_factory):
    import ngtmc
    from scenes import tension_bar
    out = tmp_path_factory.mktemp("plain") / "bar"
    ngtmc.simulate(tension_bar(maxh=0.1, fracture=False), 0.002, ngtmc.AdaptiveStepControl(du_max=5e-4),
                   out_dir=out, report=True, name="plain_bar")
    return out


def test_real_scene_without_fracture_or_gap(plain_bar, tmp_path):
    meta = json.loads((plain_bar / "metadata.json").read_text())
    assert meta["features"] == {"fracture": False, "void": False, "regulariser": False}
    assert meta["mesh"]["ndof_alpha"] == 0 and meta["study"] == "plain_bar"
    page = (plain_bar / "report.html").read_text(encoding="utf-8")
    for words in FRACTURE_WORDS + ["near-zero force until the gap closes", "third medium filling the gap",
                                   "regularisation energy"]:
        assert words not in page, words
    assert "fig-wf-alpha" not in _figs(page) and _dofs_card(page).endswith("(u)")
    assert "Snapshots of the deformed mesh" in page
    from test_report_browser import _check_page, _chromium
    exe = _chromium()
    if exe is None:
        pytest.skip("no chromium binary (install the Debian package 'chromium')")
    _check_page(exe, plain_bar / "report.html", tmp_path, min_plots=4)
