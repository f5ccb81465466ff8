"""Simplified refined instrumental variables for continuous-time models (method ``"srivc"``).

For a model whose transfer function, written as polynomials in s from its own matrices,

    G(s, θ) = N(s, θ) / D(s, θ),   D = det(sI − A),  N = C adj(sI − A) B + D·det(sI − A)
    (second order: D = det(M s² + V s + K), N = C adj(M s² + V s + K) B, times s or s²
    for a velocity or acceleration output),

has every coefficient of N and D affine in θ, the input-output equation
D(p, θ) y(t) = N(p, θ) u(t) (p = d/dt) is linear in θ at every instant. It is homogeneous,
so it fixes θ only when some coefficient holds a known nonzero constant (a monic D, as
det(sI − A) always is, or B = 1 in m q̈ + c q̇ + k q = u). A mass-spring-damper with
position output qualifies; a two-compartment model with rate constants does not (the
constant term of det(sI − A) is the product k₁₀k₂₁): use ``oe`` there.

SRIVC (Young & Jakeman, *Int. J. Control* 31, 1980; Young, *Recursive Estimation and
Time-Series Analysis*, 2nd ed., 2011, §8; CONTSID's ``srivc``, Garnier, Mensler & Richard,
*Int. J. Control* 76, 2003) iterates, from a start θ̂:

1. prefilter the inputs and outputs by 1/D(s, θ̂): the filter's companion-form states are
   the filtered signal's derivatives of order 0 … n − 1 exactly, the n-th follows from its
   equation (between samples the outputs are linear and the inputs held, ``hold="zoh"``,
   or linear, ``"foh"``; each interval advanced exactly by one matrix exponential);
2. simulate the noise-free output x̂ = N(s, θ̂)/D(s, θ̂) u (exact, from the same filtered
   input derivatives) and prefilter it alike: its derivatives are the instruments;
3. solve the instrumental-variable equations ZᵀΦ θ = Zᵀb of the filtered equation;

until θ̂ moves less than ``tol`` relative. At convergence the prefilter is the model's own
denominator: the equation error is then the output error filtered by nothing but the
noise, which is why SRIVC is consistent and, for white output noise, close to the
output-error estimate, where least squares on fixed-filter derivatives (``svf``'s first
step) is biased. The default start is that least squares with the filter (s + λ)ⁿ,
λ = 0.1/Δt. An iterate whose D has roots in the right half plane is stabilised for
filtering by reflecting them (the message counts how often).

Records are taken to start at rest (the model's zero initial state), so the filters start
at rest too; with another initial state the first ``skip`` seconds of each record are left
out (default 15 time constants of the slowest root of D at the current iterate).

The estimate is judged like every time-series method on the measured samples
(:class:`~symid.fit.timeseries.blackbox.JudgedOnSamples`); ``polish=True`` refines it by
output error.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import scipy.linalg
import sympy as sp

from symid.errors import DataError, ModelError, OptionError
from symid.fit.options import check_choice, check_float, check_int, check_time_limit
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import budget_message
from symid.fit.timeseries.blackbox import JudgedOnSamples
from symid.fit.timeseries.oe import OutputError
from symid.fit.timeseries.response import interval_groups

__all__ = ["SimplifiedRIVC", "TransferPolynomials", "prefiltered_derivatives", "transfer_polynomials"]

_HOLDS = ("zoh", "foh")
_INITS = ("ls", "start")


def prefiltered_derivatives(t: np.ndarray, w: np.ndarray, den: np.ndarray, hold: str = "foh") -> np.ndarray:
    """dᵏ/dtᵏ of w / D(s), D(s) = sⁿ + Σₖ dₖ sᵏ monic, k = 0 … n, at the sample times; shape (n + 1, N, channels).

    ``den`` holds d₀ … dₙ₋₁ (lowest power first). The filter starts at rest at t[0];
    between samples w is linear (``"foh"``) or held (``"zoh"``), and the filter's
    companion-form state (the filtered signal and its first n − 1 derivatives) is
    advanced exactly over each interval (one matrix exponential per distinct interval).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.timeseries.srivc import prefiltered_derivatives
    >>> t = np.linspace(0, 30, 3001)
    >>> d = prefiltered_derivatives(t, np.sin(t)[:, None], np.array([2.0, 3.0]))   # 1/(s² + 3s + 2)
    >>> F = 1 / ((1j) ** 2 + 3j + 2)                     # at ω = 1: d/dt F sin t = Im(jF e^{jt})
    >>> bool(np.allclose(d[1, 2000:, 0], (1j * F * np.exp(1j * t[2000:])).imag, atol=1e-5))
    True
    """
    coeff = np.asarray(den, dtype=float).reshape(-1)
    r = coeff.size
    w = np.asarray(w, dtype=float)
    N, C = w.shape
    F = np.zeros((r, r))
    F[:-1, 1:] = np.eye(r - 1)
    F[-1, :] = -coeff
    reps, group = interval_groups(t)
    steps = []
    for h in reps:
        big = np.zeros((r + 2, r + 2))
        big[:r, :r] = F * h
        big[r - 1, r] = h
        big[r, r + 1] = h
        E = scipy.linalg.expm(big)
        steps.append((E[:r, :r], E[:r, r], E[:r, r + 1] / h))
    slopes = np.diff(w, axis=0) if hold == "foh" else np.zeros((max(N - 1, 0), C))
    out = np.empty((r + 1, N, C))
    if len(steps) == 1:  # uniform sampling: the same recursion in blocks, vectorised
        Phi, g0, g1 = steps[0]
        drive = g0[None, :, None] * w[:-1, None, :] + g1[None, :, None] * slopes[:, None, :]
        out[:r] = np.moveaxis(_uniform_scan(Phi, drive), 0, 1)
    else:
        z = np.zeros((r, C))
        for k in range(N):
            out[:r, k] = z
            if k < N - 1:
                Phi, g0, g1 = steps[group[k]]
                z = Phi @ z + np.outer(g0, w[k]) + np.outer(g1, slopes[k])
    out[r] = w - np.einsum("i,iNc->Nc", coeff, out[:r])
    return out


def _uniform_scan(Phi: np.ndarray, drive: np.ndarray, block: int = 32) -> np.ndarray:
    """z₀ = 0, z_{k+1} = Φ z_k + drive_k for k = 0 … K − 1; returns z₀ … z_K, shape (K + 1, r, C).

    Within a block of L steps the forced part is one product with the block's lower-triangular
    Toeplitz array of Φ powers; only the block starts are advanced one after the other.
    """
    K, r, C = drive.shape
    L = block
    powers = np.empty((L + 1, r, r))
    powers[0] = np.eye(r)
    for j in range(1, L + 1):
        powers[j] = Phi @ powers[j - 1]
    T = np.zeros((L + 1, L, r, r))  # T[j, i] = Φ^(j−1−i) for i < j
    for j in range(1, L + 1):
        T[j, :j] = powers[j - 1::-1][:j]
    nb = -(-K // L)
    padded = np.zeros((nb * L, r, C))
    padded[:K] = drive
    T2 = T.transpose(0, 2, 1, 3).reshape((L + 1) * r, L * r)
    forced = np.matmul(T2, padded.reshape(nb, L * r, C)).reshape(nb, L + 1, r, C)
    starts = np.empty((nb, r, C))
    z = np.zeros((r, C))
    PL = powers[L]
    for b in range(nb):
        starts[b] = z
        z = PL @ z + forced[b, L]
    free = np.matmul(powers.reshape((L + 1) * r, r), starts).reshape(nb, L + 1, r, C)
    blocks = free + forced
    out = np.empty((nb * L + 1, r, C))
    out[:-1] = blocks[:, :L].reshape(nb * L, r, C)
    out[-1] = blocks[-1, L]
    return out[:K + 1]


@dataclass(frozen=True)
class TransferPolynomials:
    """The model's transfer function N(s, θ)/D(s, θ) with coefficients affine in θ (lowest power first).

    Attributes
    ----------
    order : int
        n, the degree of D in s.
    den0, den_theta : ndarray
        D's coefficients: ``den0[k] + den_theta[k] @ θ`` for sᵏ, shapes (n + 1,) and (n + 1, l).
    num0, num_theta : ndarray
        N's coefficients per output and input: ``num0[i, j, k] + num_theta[i, j, k] @ θ``,
        shapes (p, m, n + 1) and (p, m, n + 1, l).
    """

    order: int
    den0: np.ndarray
    den_theta: np.ndarray
    num0: np.ndarray
    num_theta: np.ndarray

    def den(self, theta: np.ndarray) -> np.ndarray:
        """D's coefficients at θ, (n + 1,)."""
        return self.den0 + self.den_theta @ theta

    def num(self, theta: np.ndarray) -> np.ndarray:
        """N's coefficients at θ, (p, m, n + 1)."""
        return self.num0 + self.num_theta @ theta


def transfer_polynomials(model: Any) -> TransferPolynomials:
    """N(s, θ) and D(s, θ) of the model's transfer function, from its symbolic matrices (module text).

    Raises
    ------
    ModelError
        When a coefficient is not affine in θ (naming it), or when no coefficient is a
        known nonzero constant (the equation D y = N u is then homogeneous in θ).

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.timeseries.srivc import transfer_polynomials
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> tp = transfer_polynomials(si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]]))
    >>> tp.order, tp.den_theta.tolist(), tp.num0.tolist()       # D = k + c s + m s², N = 1
    (2, [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]], [[[1.0, 0.0, 0.0]]])
    """
    s = sp.Dummy("s")
    params = list(model.parameters)
    # floats (known values) as the exact rationals they are: a determinant in floating point leaves terms like
    # 1e-26·G12²·G23 where exact arithmetic cancels them, and an affine coefficient would look quadratic
    sym = {k: v.applyfunc(lambda e: e.xreplace({f: sp.Rational(f) for f in e.atoms(sp.Float)}))
           for k, v in model.symbolic.items()}
    if "M" in sym:
        Z = sym["M"] * s**2 + sym["V"] * s + sym["K"]
        den = Z.det(method="berkowitz")
        # each output row times sᵈ, d its derivative order
        num = sp.diag(*[s**d for d in model.output_orders]) * sym["C"] * Z.adjugate(method="berkowitz") * sym["B"]
        where_den = "det(M s² + V s + K)"
    else:
        n = sym["A"].rows
        Z = s * sp.eye(n) - sym["A"]
        den = Z.det(method="berkowitz")
        num = sym["C"] * Z.adjugate(method="berkowitz") * sym["B"] + sym["D"] * den
        where_den = "det(sI − A)"
    den_poly = sp.Poly(sp.expand(den), s)
    num_polys = [[sp.Poly(sp.expand(num[i, j]), s) for j in range(num.cols)] for i in range(num.rows)]
    order = den_poly.degree()
    top = max([order] + [q.degree() for row in num_polys for q in row])
    if order < 1 or top > order:
        raise ModelError(f"method 'srivc' needs a proper transfer function with dynamics: D(s) = {where_den} has "
                         f"degree {order}, N(s) degree {top}. Use method='oe'.")
    l = len(params)

    def split(poly: sp.Poly, what: str) -> tuple[np.ndarray, np.ndarray]:
        c0, ct = np.zeros(order + 1), np.zeros((order + 1, l))
        for k in range(order + 1):
            expr = sp.expand(poly.coeff_monomial(s**k))
            if expr == 0:
                continue
            if any(p in expr.free_symbols for p in params) and sp.Poly(expr, *params).total_degree() > 1:
                text = str(sp.N(expr, 6))  # the exact rationals of the known values, shown as decimals
                text = text if len(text) <= 120 else text[:117] + "..."
                raise ModelError(f"method 'srivc' needs every coefficient of the transfer function affine in θ: the "
                                 f"coefficient of s^{k} in {what} is {text}, not affine. Use method='oe' (or "
                                 "reparametrise the model in its transfer-function coefficients).")
            c0[k] = float(expr.subs({p: 0 for p in params}))
            for i, p in enumerate(params):
                ct[k, i] = float(sp.diff(expr, p))
        return c0, ct

    den0, den_theta = split(den_poly, f"D(s) = {where_den}")
    p_out, m_in = num.rows, num.cols
    num0, num_theta = np.zeros((p_out, m_in, order + 1)), np.zeros((p_out, m_in, order + 1, l))
    for i in range(p_out):
        for j in range(m_in):
            num0[i, j], num_theta[i, j] = split(num_polys[i][j], f"the numerator N(s) of G[{i}, {j}]")
    if not np.any(den0) and not np.any(num0):
        raise ModelError("method 'srivc' fits D(s, θ) y = N(s, θ) u, which is homogeneous in θ unless some "
                         "coefficient of the transfer function is a known nonzero constant (a monic denominator, or a "
                         "known input gain such as B = 1): here every coefficient holds parameters, so the scale of θ "
                         "is not fixed. Use method='oe', or fix one coefficient in the model.")
    return TransferPolynomials(order, den0, den_theta, num0, num_theta)


def _stable(den: np.ndarray) -> tuple[np.ndarray, bool]:
    """Monic D (d₀ … dₙ₋₁, lowest first) with its right-half-plane roots reflected; whether any were."""
    roots = np.roots(np.concatenate([[1.0], den[::-1]]))
    bad = roots.real >= 0
    if not np.any(bad):
        return den, False
    size = np.maximum(np.abs(roots), 1e-12)
    roots = np.where(bad, -np.maximum(np.abs(roots.real), 1e-6 * size) + 1j * roots.imag, roots)
    return np.real(np.poly(roots))[1:][::-1].copy(), True


def _relative_residual(Phi: np.ndarray, b: np.ndarray, theta: np.ndarray) -> float:
    """‖Φθ − b‖ / ‖b‖ (0 when b = 0)."""
    size = float(np.linalg.norm(b))
    return float(np.linalg.norm(Phi @ theta - b)) / size if size > 0 else 0.0


class SimplifiedRIVC(JudgedOnSamples):
    """SRIVC: prefilter by the model's own denominator, instruments from its noise-free output (module text).

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
        Its transfer function's coefficients (:func:`transfer_polynomials`) affine in θ,
        with at least one known nonzero coefficient.
    data : IOData, TimeSeries or a list of them
    init : {"ls", "start"}, optional
        Where the iteration starts: least squares on derivatives filtered by (s + λ)ⁿ
        (default; :func:`symid.identify`'s start plays no part) or the start of
        :func:`symid.identify` (``x0=``, else one drawn start).
    bandwidth : float, optional
        λ in rad/s of the least-squares start's filter (default 0.1 / Δt, the median
        sample interval, as method ``svf``).
    max_iter : int, optional
        Largest number of SRIVC iterations (default 20).
    tol : float, optional
        Stop when θ moves less than this, relative to its norm (default 1e-9).
    hold : {"zoh", "foh"}, optional
        Inputs between samples: held (default, as IOData and TimeSeries define them) or
        piecewise linear like the outputs.
    skip : float, optional
        Time left out at the start of each record, where the filters' start from rest
        differs from the record's. Default 0 when the model starts at rest, else 15 time
        constants of the slowest root of D at each iterate.
    initial_state : None, "estimate" or array_like, optional
        For the misfit to the samples (as :class:`~symid.fit.timeseries.oe.OutputError`).
    time_limit : float, optional
        Wall-time budget of one start in seconds, the least-squares start included,
        checked after every iteration (status ``"time_limit"``; the last iterate is kept,
        and the start is not finished; a success only if that estimate fits the data). Default: none.
    callback : callable, optional
        Called after every iteration with a :class:`symid.engine.scr.ScrProgress`
        (iteration, residual ‖Φθ − b‖ / ‖b‖ of the equation prefiltered by the iteration's
        1/D(s, θ̂), misfit to the samples, elapsed seconds, θ); a true return value stops
        the start (status ``"stopped"``).
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
    >>> res = si.identify(model, io, method="srivc")
    >>> np.round(res.theta_vector, 5).tolist()
    [2.0, 0.5, 3.0]
    """

    method: ClassVar[str] = "srivc"  # type: ignore[misc]
    route = "the prefiltered input-output equation (instrumental variables)"

    def __init__(self, model: Any, data: Any, *, init: str = "ls", bandwidth: float | None = None,
                 max_iter: int = 20, tol: float = 1e-9, hold: str = "zoh", skip: float | None = None,
                 initial_state: Any = None, time_limit: float | None = None, callback: Any = None,
                 verbose: bool = False):
        # the samples the estimate is judged on, simulated with the same hold as the filters take the input
        if hold == "bandlimited":  # output error's; the filters here take the input held or linear
            raise OptionError("hold='bandlimited' is output error's (method='oe' or 'auto'); srivc filters the input "
                              "as held ('zoh') or linear ('foh') between samples: 'foh' is the nearest")
        self.samples = OutputError(model, data, initial_state=initial_state, hold=check_choice("hold", hold, _HOLDS))
        self.model, self.data = model, data
        self.poly = transfer_polynomials(model)
        records = self.samples.records
        if self.samples.n_missing:
            raise DataError(f"{self.samples.n_missing} output value(s) are missing (NaN): method {self.method!r} "
                            "filters every output sample; method='oe' or 'auto' leaves missing values out of its "
                            "misfit")
        dt = float(np.median(np.concatenate([np.diff(r.t) for r in records])))
        self._init = check_choice("init", init, _INITS)
        self._lambda = (0.1 / dt if bandwidth is None
                        else check_float("bandwidth", bandwidth, low=0, strict_low=True))
        self._max_iter = check_int("max_iter", max_iter, low=1, high=10**4)
        self._tol = check_float("tol", tol, low=0, strict_low=True)
        self._hold = check_choice("hold", hold, _HOLDS)
        self.time_limit = check_time_limit("time_limit", time_limit)
        self._progress_options(callback, verbose)
        at_rest = self.samples.options["initial_state"] == "zero"
        self._skip = (None if skip is None and not at_rest else 0.0 if skip is None
                      else check_float("skip", skip, low=0))
        rms = np.sqrt(sum(np.sum(r.y**2, axis=0) for r in records) / sum(r.n_samples for r in records))
        self._out_weight = 1.0 / np.where(rms > 0, rms, 1.0)
        self.options = {"init": self._init, "bandwidth": self._lambda, "max_iter": self._max_iter, "tol": self._tol,
                        "hold": self._hold, "skip": "15 time constants of D" if self._skip is None else self._skip,
                        "initial_state": self.samples.options["initial_state"], "time_limit": self.time_limit,
                        "callback": None if callback is None else "given", "verbose": self._verbose,
                        "fits": "the input-output equation prefiltered by 1/D(s, θ̂) (instrumental variables); "
                                "cost, success and uncertainty on the measured samples"}
        if self._skip is not None:
            used = sum(int(np.sum(r.t - r.t[0] >= self._skip)) for r in records) * model.n_outputs
            if used <= model.n_parameters:
                raise OptionError(f"skip={self._skip:g} leaves {used} output value(s) for {model.n_parameters} "
                                  "parameters: give a shorter skip or longer records")

    def _equations(self, den: np.ndarray, theta: np.ndarray | None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, int]:
        """Filtered regression Φ θ = b over all records with the monic prefilter ``den`` and, when ``theta`` is
        given, the instruments Z from the noise-free output at θ; number of samples used."""
        P = self.poly
        if self._skip is None:
            slowest = float(np.min(np.abs(np.roots(np.concatenate([[1.0], den[::-1]])).real)))
            skip = 15.0 / max(slowest, 1e-300)
        else:
            skip = self._skip
        num = None
        if theta is not None:
            num = P.num(theta) / P.den(theta)[-1]
        rows, rhs, inst, used = [], [], [], 0
        for r in self.samples.records:
            keep = (r.t - r.t[0]) >= skip
            if not np.any(keep):
                continue
            uf = prefiltered_derivatives(r.t, r.u, den, self._hold)     # (n+1, N, m)
            yf = prefiltered_derivatives(r.t, r.y, den, "foh")           # (n+1, N, p)
            xf = None
            if num is not None:
                xhat = np.einsum("ijk,kNj->Ni", num, uf)                   # N̂/D̂ u, exact for the hold
                xf = prefiltered_derivatives(r.t, xhat, den, "foh")
            uk = uf[:, keep]
            for i in range(r.n_outputs):
                wgt = self._out_weight[i]
                forced = np.einsum("kNj,jkl->Nl", uk, P.num_theta[i])
                rows.append(wgt * (np.einsum("kN,kl->Nl", yf[:, keep, i], P.den_theta) - forced))
                rhs.append(wgt * (np.einsum("kNj,jk->N", uk, P.num0[i]) - yf[:, keep, i].T @ P.den0))
                if xf is not None:
                    inst.append(wgt * (np.einsum("kN,kl->Nl", xf[:, keep, i], P.den_theta) - forced))
            used += int(keep.sum())
        l = self.model.n_parameters
        if not rows:
            return np.zeros((0, l)), np.zeros(0), (np.zeros((0, l)) if theta is not None else None), 0
        return np.vstack(rows), np.concatenate(rhs), (np.vstack(inst) if theta is not None else None), used

    def least_squares(self) -> tuple[np.ndarray, int, int]:
        """θ from least squares on derivatives filtered by (s + λ)ⁿ (the default start), its rank, samples used.

        Noise on the outputs enters the filtered derivatives, so this estimate is biased
        (toward zero for the highest derivative's coefficient); SRIVC's iteration removes that.
        """
        n = self.poly.order
        den = np.poly(np.full(n, -self._lambda))[1:][::-1].copy()
        Phi, b, _, used = self._equations(den, None)
        scale = np.linalg.norm(Phi, axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        sol, _, rank, _ = np.linalg.lstsq(Phi / scale, b, rcond=None)
        return sol / scale, int(rank), used

    def run(self, x0: np.ndarray) -> StartOutcome:
        """The SRIVC iteration from the least-squares start (``init="ls"``) or from ``x0`` (``init="start"``).

        Each iteration solves θ = (ZᵀΦ)⁻¹ Zᵀ b with Φ, b the equation prefiltered by
        1/D(s, θ̂) and Z the same built from x̂ = N̂/D̂ u (Young & Jakeman 1980). Stops
        when θ moves less than ``tol`` relative (status ``"converged"``), after
        ``max_iter`` iterations (``"max_iter"``), when D's leading coefficient
        vanishes or the instruments are singular at an iterate (the last good θ is kept), or
        after an iteration when ``callback`` asks to (``"stopped"``) or ``time_limit`` is
        spent with iterations left (``"time_limit"``). Only ``"converged"`` is finished.
        """
        t0 = time.perf_counter()
        deadline = None if self.time_limit is None else t0 + self.time_limit
        report = self.progress_reporter(t0)
        l = self.model.n_parameters
        start = np.asarray(x0, dtype=float).reshape(-1)
        used = 0
        if self._init == "ls":
            theta, rank, used = self.least_squares()
            if rank < l:
                return self.outcome(start, theta, finished=False, status="rank deficient",
                                    message=f"the filtered regression has rank {rank} < {l}: the records do not "
                                            "determine θ", iterations=0, wall_time=time.perf_counter() - t0)
            begin = f"least-squares start (λ = {self._lambda:.4g} rad/s)"
        else:
            theta = start.copy()
            begin = "the given start"
        status, why, reflected, steps = "max_iter", "", 0, 0
        for _ in range(self._max_iter):
            den_full = self.poly.den(theta)
            lead = den_full[-1]
            if not np.all(np.isfinite(den_full)) or abs(lead) <= 1e-12 * max(float(np.abs(den_full).max()), 1e-300):
                status, why = "stopped", "; D's leading coefficient vanishes at the iterate: stopped there"
                break
            den, flipped = _stable(den_full[:-1] / lead)
            reflected += int(flipped)
            Phi, b, Z, used = self._equations(den, theta)
            if used * self.model.n_outputs <= l:
                status, why = "stopped", f"; only {used} samples left after skip: stopped"
                break
            scale = np.linalg.norm(Phi, axis=0)
            scale = np.where(scale > 0, scale, 1.0)
            G = (Z / scale).T @ (Phi / scale)
            try:
                new = np.linalg.solve(G, (Z / scale).T @ b) / scale
            except np.linalg.LinAlgError:
                status, why = "stopped", "; the instruments are singular: stopped"
                break
            if not np.all(np.isfinite(new)):
                status, why = "stopped", "; the IV solution is not finite: stopped"
                break
            steps += 1
            moved = np.linalg.norm(new - theta) / max(np.linalg.norm(new), 1e-300)
            theta = new
            asked = report is not None and report(steps, _relative_residual(Phi, b, theta), theta)
            if moved < self._tol:
                status = "converged"
                break
            if asked:
                status, why = "stopped", "; stopped by the callback"
                break
            if deadline is not None and time.perf_counter() >= deadline and steps < self._max_iter:
                status, why = "time_limit", "; " + budget_message(self.time_limit, steps)
                break
        flips = f"; D had right-half-plane roots at {reflected} iterate(s), reflected for the prefilter" \
            if reflected else ""
        message = (f"SRIVC from {begin}: {steps} iteration(s), {status} (tol {self._tol:g}) on {used} filtered "
                   f"samples ({self._hold}){flips}{why}")
        return self.outcome(start, theta, finished=status == "converged", status=status, message=message,
                            iterations=steps, wall_time=time.perf_counter() - t0)
