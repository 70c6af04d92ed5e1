"""FE/BE coupling: Nitsche interface terms (Chapter 2) with their error measures and the
coercivity threshold, the mortar projection (4.87).  The Chapter 2 model problems:
:mod:`hpfebe.scenes.interface`."""

from .coercivity import coercivity_threshold, inverse_constant, lemma_2_2_3_bound
from .errors import (BEDomainSetup, be_domain_errors, be_domain_errors_both,
                     be_solution_at, be_trace_energy_error, fe_errors)
from .mortar import MortarProjection
from .nitsche import (DEFAULT_ALPHA, DEFAULT_LAMBDA, InterfaceProblem, NitscheFEBE,
                      NitscheSolution)

__all__ = ["InterfaceProblem", "DEFAULT_ALPHA",
           "DEFAULT_LAMBDA", "MortarProjection", "NitscheFEBE", "NitscheSolution"]
__all__ += ["coercivity_threshold", "inverse_constant", "lemma_2_2_3_bound", "BEDomainSetup",
            "be_domain_errors", "be_domain_errors_both", "be_solution_at",
            "be_trace_energy_error", "fe_errors"]
