"""IPOPT on the spectral misfit of thesis (5-13): Σᵢ ‖Φyyᵢ − H Φuuᵢ Hᴴ‖²_F, H = C X⁻¹ B."""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from symid.engine.ipopt import HESSIANS, ScaledIpopt, casadi_frf, casadi_matrices, iteration_reporter
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
from symid.fit.spectra.equations import SpectraEstimator, check_spectral, spectral_equations

__all__ = ["IpoptPSD"]

_OBJECTIVES = ("output", "equation")
_WEIGHTINGS = ("none", "frequency")


def _sandwich(Ar: Any, Ai: Any, Pr: np.ndarray, Pi: np.ndarray) -> tuple[Any, Any]:
    """Real and imaginary parts of A Φ Aᴴ for A = Ar + jAi and a constant Φ = Pr + jPi."""
    Fr = Ar @ ca.DM(Pr) - Ai @ ca.DM(Pi)
    Fi = Ar @ ca.DM(Pi) + Ai @ ca.DM(Pr)
    return Fr @ Ar.T + Fi @ Ai.T, Fi @ Ar.T - Fr @ Ai.T


class IpoptPSD(SpectraEstimator):
    """Nonlinear least squares on spectra with CasADi/IPOPT, built once, run per start.

    Every fair advantage is on by default: exact Hessian by automatic differentiation,
    an objective normalised by Σᵢ ‖Φyyᵢ‖²_F (or weighted per frequency), bounds θ ≥ 0 on
    parameters declared positive, and IPOPT working on θ / s with s the start's own
    magnitudes (or ``scale``), on the objective divided by its start's decade, with a
    barrier that does not push a start at a converged fit away
    (:class:`symid.engine.ipopt.ScaledIpopt`).

    Parameters
    ----------
    model : SecondOrderModel
    data : SpectralData
    objective : {"output", "equation"}
        ``"output"`` (default): the output-spectrum misfit (5-13),
        Σᵢ ‖Φyyᵢ − C Xᵢ⁻¹ B Φuuᵢ Bᴴ Xᵢ⁻ᴴ Cᴴ‖²_F. ``"equation"``: the equation error of
        (5-8) that "variants hereof (using the invertibility of C, X)" allude to,
        Σᵢ ‖Xᵢ Pᵢ Xᵢᴴ − Qᵢ‖²_F, a polynomial of degree 4 in θ without inverses (needs a
        full sensor set, as Algorithm 5.1 does).
    weighting : {"none", "frequency"}
        ``"none"`` (default, as (5-13)): one normalisation for all terms.
        ``"frequency"``: each frequency's term divided by its own ‖Φyyᵢ‖²_F (or ‖Qᵢ‖²_F),
        so that the weak high-frequency spectra count as much as the strong ones.
    scale : array_like, optional
        Typical magnitude of each parameter; IPOPT works on θ / scale. Default: each
        start's own magnitudes |θ₀| (where θ₀ is 0: the largest finite bound, else 1).
    bounds : dict or array_like, optional
        Lower and upper bounds: a dict by parameter name of (low, high) (``None`` for an
        open side), or an (l, 2) array; combined with ``positivity``. A start outside
        them is moved onto them.
    positivity : bool
        θₖ ≥ 0 for parameters declared ``positive=True`` (default True).
    hessian : {"exact", "limited-memory"}
        Exact Hessian by automatic differentiation (default) or L-BFGS.
    max_iter : int
        IPOPT iteration limit (default 3000).
    tol : float
        IPOPT tolerance (default 1e-12 on the normalised objective).
    time_limit : float, optional
        Wall-time budget of one start in seconds (IPOPT's ``max_wall_time``). Default: none.
    callback : callable, optional
        Called after every IPOPT iteration with a
        :class:`~symid.engine.ipopt.IpoptIteration` (iteration, objective, elapsed, θ); a
        true return value stops the start.
    verbose : bool, optional
        Print one line per iteration (iteration, objective, elapsed). Default False.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.spectra.ipopt import IpoptPSD
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], np.linspace(0.5, 3, 8), Phi_uu=1.0)
    >>> out = IpoptPSD(model, spec).run(np.array([1.2, 0.4, 3.5]))
    >>> np.round(out.theta, 4)
    array([1. , 0.5, 4. ])
    """

    method: ClassVar[str] = "ipopt"

    def __init__(self, model: Any, data: Any, *, objective: str = "output", weighting: str = "none",
                 scale: Any = None, bounds: Any = None, positivity: bool = True, hessian: str = "exact",
                 max_iter: int = 3000, tol: float = 1e-12, time_limit: float | None = None, callback: Any = None,
                 verbose: bool = False):
        objective = check_choice("objective", objective, _OBJECTIVES)
        weighting = check_choice("weighting", weighting, _WEIGHTINGS)
        hessian = check_choice("hessian", hessian, HESSIANS)
        positivity = check_bool("positivity", positivity)
        max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        tol = check_float("tol", tol, low=0, strict_low=True)
        time_limit = check_time_limit("time_limit", time_limit)
        verbose = check_bool("verbose", verbose)
        check_callback("callback", callback, "IpoptIteration")
        check_spectral(model, data)
        self.model, self.data = model, data
        l = model.n_parameters
        self.scale = None if scale is None else check_scale("scale", scale, l)
        self.lower, self.upper = parameter_bounds(model, bounds, positivity)
        named = {n: [float(lo), float(hi)] for n, lo, hi in zip(model.parameter_names, self.lower, self.upper,
                                                                strict=True) if np.isfinite(lo) or np.isfinite(hi)}
        self.options = {"objective": objective, "weighting": weighting,
                        "scale": "start" if self.scale is None else self.scale.tolist(), "bounds": named or None,
                        "positivity": positivity, "hessian": hessian, "max_iter": max_iter, "tol": tol,
                        "time_limit": time_limit, "callback": None if callback is None else "given",
                        "verbose": verbose}
        theta = ca.MX.sym("theta", l)
        parts = (self._objective_output(theta) if objective == "output"
                 else self._objective_equation(theta, spectral_equations(model, data)))
        self._solver = ScaledIpopt("symid_ipopt_psd", theta, self._weighted_sum(parts), lower=self.lower,
                                   upper=self.upper, scale=self.scale, max_iter=max_iter, tol=tol, hessian=hessian,
                                   time_limit=time_limit, callback=iteration_reporter(callback, verbose))

    def _objective_output(self, theta: Any) -> list[tuple[Any, np.ndarray]]:
        """Per frequency (squared misfit, reference spectrum) of (5-13)."""
        Hr, Hi = casadi_frf(self.model, theta, np.asarray(self.data.w))
        Phi, Puu = np.asarray(self.data.Phi_yy), np.asarray(self.data.Phi_uu)
        out = []
        for i in range(len(Hr)):
            Sr, Si = _sandwich(Hr[i], Hi[i], Puu[i].real, Puu[i].imag)
            out.append((ca.sumsqr(Sr - ca.DM(Phi[i].real)) + ca.sumsqr(Si - ca.DM(Phi[i].imag)), Phi[i]))
        return out

    def _objective_equation(self, theta: Any, eq: Any) -> list[tuple[Any, np.ndarray]]:
        """Per frequency (squared residual of (5-8), Qᵢ)."""
        mats = casadi_matrices(self.model, theta)
        M, V, K = (mats[k] for k in "MVK")
        out = []
        for i, wi in enumerate(eq.w):
            Sr, Si = _sandwich(K - wi**2 * M, wi * V, eq.P[i].real, eq.P[i].imag)
            out.append((ca.sumsqr(Sr - ca.DM(eq.Q[i].real)) + ca.sumsqr(Si - ca.DM(eq.Q[i].imag)), eq.Q[i]))
        return out

    def _weighted_sum(self, parts: list[tuple[Any, np.ndarray]]) -> Any:
        norms = np.array([float(np.sum(np.abs(ref) ** 2)) for _, ref in parts])
        f = 0
        if self.options["weighting"] == "frequency":
            for (r, _), nrm in zip(parts, norms, strict=True):
                f = f + r / (nrm if nrm > 0 else 1.0)
            return f / len(parts)
        for r, _ in parts:
            f = f + r
        total = float(norms.sum())
        return f / (total if total > 0 else 1.0)

    def run(self, x0: np.ndarray, *, max_iter: int | None = None, time_limit: float | None = None) -> StartOutcome:
        """Solve from the start ``x0`` (parameter vector); never raises on solver failure.

        ``max_iter`` and ``time_limit`` cap this start below the estimator's own.
        """
        x0 = np.asarray(x0, dtype=float)
        if max_iter is not None:
            max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        run = self._solver.solve(x0, max_iter=max_iter, time_limit=check_time_limit("time_limit", time_limit))
        message = run.status + run.note + moved_onto_bounds(x0, self.lower, self.upper, self.model.parameter_names)
        return self.outcome(x0, run.z, finished=run.finished, status=run.status, message=message,
                            iterations=run.iterations, wall_time=run.seconds)

    def check_start(self, x0: Any) -> None:
        """Refuse a start outside the bounds (an :class:`OptionError` naming the parameter)."""
        check_start_bounds(x0, self.lower, self.upper, self.model.parameter_names)
