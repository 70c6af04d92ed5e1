"""Error norms, observed convergence rates and extrapolation."""

from .norms import (boundary_l2_error, dual_energy_norm, energy_error_dirichlet,
                    energy_error_neumann, neumann_functional)
from .rates import aitken, observed_rates

__all__ = ["boundary_l2_error", "dual_energy_norm", "energy_error_dirichlet", "energy_error_neumann",
           "neumann_functional", "observed_rates", "aitken"]
