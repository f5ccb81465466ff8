"""Gradient-based (quasi-Newton BFGS) minimisation of the similarity misfit (thesis appendix C-2; [28], [46])."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.optimize

from symid.baselines.objective import SimilarityMisfit
from symid.errors import ModelError
from symid.formulations.similarity_data import SimilarityData, transform_outcome
from symid.formulations.similarity_start import INITS, initial_point
from symid.result import StartOutcome

__all__ = ["GbSimilarity"]


class GbSimilarity:
    """GB: BFGS on F(θ, T)/scale over z = (θ, vec T) with the analytic gradients (C-12)–(C-18).

    The thesis runs MATLAB's ``fminunc`` with step and optimality tolerances 1e-6 on the
    raw F. Here the objective is divided by ‖𝔸‖² + ‖𝔹‖² + ‖ℂ‖² (so one tolerance fits
    every black box) and :func:`scipy.optimize.minimize` (BFGS) stops when the largest
    gradient entry is ≤ ``gtol`` (default 1e-10: the valleys of F are long and flat, and
    a looser stop leaves parameter errors above the study's 1e-3 even in the right basin).

    Parameters
    ----------
    model : StateSpaceModel
    data : SimilarityData
    init : {"random", "theta", "zero", "identity"}
    seed : int
    max_iter : int
        BFGS iteration limit (default 10 000).
    gtol : float
    """

    method = "gb"

    def __init__(self, model: Any, data: SimilarityData, *, init: str = "random", seed: int = 0,
                 max_iter: int = 10000, gtol: float = 1e-10):
        if init not in INITS:
            raise ModelError(f"init must be one of {', '.join(map(repr, INITS))}; got {init!r}")
        self.model, self.data, self.frf = model, data, data.frf
        self.init, self.seed = init, int(seed)
        self.max_iter, self.gtol = int(max_iter), float(gtol)
        self.objective = SimilarityMisfit(model.maps, data.blackbox)
        self.options = {"init": init, "seed": int(seed), "max_iter": int(max_iter), "gtol": float(gtol),
                        "black_box": data.source}

    def solve(self, x0: np.ndarray) -> scipy.optimize.OptimizeResult:
        """The raw :func:`scipy.optimize.minimize` result (``x`` = (θ, vec T)) from the start x₀."""
        theta, T, _ = initial_point(self.init, x0, self.seed, self.model.maps, self.data.blackbox)
        z0 = self.objective.join(theta, T)
        with np.errstate(over="ignore", invalid="ignore"):
            return scipy.optimize.minimize(self.objective.value_and_grad, z0, jac=True, method="BFGS",
                                           options={"gtol": self.gtol, "maxiter": self.max_iter})

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start x₀; never raises on solver failure."""
        t0 = time.perf_counter()
        res = self.solve(np.asarray(x0, dtype=float))
        theta, T = self.objective.split(res.x)
        return transform_outcome(self.model, self.data, x0, theta, T, bool(res.success), int(res.nit),
                                 time.perf_counter() - t0, f"BFGS: {res.message} (F/scale = {res.fun:.3e})")
