"""The discrete problem on a mesh: finite-element spaces and integration rules (spaces), the energy
forms (energy_forms, displacement_energy), the displacement Newton (newton) and its line search
(energy_search), the phase field and its
dissipation, boundary conditions, the compiled-code cache, the BLAS threads of a step, NGSolve's sparse matrices as scipy's (sparse), and the Solver that holds one scene's
discrete state."""
from ngtmc.discrete.blas_threads import limited as blas_limited
from ngtmc.discrete.dissipation import Dissipation
from ngtmc.discrete.energy_forms import QuadraticPlus, merged_terms
from ngtmc.discrete.newton import (
    FLOOR_RTOL, NewtonOptions, NewtonResult, lifted_direction, meets, residual_split,
)
from ngtmc.discrete.phase_field import history_pieces, phase_field_piece
from ngtmc.discrete.solver import Solver
from ngtmc.discrete.spaces import bilinear_form, rules
from ngtmc.discrete.sparse import to_scipy

__all__ = [
    'Dissipation', 'FLOOR_RTOL', 'NewtonOptions', 'NewtonResult', 'QuadraticPlus', 'Solver',
    'bilinear_form', 'blas_limited', 'history_pieces', 'lifted_direction', 'meets', 'merged_terms',
    'phase_field_piece', 'residual_split', 'rules', 'to_scipy',
]
