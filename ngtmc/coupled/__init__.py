"""The monolithic Newton on displacement and phase field together: its solve (monolithic), one
iteration (iteration) and its linear solvers (linear)."""
