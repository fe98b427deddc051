"""Plotly figures of the reports (plain dicts, serialised once with json); the compact mesh
payloads of the 2D snapshots are in :mod:`ngtmc.report.mesh_frames`."""
from __future__ import annotations

import numpy as np

from ngtmc.report.loading import _case_rows, _param_value
from ngtmc.model import gamma_interpolation, gc_interpolation
from ngtmc.report.numbers import _finite, _rs, fmt, unit_factor
from ngtmc.report.plot_style import (CASE_COLORS, REF_COLORS, _axis, _layout, _legend_below, _legend_rows, _line, _log_axis,
                         _log_toggle)


def _fig_force(meta, history, cases, styles, log_y=False):
    fu = meta.get("force_unit") or "N"
    data = []
    for k, ref in enumerate(r for r in meta.get("references") or [] if isinstance(r, dict)):
        fac = unit_factor(ref.get("y_unit"), fu)
        fac = 1.0 if fac is None else fac
        color = REF_COLORS[k % len(REF_COLORS)]
        label = str(ref.get("label", "reference"))
        x = np.asarray(ref.get("x") or [], dtype=float)
        if ref.get("kind") == "band":
            lo = np.asarray(ref.get("y_lower") or [], dtype=float) * fac
            hi = np.asarray(ref.get("y_upper") or [], dtype=float) * fac
            n = min(len(x), len(lo), len(hi))
            if n == 0:
                continue
            if log_y:
                lo, hi = np.abs(lo), np.abs(hi)
                lo[lo <= 0] = np.nan
                hi[hi <= 0] = np.nan
            data.append(_line(x[:n], hi[:n], label, "rgba(120,120,120,0.6)", width=0.8, units=("mm", fu),
                              legendgroup=f"ref{k}", showlegend=False, hoverinfo="skip"))
            data.append(_line(x[:n], lo[:n], label, "rgba(120,120,120,0.6)", width=0.8, units=("mm", fu),
                              legendgroup=f"ref{k}", fill="tonexty",
                              fillcolor="rgba(150,150,150,0.30)"))
        else:
            y = np.asarray(ref.get("y") or [], dtype=float) * fac
            n = min(len(x), len(y))
            if n == 0:
                continue
            if log_y:
                y = np.abs(y)
                y[y <= 0] = np.nan
            data.append(_line(x[:n], y[:n], label, color, dash="dash", width=2, units=("mm", fu),
                              legendgroup=f"ref{k}"))
    for c in cases:
        h = _case_rows(history, c["name"])
        if log_y and len(h):
            h = h[h["load"] > 0]  # the initial state carries round-off only
        if not len(h):
            continue
        y = h["force"].to_numpy(dtype=float)
        if log_y:
            y = np.abs(y)
            y[y <= 0] = np.nan
        st = styles[c["name"]]
        data.append(_line(h["load"], y, c["label"], st["color"], dash=st["dash"], width=2.2,
                          units=("mm", fu),
                          mode="lines+markers" if len(h) < 40 else "lines"))
    if log_y:
        lay = _layout("|Force| against applied displacement (log scale)",
                      "applied displacement u (mm)", f"|force| |F| ({fu})")
        ys = [v for t in data for v in t["y"] if v is not None]
        _log_axis(lay["yaxis"], ys)
    else:
        lay = _layout("Force against applied displacement", "applied displacement u (mm)",
                      f"force F ({fu})")
    return {"data": data, "layout": lay}


def fig_study(spec: dict) -> dict:
    """A figure a study adds to its report (its optional ``figures(p)``, recorded in the metadata
    as ``figures``; docs/study-interface.md): ``title``, ``x_title``, ``y_title``, ``x_log``
    (bool) and ``series``, each a dict with ``label``, ``kind`` ('curve', 'points', 'band' or
    'image'), ``x`` and ``y`` (or ``y_lower`` and ``y_upper`` for a band; for an image ``z``, a
    list of rows bottom to top with values in [0, 1] drawn black to white (``reverse``: white to
    black), and its grid ``x0``, ``dx``, ``y0``, ``dy``). Units belong in the titles."""
    data, images = [], False
    for k, ser in enumerate(s for s in spec.get("series") or [] if isinstance(s, dict)):
        label = str(ser.get("label", f"series {k + 1}"))
        x = np.asarray(ser.get("x") or [], dtype=float)
        if ser.get("kind") == "band":
            lo = np.asarray(ser.get("y_lower") or [], dtype=float)
            hi = np.asarray(ser.get("y_upper") or [], dtype=float)
            n = min(len(x), len(lo), len(hi))
            if n == 0:
                continue
            data.append(_line(x[:n], hi[:n], label, "rgba(120,120,120,0.6)", width=0.8, legendgroup=f"s{k}",
                              showlegend=False, hoverinfo="skip"))
            data.append(_line(x[:n], lo[:n], label, "rgba(120,120,120,0.6)", width=0.8, legendgroup=f"s{k}",
                              fill="tonexty", fillcolor="rgba(150,150,150,0.30)"))
            continue
        if ser.get("kind") == "image":   # values on a regular grid: z rows bottom to top
            z = np.asarray(ser.get("z") or [], dtype=float)
            if z.ndim != 2 or z.size == 0:
                continue
            data.append({"type": "heatmap", "z": np.where(np.isfinite(z), z, None).tolist(), "name": label,
                         "x0": float(ser.get("x0", 0.0)), "dx": float(ser.get("dx", 1.0)),
                         "y0": float(ser.get("y0", 0.0)), "dy": float(ser.get("dy", 1.0)),
                         "colorscale": "Greys", "reversescale": bool(ser.get("reverse", False)), "zmin": 0.0, "zmax": 1.0,
                         "showscale": k == 0,
                         "hovertemplate": f"{label}<br>x %{{x:.3f}} mm, y %{{y:.3f}} mm: %{{z:.2f}}<extra></extra>"})
            images = True
            continue
        y = np.asarray(ser.get("y") or [], dtype=float)
        n = min(len(x), len(y))
        if n == 0:
            continue
        points = ser.get("kind") == "points"
        data.append(_line(x[:n], y[:n], label, (REF_COLORS if points else CASE_COLORS)[k % 5],
                          mode="markers" if points else "lines+markers", width=2.0))
    lay = _layout(str(spec.get("title", "")), str(spec.get("x_title", "")), str(spec.get("y_title", "")))
    if spec.get("x_log"):
        lay["xaxis"]["type"] = "log"
    if images:   # lengths drawn to scale
        lay["yaxis"]["scaleanchor"] = "x"
    return {"data": data, "layout": lay}


def _fig_step_size(history, cases, styles):
    data = []
    for c in cases:
        h = _case_rows(history, c["name"])
        h = h[h["step"].fillna(1) > 0] if len(h) else h
        if not len(h) or not h["step_size"].notna().any():
            continue
        st = styles[c["name"]]
        data.append(_line(h["load"], h["step_size"].abs(), c["label"], st["color"], dash=st["dash"],
                          mode="lines+markers", width=1.2, log_y=True, units=("mm", "mm"),
                          marker={"color": st["color"], "size": 4}))
    lay = _layout("Step size against displacement (Fig. 10)",
                  "applied displacement u (mm)", "step size |Δu| (mm)")
    _log_axis(lay["yaxis"], [v for t in data for v in t["y"] if v is not None])
    _legend_below(lay, rows=_legend_rows([t["name"] for t in data]))
    return {"data": data, "layout": lay}


def _fig_wf_alpha(history, cases, styles):
    data = []
    for c in cases:
        h = _case_rows(history, c["name"])
        if not len(h):
            continue
        st = styles[c["name"]]
        if h["fracture_energy"].notna().any():
            data.append(_line(h["load"], h["fracture_energy"], f"W_f – {c['label']}",
                              st["color"], dash="solid", legendgroup=c["name"],
                              units=("mm", "N mm")))
        if h["max_alpha"].notna().any():
            data.append(_line(h["load"], h["max_alpha"], f"max α – {c['label']}",
                              st["color"], dash="dot", yaxis="y2", legendgroup=c["name"],
                              units=("mm", "-")))
    lay = _layout("W_f and max α against displacement",
                  "applied displacement u (mm)", "fracture energy W_f (N mm)")
    lay["yaxis2"] = _axis("max α (-)", overlaying="y", side="right", range=[0, 1.05],
                          showgrid=False, mirror=False, tickmode="auto")
    lay["margin"]["r"] = 70
    _legend_below(lay, rows=_legend_rows([t["name"] for t in data]))
    if data and all((v or 0) == 0 for t in data for v in t["y"]):
        lay["annotations"] = [{"text": "no fracture in this run: W_f = 0 and α = 0 throughout",
                               "xref": "paper", "yref": "paper", "x": 0.5, "y": 0.6,
                               "showarrow": False, "font": {"size": 13, "color": "#555"}}]
    return {"data": data, "layout": lay}


def _fig_newton(history, cases, styles):
    data = []
    for c in cases:
        h = _case_rows(history, c["name"])
        h = h[h["step"].fillna(1) > 0] if len(h) else h
        if not len(h):
            continue
        st = styles[c["name"]]
        if h["newton_iterations"].notna().any():
            data.append(_line(h["step"], h["newton_iterations"], f"Newton iterations – {c['label']}",
                              st["color"], width=1.2, mode="lines", legendgroup=c["name"],
                              units=("-", "-")))
        if h["cutbacks"].notna().any():
            hc = h[h["cutbacks"].fillna(0) > 0]
            data.append({"type": "scatter", "mode": "markers", "x": _rs(hc["step"]),
                         "y": _rs(hc["cutbacks"]), "yaxis": "y2", "legendgroup": c["name"],
                         "name": f"cut-backs – {c['label']}",
                         "marker": {"color": st["color"], "symbol": "x", "size": 7}})
    lay = _layout("Newton iterations and cut-backs per accepted step", "accepted step (-)",
                  "Newton iterations per step (-)")
    lay["yaxis"]["rangemode"] = "tozero"
    lay["yaxis2"] = _axis("cut-backs per step (-)", overlaying="y", side="right",
                          showgrid=False, mirror=False, rangemode="tozero", tickmode="linear",
                          tick0=0, dtick=1)
    lay["margin"]["r"] = 70
    _legend_below(lay, rows=_legend_rows([t["name"] for t in data], 140))
    return {"data": data, "layout": lay}


def _fig_energies(history, cases, styles, features: dict | None = None):
    """Elastic energy, and the regularisation energy and W_f where the run has them (``features``
    of :func:`run_features`; None: all three)."""
    data = []
    spec = [("elastic_energy", "elastic", "solid"),
            ("regularisation_energy", "regularisation", "dot"),
            ("fracture_energy", "fracture W_f", "dash")]
    if features is not None:
        spec = [sp for sp in spec if (sp[0] != "regularisation_energy" or features.get("regulariser"))
                and (sp[0] != "fracture_energy" or features.get("fracture"))]
    for c in cases:
        h = _case_rows(history, c["name"])
        if not len(h):
            continue
        st = styles[c["name"]]
        for col, label, dash in spec:
            if h[col].notna().any():
                name = label if len(cases) == 1 else f"{label} – {c['label']}"
                data.append(_line(h["load"], h[col], name, st["color"] if len(cases) > 1 else
                                  {"elastic_energy": "#1f77b4", "regularisation_energy": "#2ca02c",
                                   "fracture_energy": "#d62728"}[col], dash=dash,
                                  legendgroup=c["name"], units=("mm", "N mm")))
    lay = _layout("Energies against applied displacement", "applied displacement u (mm)",
                  "energy (N mm)")
    lay["updatemenus"] = _log_toggle()
    lay["yaxis"]["exponentformat"] = "power"
    return {"data": data, "layout": lay}


def _fig_interpolation(meta, cases):
    params = meta.get("parameters") or {}
    gamma0s = []
    for c in cases:
        g = _param_value(c.get("parameters") or {}, "gamma0")
        if g is not None and g > 0:
            gamma0s.append((c["label"], g))
    if not gamma0s:
        g = _param_value(params, "gamma0")
        gamma0s = [(f"γ0 = {fmt(g if g else 1e-5)}", g if g else 1e-5)]
    a = _param_value(params, "gc_a") or 10.0
    b = _param_value(params, "gc_b") or 100.0
    rho = np.unique(np.concatenate([np.linspace(0, 0.1, 201), np.linspace(0.1, 1, 91)]))
    data = []
    seen = set()
    for k, (label, g) in enumerate(gamma0s):
        if g in seen:
            continue
        seen.add(g)
        color = CASE_COLORS[k % len(CASE_COLORS)]
        data.append(_line(rho, gamma_interpolation(rho, g), f"γ(ρ), γ0 = {fmt(g, 3)}", color, width=2,
                          legendgroup=f"g{k}"))
        data.append({"type": "scatter", "mode": "markers", "x": [0.0], "y": [float(g)],
                     "marker": {"color": color, "size": 9, "symbol": "circle-open",
                                "line": {"width": 2}}, "showlegend": False,
                     "legendgroup": f"g{k}", "name": f"γ(0) = γ0 = {fmt(g, 3)}",
                     "cliponaxis": False})
    lay1 = _layout("γ(ρ) = γ0 + (1 − γ0) ρ (Eq. 17)",
                   "pseudo-density ρ (-)", "γ(ρ) = K/K0 = G/G0 (-)", height=380)
    _log_axis(lay1["yaxis"], [1e-12, 1] if not gamma0s else [min(g for _, g in gamma0s), 1])
    _legend_below(lay1, rows=_legend_rows([t["name"] for t in data if t.get("showlegend", True)]))
    gc = gc_interpolation(rho, a, b)
    data2 = [_line(rho, gc, f"Gc(ρ)/Gc0, a = {fmt(a)}, b = {fmt(b)}", "#d62728", width=2.2),
             _line([0, 1], [a / 2, a / 2], f"void limit a/2 = {fmt(a / 2)}", "#777", dash="dot",
                   width=1.2)]
    lay2 = _layout("Gc(ρ)/Gc0 = a / (1 + exp(b ρ)) + ρ (Eq. 18)",
                   "pseudo-density ρ (-)", "Gc(ρ) / Gc0 (-)", height=380)
    _legend_below(lay2, rows=1)
    return ({"data": data, "layout": lay1}, {"data": data2, "layout": lay2},
            {"a": a, "b": b, "gamma0s": [g for _, g in gamma0s]})



def _fig_speed_error(entries: list[dict], title: str, size_label: str):
    pts = sorted((e for e in entries if _finite(e.get("wall_time_s"))),
                 key=lambda e: float(e["wall_time_s"]))
    data = []
    for key, name, color, sym in (("err_finest", "error vs finest", "#1f77b4", "circle"),
                                  ("err_published", "error vs published", "#d62728", "diamond")):
        p = [e for e in pts if _finite(e.get(key))]
        if not p:
            continue
        data.append({"type": "scatter", "mode": "markers+text+lines",
                     "x": _rs([e["wall_time_s"] for e in p]), "y": _rs([e[key] for e in p]),
                     "text": [e["label"] for e in p], "textposition": "top center",
                     "cliponaxis": False,
                     "name": name, "line": {"color": color, "width": 1, "dash": "dot"},
                     "marker": {"color": color, "size": 10, "symbol": sym},
                     "hovertemplate": "%{text}<br>wall time %{x} s<br>error %{y:.3g} %<extra></extra>"})
    lay = _layout(title, "wall time (s)", "relative error in peak force (%)")
    times = [float(e["wall_time_s"]) for e in pts if float(e["wall_time_s"]) > 0]
    if times and max(times) / min(times) > 20:
        lay["xaxis"]["type"] = "log"
    lay["yaxis"]["rangemode"] = "tozero"
    return {"data": data, "layout": lay}
