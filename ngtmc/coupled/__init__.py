"""The monolithic Newton on displacement and phase field together: its solve (monolithic), one
iteration (iteration) and its linear solvers (linear)."""
from ngtmc.coupled.linear import CoupledLinearSolver, LINEAR_SOLVERS
from ngtmc.coupled.monolithic import CoupledNewton

__all__ = ['CoupledLinearSolver', 'CoupledNewton', 'LINEAR_SOLVERS']
