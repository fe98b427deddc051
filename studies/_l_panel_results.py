"""Post-processing of the L-panel study (``studies/l_panel.py``): the key numbers of a case's
history (forces in N for the whole 100 mm panel, loads in mm, W_f in N mm).

The file name starts with an underscore: it is a helper, not a study.
"""
from __future__ import annotations

import numpy as np

from ngtmc.simulation import peak_index
from ngtmc.studies._l_panel_geometry import effective_gap, effective_schedule


def monotonic_numbers(hist) -> dict:
    """Peak of the monotonic case and whether it was passed: ``first_peak_force`` (N) and
    ``first_peak_load`` (mm, the peak of ngtmc), ``final_force``, ``drop_after_peak`` (1 - final
    force / peak force) and ``peak_passed`` (the force fell by more than 5 % after the peak)."""
    h = hist.sort_values("step").reset_index(drop=True)
    j = peak_index(h["force"])
    if j is None:
        return {}
    fp, ff = float(h["force"].iloc[j]), float(h["force"].iloc[-1])
    drop = 1.0 - ff / fp if fp > 0 else float("nan")
    return {"first_peak_force": fp, "first_peak_load": float(h["load"].iloc[j]), "final_force": ff,
            "final_load": float(h["load"].iloc[-1]), "drop_after_peak": drop,
            "peak_passed": bool(j < len(h) - 1 and drop > 0.05),
            "wf_final": float(h["fracture_energy"].iloc[-1]), "max_alpha_final": float(h["max_alpha"].iloc[-1])}


def phases(hist, p: dict, settle: float = 0.25) -> dict:
    """Split a history (DataFrame of one case) into the schedule's phases and return the key numbers.

    first_peak_force / first_peak_load: largest force while loading to 6.3 mm (at the turning point
    if the peak was not reached); force_first_loading_at_gap: force at u = l_h on the first loading
    (interpolated); force_unloaded_at_gap: force at the end of unloading (u = l_h);
    reload_peak_force / reload_peak_load: largest force while reloading to 7 mm.

    Damage while unloading: the single-pass staggered scheme lags damage by one step, and the step
    rule (Eq. 20) makes the first unloading steps tiny when W_f grew fast just before the turning
    point, so the damage driven by the last loading states is still being applied in the first
    unloading steps, at loads within a few hundredths of a mm of the turning point.
    ``unload_wf_change`` and ``unload_max_alpha_change`` are therefore measured over the unloading
    steps after the first ``settle`` fraction of the unloading path (default 25 %, 0.075 mm);
    ``unload_wf_lag`` is the growth of W_f before that (from the turning point).
    """
    sched = effective_schedule(p)
    u1, u2, u3 = sched[1], sched[2], sched[3]
    h = hist.sort_values("step").reset_index(drop=True)
    load = h["load"].to_numpy()
    idx = np.arange(len(load))
    i1 = int(np.argmax(np.isclose(load, u1, atol=1e-9)))
    rest = np.where(np.isclose(load, u2, atol=1e-9) & (idx > i1))[0]
    i2 = int(rest[0]) if rest.size else len(load) - 1
    first = h.iloc[: i1 + 1]
    unload = h.iloc[i1: i2 + 1]
    reload = h.iloc[i2:]
    j = peak_index(first["force"]) or 0  # the peak of ngtmc (largest finite force), row 0 if none
    gap = effective_gap(p)
    u_settle = u1 - settle * abs(u1 - u2)
    settled = unload[unload["load"] <= u_settle + 1e-12]
    out = {
        "first_peak_force": float(first["force"].iloc[j]), "first_peak_load": float(first["load"].iloc[j]),
        "first_peak_before_turning_point": bool(j < len(first) - 1 and first["force"].iloc[-1] < first["force"].iloc[j]),
        "force_at_turning_point": float(first["force"].iloc[-1]),
        "force_first_loading_at_gap": float(np.interp(gap, first["load"], first["force"])),
        "force_unloaded_at_gap": float(unload["force"].iloc[-1]),
        "unload_steps": int(len(unload) - 1),
        "wf_at_turning_point": float(unload["fracture_energy"].iloc[0]),
        "max_alpha_at_turning_point": float(unload["max_alpha"].iloc[0]),
        "unload_wf_lag": float(settled["fracture_energy"].iloc[0] - unload["fracture_energy"].iloc[0]) if len(settled) else float("nan"),
        "unload_wf_change": float(settled["fracture_energy"].iloc[-1] - settled["fracture_energy"].iloc[0]) if len(settled) else float("nan"),
        "unload_max_alpha_change": float(settled["max_alpha"].iloc[-1] - settled["max_alpha"].iloc[0]) if len(settled) else float("nan"),
        "unload_settled_steps": int(len(settled)),
        "completed": bool(np.isclose(load[-1], u3)),
    }
    if len(reload) > 1:
        k = peak_index(reload["force"]) or 0
        out.update({"reload_peak_force": float(reload["force"].iloc[k]), "reload_peak_load": float(reload["load"].iloc[k]),
                    "final_force": float(reload["force"].iloc[-1]),
                    "wf_final": float(reload["fracture_energy"].iloc[-1])})
    return out
