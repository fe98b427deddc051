"""How a load path is walked: adaptive step control (control), the step schemes (schemes), and path
following with its predictor, step sizing and refinement."""
