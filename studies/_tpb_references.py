"""Digitised reference curves of the three-point-bending study (``studies/three_point_bending.py``).

The file name starts with an underscore: it is a helper, not a study.
"""
from __future__ import annotations

import numpy as np

from ngtmc.study import data_path


AMBATI_SOURCE = ("Ambati, Gerasimov & De Lorenzis (2015), Comput Mech 55:383, Fig. 22 (hybrid model), hand-digitised; "
                 "file from github tiantian0347/fractureX, docs/benchmarks/figures/loaddisp/"
                 "ambati_fig22_model5_tpb_digitized.csv @ ed1a6f68")
MIEHE_SOURCE = ("Three-point bending curve labelled 'Miehe' (Miehe et al. 2010), digitised; file from github "
                "CastillonMiguel/phasefieldx, examples/PhaseFieldFracture/reference_solutions/miehe_three_point.csv "
                "@ ed64055c (MIT licence)")

#: Miehe et al. (2010)'s three-point bending as study overrides, as the example that carries the
#: digitised Miehe curve sets it up (phasefieldx, examples/PhaseFieldFracture/plot_1714.py):
#: E = 20.8e3 MPa and nu = 0.3 (the study's), Gc = 5e-4 kN/mm = 0.5 N/mm (the study's 0.54), the
#: anisotropic formulation with the spectral split, u_y imposed on the beam top over a 0.5 mm window
#: at mid-span with the tangential displacement free, supports on 0.1 mm segments (the study's).
#: The band above the notch is widened to 0.3 mm on each side so that it holds the window. The length
#: scale is not certain (0.06 mm in that example's code, 0.006 mm in its text), so l0 keeps the
#: study's 0.03 mm; ``--set l0=0.06`` gives the other reading.
MIEHE_SET_UP = {"loading": "window", "window_width": 0.5, "band_half_width": 0.3, "Gc": 0.5,
                "split": "spectral", "formulation": "anisotropic"}


def reference_peaks() -> dict:
    """Peaks of the digitised curves, unshifted: {"ambati" or "miehe": (force in N/mm, load-point
    displacement in mm)}."""
    out = {}
    for name, (x, y) in reference_curves(0.0).items():
        i = int(np.argmax(y))
        out[name] = (float(y[i]), float(x[i]))
    return out


def reference_curves(gap: float) -> dict:
    """Ambati and Miehe curves shifted by the gap, in mm and N/mm: {name: (x, y)}."""
    import pandas as pd
    amb = pd.read_csv(data_path("tpb_ambati2015_fig22_fractureX_digitized_kN_mm.csv"))
    mie = np.loadtxt(data_path("tpb_miehe_phasefieldx_digitized_kN_mm.txt"))
    return {
        "ambati": (amb["u_mm"].to_numpy() + gap, 1000.0 * amb["force_kN"].to_numpy()),
        "miehe": (mie[:, 0] + gap, 1000.0 * mie[:, 1]),
    }
