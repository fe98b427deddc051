"""How a load path is walked: adaptive step control (control), the step schemes (schemes), and path
following with its predictor, step sizing and refinement."""
from ngtmc.stepping.control import AdaptiveStepControl, ControlState, Schedule
from ngtmc.stepping.path import N_S
from ngtmc.stepping.schemes import PATH_STEPS, SCHEMES, StepSchemes, alpha_u_passes

__all__ = [
    'AdaptiveStepControl', 'ControlState', 'N_S', 'PATH_STEPS', 'SCHEMES', 'Schedule',
    'StepSchemes', 'alpha_u_passes',
]
