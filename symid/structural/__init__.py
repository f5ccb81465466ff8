"""Structural identifiability of linear grey-box models (thesis §1-2, §6-6).

``identifiability(model)`` answers, before any estimation, which parameters can be
recovered from noise-free input-output data: per parameter "global", "local" (proven
not global), "local, global undetermined" or "none", the number of solutions,
identifiable combinations and a reparameterisation. The random point θ* is checked to
be generic and global claims are confirmed at a second point; the report is a
deterministic function of the model, the options and the seed.

Modules: :mod:`~symid.structural.summary` (exhaustive summary),
:mod:`~symid.structural.local` (exact Jacobian rank),
:mod:`~symid.structural.global_` (Gröbner basis, solution count),
:mod:`~symid.structural.witness` (numerical second solutions when the basis does not finish),
:mod:`~symid.structural.combinations`, :mod:`~symid.structural.report`,
:mod:`~symid.structural.numeric` (floating-point screen for large models),
:mod:`~symid.structural.order` (memoised grevlex for sympy's Gröbner bases),
:mod:`~symid.structural.deadline` (timeout without hangs).
"""

from symid.structural.analyse import (
    DEFAULT_TIMEOUT,
    check_local,
    identifiability,
    warn_if_not_identifiable,
)
from symid.structural.report import IdentifiabilityReport, NecessaryCondition
from symid.structural.summary import ExhaustiveSummary, exhaustive_summary

__all__ = [
    "DEFAULT_TIMEOUT",
    "ExhaustiveSummary",
    "IdentifiabilityReport",
    "NecessaryCondition",
    "check_local",
    "exhaustive_summary",
    "identifiability",
    "warn_if_not_identifiable",
]
