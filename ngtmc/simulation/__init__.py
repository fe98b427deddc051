"""The load-stepping loop (loop: Simulation), its records and history (records), its state, in-run
refinement, run options and plugins (Plugin, Progress)."""
from ngtmc.simulation.history import HISTORY_COLUMNS, HISTORY_UNITS, force_unit, peak, peak_index
from ngtmc.simulation.loop import SCHEMES, Simulation, SimulationResult, StepFailure, check_stop_after_drop
from ngtmc.simulation.options import RUN_FOLDER_OPTIONS, check_options, simulation_keywords
from ngtmc.simulation.plugins import Plugin, Progress, RowCallbacks, emit

__all__ = [
    'HISTORY_COLUMNS', 'HISTORY_UNITS', 'Plugin', 'Progress', 'RUN_FOLDER_OPTIONS', 'RowCallbacks',
    'SCHEMES', 'Simulation', 'SimulationResult', 'StepFailure', 'check_options',
    'check_stop_after_drop', 'emit', 'force_unit', 'peak', 'peak_index', 'simulation_keywords',
]
