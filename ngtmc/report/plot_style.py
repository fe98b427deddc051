"""The look of the reports' plotly figures: colours, fonts, axes, layouts, lines, legends, and the
thinning of long curves (used by :mod:`ngtmc.report.figures` and :mod:`ngtmc.report.figures3d`)."""
from __future__ import annotations

import math

import numpy as np

from ngtmc.report.numbers import _rs


#: Largest number of points drawn per history curve (longer curves are thinned, shape kept).
MAX_POINTS = 400


CASE_COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
               "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"]


REF_COLORS = ["#000000", "#555555", "#8c6d31", "#393b79", "#637939"]


ALPHA_COLORSCALE = [[0.0, "#e4ecf6"], [0.12, "#b9d3ea"], [0.3, "#fee391"], [0.5, "#fdae61"],
                    [0.75, "#e6492d"], [1.0, "#7f0000"]]


RHO_COLORSCALE = [[0.0, "#f7fbff"], [1.0, "#2b5b8a"]]


FONT = ("system-ui, -apple-system, 'Segoe UI', Roboto, 'Helvetica Neue', Arial, "
        "'Liberation Sans', sans-serif")


def _case_style(cases: list[dict]) -> dict[str, dict]:
    styles = {}
    k = 0
    for c in cases:
        if "classical" in c["name"].lower() or "classical" in c["label"].lower():
            styles[c["name"]] = {"color": "#000000", "dash": "dot"}
        else:
            styles[c["name"]] = {"color": CASE_COLORS[k % len(CASE_COLORS)], "dash": "solid"}
            k += 1
    return styles


def _axis(title: str, **kw) -> dict:
    ax = {"title": {"text": title}, "showgrid": True, "gridcolor": "#e6e6e6",
          "exponentformat": "power",
          "zeroline": False, "showline": True, "linecolor": "#444", "mirror": True,
          "ticks": "outside", "automargin": True}
    ax.update(kw)
    return ax


def _title(text: str) -> dict:
    """Title of a report figure: left-aligned, 15 pt."""
    return {"text": text, "x": 0.01, "xanchor": "left", "font": {"size": 15}}


def _font() -> dict:
    """Text style of a report figure."""
    return {"family": FONT, "size": 12, "color": "#222"}


def _layout(title: str, xtitle: str, ytitle: str, height: int = 430, **kw) -> dict:
    lay = {
        "title": _title(title),
        "font": _font(),
        "paper_bgcolor": "#ffffff", "plot_bgcolor": "#ffffff",
        "xaxis": _axis(xtitle), "yaxis": _axis(ytitle),
        "height": height, "margin": {"l": 70, "r": 30, "t": 50, "b": 60},
        "legend": {"bgcolor": "rgba(255,255,255,0.85)", "bordercolor": "#ccc", "borderwidth": 1},
        "hovermode": "closest",
    }
    lay.update(kw)
    return lay


def decimate(x, y, max_points: int = MAX_POINTS, log_y: bool = False) -> np.ndarray:
    """Indices of at most about ``max_points`` points keeping the shape of the curve (x, y).

    Points are kept evenly in arc length of the curve normalised by its x and y ranges (log10 of
    y when ``log_y``), so steep drops and spikes survive while long smooth stretches are thinned;
    the first, last, largest and smallest points are always kept.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    n = len(x)
    if n <= max_points:
        return np.arange(n)
    yy = np.log10(np.where(y > 0, y, np.nan)) if log_y else y.copy()
    ok = np.isfinite(x) & np.isfinite(yy)
    if not ok.any():
        return np.unique(np.linspace(0, n - 1, max_points).astype(int))
    xs = np.where(ok, x, np.nan)
    rx = np.nanmax(xs) - np.nanmin(xs) or 1.0
    ry = np.nanmax(np.where(ok, yy, np.nan)) - np.nanmin(np.where(ok, yy, np.nan)) or 1.0
    xn = np.nan_to_num((x - np.nanmin(xs)) / rx)
    yn = np.nan_to_num((yy - np.nanmin(np.where(ok, yy, np.nan))) / ry)
    ds = np.hypot(np.diff(xn), np.diff(yn)) + 1.0 / (4 * max_points)  # small floor: index spread
    s = np.r_[0.0, np.cumsum(ds)]
    cells = np.floor(s / s[-1] * (max_points - 4)).astype(int)
    keep = np.r_[True, cells[1:] != cells[:-1]]
    keep[-1] = True
    for i in (np.nanargmax(np.where(ok, y, np.nan)), np.nanargmin(np.where(ok, y, np.nan))):
        keep[int(i)] = True
    return np.flatnonzero(keep)


def _legend_rows(names: list, width_chars: int = 64) -> int:
    """Rough number of rows a horizontal legend needs for these entry names."""
    rows, used = 1, 0
    for n in names:
        w = len(str(n or "")) + 7
        if used and used + w > width_chars:
            rows, used = rows + 1, 0
        used += w
    return rows


def _legend_below(lay: dict, rows: int = 2) -> dict:
    """Put the legend under the plot (for half-width plots and plots with a right y axis)."""
    lay["legend"].update({"orientation": "h", "x": 0.0, "xanchor": "left", "y": -0.2,
                          "yanchor": "top", "font": {"size": 11}})
    lay["margin"]["b"] = 80 + 20 * rows
    lay["height"] = lay.get("height", 430) + 20 * rows
    return lay


def _log_axis(ax: dict, values) -> dict:
    """Log axis with ticks at whole decades when the data span two decades or more."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v > 0)]
    ax.update({"type": "log", "exponentformat": "power"})
    if v.size and v.max() / v.min() >= 100:
        decades = math.log10(v.max() / v.min())
        ax["dtick"] = 1 if decades <= 8 else int(math.ceil(decades / 8))
    return ax


def _line(x, y, name, color, dash="solid", width=2.0, mode="lines", yaxis=None,
          legendgroup=None, showlegend=True, sig=5, log_y=False, max_points=None,
          units: tuple[str, str] | None = None, **kw) -> dict:
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    idx = decimate(x, y, max_points or MAX_POINTS, log_y=log_y)
    x, y = x[idx], y[idx]
    tr = {"type": "scatter", "mode": mode, "x": _rs(x, sig), "y": _rs(y, sig), "name": name,
          "line": {"color": color, "dash": dash, "width": width}, "showlegend": showlegend}
    if "markers" in mode:
        tr["marker"] = {"color": color, "size": 6}
    if units:
        ux, uy = (f" {u}" if u and u not in ("-", "1") else "" for u in units)
        tr["hovertemplate"] = f"%{{x:.5g}}{ux}, %{{y:.5g}}{uy}<extra>%{{fullData.name}}</extra>"
    if yaxis:
        tr["yaxis"] = yaxis
    if legendgroup:
        tr["legendgroup"] = legendgroup
    tr.update(kw)
    return tr


def _log_toggle(axis: str = "yaxis", initial: str = "linear") -> list:
    return [{"type": "buttons", "direction": "left", "x": 1.0, "xanchor": "right", "y": 1.13,
             "yanchor": "top", "showactive": True, "active": 0 if initial == "linear" else 1,
             "bgcolor": "#f4f4f4", "bordercolor": "#bbb", "font": {"size": 11},
             "buttons": [{"label": "linear y", "method": "relayout", "args": [{f"{axis}.type": "linear"}]},
                         {"label": "log y", "method": "relayout", "args": [{f"{axis}.type": "log"}]}]}]
