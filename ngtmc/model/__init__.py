"""The equations of the model, free of any mesh: hyperelastic materials and their energies (materials),
the AT-2 fracture energy and degradation (fracture), the third-medium contact regulariser
(regularisation), and the tension/compression splits of the strain energy (splits)."""
from ngtmc.model.materials import (
    Material, check_number, deformation_gradient, full_deformation_gradient, gamma_interpolation,
    gc_interpolation, psi_dev, psi_plus, psi_vol,
)
from ngtmc.model.splits import DEFAULT_FORMULATION, DEFAULT_SPLIT, FORMULATIONS, SPLITS, check_split

__all__ = [
    'DEFAULT_FORMULATION', 'DEFAULT_SPLIT', 'FORMULATIONS', 'Material', 'SPLITS', 'check_number',
    'check_split', 'deformation_gradient', 'full_deformation_gradient', 'gamma_interpolation',
    'gc_interpolation', 'psi_dev', 'psi_plus', 'psi_vol',
]
