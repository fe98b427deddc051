"""Reference data of the L-panel study (``studies/l_panel.py``): Winkler's experiments (scatter
band and test series A, whole 100 mm panel) and the source of Ambati et al. 2015's peak.

The file name starts with an underscore: it is a helper, not a study.
"""
from __future__ import annotations

from ngtmc.study import data_path
from ngtmc.studies._l_panel_geometry import effective_gap


WINKLER_BAND_SOURCE = ("Winkler L-shaped panel experiments, scatter band (Winkler et al. 2004 IJNAMG Fig. 10 and "
                       "Winkler et al. 2001 Fig. 5), digitised; file from github fpled/MYCODE, examples/phasefield/"
                       "dataLshapedPanelWinkler/force_displacement_Win04_fig10_Win01_fig5.csv @ 626a87f0")
WINKLER_A_SOURCE = ("Winkler PhD thesis (2001), Abb. 7.12, test series A; file from github PSAAPGroupLinder/"
                    "lShapedPanelBenchmark, experimental/Winkler_Abb-7.12_Versuchsreihe-A.csv @ 70a51eeb")


def references(p: dict) -> list[dict]:
    """Winkler band and series A (whole 100 mm panel, N), shifted by the gap, scaled to the scene
    thickness (thickness / 100 mm)."""
    import pandas as pd
    gap = effective_gap(p)
    scale = float(p["thickness"]) / 100.0
    band = pd.read_csv(data_path("lshape_winkler_experiment_envelope_kN_mm.csv"))
    a = pd.read_csv(data_path("lshape_winkler_experiment_seriesA_N_mm.csv"))
    unit = "N" if scale == 1.0 else f"N per {float(p['thickness']):g} mm"
    return [
        {"label": "Winkler experiments, scatter band (shifted by the gap)", "source": WINKLER_BAND_SOURCE,
         "kind": "band", "x": (band["U_mm"] + gap).tolist(), "y_lower": (1000 * scale * band["F_lb_kN"]).tolist(),
         "y_upper": (1000 * scale * band["F_ub_kN"]).tolist(), "x_unit": "mm", "y_unit": unit},
        {"label": "Winkler series A (shifted by the gap)", "source": WINKLER_A_SOURCE, "kind": "curve",
         "x": (a["#x"] + gap).tolist(), "y": (scale * a["Winkel-A"]).tolist(), "x_unit": "mm", "y_unit": unit},
    ]


AMBATI_SOURCE = ("Ambati et al. 2015 (Comput. Mech. 55), Fig. 19, L-shaped panel with the same AT-2 parameters: "
                 "first-loading peak about 16 kN, read as the whole 100 mm panel (see the study docstring)")
