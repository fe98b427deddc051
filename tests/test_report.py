"""HTML report: rendering from a small recorded (synthetic) run directory."""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from report_fixtures import page_json, write_run  # noqa: E402

from ngtmc import report  # noqa: E402

SECTIONS = ["parameters", "force-displacement", "key-numbers", "step-history", "snapshots",
            "mesh-density", "energies", "speed-error"]
MAX_BYTES = 5 * 1024 * 1024  # 5 MB (MiB); plotly.js alone is about 4.8 MB


def _ids(page: str) -> set[str]:
    return set(re.findall(r'\bid="([^"]+)"', page))


def _fig_data(page: str) -> dict:
    return page_json(page, "fig-data")


def _mesh_data(page: str) -> dict:
    return page_json(page, "mesh-data")


def _external_refs(page: str) -> list[str]:
    """src/href attributes pointing to another host (http(s) or protocol-relative)."""
    return re.findall(r'''<(?:script|link|img|iframe|source|video|audio)\b[^>]*?\b(?:src|href)\s*=\s*["']?\s*((?:https?:)?//[^"'\s>]+)''',
                      page, re.I)


@pytest.fixture
def tpb_run(tmp_path):
    return write_run(tmp_path / "tpb_quick")


def test_report_has_every_section(tpb_run):
    out = report.render_report(tpb_run)
    assert out == tpb_run / "report.html"
    page = out.read_text(encoding="utf-8")
    ids = _ids(page)
    for sid in SECTIONS:
        assert sid in ids, f"section {sid} missing"
    assert "interpolation" not in ids, "interpolation belongs to contact_gamma0 only"
    # header facts
    for text in ("three_point_bending", "quick", "2026-11-22", "0.1.0", "6.2.2608",
                 "160 elements", "wall time", "Young&#39;s modulus", "MPa"):
        assert text in page, text
    # every plot has its data, the JS error hook is at the very top, the status marker exists
    figs = _fig_data(page)
    for fid in ("fig-force", "fig-step-size", "fig-wf-alpha", "fig-newton", "fig-energies",
                "fig-speed-error"):
        assert fid in figs and f'id="{fid}"' in page
        assert figs[fid]["data"], f"{fid} has no traces"
        lay = figs[fid]["layout"]
        assert lay["title"]["text"] and lay["xaxis"]["title"]["text"] and lay["yaxis"]["title"]["text"]
    head = page[:page.index("</head>")]
    assert "window.__errors=[]" in head
    assert page.index("window.__errors=[]") < page.index("<title>")
    assert 'id="render-status"' in page
    # plotly.js embedded exactly once
    assert page.count("plotly.js v") == 1 or page.count("* plotly.js") == 1
    # snapshot frames: shared triangles, deformation scale stated
    meshes = _mesh_data(page)
    assert set(meshes) == {"coarse", "fine"}
    assert len(meshes["fine"]["frames"]) == 7
    assert "deformation scale: ×" in page
    # captions under plots
    assert page.count('class="caption"') >= 8


def test_force_plot_has_cases_and_references(tpb_run):
    page = report.render_report(tpb_run).read_text(encoding="utf-8")
    fig = _fig_data(page)["fig-force"]
    names = [t.get("name") for t in fig["data"]]
    assert "du_max = 2e-3 mm" in names and "du_max = 1e-3 mm" in names
    assert any("Ambati" in (n or "") for n in names)
    assert any(t.get("fill") == "tonexty" for t in fig["data"]), "band not drawn"
    # the kN/mm reference is converted to the run's N/mm: peak of order 40, not 0.04
    ref = next(t for t in fig["data"] if "Ambati" in (t.get("name") or ""))
    assert max(v for v in ref["y"] if v is not None) > 30
    assert "(N/mm)" in fig["layout"]["yaxis"]["title"]["text"]
    assert "(mm)" in fig["layout"]["xaxis"]["title"]["text"]


def test_key_numbers(tpb_run):
    meta, history, _ = report.load_run(tpb_run)
    rows = report.key_number_rows(meta, history)
    assert len(rows) == 3
    first = rows[0]
    assert first["quantity"] == "peak force"
    assert first["published"] == "42 N/mm"
    assert first["ok"] is True and first["rel"].endswith("%")
    assert rows[1]["quantity"] == "peak load" and rows[1]["computed"].endswith("mm")
    # target in kN/mm compared after conversion: 42.8 N/mm vs 0.042 kN/mm -> +2 %, tol 1 % -> fail
    assert rows[2]["ok"] is False and rows[2]["rel"].startswith("+2.")
    page = report.render_report(tpb_run).read_text(encoding="utf-8")
    sec = page[page.index('id="key-numbers"'):page.index('id="step-history"')]
    assert "pass" in sec and "fail" in sec and "N/mm" in sec and " mm" in sec


def test_speed_error_within_run(tpb_run):
    meta, history, _ = report.load_run(tpb_run)
    entries = report._run_speed_entries(meta, history, report._case_list(meta))
    assert len(entries) == 2
    finest = [e for e in entries if e["finest"]]
    assert len(finest) == 1 and finest[0]["label"] == "du_max = 1e-3 mm"
    assert finest[0]["err_finest"] == 0
    coarse = next(e for e in entries if not e["finest"])
    assert coarse["err_finest"] > 0 and coarse["err_published"] is not None
    page = report.render_report(tpb_run).read_text(encoding="utf-8")
    sec = page[page.index('id="speed-error"'):]
    assert 'id="fig-speed-error"' in sec and "finest" in sec and " s<" in sec


def test_contact_gamma0_has_interpolation(tmp_path):
    # with a phase field (the real study has none: see test_no_fracture_report_has_no_fracture_parts)
    run = write_run(tmp_path / "cg", study="contact_gamma0", fracture=True)
    page = report.render_report(run).read_text(encoding="utf-8")
    ids = _ids(page)
    for sid in SECTIONS + ["interpolation"]:
        assert sid in ids, sid
    figs = _fig_data(page)
    assert "fig-gamma" in figs and "fig-gc" in figs and "fig-force-log" in figs
    gamma_lines = [t["name"] for t in figs["fig-gamma"]["data"] if t["mode"] == "lines"]
    assert len(gamma_lines) == 3  # one per gamma0 (the classical case has none)
    # Gc(rho)/Gc0 -> a/2 = 5 in the void, 1 in the solid
    gc = figs["fig-gc"]["data"][0]
    assert gc["y"][0] == pytest.approx(5.0, rel=1e-3)
    assert gc["y"][-1] == pytest.approx(1.0, rel=1e-3)
    names = [t.get("name") for t in figs["fig-force"]["data"]]
    assert "classical contact (penalty)" in names


def test_interpolation_parameters_from_metadata(tmp_path):
    run = write_run(tmp_path / "cg", study="contact_gamma0", cases=[("main", "main", 2e-3, {})], fracture=True)
    meta = json.loads((run / "metadata.json").read_text())
    meta["parameters"]["gc_a"] = {"value": 4.0, "unit": "-", "description": "a"}
    meta["parameters"]["gc_b"] = {"value": 50.0, "unit": "-", "description": "b"}
    meta["parameters"]["gamma0"] = {"value": 1e-3, "unit": "-", "description": "gamma0"}
    (run / "metadata.json").write_text(json.dumps(meta))
    figs = _fig_data(report.render_report(run).read_text(encoding="utf-8"))
    assert figs["fig-gc"]["data"][0]["y"][0] == pytest.approx(2.0, rel=1e-3)
    assert figs["fig-gamma"]["data"][0]["y"][0] == pytest.approx(1e-3, rel=1e-3)
    assert report.gc_ratio_of_rho(1.0) == pytest.approx(1.0)
    assert report.gamma_of_rho(0.0, 1e-5) == pytest.approx(1e-5)


def test_offline_and_size(tpb_run):
    out = report.render_report(tpb_run)
    page = out.read_text(encoding="utf-8")
    assert _external_refs(page) == [], _external_refs(page)
    assert not re.search(r'<link\b[^>]*href\s*=\s*["\']?https?:', page, re.I)
    assert "cdn.plot.ly" not in page.split("<script>", 1)[0]
    assert out.stat().st_size < MAX_BYTES, out.stat().st_size


def test_external_ref_detector_works():
    bad = '<script src="https://cdn.plot.ly/plotly.min.js"></script><link href="//fonts.x/y" rel="stylesheet">'
    assert len(_external_refs(bad)) == 2


def test_tolerates_missing_pieces(tmp_path):
    run = write_run(tmp_path / "bare", with_snapshots=False, with_references=False,
                    with_targets=False, with_results=False, status="failed",
                    drop_columns=("regularisation_energy", "min_J", "cutbacks", "solve_time",
                                  "staggered_iterations"))
    meta, history, snaps = report.load_run(run)
    assert snaps is None
    assert "cutbacks" in history.columns and history["cutbacks"].isna().all()
    page = report.render_report(run).read_text(encoding="utf-8")
    ids = _ids(page)
    for sid in SECTIONS:
        assert sid in ids, sid
    assert 'id="status-banner"' in page and "FAILED" in page
    assert "No snapshots recorded" in page
    assert "no published target" in page


def test_running_status_and_no_history(tmp_path):
    run = write_run(tmp_path / "running", status="running")
    (run / "history.csv").unlink()
    (run / "snapshots.npz").write_bytes(b"not a zip file")
    with pytest.warns(UserWarning):
        meta, history, snaps = report.load_run(run)
    assert len(history) == 0 and snaps is None
    with pytest.warns(UserWarning):
        page = report.render_report(run).read_text(encoding="utf-8")
    assert 'id="status-banner"' in page and "RUNNING" in page
    for sid in SECTIONS:
        assert f'id="{sid}"' in page
    # key numbers fall back to metadata results when the history is missing
    sec = page[page.index('id="key-numbers"'):page.index('id="step-history"')]
    assert "N/mm" in sec


def test_completed_run_has_no_banner(tpb_run):
    page = report.render_report(tpb_run).read_text(encoding="utf-8")
    assert 'id="status-banner"' not in page


def test_output_argument(tpb_run, tmp_path):
    out = report.render_report(tpb_run, output=tmp_path / "elsewhere" / "r.html")
    assert out.is_file() and not (tpb_run / "report.html").exists()


def test_snapshot_decimation_and_scale(tmp_path):
    run = write_run(tmp_path / "many", cases=[("main", "main", 2e-3, {})])
    with np.load(run / "snapshots.npz") as z:
        d = {k: z[k] for k in z.files}
    k = 20
    d["main__loads"] = np.linspace(0, 0.15, k)
    d["main__u"] = np.repeat(d["main__u"][-1:] * 0.01, k, axis=0)  # tiny: must be scaled
    d["main__alpha"] = np.repeat(d["main__alpha"][-1:], k, axis=0)
    np.savez(run / "snapshots.npz", **d)
    _, _, snaps = report.load_run(run)
    payload = report.mesh_payload(snaps["main"])
    assert len(payload["frames"]) == report.MAX_FRAMES
    assert payload["frames"][-1]["load"] == pytest.approx(0.15)
    assert payload["scale"] > 1
    assert len(payload["t"]) == 3 * payload["nt"]
    page = report.render_report(run).read_text(encoding="utf-8")
    assert f"deformation scale: × {report.fmt(payload['scale'])}" in page


def test_deformation_scale_rules():
    v = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 2.0]])
    assert report.deformation_scale(v, np.full((1, 3, 2), 1.0)) == 1.0  # already visible
    s = report.deformation_scale(v, np.full((1, 3, 2), 1e-3 / np.sqrt(2)))
    assert s == 500.0  # 5 % of 10 mm / 1e-3 mm


def test_decimate_keeps_shape():
    x = np.linspace(0, 1, 5000)
    y = np.where(x < 0.5, x, 0.1)
    idx = report.decimate(x, y, 300)
    assert len(idx) <= 320
    assert 0 in idx and 4999 in idx and int(np.argmax(y)) in idx


def test_index_groups_and_compares(tmp_path):
    reports = tmp_path / "reports"
    a = write_run(reports / "tpb_quick", cases=[("main", "main", 2e-3, {})], n_elements=160,
                  wall_time_s=10.0, force_scale=0.95, resolution="quick")
    b = write_run(reports / "tpb_fine", cases=[("main", "main", 1e-3, {})], n_elements=2000,
                  wall_time_s=300.0, resolution="fine")
    c = write_run(reports / "cg_quick", study="contact_gamma0")
    report.render_report(a)
    out = report.render_index(reports)
    assert out == reports / "index.html"
    page = out.read_text(encoding="utf-8")
    assert 'href="tpb_quick/report.html"' in page
    assert "tpb_fine" in page and "cg_quick" in page
    assert "three_point_bending" in page and "contact_gamma0" in page
    assert 'id="speed-error"' in page
    figs = _fig_data(page)
    assert len(figs) == 1  # only the study with two runs gets a comparison
    fig = next(iter(figs.values()))
    assert fig["data"] and "wall time (s)" in fig["layout"]["xaxis"]["title"]["text"]
    sec = page[page.index('id="speed-error"'):]
    assert "finest" in sec and "%" in sec
    assert _external_refs(page) == []
    assert b.exists() and c.exists()


def test_report_main(tmp_path, capsys):
    reports = tmp_path / "reports"
    write_run(reports / "r1", cases=[("main", "main", 2e-3, {})])
    assert report.report_main([str(reports / "r1")]) == 0
    assert (reports / "r1" / "report.html").is_file()
    assert report.report_main(["--index", str(reports)]) == 0
    assert (reports / "index.html").is_file()
    assert report.report_main([str(tmp_path / "nothing")]) == 2


def test_index_leaves_failed_runs_out_of_the_comparison(tmp_path):
    reports = tmp_path / "reports"
    write_run(reports / "a", cases=[("main", "main", 2e-3, {})], n_elements=100, wall_time_s=5.0)
    write_run(reports / "b", cases=[("main", "main", 1e-3, {})], n_elements=400, wall_time_s=50.0)
    write_run(reports / "c", cases=[("main", "main", 1e-3, {})], n_elements=9000,
              wall_time_s=10.0, status="failed", force_scale=0.5)
    page = report.render_index(reports).read_text(encoding="utf-8")
    sec = page[page.index('id="speed-error"'):]
    assert "<td>a</td>" in sec
    assert "<td>c</td>" not in sec and "<td>c <span" not in sec  # listed, not compared
    assert '<td>b <span class="pill">finest</span></td>' in sec
    runs_sec = page[page.index('id="runs"'):page.index('id="speed-error"')]
    assert "pill-failed" in runs_sec and "c <span" in runs_sec


def test_speed_error_honours_reference_case(tpb_run):
    meta = json.loads((tpb_run / "metadata.json").read_text())
    for r in meta["results"].values():
        r["reference_case"] = "coarse"
    (tpb_run / "metadata.json").write_text(json.dumps(meta))
    meta, history, _ = report.load_run(tpb_run)
    entries = report._run_speed_entries(meta, history, report._case_list(meta))
    finest = [e for e in entries if e["finest"]]
    assert [e["label"] for e in finest] == ["du_max = 2e-3 mm"]


def test_time_split_table():
    """Each case with a recorded time split gets a row: ms per Newton iteration, its NGSolve
    threads and the share of its wall time per part, the rest as 'other'."""
    import pandas as pd
    meta = {"cases": [{"name": "main", "label": "main case", "threads": 2}],
            "results": {"main": {"wall_time_s": 100.0, "newton_iterations": 400, "steps": 200,
                                 "time_split_s": {"assembly": 45.0, "residual": 10.0, "factorization": 5.0,
                                                  "solve": 1.0, "line_search": 9.0, "phase_field": 2.0,
                                                  "history": 3.0, "record": 5.0}}}}
    history = pd.DataFrame({"case": ["main"] * 3, "step": [0, 1, 2], "load": [0.0, 0.1, 0.2],
                            "force": [0.0, 1.0, 2.0], "newton_iterations": [0, 200, 200], "cutbacks": [0, 0, 0],
                            "wall_time": [0.0, 50.0, 100.0], "solve_time": [0.0, 1.0, 1.0],
                            "fracture_energy": [0.0, 0.0, 0.0], "max_alpha": [0.0, 0.0, 0.0]})
    rows = report.time_split_rows(meta, history, meta["cases"])
    assert len(rows) == 1
    r = rows[0]
    assert r["ms_per_it"] == pytest.approx(250.0) and r["newton"] == 400 and r["threads"] == 2
    assert dict(r["parts"])["assembly"] == pytest.approx(45.0)
    assert r["other"] == pytest.approx(20.0)
    meta["results"]["main"].pop("time_split_s")
    assert report.time_split_rows(meta, history, meta["cases"]) == []


def test_study_figures_from_metadata(tpb_run):
    """A study's figures(p), recorded in the metadata as ``figures``, get their own section: each
    series drawn with its numbers (a band as two traces, the lower one filled to the upper)."""
    meta = json.loads((tpb_run / "metadata.json").read_text())
    meta["figures"] = [{"title": "peak against l0", "x_title": "l0 (mm)", "y_title": "peak (N)", "x_log": True,
                        "caption": "recorded sweep <b>", "series": [
                            {"label": "peaks", "kind": "curve", "x": [1.0, 4.0], "y": [20.0, 10.0]},
                            {"label": "band", "kind": "band", "x": [0.5, 5.0], "y_lower": [6.0, 6.0],
                             "y_upper": [7.0, 7.0]},
                            {"label": "point", "kind": "points", "x": [1.0], "y": [16.0]}]}]
    (tpb_run / "metadata.json").write_text(json.dumps(meta))
    page = report.render_report(tpb_run).read_text(encoding="utf-8")
    assert "study-figures" in _ids(page) and "fig-study-0" in _ids(page)
    assert "recorded sweep &lt;b&gt;" in page  # the caption is escaped
    fig = _fig_data(page)["fig-study-0"]
    assert fig["layout"]["xaxis"]["type"] == "log"
    by_name = {}
    for t in fig["data"]:
        by_name.setdefault(t["name"], []).append(t)
    assert by_name["peaks"][0]["y"] == pytest.approx([20.0, 10.0]) and by_name["peaks"][0]["mode"] == "lines+markers"
    assert by_name["point"][0]["mode"] == "markers"
    assert [t["y"] for t in by_name["band"]] == [pytest.approx([7.0, 7.0]), pytest.approx([6.0, 6.0])]
    assert by_name["band"][1]["fill"] == "tonexty"


def test_no_study_figures_section_without_figures(tpb_run):
    page = report.render_report(tpb_run).read_text(encoding="utf-8")
    assert "study-figures" not in _ids(page)


def test_units_note_states_what_forces_and_energies_are_for(tmp_path):
    """The forces and energies of a 2D run are for its thickness: per mm of thickness at 1 mm, for
    the whole specimen otherwise (the L-panel's 100 mm), and no thickness phrase in 3D."""
    from ngtmc.report.page import thickness_phrase
    assert thickness_phrase(1.0) == "per mm of thickness"
    assert thickness_phrase(100.0) == "for the thickness of 100 mm"
    assert thickness_phrase(None) == ""
    run = write_run(tmp_path / "thick")
    meta = json.loads((run / "metadata.json").read_text(encoding="utf-8"))
    meta.update(thickness_mm=100.0, force_unit="N")
    (run / "metadata.json").write_text(json.dumps(meta), encoding="utf-8")
    page = report.render_report(run).read_text(encoding="utf-8")
    assert "forces N (for the thickness of 100 mm)" in page
    assert "all in N mm (for the thickness of 100 mm)" in page
    assert "per mm of thickness" not in page
    page1 = report.render_report(write_run(tmp_path / "thin")).read_text(encoding="utf-8")
    assert "forces N/mm (per mm of thickness)" in page1
