"""Self-contained HTML reports of ngtmc runs, rendered from the recorded files only.

A run directory (see ``docs/run-directory.md``) holds ``metadata.json``, ``history.csv`` and
optionally ``snapshots.npz``. :func:`render_report` turns one such folder into
``report.html``; :func:`render_index` writes ``index.html`` for a folder of runs, linking every
run and comparing runs of the same study (wall time against error in peak force).

Nothing is re-run and NGSolve is not imported: the report needs numpy, pandas, jinja2 and plotly
only. The pages are fully offline: plotly's JavaScript is embedded once per page and nothing is
requested from any other host.

Units follow the run directory: lengths and displacements in mm, forces in the unit recorded in
``metadata["force_unit"]`` (N/mm per thickness in 2D), energies in N mm, times in s.

Modules: :mod:`.loading` (reading a run folder), :mod:`.numbers` (formatting with units,
features, key numbers, speed against error), :mod:`.figures` (plotly figures; their look in :mod:`.plot_style`),
:mod:`.page` (``report.html``), :mod:`.index` (``index.html``), :mod:`.command` (``python -m
ngtmc.report``). Every name is importable from ``ngtmc.report`` as before.

Public functions
----------------
- ``load_run(run_dir) -> (metadata: dict, history: pandas.DataFrame, snapshots: dict | None)``
- ``render_report(run_dir, output=None) -> pathlib.Path``
- ``render_index(reports_dir) -> pathlib.Path``
- ``report_main(argv=None) -> int``  (command line: ``ngtmc report RUN_DIR``)
"""
from __future__ import annotations

from ngtmc.report.loading import (  # noqa: F401
    HISTORY_COLUMNS, load_run, _load, _case_list, _param_value, _case_rows, _find_runs)
from ngtmc.model import (  # noqa: F401  (Eqs. 17 and 18 under the report's names)
    gamma_interpolation as gamma_of_rho, gc_interpolation as gc_ratio_of_rho)
from ngtmc.report.numbers import (  # noqa: F401
    _finite, fmt, fmt_u, _pct, fmt_duration, fmt_date, _rs, _UNIT_PREFIX,
    unit_factor, _any_positive, run_features, overrides_text, physics_key, case_numbers, _targets_for,
    key_number_rows, reference_peaks, _published_peak, speed_error_rows, TIME_SPLIT_PARTS,
    time_split_rows, _run_speed_entries)
from ngtmc.report.plot_style import (  # noqa: F401
    MAX_POINTS, CASE_COLORS, REF_COLORS, ALPHA_COLORSCALE, RHO_COLORSCALE, FONT, _case_style, _axis, _layout, decimate,
    _legend_rows, _legend_below, _log_axis, _line, _log_toggle)
from ngtmc.report.figures import (  # noqa: F401
    _fig_force, _fig_step_size, _fig_wf_alpha, _fig_newton, _fig_energies, _fig_interpolation, _fig_speed_error)
from ngtmc.report.mesh_frames import (  # noqa: F401
    MAX_FRAMES, MAX_VERTEX_FRAMES, MAX_EDGE_TRIANGLES, N_LEVELS, _nice_scale, deformation_scale, _frame_indices,
    mesh_payload, _same_mesh, _level_colors)
from ngtmc.report.page import (  # noqa: F401
    _env, _script_json, _json_default, _clean, _plotly_js, _status_banner, _parameter_rows, _mesh_rows,
    render_report)
from ngtmc.report.index import (  # noqa: F401
    render_index)
from ngtmc.report.command import (  # noqa: F401
    report_main)

__all__ = ["load_run", "render_report", "render_index", "report_main",
           "HISTORY_COLUMNS", "gamma_of_rho", "gc_ratio_of_rho", "run_features"]
