"""Error norms, observed and fitted convergence rates, log-log interpolation and
extrapolation."""

from .norms import (boundary_l2_error, dual_energy_norm, energy_error_dirichlet,
                    energy_error_neumann, energy_norm, neumann_functional)
from .rates import aitken, fitted_rate, loglog_interpolate, observed_rates

__all__ = ["boundary_l2_error", "dual_energy_norm", "energy_error_dirichlet",
           "energy_error_neumann", "energy_norm", "neumann_functional", "observed_rates",
           "loglog_interpolate", "fitted_rate", "aitken"]
