"""Plotly figures of the snapshots of 3D runs (plain dicts, like :mod:`.figures`): the deformed
surface of the solid coloured by the phase field, and the phase field in a section plane, each
with a slider over the load levels (``restyle`` steps, so no plotly frames are needed).

Every number shown is sent once per frame, so the frames kept are limited to a budget of
numbers per page (:data:`MAX_VALUES_3D`); coordinates are rounded to 1e-4 of the domain size and
alpha to 1e-3. Units: mm for coordinates, loads and displacements; alpha dimensionless.
"""
from __future__ import annotations

import math

import numpy as np

from ngtmc.report.plot_style import ALPHA_COLORSCALE, _font, _title
from ngtmc.report.mesh_frames import MAX_FRAMES, _frame_indices, deformation_scale
from ngtmc.report.numbers import fmt


#: Budget of numbers (coordinates, alpha and section values of every frame shown, the first
#: frame drawn counted twice) in the 3D snapshot figures of a page: about 3.5 MB of JSON, so that
#: a report with plotly.js (about 4.8 MB) stays well below 10 MB.
MAX_VALUES_3D = 500_000

AXES = "xyz"


def is_3d(snap) -> bool:
    """Whether an entry of ``snapshots.npz`` is of a 3D run (vertices with 3 coordinates)."""
    v = snap.get("vertices") if isinstance(snap, dict) else None
    return v is not None and np.ndim(v) == 2 and np.shape(v)[1] == 3


def _decimals(extent: float, rel: float = 1e-4) -> int:
    """Decimals that resolve ``rel`` of ``extent`` (mm)."""
    if not extent > 0 or not math.isfinite(extent):
        return 6
    return max(0, int(-math.floor(math.log10(extent * rel))))


def _round_list(a, decimals: int) -> list:
    """Flat list of floats rounded to ``decimals`` (NaN/inf become None), short in JSON."""
    a = np.round(np.asarray(a, dtype=float).ravel(), decimals)
    a[a == 0] = 0.0   # no "-0.0"
    out = a.tolist()
    if not np.isfinite(a).all():
        out = [v if math.isfinite(v) else None for v in out]
    return out


def _round_rows(a, decimals: int) -> list:
    """2D array as a list of rows of rounded floats (NaN as None: blank in a heatmap)."""
    a = np.asarray(a, dtype=float)
    return [_round_list(row, decimals) for row in a]


def _load_label(v: float) -> str:
    """Load of a slider step (mm) with 4 significant digits, as the 2D slider writes it."""
    return f"{v:.4g}"


def _slider(steps: list[dict], active: int) -> dict:
    return {"active": active, "pad": {"t": 40, "l": 10, "r": 10}, "len": 1,
            "currentvalue": {"prefix": "applied displacement u = ", "suffix": " mm",
                             "font": {"size": 13}},
            "steps": steps}


def _arrays(snap: dict):
    """Vertices (nv, 3), triangles (nt, 3), loads (k,), u (k, nv, 3) and alpha (k, nv) or None,
    checked; None when the entry has no surface to draw."""
    if not is_3d(snap) or "triangles" not in snap:
        return None
    V = np.asarray(snap["vertices"], dtype=float)
    T = np.asarray(snap["triangles"])
    if T.ndim != 2 or T.shape[1] != 3 or T.size == 0 or not np.issubdtype(T.dtype, np.integer):
        return None
    T = T.astype(np.int64)
    nv = V.shape[0]
    if T.min() < 0 or T.max() >= nv:
        return None
    loads = np.asarray(snap.get("loads", []), dtype=float).ravel()
    k = len(loads)
    U = snap.get("u")
    U = np.asarray(U, dtype=float) if U is not None else np.zeros((k, nv, 3))
    if U.ndim != 3 or U.shape[0] < k or U.shape[1] != nv or U.shape[2] != 3:
        return None
    U = np.nan_to_num(U[:k], nan=0.0)
    A = snap.get("alpha")
    if A is not None:
        A = np.asarray(A, dtype=float)
        if A.ndim != 2 or A.shape[0] < k or A.shape[1] != nv:
            A = None
        else:
            A = A[:k]
    return V, T, loads, U, A


def _section_arrays(snap: dict, k: int):
    """Plane axis (0, 1, 2), its coordinate (mm), grid coordinates c1, c2 (mm) and alpha (k, n1, n2)
    of the section of a 3D entry, or None when it has none (or it does not fit)."""
    if not all(key in snap for key in ("section_plane", "section_c1", "section_c2", "section_alpha")):
        return None
    plane = np.asarray(snap["section_plane"], dtype=float).ravel()
    c1 = np.asarray(snap["section_c1"], dtype=float).ravel()
    c2 = np.asarray(snap["section_c2"], dtype=float).ravel()
    S = np.asarray(snap["section_alpha"], dtype=float)
    if plane.size != 2 or not np.isfinite(plane).all() or int(plane[0]) not in (0, 1, 2):
        return None
    if S.ndim != 3 or S.shape[0] < k or S.shape[1:] != (c1.size, c2.size) or k == 0:
        return None
    return int(plane[0]), float(plane[1]), c1, c2, S[:k]


def frames_3d(snap: dict, max_frames: int = MAX_FRAMES, budget: int = MAX_VALUES_3D) -> list[int]:
    """Indices of the snapshots of a 3D entry to show: at most ``max_frames``, evenly spread and
    always including the last, fewer when the numbers sent (3 per surface triangle once, then per
    frame 4 per surface vertex and 1 per section cell, the frame drawn first twice) would exceed
    ``budget``; at least one."""
    arr = _arrays(snap)
    if arr is None or not len(arr[2]):
        return []
    V, T, loads, U, A = arr
    k = len(loads)
    per_frame = 4 * np.unique(T).size
    sec = _section_arrays(snap, k)
    if sec is not None:
        per_frame += sec[2].size * sec[3].size
    cap = max(1, min(max_frames, (budget - 3 * T.shape[0]) // max(per_frame, 1) - 1))
    return _frame_indices(k, cap) if cap > 1 else [k - 1]


def fig_surface(snap: dict, label: str, frames: list[int]) -> tuple[dict, dict] | None:
    """Deformed surface of the solid of a 3D entry of ``snapshots.npz``, coloured by alpha.

    A plotly ``mesh3d`` of the surface triangles (``triangles``), vertices displaced by
    ``scale * u`` (mm; ``scale`` from :func:`.mesh_frames.deformation_scale`), colour = alpha at the
    vertices on a fixed scale 0..1, with one slider step per snapshot in ``frames`` labelled with
    its applied displacement (mm); the last one is drawn first. Coordinates are rounded to 1e-4
    of the domain size, alpha to 1e-3. Aspect mode "data": lengths are not distorted.

    Returns ``(figure, info)``, info holding ``scale``, ``u_max`` (mm), ``loads`` (mm, shown),
    ``n_recorded``, ``alpha_max`` (largest alpha shown), ``nt`` and ``nv`` (surface triangles and
    their vertices); None when the entry has nothing to draw.
    """
    arr = _arrays(snap)
    if arr is None or not frames:
        return None
    V, T, loads, U, A = arr
    used = np.unique(T)                       # only the vertices of the surface are sent
    renum = np.full(V.shape[0], -1, dtype=np.int64)
    renum[used] = np.arange(used.size)
    Tn = renum[T]
    Vs = V[used]
    scale = deformation_scale(V, U)
    u_max = float(np.max(np.linalg.norm(U, axis=-1))) if U.size else 0.0
    ext = float(np.max(np.ptp(Vs, axis=0))) if Vs.size else 0.0
    dec = _decimals(ext)

    def frame(i):
        P = Vs + scale * U[i][used]
        a = np.clip(np.nan_to_num(A[i][used], nan=0.0), 0.0, 1.0) if A is not None else np.zeros(used.size)
        return {"x": _round_list(P[:, 0], dec), "y": _round_list(P[:, 1], dec),
                "z": _round_list(P[:, 2], dec), "intensity": _round_list(a, 3)}

    last = frame(frames[-1])
    trace = {"type": "mesh3d", "name": label, **last,
             "i": Tn[:, 0], "j": Tn[:, 1], "k": Tn[:, 2], "intensitymode": "vertex",
             "colorscale": ALPHA_COLORSCALE, "cmin": 0, "cmax": 1, "showscale": True,
             "colorbar": {"title": {"text": "phase field α (-)", "side": "right"}, "thickness": 14,
                          "len": 0.8},
             "flatshading": False, "hoverinfo": "skip",
             "lighting": {"ambient": 0.75, "diffuse": 0.5, "specular": 0.05, "roughness": 0.9},
             "lightposition": {"x": 1e5, "y": 2e5, "z": 3e5}}
    steps = []
    for n, i in enumerate(frames):
        f = last if n == len(frames) - 1 else frame(i)
        steps.append({"label": _load_label(loads[i]), "method": "restyle",
                      "args": [{key: [f[key]] for key in ("x", "y", "z", "intensity")}, [0]]})
    ax = {"showgrid": True, "gridcolor": "#e6e6e6", "zeroline": False, "showbackground": False,
          "ticks": "outside", "exponentformat": "power"}
    scene = {"aspectmode": "data",
             "xaxis": dict(ax, title={"text": "x (mm)"}), "yaxis": dict(ax, title={"text": "y (mm)"}),
             "zaxis": dict(ax, title={"text": "z (mm)"}),
             # y up (the height of the 2D scenes extruded along z), looking at the front face z = max
             "camera": {"up": {"x": 0, "y": 1, "z": 0}, "eye": {"x": 1.2, "y": 1.0, "z": 4.2}}}
    title = (f"Phase field α on the deformed surface – {label} (deformation scale: × {fmt(scale)})")
    layout = {"title": _title(title), "font": _font(),
              "paper_bgcolor": "#ffffff", "height": 680, "margin": {"l": 10, "r": 10, "t": 50, "b": 90},
              "showlegend": False, "scene": scene, "uirevision": "surface",
              "sliders": [_slider(steps, len(frames) - 1)]}
    shown = np.asarray([A[i] for i in frames]) if A is not None else np.zeros(1)
    info = {"scale": scale, "u_max": u_max, "loads": [float(loads[i]) for i in frames],
            "n_recorded": len(loads), "alpha_max": float(np.nanmax(shown)) if shown.size else 0.0,
            "nt": int(T.shape[0]), "nv": int(used.size)}
    return {"data": [trace], "layout": layout}, info


def fig_section(snap: dict, label: str, frames: list[int]) -> tuple[dict, str] | None:
    """Phase field in the section plane of a 3D entry of ``snapshots.npz`` (``section_*`` keys).

    A plotly heatmap of ``section_alpha`` over the grid ``section_c1`` x ``section_c2`` (mm; the
    two axes other than the plane's, in the order x, y, z), alpha on a fixed scale 0..1, NaN cells
    (outside the fracture regions) blank, one slider step per snapshot in ``frames`` labelled with
    its applied displacement (mm). The height axis y is vertical when it is one of the two, else
    the second grid axis; both axes have equal scaling.

    Returns ``(figure, plane)``, plane the text "y = 0.5 mm"; None when the entry has no section.
    """
    loads = np.asarray(snap.get("loads", []), dtype=float).ravel() if isinstance(snap, dict) else []
    sec = _section_arrays(snap, len(loads)) if is_3d(snap) and frames else None
    if sec is None:
        return None
    axis, at, c1, c2, S = sec
    others = [i for i in range(3) if i != axis]
    # heatmap rows run along the vertical axis: transpose unless c1 (not c2) is vertical
    c1_vertical = others[0] == 1
    hx, hy = (c2, c1) if c1_vertical else (c1, c2)
    nx, ny = (AXES[others[1]], AXES[others[0]]) if c1_vertical else (AXES[others[0]], AXES[others[1]])
    ext = float(max(np.ptp(c1), np.ptp(c2))) if c1.size and c2.size else 0.0
    dec = _decimals(ext)

    def z(i):
        return _round_rows(S[i] if c1_vertical else S[i].T, 3)

    last = z(frames[-1])
    plane = f"{AXES[axis]} = {fmt(at)} mm"
    trace = {"type": "heatmap", "name": label, "x": _round_list(hx, dec), "y": _round_list(hy, dec),
             "z": last, "zmin": 0, "zmax": 1, "zauto": False, "colorscale": ALPHA_COLORSCALE,
             "hoverongaps": False,
             "colorbar": {"title": {"text": "phase field α (-)", "side": "right"}, "thickness": 14,
                          "len": 0.9},
             "hovertemplate": f"{nx} = %{{x:.4g}} mm, {ny} = %{{y:.4g}} mm<br>α = %{{z:.3f}}<extra></extra>"}
    steps = []
    for n, i in enumerate(frames):
        steps.append({"label": _load_label(loads[i]), "method": "restyle",
                      "args": [{"z": [last if n == len(frames) - 1 else z(i)]}, [0]]})
    rx = float(np.ptp(hx)) if hx.size > 1 else 1.0
    ry = float(np.ptp(hy)) if hy.size > 1 else 1.0
    # equal scaling: about 900 px of width for the horizontal extent, height to match
    height = int(min(760, max(300, 900 * ry / max(rx, 1e-12) + 200)))
    axis_style = {"showgrid": False, "zeroline": False, "showline": True, "linecolor": "#444",
                  "mirror": True, "ticks": "outside", "constrain": "domain"}
    layout = {"title": _title(f"Phase field α in the plane {plane} – {label}"),
              "font": _font(),
              "paper_bgcolor": "#ffffff", "plot_bgcolor": "#ffffff", "height": height,
              "margin": {"l": 70, "r": 30, "t": 50, "b": 110}, "showlegend": False,
              "xaxis": dict(axis_style, title={"text": f"{nx} (mm)"}),
              "yaxis": dict(axis_style, title={"text": f"{ny} (mm)"}, scaleanchor="x", scaleratio=1),
              "sliders": [_slider(steps, len(frames) - 1)]}
    return {"data": [trace], "layout": layout}, plane


def snapshot_figures_3d(snap: dict, label: str, max_frames: int = MAX_FRAMES,
                        budget: int = MAX_VALUES_3D) -> dict | None:
    """The figures of one 3D entry of ``snapshots.npz`` for the report: ``surface`` (see
    :func:`fig_surface`), ``section`` (:func:`fig_section`, None without a section) and what the
    captions say: ``scale``, ``u_max`` (mm), ``loads`` (mm, shown), ``n_frames``, ``n_recorded``,
    ``alpha_max``, ``plane`` ("y = 0.5 mm" or None), ``nt``, ``nv``. Frames as :func:`frames_3d`
    with ``max_frames`` and ``budget`` (numbers). None when the entry has no snapshot to draw."""
    frames = frames_3d(snap, max_frames, budget)
    surf = fig_surface(snap, label, frames)
    if surf is None:
        return None
    fig, info = surf
    sec = fig_section(snap, label, frames)
    return dict(info, surface=fig, section=sec[0] if sec else None, plane=sec[1] if sec else None,
                n_frames=len(frames))
