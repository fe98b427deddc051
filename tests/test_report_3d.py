"""HTML report of a 3D run: the deformed surface of the solid coloured by the phase field and the
phase field in the section plane, plotly figures with a slider over the load levels; the page stays
below 10 MB and loads nothing from the web, and a 2D run's report has no 3D figure.

The run: the notched plate of tests/scenes.py extruded into a slab 0.05 mm thick (2 layers of
prisms), pulled to 0.012 mm by path following, the crack running through it; snapshots at three
loads and a section at y = 0.5 mm (the crack plane). Units: mm.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from report_fixtures import page_json, write_run  # noqa: E402
from scenes import notched_plate  # noqa: E402

import ngtmc  # noqa: E402
from ngtmc import report  # noqa: E402
from ngtmc.scene.extrusion import plane_strain_slab  # noqa: E402
from ngtmc.report.mesh_frames import deformation_scale  # noqa: E402
from ngtmc.report.figures3d import frames_3d, snapshot_figures_3d  # noqa: E402

THICKNESS = 0.05                 # mm
LOADS = [0.004, 0.006, 0.012]    # mm, snapshot loads
MAX_BYTES = 10 * 1024 * 1024


def _fig_data(page: str) -> dict:
    return page_json(page, "fig-data")


def _mesh_data(page: str) -> dict:
    return page_json(page, "mesh-data")


@pytest.fixture(scope="module")
def slab_run(tmp_path_factory):
    """(run folder, page text, snapshots) of the 3D slab run, its report rendered."""
    sc2 = notched_plate(maxh=0.2, h_band=0.05, l0=0.1)
    sc3 = plane_strain_slab(sc2, THICKNESS, layers=2, name="slab")
    out = tmp_path_factory.mktemp("report3d") / "slabrun"
    ngtmc.simulate(sc3, 0.012, ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=20.0 / THICKNESS), out_dir=out,
                   scheme="path-following", section=("y", 0.5), snapshot_loads=LOADS,
                   report=False, vtk=False, progress=False, threads=1)
    page = report.render_report(out).read_text(encoding="utf-8")
    _, _, snaps = report.load_run(out)
    return out, page, snaps["main"]


def test_surface_figure_has_one_slider_step_per_snapshot(slab_run):
    out, page, snap = slab_run
    figs = _fig_data(page)
    assert 'id="snap3d-0"' in page
    fig = figs["snap3d-0"]
    (trace,) = fig["data"]
    assert trace["type"] == "mesh3d"
    assert trace["cmin"] == 0 and trace["cmax"] == 1
    assert fig["layout"]["scene"]["aspectmode"] == "data"
    for ax in "xyz":
        assert fig["layout"]["scene"][f"{ax}axis"]["title"]["text"] == f"{ax} (mm)"
    (slider,) = fig["layout"]["sliders"]
    loads = snap["loads"]
    assert len(loads) == len(LOADS)
    assert len(slider["steps"]) == len(loads)
    assert slider["currentvalue"]["suffix"] == " mm"
    for st, load in zip(slider["steps"], loads):
        assert float(st["label"]) == pytest.approx(load, rel=1e-3)   # the load in mm
        assert st["method"] == "restyle"
    assert slider["active"] == len(loads) - 1
    # the scale is said in the title and the caption
    scale = deformation_scale(snap["vertices"], snap["u"])
    assert f"deformation scale: × {report.fmt(scale)}" in fig["layout"]["title"]["text"]
    sec = page[page.index('id="snapshots"'):page.index('id="mesh-density"')]
    assert f"displaced by {report.fmt(scale)} × u" in sec
    assert f"{len(loads)} of {len(loads)} recorded frames shown" in sec
    assert "left out" not in sec


def test_surface_colours_and_positions_are_the_snapshot(slab_run):
    out, page, snap = slab_run
    fig = _fig_data(page)["snap3d-0"]
    trace = fig["data"][0]
    V, T, U, A = snap["vertices"], snap["triangles"], snap["u"], snap["alpha"]
    used = np.unique(T)                      # the figure holds the surface vertices only
    assert len(trace["x"]) == used.size
    tri = np.column_stack([trace["i"], trace["j"], trace["k"]])
    np.testing.assert_array_equal(used[tri], T)
    scale = deformation_scale(V, U)
    ext = float(np.max(np.ptp(V, axis=0)))
    assert A[-1].max() > 0.9, "the crack ran: the last snapshot has alpha near 1"
    # the trace shows the last snapshot, each slider step its own
    np.testing.assert_allclose(trace["intensity"], A[-1][used], atol=6e-4)
    for n, st in enumerate(fig["layout"]["sliders"][0]["steps"]):
        upd = st["args"][0]
        a = np.asarray(upd["intensity"][0])
        pick = np.linspace(0, used.size - 1, 7).astype(int)   # a few values
        np.testing.assert_allclose(a[pick], A[n][used][pick], atol=6e-4)
        np.testing.assert_allclose(a, A[n][used], atol=6e-4)
        for c, key in enumerate("xyz"):
            np.testing.assert_allclose(upd[key][0], V[used, c] + scale * U[n][used, c], atol=1e-4 * ext)
    assert fig["layout"]["sliders"][0]["steps"][0]["args"][0]["intensity"][0] != trace["intensity"]


def test_section_heatmap_with_blank_outside_the_fracture_regions(slab_run):
    out, page, snap = slab_run
    assert 'id="section3d-0"' in page
    fig = _fig_data(page)["section3d-0"]
    (trace,) = fig["data"]
    assert trace["type"] == "heatmap"
    assert trace["zmin"] == 0 and trace["zmax"] == 1
    lay = fig["layout"]
    assert "in the plane y = 0.5 mm" in lay["title"]["text"]
    # plane y: the grid axes are x (section_c1, horizontal) and z (section_c2, vertical)
    assert lay["xaxis"]["title"]["text"] == "x (mm)" and lay["yaxis"]["title"]["text"] == "z (mm)"
    assert lay["yaxis"]["scaleanchor"] == "x" and lay["yaxis"]["scaleratio"] == 1
    np.testing.assert_allclose(trace["x"], snap["section_c1"], atol=1e-6)
    np.testing.assert_allclose(trace["y"], snap["section_c2"], atol=1e-6)
    S = snap["section_alpha"]
    steps = lay["sliders"][0]["steps"]
    assert len(steps) == len(snap["loads"]) == S.shape[0]
    for n, st in enumerate(steps):
        assert float(st["label"]) == pytest.approx(snap["loads"][n], rel=1e-3)
        z = st["args"][0]["z"][0]
        assert len(z) == S.shape[2] and len(z[0]) == S.shape[1]      # rows along z
        zz = np.array([[np.nan if v is None else v for v in row] for row in z])
        np.testing.assert_array_equal(np.isnan(zz), np.isnan(S[n].T))  # NaN -> null -> blank
        np.testing.assert_allclose(zz, S[n].T, atol=6e-4, equal_nan=True)
    assert np.isnan(S).any() and (~np.isnan(S)).any()
    m = re.search(r'<script type="application/json" id="fig-data">(.*?)</script>', page, re.S)
    assert "null" in m.group(1) and "NaN" not in m.group(1)
    sec = page[page.index('id="snapshots"'):page.index('id="mesh-density"')]
    assert "in the plane y = 0.5 mm" in sec


def test_3d_report_is_small_offline_and_without_2d_payload(slab_run):
    out, page, snap = slab_run
    size = (out / "report.html").stat().st_size
    assert size < MAX_BYTES, f"report is {size / 1e6:.1f} MB"
    assert not re.search(r'<script[^>]*\bsrc="http', page, re.I)
    # no element loading from another host (plotly.js itself holds such text in strings)
    tags = r"<(?:script|link|img|iframe|source|video|audio)\b[^>]*?\b(?:src|href)\s*=\s*"
    assert not re.findall(tags + r'''["']?\s*((?:https?:)?//[^"'\s>]+)''', page, re.I)
    assert _mesh_data(page) == {}, "no 2D mesh payload for a 3D run"
    assert "snap-0" not in re.findall(r'\bid="([^"]+)"', page)


def test_2d_report_has_no_3d_figure(tmp_path):
    page = report.render_report(write_run(tmp_path / "tpb")).read_text(encoding="utf-8")
    figs = _fig_data(page)
    assert not [k for k in figs if "3d" in k]
    assert not [t for f in figs.values() for t in f["data"] if t.get("type") in ("mesh3d", "heatmap")]
    assert set(_mesh_data(page)) == {"coarse", "fine"}


def _synthetic_3d(n: int, k: int, section: tuple[int, int] | None = None) -> dict:
    """Snapshots of a slab 10 x 10 x 1 mm: its front and back faces as (2 n^2) triangles each, k
    loads, alpha rising with the load along a band at y = 5 mm; with ``section`` (n1, n2) a grid
    in the plane y = 5 mm, NaN on its first rows."""
    s = np.linspace(0.0, 10.0, n + 1)
    X, Y = np.meshgrid(s, s, indexing="ij")
    face = np.column_stack([X.ravel(), Y.ravel()])
    V = np.vstack([np.column_stack([face, np.zeros(len(face))]), np.column_stack([face, np.ones(len(face))])])
    q = [(i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, i * (n + 1) + j + 1)
         for i in range(n) for j in range(n)]
    tri = np.array([t for a, b, c, d in q for t in ((a, b, c), (a, c, d))], dtype=np.int64)
    T = np.vstack([tri, tri + len(face)])
    loads = np.linspace(0.01, 0.1, k)
    U = np.zeros((k, len(V), 3))
    U[:, :, 1] = loads[:, None] * V[None, :, 1] / 10.0
    A = np.clip(loads[:, None] / 0.1 - np.abs(V[None, :, 1] - 5.0), 0.0, 1.0)
    snap = {"vertices": V, "triangles": T, "rho": np.ones(len(T)), "loads": loads,
            "steps": np.arange(1, k + 1), "u": U, "alpha": A}
    if section:
        n1, n2 = section
        S = np.tile(loads[:, None, None] / 0.1, (1, n1, n2))
        S[:, :3, :] = np.nan
        snap.update(section_plane=np.array([1.0, 5.0]), section_c1=np.linspace(0, 10, n1),
                    section_c2=np.linspace(0, 1, n2), section_alpha=S)
    return snap


def test_frames_left_out_for_a_large_surface(tmp_path):
    """A surface of 2 x 80^2 vertices with 12 snapshots does not fit the budget: fewer frames,
    the last among them, said in the caption, the page still below 10 MB."""
    snap = _synthetic_3d(80, 12, section=(101, 11))
    frames = frames_3d(snap)
    assert 1 <= len(frames) < 8 and frames[-1] == 11 and frames[0] == 0
    assert frames_3d(_synthetic_3d(4, 12)) == frames_3d(_synthetic_3d(4, 12), max_frames=8)
    assert len(frames_3d(_synthetic_3d(4, 12))) == 8
    run = write_run(tmp_path / "big", cases=[("main", "slab", 1e-3, {})], with_snapshots=False)
    np.savez_compressed(run / "snapshots.npz", **{f"main__{k}": v for k, v in snap.items()})
    out = report.render_report(run)
    page = out.read_text(encoding="utf-8")
    assert out.stat().st_size < MAX_BYTES
    fig = _fig_data(page)["snap3d-0"]
    assert len(fig["layout"]["sliders"][0]["steps"]) == len(frames)
    assert len(_fig_data(page)["section3d-0"]["layout"]["sliders"][0]["steps"]) == len(frames)
    sec = page[page.index('id="snapshots"'):page.index('id="mesh-density"')]
    assert f"{len(frames)} of 12 recorded frames shown" in sec
    assert f"{12 - len(frames)} of the 12 recorded frames are left out" in sec


def test_section_axes_put_y_vertical():
    """A plane x = 5 mm: grid axes y (section_c1) and z (section_c2); y is drawn vertical."""
    snap = _synthetic_3d(4, 2)
    S = np.arange(2 * 6 * 3, dtype=float).reshape(2, 6, 3) / 36.0
    snap.update(section_plane=np.array([0.0, 5.0]), section_c1=np.linspace(0, 10, 6),
                section_c2=np.linspace(0, 1, 3), section_alpha=S)
    fig = snapshot_figures_3d(snap, "slab")
    sec = fig["section"]
    assert fig["plane"] == "x = 5 mm" and "in the plane x = 5 mm" in sec["layout"]["title"]["text"]
    assert sec["layout"]["xaxis"]["title"]["text"] == "z (mm)"
    assert sec["layout"]["yaxis"]["title"]["text"] == "y (mm)"
    tr = sec["data"][0]
    np.testing.assert_allclose(tr["y"], snap["section_c1"])
    np.testing.assert_allclose(tr["z"], np.round(S[-1], 3))        # rows along y (c1)
