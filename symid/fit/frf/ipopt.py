"""IPOPT on the frequency-response misfit Σᵢ ‖Hᵢ − H(ωᵢ, θ)‖²_F (noise-weighted when the variance is known)."""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from symid.engine.ipopt import HESSIANS, ScaledIpopt, casadi_frf, iteration_reporter
from symid.fit.bounded import on_bounds
from symid.fit.frf.misfit import FrfEstimator, NoiseWeighted
from symid.fit.options import (
    check_bool,
    check_callback,
    check_choice,
    check_float,
    check_int,
    check_scale,
    check_start_bounds,
    check_time_limit,
    moved_onto_bounds,
    parameter_bounds,
)
from symid.fit.result import StartOutcome

__all__ = ["IpoptFRF", "frf_objective"]


def frf_objective(model: Any, data: Any, theta: Any, weights: np.ndarray | None = None) -> Any:
    """The relative misfit Σᵢ ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σᵢ ‖Hᵢ‖²_F as a CasADi expression in ``theta``.

    With ``weights`` (one per entry of H, :func:`symid.fit.frf.misfit.frf_weights`),
    Σ w |Hᵢ − H(ωᵢ, θ)|² / Σ w |Hᵢ|² entry by entry, as
    :func:`symid.fit.frf.misfit.relative_misfit` computes it.
    """
    Hr, Hi = casadi_frf(model, theta, np.asarray(data.w))
    H = np.asarray(data.H)
    f = 0
    if weights is None:
        for i in range(len(Hr)):
            f = f + ca.sumsqr(Hr[i] - ca.DM(H[i].real)) + ca.sumsqr(Hi[i] - ca.DM(H[i].imag))
        return f / (float(np.sum(np.abs(H) ** 2)) or 1.0)
    wts = np.asarray(weights, dtype=float).reshape(H.shape)
    for i in range(len(Hr)):
        W = ca.DM(wts[i])
        f = f + ca.sum1(ca.sum2(W * ((Hr[i] - ca.DM(H[i].real)) ** 2 + (Hi[i] - ca.DM(H[i].imag)) ** 2)))
    return f / (float(np.sum(wts * np.abs(H) ** 2)) or 1.0)


class IpoptFRF(NoiseWeighted, FrfEstimator):
    """Nonlinear least squares on a frequency response with CasADi/IPOPT, built once, run per start.

    The objective is the relative misfit Σᵢ ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σᵢ ‖Hᵢ‖²_F (real and
    imaginary parts), weighted by the noise variance of every line when it is known
    (``variance``), so its scale does not depend on the units of H. Exact first and
    second derivatives come from CasADi's automatic differentiation. IPOPT works on
    θ / s, with s the start's own magnitudes unless ``scale`` is given, on the objective
    divided by its start's decade, and with a barrier on the bounds that starts no
    stronger than the objective's pull at the start
    (:class:`symid.engine.ipopt.ScaledIpopt`): the estimate does not depend on the
    units of θ, ω or H, and a start at a converged fit stays there.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData
    scale : array_like, optional
        Typical magnitude of each parameter (one number or one per parameter); IPOPT
        works on θ / scale. Default: each start's own magnitudes |θ₀| (where θ₀ is 0:
        the largest finite bound, else 1).
    bounds : dict or array_like, optional
        Lower and upper bounds: a dict by parameter name of (low, high) (``None`` for an
        open side), or an (l, 2) array. Combined with ``positivity``. A start outside
        them is moved onto them (the outcome's message says so; an explicit ``x0`` of
        :func:`symid.identify` outside them is an :class:`~symid.errors.OptionError`).
    positivity : bool, optional
        Bound parameters declared ``positive=True`` below by 0. Default True.
    variance : "data", None or array_like, optional
        Noise weighting of the FRF criterion, Σᵢ Σ_jk |Hᵢ,jk − H(ωᵢ, θ)_jk|² / σ²ᵢ,jk
        (the maximum-likelihood criterion for independent complex Gaussian noise on H,
        as frequency-domain toolboxes such as FDIDENT use): ``"data"`` (default) takes
        σ² from the data's per-line variance (``FrequencyData.variance``, e.g. from
        :func:`symid.estimate_frf`) and weighs every line alike when the data have none;
        ``None`` weighs every line alike; an array gives σ², one per frequency (s,) or per
        entry (s, p, m). With a variance, the uncertainty of θ̂ uses it as the noise
        (unless ``noise_std`` is given) and the fit is judged against the misfit that
        noise leaves.
    hessian : {"exact", "limited-memory"}, optional
        Exact Hessian (default) or L-BFGS.
    max_iter : int, optional
        IPOPT iteration limit (default 3000).
    tol : float, optional
        IPOPT convergence tolerance (default 1e-12 on the relative objective).
    time_limit : float, optional
        Wall-time budget of one start in seconds (IPOPT's ``max_wall_time``). Default: none.
    callback : callable, optional
        Called after every IPOPT iteration with a
        :class:`~symid.engine.ipopt.IpoptIteration` (iteration, misfit, elapsed seconds,
        θ); a true return value stops the start (status ``"User_Requested_Stop"``).
    verbose : bool, optional
        Print one line per iteration (iteration, misfit, elapsed). Default False.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.ipopt import IpoptFRF
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 5))
    >>> out = IpoptFRF(model, frf).run(np.array([1.5, 0.4, 2.0]))
    >>> np.round(out.theta, 6).tolist(), out.success, out.status
    ([2.0, 0.5, 3.0], True, 'Solve_Succeeded')

    Bounds by name, and progress through a callback:

    >>> seen = []
    >>> est = IpoptFRF(model, frf, bounds={"m": (1.0, 10.0)}, callback=seen.append)
    >>> out = est.run(np.array([1.5, 0.4, 2.0]))
    >>> seen[0].iteration, len(seen) == out.iterations + 1, bool(seen[-1].objective < 1e-20)
    (0, True, True)
    """

    method: ClassVar[str] = "ipopt"

    def __init__(self, model: Any, data: Any, *, scale: Any = None, bounds: Any = None, positivity: bool = True,
                 variance: Any = "data", hessian: str = "exact", max_iter: int = 3000, tol: float = 1e-12,
                 time_limit: float | None = None, callback: Any = None, verbose: bool = False):
        self.model, self.data = model, data
        l = model.n_parameters
        self.scale = None if scale is None else check_scale("scale", scale, l)
        positivity = check_bool("positivity", positivity)
        hessian = check_choice("hessian", hessian, HESSIANS)
        max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        tol = check_float("tol", tol, low=0, strict_low=True)
        time_limit = check_time_limit("time_limit", time_limit)
        verbose = check_bool("verbose", verbose)
        check_callback("callback", callback, "IpoptIteration")
        self.lower, self.upper = parameter_bounds(model, bounds, positivity)
        label = self.set_variance(variance)  # weights, the given noise and the noise floor it declares
        named = {n: [float(lo), float(hi)] for n, lo, hi in zip(model.parameter_names, self.lower, self.upper,
                                                                strict=True) if np.isfinite(lo) or np.isfinite(hi)}
        self.options = {"scale": "start" if self.scale is None else self.scale.tolist(),
                        "bounds": named or None, "positivity": positivity,
                        "variance": label, "hessian": hessian,
                        "max_iter": max_iter, "tol": tol, "time_limit": time_limit,
                        "callback": None if callback is None else "given", "verbose": verbose}
        report = iteration_reporter(callback, verbose)
        theta = ca.MX.sym("theta", l)
        self._solver = ScaledIpopt("symid_ipopt_frf", theta, frf_objective(model, data, theta, self.line_weights),
                                   lower=self.lower, upper=self.upper, scale=self.scale, max_iter=max_iter, tol=tol,
                                   hessian=hessian, time_limit=time_limit, callback=report)

    # -- starts ---------------------------------------------------------------------------------
    def check_start(self, x0: Any) -> None:
        """Refuse a start outside the bounds (an :class:`OptionError` naming the parameter)."""
        check_start_bounds(x0, self.lower, self.upper, self.model.parameter_names)

    def run(self, x0: np.ndarray, *, max_iter: int | None = None, time_limit: float | None = None) -> StartOutcome:
        """Solve from the start ``x0`` (parameter vector); never raises on solver failure.

        ``max_iter`` and ``time_limit`` cap this start below the estimator's own (a trial
        polish that does not reach a fit stops early); a start outside the bounds is moved
        onto them, and the message says so.
        """
        x0 = np.asarray(x0, dtype=float)
        if max_iter is not None:
            max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        time_limit = check_time_limit("time_limit", time_limit)
        run = self._solver.solve(x0, max_iter=max_iter, time_limit=time_limit)
        names = self.model.parameter_names
        message = (run.status + run.note + moved_onto_bounds(x0, self.lower, self.upper, names)
                   + on_bounds(run.z, self.lower, self.upper, names, np.asarray(self.model.positive, dtype=bool)))
        return self.outcome(x0, run.z, finished=run.finished, status=run.status, message=message,
                            iterations=run.iterations, wall_time=run.seconds)

