"""Baselines of the thesis's comparison study (§6-7, appendix C) for the similarity transformation.

Both minimise the similarity misfit (C-1) over θ and T: ALS by alternating linear least
squares (C-2)–(C-8), GB by BFGS with the analytic gradients (C-12)–(C-18).
"""

from symid.baselines.als import AlsSimilarity
from symid.baselines.gb import GbSimilarity
from symid.baselines.objective import SimilarityMisfit

__all__ = ["AlsSimilarity", "GbSimilarity", "SimilarityMisfit"]
