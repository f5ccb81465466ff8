"""Gradient-based (quasi-Newton BFGS) minimisation of the similarity misfit (thesis appendix C-2; [28], [46])."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.optimize

from symid.fit.options import check_choice, check_float, check_int, check_seed
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import SimilarityData, SimilarityEstimator
from symid.fit.similarity.objective import SimilarityMisfit
from symid.fit.similarity.start import INITS, initial_point, unknown_scale

__all__ = ["GbSimilarity"]


class GbSimilarity(SimilarityEstimator):
    """GB: BFGS on F(θ, T)/scale over z = (θ, vec T) with the analytic gradients (C-12)–(C-18).

    The thesis runs MATLAB's ``fminunc`` with step and optimality tolerances 1e-6 on the
    raw F. Here the objective is divided by ‖𝔸‖² + ‖𝔹‖² + ‖ℂ‖² (so one tolerance fits
    every black box) and :func:`scipy.optimize.minimize` (BFGS) stops when the largest
    gradient entry is ≤ ``tol`` (default 1e-10: the valleys of F are long and flat, and
    a looser stop leaves parameter errors above the study's 1e-3 even in the right basin).
    BFGS works on z / s, s the start's magnitudes
    (:func:`~symid.fit.similarity.start.unknown_scale`), so that a parameter declared in
    other units is the same unknown (its first step and the gradient test alike).

    Parameters
    ----------
    model : StateSpaceModel
    data : SimilarityData
    aux_init : {"random", "model", "zero", "identity"}
        How (θ₀, T₀) follow from a start (:mod:`~symid.fit.similarity.start`).
    seed : int
        Seed of the random T₀.
    max_iter : int
        BFGS iteration limit (default 10 000).
    tol : float
        Gradient tolerance (scipy's ``gtol``).
    """

    method = "gb"

    def __init__(self, model: Any, data: SimilarityData, *, aux_init: str = "random", seed: int = 0,
                 max_iter: int = 10000, tol: float = 1e-10):
        self.init = check_choice("aux_init", aux_init, INITS)
        self.seed = check_seed("seed", seed)
        self.max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        self.gtol = check_float("tol", tol, low=0, strict_low=True)
        self.model, self.data, self.frf = model, data, data.frf
        self.objective = SimilarityMisfit(model.maps, data.blackbox)
        self.options = {"aux_init": aux_init, "seed": seed, "max_iter": max_iter, "tol": tol,
                        "black_box": data.source}

    def solve(self, x0: np.ndarray) -> scipy.optimize.OptimizeResult:
        """The raw :func:`scipy.optimize.minimize` result (``x`` = (θ, vec T)) from the start x₀."""
        theta, T, _ = initial_point(self.init, x0, self.seed, self.model.maps, self.data.blackbox)
        s = unknown_scale(theta, T)

        def scaled(y: np.ndarray) -> tuple[float, np.ndarray]:
            f, g = self.objective.value_and_grad(y * s)
            return f, g * s

        with np.errstate(over="ignore", invalid="ignore"):
            res = scipy.optimize.minimize(scaled, self.objective.join(theta, T) / s, jac=True, method="BFGS",
                                          options={"gtol": self.gtol, "maxiter": self.max_iter})
        res.x = res.x * s
        return res

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start x₀; never raises on solver failure."""
        t0 = time.perf_counter()
        res = self.solve(np.asarray(x0, dtype=float))
        theta, T = self.objective.split(res.x)
        return self.transform_outcome(x0, theta, T, finished=bool(res.success),
                                      status="converged" if res.success else "stopped",
                                      message=f"BFGS: {res.message} (F/scale = {res.fun:.3e})", iterations=int(res.nit),
                                      wall_time=time.perf_counter() - t0)
