"""IPOPT on the spectral misfit of thesis (5-13): Σᵢ ‖Φyyᵢ − H Φuuᵢ Hᴴ‖²_F, H = C X⁻¹ B."""

from __future__ import annotations

import time
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from symid.engine.ipopt import HESSIANS, ScaledIpopt, casadi_frf, casadi_matrices, iteration_reporter
from symid.errors import OptionError
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
from symid.fit.spectra.welch import VARIANCE_ROUNDS, data_weights, spectra_averages, variance_weights

__all__ = ["IpoptPSD"]

_OBJECTIVES = ("output", "equation")
_WEIGHTINGS = ("none", "frequency", "variance")


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
    weighting : {"none", "frequency", "variance"}
        ``"none"`` (default, as (5-13)): one normalisation for all terms.
        ``"frequency"``: each frequency's term divided by its own ‖Φyyᵢ‖²_F (or ‖Qᵢ‖²_F),
        so that the weak high-frequency spectra count as much as the strong ones.
        ``"variance"`` (``objective="output"`` only): each entry by its scatter in a Welch
        estimate, 1/(Φⱼⱼ Φₖₖ) of the model at the estimate, iterated up to
        :data:`~symid.fit.spectra.welch.VARIANCE_ROUNDS` times from the measured
        auto-spectra's; with the number of averages known the fit is judged against the
        noise they leave (:mod:`symid.fit.spectra.welch`).
    averages : float, optional
        With ``weighting="variance"``: the independent averages behind each line of Φyy
        (Welch segments), for spectra estimated elsewhere; default: those of
        :func:`symid.estimate_spectra` with a given input spectrum, else unknown.
    sensor_noise : bool
        Fit a white noise νⱼ ≥ 0 on each output's auto-spectrum beside the model's
        spectra, Φyy = H Φuu Hᴴ + diag(ν) (``objective="output"`` only; default False):
        sensor noise the model does not hold, which the weights of ``"variance"`` would
        otherwise let carry the lines far from the modes. ν is a nuisance unknown:
        profiled out of the misfit and of the uncertainty
        (:func:`~symid.fit.spectra.welch.profiled_sensor_noise`).
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
                 averages: float | None = None, sensor_noise: bool = False, scale: Any = None, bounds: Any = None,
                 positivity: bool = True, hessian: str = "exact", max_iter: int = 3000, tol: float = 1e-12,
                 time_limit: float | None = None, callback: Any = None, verbose: bool = False):
        objective = check_choice("objective", objective, _OBJECTIVES)
        weighting = check_choice("weighting", weighting, _WEIGHTINGS)
        if weighting == "variance" and objective != "output":
            raise OptionError("weighting='variance' weighs the output spectra's entries (objective='output'); the "
                              "equation error of (5-8) takes weighting 'none' or 'frequency'")
        if averages is not None:
            averages = check_float("averages", averages, low=1.0)
        self.sensor_noise = check_bool("sensor_noise", sensor_noise)
        if self.sensor_noise and objective != "output":
            raise OptionError("sensor_noise=True adds a noise to the output spectra (objective='output'); the "
                              "equation error of (5-8) has none")
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
        self.averages = averages if averages is not None or weighting != "variance" else spectra_averages(data)
        self.options = {"objective": objective, "weighting": weighting, "averages": self.averages,
                        "sensor_noise": self.sensor_noise,
                        "scale": "start" if self.scale is None else self.scale.tolist(), "bounds": named or None,
                        "positivity": positivity, "hessian": hessian, "max_iter": max_iter, "tol": tol,
                        "time_limit": time_limit, "callback": None if callback is None else "given",
                        "verbose": verbose}
        theta = ca.MX.sym("theta", l)
        terms, self._refs = (self._objective_output(theta) if objective == "output"
                             else self._objective_equation(theta, spectral_equations(model, data)))
        s, p, _ = self._refs.shape
        # the sensor noise ν = ν_unit·η: η ≥ 0 of order one beside θ (ν_unit the median auto-spectrum of each output)
        self._noise_unit = np.median(np.abs(np.real(np.diagonal(self._refs, axis1=1, axis2=2))), axis=0)
        self._noise_unit = np.where(self._noise_unit > 0, self._noise_unit, 1.0)
        n_noise = p if self.sensor_noise else 0
        eta = ca.MX.sym("eta", n_noise)
        noise = ca.diag(ca.DM(self._noise_unit) * eta) if n_noise else 0
        q = ca.MX.sym("q", s * p * p)  # each entry's weight, a parameter: reweighting rebuilds nothing
        f = 0
        for i, (Er, Ei) in enumerate(terms):
            Wi = ca.reshape(q[i * p * p:(i + 1) * p * p], p, p)
            Er = Er + noise
            f = f + ca.sum1(ca.sum2(Wi * (Er * Er + Ei * Ei)))
        zscale = None if self.scale is None or not n_noise else np.concatenate([self.scale, np.ones(n_noise)])
        self._solver = ScaledIpopt("symid_ipopt_psd", ca.vertcat(theta, eta), f,
                                   lower=np.concatenate([self.lower, np.zeros(n_noise)]),
                                   upper=np.concatenate([self.upper, np.full(n_noise, np.inf)]),
                                   scale=self.scale if zscale is None else zscale, max_iter=max_iter, tol=tol,
                                   hessian=hessian, time_limit=time_limit,
                                   callback=iteration_reporter(callback, verbose), parameters=q)
        if weighting == "variance":
            self.set_entry_weights(data_weights(data))

    def _objective_output(self, theta: Any) -> tuple[list[tuple[Any, Any]], np.ndarray]:
        """Per frequency the real and imaginary parts of Φyyᵢ − H Φuuᵢ Hᴴ of (5-13), and Φyy."""
        Hr, Hi = casadi_frf(self.model, theta, np.asarray(self.data.w))
        Phi, Puu = np.asarray(self.data.Phi_yy), np.asarray(self.data.Phi_uu)
        out = []
        for i in range(len(Hr)):
            Sr, Si = _sandwich(Hr[i], Hi[i], Puu[i].real, Puu[i].imag)
            out.append((Sr - ca.DM(Phi[i].real), Si - ca.DM(Phi[i].imag)))
        return out, Phi

    def _objective_equation(self, theta: Any, eq: Any) -> tuple[list[tuple[Any, Any]], np.ndarray]:
        """Per frequency the real and imaginary parts of the residual of (5-8), and the Qᵢ."""
        mats = casadi_matrices(self.model, theta)
        M, V, K = (mats[k] for k in "MVK")
        out = []
        for i, wi in enumerate(eq.w):
            Sr, Si = _sandwich(K - wi**2 * M, wi * V, eq.P[i].real, eq.P[i].imag)
            out.append((Sr - ca.DM(eq.Q[i].real), Si - ca.DM(eq.Q[i].imag)))
        return out, np.asarray(eq.Q)

    def _weight_values(self) -> np.ndarray:
        """The value of every entry's weight in the objective (column-major per frequency, as CasADi reshapes)."""
        ref = np.abs(self._refs) ** 2
        s = ref.shape[0]
        if self.options["weighting"] == "frequency":
            norms = ref.sum(axis=(1, 2))
            w = np.broadcast_to((1.0 / np.where(norms > 0, norms, 1.0) / s)[:, None, None], ref.shape)
        elif self.entry_weights is not None:
            w = self.entry_weights / (float(np.sum(self.entry_weights * ref)) or 1.0)
        else:
            w = np.full(ref.shape, 1.0 / (float(ref.sum()) or 1.0))
        return np.swapaxes(w, 1, 2).reshape(-1)

    def _with_noise(self, theta: np.ndarray) -> np.ndarray:
        """θ and, with ``sensor_noise``, the noise that fits best there in the current weights (as η = ν / ν_unit)."""
        if not self.sensor_noise:
            return theta
        nu = self.sensor_noise_at(np.clip(theta, self.lower, self.upper))
        eta = np.zeros(self._noise_unit.size) if nu is None else nu / self._noise_unit
        return np.concatenate([theta, eta])

    def reweigh_relative(self, theta: Any) -> None:
        """With ``weighting="variance"``: weigh the entries by the model's spectra at θ
        (:func:`~symid.fit.spectra.welch.variance_weights`); nothing otherwise, or where the model cannot be
        evaluated there."""
        if self.options["weighting"] != "variance":
            return
        w = variance_weights(self.model, self.data, theta, self.averages)
        if w is not None:
            self.set_entry_weights(w)

    def run(self, x0: np.ndarray, *, max_iter: int | None = None, time_limit: float | None = None,
            rounds: int | None = None) -> StartOutcome:
        """Solve from the start ``x0`` (parameter vector); never raises on solver failure.

        ``max_iter`` and ``time_limit`` cap this start below the estimator's own. With
        ``weighting="variance"`` the start begins in the measured auto-spectra's weights and
        is followed by up to ``rounds`` (default :data:`~symid.fit.spectra.welch.VARIANCE_ROUNDS`)
        solves reweighted at the estimate; ``rounds=0`` solves once in the current weights.
        """
        t0 = time.perf_counter()
        x0 = np.asarray(x0, dtype=float)
        if max_iter is not None:
            max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        time_limit = check_time_limit("time_limit", time_limit)
        if time_limit is None:
            time_limit = self.options["time_limit"]
        variance = self.options["weighting"] == "variance"
        if variance and rounds is None:
            self.set_entry_weights(data_weights(self.data))
        l = self.lower.size
        run = self._solver.solve(self._with_noise(x0), max_iter=max_iter, time_limit=time_limit,
                                 values=self._weight_values())
        message = run.status + run.note + moved_onto_bounds(x0, self.lower, self.upper, self.model.parameter_names)
        z, iterations, finished, status = run.z[:l], run.iterations, run.finished, run.status
        done = 0
        for _ in range(VARIANCE_ROUNDS if variance and rounds is None else (rounds or 0) if variance else 0):
            left = None if time_limit is None else time_limit - (time.perf_counter() - t0)
            if left is not None and left <= 0:
                break
            before = self.entry_weights
            self.reweigh_relative(z)
            if self.entry_weights is before:  # the model cannot be evaluated at the estimate
                break
            again = self._solver.solve(self._with_noise(z), max_iter=max_iter, time_limit=left,
                                       values=self._weight_values())
            moved = float(np.max(np.abs(again.z[:l] - z) / np.maximum(np.abs(z), 1e-300)))
            z, iterations = again.z[:l], iterations + again.iterations
            finished, status = again.finished, again.status
            done += 1
            if moved < 1e-6:
                break
        if done:
            self.reweigh_relative(z)  # the weights the outcome (and the uncertainty) are judged in
            message += f"; {done} solve(s) reweighted by the model's spectra at the estimate (weighting='variance')"
        return self.outcome(x0, z, finished=finished, status=status, message=message, iterations=iterations,
                            wall_time=time.perf_counter() - t0)

    def check_start(self, x0: Any) -> None:
        """Refuse a start outside the bounds (an :class:`OptionError` naming the parameter)."""
        check_start_bounds(x0, self.lower, self.upper, self.model.parameter_names)
