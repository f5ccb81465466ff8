"""Least squares on state-variable-filtered derivatives (method ``"svf"``): measured positions and inputs.

When every state-space coordinate is measured — a second-order model with a known,
square, invertible C and position output (q = C⁻¹y), or a state-space model with a known
invertible C and D = 0 (x = C⁻¹y) — the model equation is affine in θ at every instant:

    M(θ) q̈ + V(θ) q̇ + K(θ) q = B(θ) u,      or      ẋ = A(θ) x + B(θ) u.

The derivatives are not measured; both sides are passed through the same stable filter
F(s) = λʳ / (s + λ)ʳ (the "state-variable filter"; Young, *Automatica* 17, 1981;
Garnier, Mensler & Richard, *Int. J. Control* 76, 2003: CONTSID's LSSVF), whose states
are the filtered signal and its first r − 1 derivatives exactly. F commutes with the
linear equation, so F q̈, F q̇, F q, F u obey it too and θ follows from one linear
least-squares problem over all samples. No decimation, no numerical differentiation:
the only choice is the bandwidth λ (default 0.1/Δt rad/s; it should pass the system's
dynamics — the estimate moves little over a wide range, see the EMPS example). Between
samples the outputs are taken as piecewise linear and the inputs as held
(``hold="zoh"``, as :class:`~symid.data.IOData` defines them; ``"foh"`` treats them like
the outputs). The first 15/λ of each record is left out: there the filter's start from
rest still shows. Noise on the outputs enters the regressors and biases least squares
toward zero; ``iv_iterations`` instrumental-variable steps remove that (instruments: the
model's simulated outputs at the current estimate; CONTSID's IVSVF).

The estimate is judged like every time-series method on the measured samples (cost =
output-error misfit of the model simulated from its initial state, success, uncertainty
with a note; :class:`~symid.fit.timeseries.blackbox.JudgedOnSamples`); ``polish=True``
refines it by output error.
"""

from __future__ import annotations

import math
import time
from typing import Any, ClassVar

import numpy as np
import scipy.linalg

from symid.errors import DataError, ModelError, OptionError
from symid.fit.options import check_choice, check_float, check_int, check_time_limit
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import budget_message
from symid.fit.timeseries.blackbox import JudgedOnSamples
from symid.fit.timeseries.oe import OutputError
from symid.fit.timeseries.response import interval_groups

__all__ = ["StateVariableFilter", "filtered_derivatives"]

_HOLDS = ("foh", "zoh")


def filtered_derivatives(t: np.ndarray, w: np.ndarray, bandwidth: float, order: int, hold: str = "foh"
                         ) -> np.ndarray:
    """dᵏ/dtᵏ of F w, F(s) = λʳ/(s + λ)ʳ, k = 0 … r, at the sample times; shape (r + 1, N, channels).

    The filter starts at rest at t[0]; between samples w is linear (``"foh"``) or held (``"zoh"``),
    and the filter is advanced exactly over each interval (one matrix exponential per distinct
    interval).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.timeseries.svf import filtered_derivatives
    >>> t = np.linspace(0, 20, 2001)
    >>> d = filtered_derivatives(t, np.sin(t)[:, None], bandwidth=50.0, order=3)
    >>> F = (50 / (50 + 1j)) ** 3                        # F(jω) at ω = 1: d/dt F sin t = Im(jF e^{jt})
    >>> bool(np.allclose(d[1, 1000:, 0], (1j * F * np.exp(1j * t[1000:])).imag, atol=1e-4))
    True
    """
    lam, r = float(bandwidth), int(order)
    w = np.asarray(w, dtype=float)
    N, C = w.shape
    coeff = np.array([math.comb(r, i) * lam ** (r - i) for i in range(r)])  # (s+λ)^r = s^r + Σ c_i s^i
    F = np.zeros((r, r))
    F[:-1, 1:] = np.eye(r - 1)
    F[-1, :] = -coeff
    g = np.zeros(r)
    g[-1] = lam**r
    reps, group = interval_groups(t)
    steps = []
    for h in reps:
        big = np.zeros((r + 2, r + 2))
        big[:r, :r] = F * h
        big[:r, r] = g * h
        big[r, r + 1] = h
        E = scipy.linalg.expm(big)
        steps.append((E[:r, :r], E[:r, r], E[:r, r + 1] / h))
    out = np.empty((r + 1, N, C))
    z = np.zeros((r, C))
    for k in range(N):
        out[:r, k] = z
        out[r, k] = lam**r * w[k] - coeff @ z
        if k < N - 1:
            Phi, g0, g1 = steps[group[k]]
            slope = (w[k + 1] - w[k]) if hold == "foh" else 0.0
            z = Phi @ z + np.outer(g0, w[k]) + np.outer(g1, slope)
    return out


class StateVariableFilter(JudgedOnSamples):
    """Least squares on filtered derivatives, for models whose states are all measured (module text).

    Parameters
    ----------
    model : SecondOrderModel or StateSpaceModel
        Second order: position output, C known (no parameters), square and invertible.
        State space: C known, square and invertible, D = 0.
    data : IOData, TimeSeries or a list of them
    bandwidth : float, optional
        λ of the filter in rad/s (per the record's time unit). Default: 0.1 / Δt (median
        sample interval), where the outputs' piecewise-linear interpolation changes the
        filtered derivatives by about 1e-5 relative (measured on a mass-spring-damper).
    order : int, optional
        r, the filter order: at least one more than the highest derivative (default: that).
    hold : {"zoh", "foh"}, optional
        Inputs between samples: held (default, as IOData and TimeSeries define them) or
        piecewise linear like the outputs.
    iv_iterations : int, optional
        Instrumental-variable steps after the least squares (default 5; 0: least squares only).
    initial_state : None, "estimate" or array_like, optional
        For the misfit to the samples (as :class:`~symid.fit.timeseries.oe.OutputError`);
        the least squares itself needs none.
    time_limit : float, optional
        Wall-time budget of one start in seconds, checked after the least squares and after
        every instrumental-variable step (status ``"time_limit"``; the last estimate is
        kept, and the start is not finished; a success only if that estimate fits the data). Default: none.
    callback : callable, optional
        Called after the least squares (iteration 1) and after every IV step with a
        :class:`symid.engine.scr.ScrProgress` (iteration, residual ‖Φθ − b‖ / ‖b‖ of the
        filtered equation with the measured regressors, misfit to the samples, elapsed
        seconds, θ); a true return value stops the start (status ``"stopped"``).
    verbose : bool, optional
        Print one line per iteration (iteration, residual, misfit, elapsed). Default False.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> u = np.sin(0.7 * np.arange(3000) * 0.01) + np.sign(np.sin(0.13 * np.arange(3000) * 0.01))
    >>> io = si.simulate_io(model, [2.0, 0.5, 3.0], u, dt=0.01)
    >>> res = si.identify(model, io, method="svf")
    >>> np.round(res.theta_vector, 4).tolist()
    [2.0, 0.5, 3.0]
    """

    method: ClassVar[str] = "svf"  # type: ignore[misc]
    route = "state-variable-filtered derivatives (equation error)"

    def __init__(self, model: Any, data: Any, *, bandwidth: float | None = None, order: int | None = None,
                 hold: str = "zoh", iv_iterations: int = 5, initial_state: Any = None,
                 time_limit: float | None = None, callback: Any = None, verbose: bool = False):
        # the samples the estimate is judged on, simulated with the same hold as the filters take the input
        if hold == "bandlimited":  # output error's; the filters here take the input held or linear
            raise OptionError("hold='bandlimited' is output error's (method='oe' or 'auto'); svf filters the input "
                              "as held ('zoh') or linear ('foh') between samples: 'foh' is the nearest")
        self.samples = OutputError(model, data, initial_state=initial_state, hold=check_choice("hold", hold, _HOLDS))
        self.model, self.data = model, data
        self._kind = _check_model(model)
        records = self.samples.records
        if self.samples.n_missing:
            raise DataError(f"{self.samples.n_missing} output value(s) are missing (NaN): method {self.method!r} "
                            "filters every output sample; method='oe' or 'auto' leaves missing values out of its "
                            "misfit")
        need = 3 if self._kind == "second order" else 2
        self._order = need if order is None else check_int("order", order, low=need, high=12)
        dt = float(np.median(np.concatenate([np.diff(r.t) for r in records])))
        self._lambda = (0.1 / dt if bandwidth is None
                        else check_float("bandwidth", bandwidth, low=0, strict_low=True))
        self._hold = check_choice("hold", hold, _HOLDS)
        self._iv = check_int("iv_iterations", iv_iterations, low=0, high=100)
        self.time_limit = check_time_limit("time_limit", time_limit)
        self._progress_options(callback, verbose)
        self.options = {"bandwidth": self._lambda, "order": self._order, "hold": self._hold, "iv_iterations": self._iv,
                        "initial_state": self.samples.options["initial_state"], "time_limit": self.time_limit,
                        "callback": None if callback is None else "given", "verbose": self._verbose,
                        "fits": "filtered derivatives (equation error); cost, success and uncertainty on the "
                                "measured samples"}
        self._rows, self._rhs, self._used = self._regression([r.y for r in records])
        if self._used <= model.n_parameters:
            raise OptionError(f"after the filter's start-up (15/λ = {15 / self._lambda:.3g} per record) "
                              f"{self._used} samples are left for {model.n_parameters} parameters: lower "
                              "bandwidth= only if the records are long enough, or give longer records")

    def _regression(self, outputs: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, int]:
        """Regressor rows and right-hand side from the records' inputs and the given outputs (measured, or
        simulated for the instruments)."""
        maps = self.model.maps
        Ci = np.linalg.inv(maps["C"].X0)
        rows, rhs, used = [], [], 0
        for r, y in zip(self.samples.records, outputs, strict=True):
            keep = (r.t - r.t[0]) >= 15.0 / self._lambda
            if not np.any(keep):
                continue
            x = y @ Ci.T                                       # q (second order) or x (state space)
            dx = filtered_derivatives(r.t, x, self._lambda, self._order)
            du = filtered_derivatives(r.t, r.u, self._lambda, self._order, self._hold)
            if self._kind == "second order":
                q0, q1, q2, u0 = dx[0][keep], dx[1][keep], dx[2][keep], du[0][keep]
                # Σ_k θ_k (M_k q̈ + V_k q̇ + K_k q − B_k u) = B0 u − M0 q̈ − V0 q̇ − K0 q
                Phi = (np.einsum("kij,Nj->Nik", maps["M"].Xi, q2) + np.einsum("kij,Nj->Nik", maps["V"].Xi, q1)
                       + np.einsum("kij,Nj->Nik", maps["K"].Xi, q0) - np.einsum("kij,Nj->Nik", maps["B"].Xi, u0))
                b = u0 @ maps["B"].X0.T - q2 @ maps["M"].X0.T - q1 @ maps["V"].X0.T - q0 @ maps["K"].X0.T
            else:
                x0, x1, u0 = dx[0][keep], dx[1][keep], du[0][keep]
                # ẋ = A x + B u: Σ_k θ_k (A_k x + B_k u) = ẋ − A0 x − B0 u
                Phi = np.einsum("kij,Nj->Nik", maps["A"].Xi, x0) + np.einsum("kij,Nj->Nik", maps["B"].Xi, u0)
                b = x1 - x0 @ maps["A"].X0.T - u0 @ maps["B"].X0.T
            rows.append(Phi.reshape(-1, Phi.shape[-1]))
            rhs.append(b.reshape(-1))
            used += int(keep.sum())
        if not rows:
            return np.zeros((0, self.model.n_parameters)), np.zeros(0), 0
        return np.vstack(rows), np.concatenate(rhs), used

    def equation_residual(self, theta: np.ndarray) -> float:
        """‖Φθ − b‖ / ‖b‖: the filtered equation's residual at θ with the measured regressors (0 when b = 0)."""
        size = float(np.linalg.norm(self._rhs))
        return float(np.linalg.norm(self._rows @ theta - self._rhs)) / size if size > 0 else 0.0

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Least squares, then ``iv_iterations`` instrumental-variable steps (``x0`` plays no role).

        The IV step (IVSVF; Young 1981, Garnier et al. 2003) replaces the measured outputs in
        the regressors by the model's simulated outputs at the current estimate as instruments:
        θ = (ZᵀΦ)⁻¹ Zᵀ b. Noise in the measured outputs enters Φ (the filtered derivatives)
        and biases least squares toward zero; the instruments carry no noise. Stops when θ
        moves less than 1e-10 relative, or when the simulation at an iterate is not finite
        (keeping the last good estimate); or, before a further step, when ``callback``
        asked to stop (status ``"stopped"``) or ``time_limit`` is spent (``"time_limit"``):
        neither is finished, so neither is a success.
        """
        t0 = time.perf_counter()
        deadline = None if self.time_limit is None else t0 + self.time_limit
        report = self.progress_reporter(t0)
        scale = np.linalg.norm(self._rows, axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        sol, _, rank, _ = np.linalg.lstsq(self._rows / scale, self._rhs, rcond=None)
        theta = sol / scale
        l = self.model.n_parameters
        status = "least squares" if rank == l else "rank deficient"
        asked = report is not None and report(1, self.equation_residual(theta), theta)
        steps, why = 0, ""
        for _ in range(self._iv if status == "least squares" else 0):
            if asked:
                status, why = "stopped", "; stopped by the callback"
                break
            if deadline is not None and time.perf_counter() >= deadline:
                status, why = "time_limit", "; " + budget_message(self.time_limit, 1 + steps)
                break
            try:
                sims = self.samples.simulate(theta)
            except (np.linalg.LinAlgError, ValueError, ModelError):
                sims = None
            if sims is None or not all(np.all(np.isfinite(y)) for y in sims):
                why = "; the model simulated at the last estimate is not finite: IV stopped there"
                break
            Z, _, _ = self._regression(sims)
            G = (Z / scale).T @ (self._rows / scale)
            try:
                new = np.linalg.solve(G, (Z / scale).T @ self._rhs) / scale
            except np.linalg.LinAlgError:
                why = "; the instruments are singular: IV stopped"
                break
            steps += 1
            moved = np.linalg.norm(new - theta) / max(np.linalg.norm(theta), 1e-300)
            theta = new
            asked = report is not None and report(1 + steps, self.equation_residual(theta), theta)
            if moved < 1e-10:
                break
        message = (f"least squares on {self._used} filtered samples (λ = {self._lambda:.4g} rad/s, order "
                   f"{self._order}, {self._hold}), {steps} IV step(s){why}" if status != "rank deficient" else
                   f"the filtered regression has rank {rank} < {l}: the records do not determine θ")
        return self.outcome(np.asarray(x0, dtype=float), theta, finished=status == "least squares",
                            status=status, message=message, iterations=1 + steps,
                            wall_time=time.perf_counter() - t0)


def _check_model(model: Any) -> str:
    """``"second order"`` or ``"state space"``; a ModelError naming what stops the method otherwise."""
    maps = model.maps
    C = maps["C"]
    r, c = C.shape
    why = []
    if not C.is_constant:
        why.append("C holds parameters")
    elif r != c or np.linalg.matrix_rank(C.X0) < r or np.linalg.cond(C.X0) > 1e12:
        why.append(f"C ({r}×{c}) is not square and invertible")
    if "M" in maps:
        if getattr(model, "output", "position") != "position":
            why.append(f"the output is {model.output}, not position" if model.output != "mixed"
                       else f"the outputs are {', '.join(model.outputs)}, not all position")
        kind = "second order"
    else:
        if "D" in maps and not (maps["D"].is_constant and not np.any(maps["D"].X0)):
            why.append("D is not zero")
        kind = "state space"
    if why:
        raise ModelError("method 'svf' needs every state measured (a position output through a known, square, "
                         f"invertible C): here {'; '.join(why)}. Use method='oe'.")
    return kind
