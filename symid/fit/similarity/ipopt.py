"""IPOPT on the similarity misfit (6-9): min over θ and T of ‖T𝔸 − A(θ)T‖² + ‖T𝔹 − B(θ)‖² + ‖ℂ − C(θ)T‖²."""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import casadi as ca
import numpy as np

from symid.engine.ipopt import ScaledIpopt, casadi_affine, iteration_reporter, positivity_bounds
from symid.fit.options import (
    check_bool,
    check_callback,
    check_choice,
    check_float,
    check_int,
    check_seed,
    check_time_limit,
)
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import SimilarityData, SimilarityEstimator, budget_message
from symid.fit.similarity.objective import SimilarityMisfit
from symid.fit.similarity.start import INITS, initial_point, io_time_normalised, unknown_scale, working_problem

__all__ = ["IpoptSimilarity", "IpoptSimilarityFRF"]


class IpoptSimilarity(SimilarityEstimator):
    """Nonlinear least squares (6-9) over z = (θ, vec T) with CasADi/IPOPT (exact Hessian).

    The objective is F(θ, T) / (‖𝔸‖² + ‖𝔹‖² + ‖ℂ‖²), the scaled misfit of
    :class:`~symid.fit.similarity.objective.SimilarityMisfit` (+ ‖𝔻 − D(θ)‖² when D holds parameters).
    Like ALS and GB it does not keep T invertible. IPOPT works on z / s, s the start's
    magnitudes (:func:`~symid.fit.similarity.start.unknown_scale`), on the objective over
    its start's decade and with a barrier no stronger than the start's gradient
    (:class:`~symid.engine.ipopt.ScaledIpopt`), so that a parameter declared in other
    units is the same unknown.

    Parameters
    ----------
    model : StateSpaceModel
    data : SimilarityData
    aux_init : {"random", "model", "zero", "identity"}
        How (θ₀, T₀) follow from a start (:mod:`~symid.fit.similarity.start`).
    seed : int
        Seed of the random T₀.
    positivity : bool
        Bound parameters declared positive below by 0 (default True).
    max_iter : int
        IPOPT iteration limit (default 3000).
    tol : float
        IPOPT tolerance (default 1e-12).
    time_limit : float, optional
        Wall-time budget of one start in seconds (IPOPT's ``max_wall_time``; status
        ``"Maximum_WallTime_Exceeded"``, the last iterate kept). Default: none.
    callback : callable, optional
        Called after every IPOPT iteration with a
        :class:`~symid.engine.ipopt.IpoptIteration` (iteration, objective F/(‖𝔸‖² + ‖𝔹‖²
        + ‖ℂ‖²), elapsed seconds, θ); a true return value stops the start (status
        ``"User_Requested_Stop"``).
    verbose : bool
        Print one line per iteration (iteration, objective, elapsed). Default False.
    """

    method = "ipopt"

    def __init__(self, model: Any, data: SimilarityData, *, aux_init: str = "random", seed: int = 0,
                 positivity: bool = True, max_iter: int = 3000, tol: float = 1e-12, time_limit: float | None = None,
                 callback: Any = None, verbose: bool = False):
        self.init = check_choice("aux_init", aux_init, INITS)
        self.seed = check_seed("seed", seed)
        positivity = check_bool("positivity", positivity)
        max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        tol = check_float("tol", tol, low=0, strict_low=True)
        time_limit = check_time_limit("time_limit", time_limit)
        callback = check_callback("callback", callback, "IpoptIteration")
        verbose = check_bool("verbose", verbose)
        self.model, self.data, self.frf = model, data, data.frf
        # the problem in the units of working_problem: inputs, outputs and time from the black box (fixed here),
        # the sizes of the model's states and of T from each start (values q = (sizes, α) given per solve)
        maps_t, bb = io_time_normalised(model.maps, data.blackbox)
        self.misfit_F = SimilarityMisfit(maps_t, bb)
        self.options = {"aux_init": aux_init, "seed": seed, "positivity": positivity, "max_iter": max_iter,
                        "tol": tol, "time_limit": time_limit, "callback": None if callback is None else "given",
                        "verbose": verbose, "black_box": data.source}
        report = iteration_reporter(callback, verbose)
        l, n = model.n_parameters, bb.n_states
        z = ca.MX.sym("z", l + n * n)
        theta = z[:l]
        T = ca.reshape(z[l:], n, n).T  # row-major vec T
        mats = {k: casadi_affine(maps_t[k], theta) for k in "ABCD" if k in maps_t}
        q = ca.MX.sym("q", n + 1)
        sizes, alpha = q[:n], q[n]
        w, wi = ca.diag(1 / sizes), ca.diag(sizes)
        f = (ca.sumsqr(T @ ca.DM(bb.A) - w @ mats["A"] @ wi @ T) + ca.sumsqr(alpha * T @ ca.DM(bb.B) - w @ mats["B"])
             + ca.sumsqr(ca.DM(bb.C) / alpha - mats["C"] @ wi @ T))
        if self.misfit_F.with_d:
            f = f + ca.sumsqr(ca.DM(bb.D) - mats["D"])
        f = f / (float(np.sum(bb.A**2)) + alpha**2 * float(np.sum(bb.B**2)) + float(np.sum(bb.C**2)) / alpha**2)
        lb, ub = positivity_bounds(model.positive, positivity, np.ones(l))
        self._lower = lb

        def on_iteration(info: Any) -> bool:  # the user sees θ, not z = (θ, vec T)
            return report(dataclasses.replace(info, theta=info.theta[:l].copy()))

        self._solver = ScaledIpopt("symid_ipopt_similarity", z, f,
                                   lower=np.concatenate([lb, np.full(n * n, -np.inf)]),
                                   upper=np.concatenate([ub, np.full(n * n, np.inf)]), max_iter=max_iter, tol=tol,
                                   hessian="exact", time_limit=time_limit, parameters=q,
                                   callback=None if report is None else on_iteration)

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start x₀; never raises on solver failure."""
        x0 = np.asarray(x0, dtype=float)
        t0 = time.perf_counter()
        work = working_problem(self.model.maps, self.data.blackbox, x0)
        theta0, T0, _ = initial_point(self.init, x0, self.seed, work.maps, work.bb)
        run = self._solver.solve(self.misfit_F.join(theta0, T0), scale=unknown_scale(theta0, T0, self._lower),
                                 values=np.append(work.sizes, work.alpha))
        theta, T = self.misfit_F.split(run.z)
        T = work.original_T(T)
        message = f"IPOPT: {run.status}{run.note}"
        if run.status == "Maximum_WallTime_Exceeded":
            message += "; " + budget_message(self.options["time_limit"], run.iterations)
        return self.transform_outcome(x0, theta, T, finished=run.finished, status=run.status,
                                      message=message, iterations=run.iterations,
                                      wall_time=time.perf_counter() - t0)


class IpoptSimilarityFRF(SimilarityEstimator):
    """IPOPT on the black box's frequency response (a second-order model), ranked by the black-box misfit.

    The second-order models of chapter 7 are not affine in state-space form, so (6-9)
    does not apply; nonlinear least squares on the black box's response on the misfit
    grid (:class:`~symid.fit.frf.ipopt.IpoptFRF`, with its options) does.

    Parameters
    ----------
    model : SecondOrderModel
    data : SimilarityData
    scale : array_like, optional
        Typical magnitude of each parameter; IPOPT works on θ / scale (default 1).
    positivity : bool
        Bound parameters declared ``positive=True`` below by 0 (default True).
    hessian : {"exact", "limited-memory"}
        Exact Hessian (default) or L-BFGS.
    max_iter : int
        IPOPT iteration limit (default 3000).
    tol : float
        IPOPT tolerance (default 1e-12).
    time_limit : float, optional
        Wall-time budget of one start in seconds (IPOPT's ``max_wall_time``; status
        ``"Maximum_WallTime_Exceeded"``). Default: none.
    callback : callable, optional
        Called after every IPOPT iteration with a
        :class:`~symid.engine.ipopt.IpoptIteration` (iteration, relative misfit to the
        black box's response, elapsed seconds, θ); a true return value stops the start
        (status ``"User_Requested_Stop"``).
    verbose : bool
        Print one line per iteration (iteration, misfit, elapsed). Default False.
    """

    method = "ipopt"

    def __init__(self, model: Any, data: SimilarityData, *, scale: Any = None, positivity: bool = True,
                 hessian: str = "exact", max_iter: int = 3000, tol: float = 1e-12, time_limit: float | None = None,
                 callback: Any = None, verbose: bool = False):
        from symid.fit.frf.ipopt import IpoptFRF

        self.model, self.data, self.frf = model, data, data.frf
        self.inner = IpoptFRF(model, data.frf, scale=scale, positivity=positivity, hessian=hessian,
                              max_iter=max_iter, tol=tol, time_limit=time_limit, callback=callback, verbose=verbose)
        self.options = {**self.inner.options, "black_box": data.source, "data": "black-box frequency response"}

    def run(self, x0: np.ndarray) -> StartOutcome:
        """IPOPT from x₀ on the black box's response; the outcome judged by the black-box misfit."""
        out = self.inner.run(x0)
        message = out.message
        if out.status == "Maximum_WallTime_Exceeded":
            message += "; " + budget_message(self.inner.options["time_limit"], out.iterations)
        return self.outcome(x0, out.theta, finished=out.finished, status=out.status, message=message,
                            iterations=out.iterations, wall_time=out.wall_time)
