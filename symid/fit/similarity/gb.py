"""Gradient-based (quasi-Newton BFGS) minimisation of the similarity misfit (thesis appendix C-2; [28], [46])."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.optimize

from symid.fit.options import check_choice, check_float, check_int, check_seed, check_time_limit
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import SimilarityData, SimilarityEstimator, budget_message
from symid.fit.similarity.objective import SimilarityMisfit
from symid.fit.similarity.start import INITS, initial_point, unknown_scale, working_problem

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
    time_limit : float, optional
        Wall-time budget of one start in seconds, the start's (θ₀, T₀) included, checked
        after every BFGS iteration (status ``"time_limit"``; the last iterate is kept).
        Default: none.
    callback : callable, optional
        Called after every BFGS iteration with a :class:`symid.engine.scr.ScrProgress`
        (iteration, residual √(F/(‖𝔸‖² + ‖𝔹‖² + ‖ℂ‖²)) of the similarity equations,
        black-box misfit, elapsed seconds, θ); a true return value stops the start
        (status ``"stopped"``).
    verbose : bool
        Print one line per iteration (iteration, residual, misfit, elapsed). Default False.
    """

    method = "gb"

    def __init__(self, model: Any, data: SimilarityData, *, aux_init: str = "random", seed: int = 0,
                 max_iter: int = 10000, tol: float = 1e-10, time_limit: float | None = None, callback: Any = None,
                 verbose: bool = False):
        self.init = check_choice("aux_init", aux_init, INITS)
        self.seed = check_seed("seed", seed)
        self.max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        self.gtol = check_float("tol", tol, low=0, strict_low=True)
        self.time_limit = check_time_limit("time_limit", time_limit)
        self._progress_options(callback, verbose)
        self.model, self.data, self.frf = model, data, data.frf
        self.objective = SimilarityMisfit(model.maps, data.blackbox)
        self.options = {"aux_init": aux_init, "seed": seed, "max_iter": max_iter, "tol": tol,
                        "time_limit": self.time_limit, "callback": None if callback is None else "given",
                        "verbose": self._verbose, "black_box": data.source}

    def solve(self, x0: np.ndarray, t0: float | None = None) -> scipy.optimize.OptimizeResult:
        """The raw :func:`scipy.optimize.minimize` result (``x`` = (θ, vec T)) from the start x₀; ``cut`` is
        ``"time_limit"`` (``time_limit`` seconds after ``t0``, default now) or ``"stopped"`` (by the callback)
        when BFGS was cut short before its own stopping rule (``x`` is then the last iterate), else ``None``."""
        t0 = time.perf_counter() if t0 is None else t0
        deadline = None if self.time_limit is None else t0 + self.time_limit
        report = self.progress_reporter(t0)
        work = working_problem(self.model.maps, self.data.blackbox, x0)  # units of time and states of the start
        objective = SimilarityMisfit(work.maps, work.bb)
        theta, T, _ = initial_point(self.init, x0, self.seed, work.maps, work.bb)
        s = unknown_scale(theta, T)
        l = theta.size
        state = {"k": 0, "cut": None}

        def scaled(y: np.ndarray) -> tuple[float, np.ndarray]:
            f, g = objective.value_and_grad(y * s)
            return f, g * s

        def each(intermediate_result: scipy.optimize.OptimizeResult) -> None:
            """After every BFGS iteration: report it; stop at the deadline or when the callback asks, unless the
            iterate meets BFGS's own stopping rule (the gradient test it runs next)."""
            state["k"] += 1
            y = intermediate_result.x
            asked = report is not None and report(state["k"], np.sqrt(max(float(intermediate_result.fun), 0.0)),
                                                  (y * s)[:l])
            late = deadline is not None and time.perf_counter() >= deadline and state["k"] < self.max_iter
            if (asked or late) and not np.max(np.abs(scaled(y)[1]), initial=0.0) <= self.gtol:
                state["cut"] = "stopped" if asked else "time_limit"
                raise StopIteration

        with np.errstate(over="ignore", invalid="ignore"):
            res = scipy.optimize.minimize(scaled, objective.join(theta, T) / s, jac=True, method="BFGS",
                                          callback=each if report is not None or deadline is not None else None,
                                          options={"gtol": self.gtol, "maxiter": self.max_iter})
        res.x = res.x * s
        theta, T = objective.split(res.x)
        res.x = objective.join(theta, work.original_T(T))  # T for the black box as given
        res.cut = state["cut"]
        return res

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start x₀; never raises on solver failure."""
        t0 = time.perf_counter()
        res = self.solve(np.asarray(x0, dtype=float), t0)
        theta, T = self.objective.split(res.x)
        k = int(res.nit)
        if res.cut == "time_limit":
            status, message, finished = "time_limit", budget_message(self.time_limit, k), False
        elif res.cut == "stopped":
            status, message, finished = "stopped", f"stopped by the callback after {k} iterations", False
        else:
            finished = bool(res.success)  # BFGS's own rule; "stopped" is the callback's, as in SCR
            status = "converged" if finished else ("max_iter" if res.status == 1 else "not_converged")
            message = f"BFGS: {res.message}"
        return self.transform_outcome(x0, theta, T, finished=finished, status=status,
                                      message=f"{message} (F/scale = {res.fun:.3e})", iterations=k,
                                      wall_time=time.perf_counter() - t0)
