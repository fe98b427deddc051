"""The compact mesh payloads of a report's 2D snapshots (the deformed mesh coloured by the phase
field, drawn in the browser as filled SVG polygons): frame choice, deformation scale, integer
coordinates and colour levels. The plotly figures are in :mod:`ngtmc.report.figures`, the 3D
snapshots in :mod:`ngtmc.report.figures3d`."""
from __future__ import annotations

import math

import numpy as np

#: Largest number of phase-field frames shown per case (frames are skipped evenly beyond this).
MAX_FRAMES = 8


#: Budget of vertex positions in all snapshot frames of a page (frames are skipped beyond it).
MAX_VERTEX_FRAMES = 150_000


#: Element edges are drawn in the density/mesh plot up to this many triangles.
MAX_EDGE_TRIANGLES = 30_000


#: Number of colour levels used to draw per-triangle fields.
N_LEVELS = 16


def _nice_scale(s: float) -> float:
    if s <= 1:
        return 1.0
    e = math.floor(math.log10(s))
    for m in (1, 2, 5, 10):
        if m * 10 ** e >= s * 0.999:
            return float(m * 10 ** e) if m < 10 else float(10 ** (e + 1))
    return float(10 ** (e + 1))


def deformation_scale(vertices: np.ndarray, u: np.ndarray) -> float:
    """Scale factor for drawing the deformed mesh (dimensionless).

    1 when the largest displacement is already visible (>= 1 % of the domain size, about ten
    pixels on screen), else a round
    number (1, 2, 5 x 10^k) making the largest displacement about 5 % of the domain size.
    """
    v = np.asarray(vertices, dtype=float)
    ext = float(np.max(np.ptp(v[:, :2], axis=0))) if v.size else 0.0
    um = float(np.nanmax(np.linalg.norm(np.asarray(u, dtype=float), axis=-1))) if np.size(u) else 0.0
    if ext <= 0 or um <= 0 or not math.isfinite(um):
        return 1.0
    if um >= 0.01 * ext:
        return 1.0
    return _nice_scale(0.05 * ext / um)


def _frame_indices(k: int, max_frames: int = MAX_FRAMES) -> list[int]:
    if k <= max_frames:
        return list(range(k))
    idx = np.unique(np.round(np.linspace(0, k - 1, max_frames)).astype(int))
    return [int(i) for i in idx]


def mesh_payload(snap: dict, max_frames: int = MAX_FRAMES) -> dict | None:
    """Compact, JSON-ready description of one case's snapshots (None if there is no mesh).

    Coordinates are integers: vertex ``i`` of the undeformed mesh is at
    ``(x0 + q * xi[i], y0 + q * yi[i])`` mm with ``q`` = 1e-4 of the domain size; frame ``f``
    moves it by ``qu * (dx[i], dy[i])`` mm, the displacement already multiplied by the
    deformation ``scale``. Triangles are stored once (``t``, flat, 0-based). Each frame lists only
    the triangles whose phase field (mean of its vertices) is not in the lowest of
    ``N_LEVELS`` colour levels, as pairs ``nz = [triangle, level, ...]``; void triangles
    (``rho_level`` < 5, i.e. rho < 0.5) are drawn grey. At most ``max_frames`` frames are kept,
    evenly spread over the recorded ones, always including the last.
    """
    if not snap or "vertices" not in snap or "triangles" not in snap:
        return None
    V = np.asarray(snap["vertices"], dtype=float)
    T = np.asarray(snap["triangles"])
    if V.ndim != 2 or V.shape[0] == 0 or V.shape[1] < 2 or T.ndim != 2 or T.shape[1] != 3 \
            or T.size == 0 or not np.issubdtype(T.dtype, np.integer):
        return None
    T = T.astype(np.int64)
    if T.max() >= V.shape[0] or T.min() < 0:
        return None
    nt, nv = T.shape[0], V.shape[0]
    x0, y0 = float(V[:, 0].min()), float(V[:, 1].min())
    ext = float(max(np.ptp(V[:, 0]), np.ptp(V[:, 1]))) or 1.0
    q = float(f"{ext * 1e-4:.3g}")
    rho = np.asarray(snap.get("rho", np.ones(nt)), dtype=float).ravel()
    if rho.size != nt:
        rho = np.ones(nt)
    rho = np.nan_to_num(rho, nan=1.0)
    void = rho < 0.5
    out = {"x0": x0, "y0": y0, "q": q,
           "xi": np.round((V[:, 0] - x0) / q).astype(np.int64),
           "yi": np.round((V[:, 1] - y0) / q).astype(np.int64),
           "t": T.ravel(), "rho_level": np.clip(np.round(rho * 10), 0, 10).astype(np.int64),
           "nt": int(nt), "nv": int(nv), "dim": int(V.shape[1]), "frames": [], "scale": 1.0,
           "n_recorded": 0, "extent": ext, "n_void": int(void.sum()), "u_max": None}
    loads = np.asarray(snap.get("loads", []), dtype=float).ravel()
    U = snap.get("u")
    A = snap.get("alpha")
    k = len(loads)
    if U is None or k == 0:
        return out
    U = np.asarray(U, dtype=float)
    if U.ndim == 2 and k == 1:
        U = U[None]
    if U.ndim != 3 or U.shape[0] < k or U.shape[1] != nv or U.shape[2] < 2:
        return out
    if A is not None:
        A = np.asarray(A, dtype=float)
        if A.ndim == 1 and k == 1:
            A = A[None]
        if A.ndim != 2 or A.shape[0] < k or A.shape[1] != nv:
            A = None
    U = np.nan_to_num(U[:k], nan=0.0)
    scale = deformation_scale(V, U)
    um = float(np.max(np.linalg.norm(U, axis=-1))) if U.size else 0.0
    qu = float(f"{max(q, scale * um / 500.0):.3g}")
    out.update({"scale": scale, "n_recorded": k, "u_max": um, "qu": qu,
                "has_alpha": A is not None})
    for i in _frame_indices(k, max_frames):
        fr = {"load": float(f"{loads[i]:.6g}"),
              "dx": np.round(scale * U[i][:, 0] / qu).astype(np.int64),
              "dy": np.round(scale * U[i][:, 1] / qu).astype(np.int64)}
        if A is not None:
            a_tri = np.nan_to_num(A[i][T].mean(axis=1), nan=0.0)
            lev = np.clip(np.floor(a_tri * N_LEVELS), 0, N_LEVELS - 1).astype(np.int64)
            lev[void] = 0
            nz = np.flatnonzero(lev)
            fr["nz"] = np.column_stack([nz, lev[nz]]).ravel()
            fr["alpha_max"] = float(f"{np.nanmax(A[i]):.4g}")
        else:
            fr["nz"] = np.zeros(0, dtype=np.int64)
            fr["alpha_max"] = None
        out["frames"].append(fr)
    return out


def _same_mesh(a: dict, b: dict) -> bool:
    return (a["nv"] == b["nv"] and a["nt"] == b["nt"] and a["x0"] == b["x0"]
            and a["y0"] == b["y0"] and a["q"] == b["q"] and np.array_equal(a["xi"], b["xi"])
            and np.array_equal(a["yi"], b["yi"]) and np.array_equal(a["t"], b["t"])
            and np.array_equal(a["rho_level"], b["rho_level"]))


def _level_colors(colorscale, n: int) -> list[str]:
    from plotly.colors import sample_colorscale, get_colorscale
    cs = get_colorscale(colorscale) if isinstance(colorscale, str) else colorscale
    return sample_colorscale(cs, [(i + 0.5) / n for i in range(n)])
