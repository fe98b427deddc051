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


def reference_curves(gap: float) -> dict:
    """Ambati and Miehe curves shifted by the gap, in mm and N/mm: {name: (x, y)}."""
    import pandas as pd
    amb = pd.read_csv(data_path("tpb_ambati2015_fig22_fractureX_digitized_kN_mm.csv"))
    mie = np.loadtxt(data_path("tpb_miehe_phasefieldx_digitized_kN_mm.txt"))
    return {
        "ambati": (amb["u_mm"].to_numpy() + gap, 1000.0 * amb["force_kN"].to_numpy()),
        "miehe": (mie[:, 0] + gap, 1000.0 * mie[:, 1]),
    }
