"""Alternating least squares on the similarity misfit (thesis appendix C-1, (C-2)–(C-8); reference [39])."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symid.fit.options import check_choice, check_float, check_int, check_seed, check_time_limit
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import SimilarityData, SimilarityEstimator, budget_message
from symid.fit.similarity.objective import SimilarityMisfit
from symid.fit.similarity.start import (
    INITS,
    initial_point,
    least_squares_theta,
    least_squares_transform,
    unknown_scale,
    working_problem,
)

__all__ = ["AlsSimilarity"]


class AlsSimilarity(SimilarityEstimator):
    """ALS: θ := argmin_θ F(θ, T) (C-8), T := argmin_T F(θ, T) (C-7), repeated.

    Stops when ‖z⁺ − z‖ / ‖z‖ ≤ ``tol`` with z = (θ, vec T) (thesis (6-31), tol = 1e-6)
    or after ``max_iter`` sweeps (10 000, the limit quoted in §6-7-2). Each sweep lowers
    F, but nothing keeps T invertible: ALS may converge to a singular T (§6-4-1).
    The step is measured on z / s, s the start's magnitudes
    (:func:`~symid.fit.similarity.start.unknown_scale`): in raw units the largest
    parameter decides it (measured, tests/test_units_invariance_similarity.py: a parameter
    declared in units of 1e±6 stopped ALS after 28–39 sweeps instead of 38, estimates up
    to 5e-5 apart), and the sweeps themselves are least squares that follow the units
    exactly.

    Parameters
    ----------
    model : StateSpaceModel
    data : SimilarityData
    aux_init : {"random", "model", "zero", "identity"}
        How (θ₀, T₀) follow from a start (:mod:`~symid.fit.similarity.start`).
    seed : int
        Seed of the random T₀.
    max_iter : int
        Sweeps at most (default 10 000, the limit quoted in §6-7-2).
    tol : float
        Stop when the relative step ‖z⁺ − z‖/‖z‖ is at most this (default 1e-6, thesis (6-31)).
    time_limit : float, optional
        Wall-time budget of one start in seconds, the start's (θ₀, T₀) included, checked
        after every sweep (status ``"time_limit"``; the last sweep's estimate is kept).
        Default: none.
    callback : callable, optional
        Called after every sweep with a :class:`symid.engine.scr.ScrProgress` (sweep,
        residual √(F/(‖𝔸‖² + ‖𝔹‖² + ‖ℂ‖²)) of the similarity equations, black-box misfit,
        elapsed seconds, θ); a true return value stops the start (status ``"stopped"``).
    verbose : bool
        Print one line per sweep (sweep, residual, misfit, elapsed). Default False.
    """

    method = "als"

    def __init__(self, model: Any, data: SimilarityData, *, aux_init: str = "random", seed: int = 0,
                 max_iter: int = 10000, tol: float = 1e-6, time_limit: float | None = None, callback: Any = None,
                 verbose: bool = False):
        self.init = check_choice("aux_init", aux_init, INITS)
        self.seed = check_seed("seed", seed)
        self.max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        self.tol = check_float("tol", tol, low=0, strict_low=True)
        self.time_limit = check_time_limit("time_limit", time_limit)
        self._progress_options(callback, verbose)
        self.model, self.data, self.frf = model, data, data.frf
        self.options = {"aux_init": aux_init, "seed": seed, "max_iter": max_iter, "tol": tol,
                        "time_limit": self.time_limit, "callback": None if callback is None else "given",
                        "verbose": self._verbose, "black_box": data.source}

    def solve(self, x0: np.ndarray, t0: float | None = None) -> tuple[np.ndarray, np.ndarray, int, str]:
        """(θ, T, sweeps, status) from the start x₀; status ``"converged"``, ``"max_iter"``, ``"time_limit"``
        (``time_limit`` seconds after ``t0``, default now) or ``"stopped"`` (by the callback)."""
        t0 = time.perf_counter() if t0 is None else t0
        deadline = None if self.time_limit is None else t0 + self.time_limit
        report = self.progress_reporter(t0)
        work = working_problem(self.model.maps, self.data.blackbox, x0)  # units of time and states of the start
        maps, bb = work.maps, work.bb
        objective = SimilarityMisfit(maps, bb)
        theta, T, _ = initial_point(self.init, x0, self.seed, maps, bb)
        s = unknown_scale(theta, T)
        z = np.concatenate([theta, T.ravel()]) / s
        for k in range(1, self.max_iter + 1):
            theta = least_squares_theta(maps, bb, T)
            T = least_squares_transform(maps, bb, theta)
            z_new = np.concatenate([theta, T.ravel()]) / s
            step = np.linalg.norm(z_new - z) / max(np.linalg.norm(z), 1e-300)
            z = z_new
            if not np.all(np.isfinite(z)):
                return theta, work.original_T(T), k, "max_iter"
            asked = report is not None and report(k, objective.relative_residual(theta, T), theta)
            if step <= self.tol:
                return theta, work.original_T(T), k, "converged"
            if asked:
                return theta, work.original_T(T), k, "stopped"
            if deadline is not None and time.perf_counter() >= deadline and k < self.max_iter:
                return theta, work.original_T(T), k, "time_limit"
        return theta, work.original_T(T), self.max_iter, "max_iter"

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start x₀; never raises on solver failure."""
        t0 = time.perf_counter()
        theta, T, k, status = self.solve(np.asarray(x0, dtype=float), t0)
        if status == "time_limit":
            msg = budget_message(self.time_limit, k, "sweep")
        else:
            msg = {"converged": f"relative step ≤ {self.tol:g} after {k} sweeps",
                   "max_iter": f"no convergence in {k} sweeps (relative step > {self.tol:g})",
                   "stopped": f"stopped by the callback after {k} sweeps"}[status]
        return self.transform_outcome(x0, theta, T, finished=status == "converged", status=status,
                                      message=msg, iterations=k, wall_time=time.perf_counter() - t0)
