"""Subspace identification (N4SID) of a discrete-time state-space model from input/output records.

Step 1 of the thesis's Algorithms 6.1 and 7.1: a black box (Ad, Bd, C, D) in an unknown
state basis, from sampled u[k], y[k]. The algorithm is the deterministic–stochastic
N4SID of Van Overschee & De Moor (1994; thesis reference [26]):

1. block Hankel matrices of the past and future inputs and outputs over a horizon of
   i samples, Up, Uf, Yp, Yf, and Wp = [Up; Yp];
2. the oblique projection O = Yf /_Uf Wp, computed on the triangular factor of one LQ
   decomposition of [Uf; Wp; Yf];
3. its singular value decomposition; the n leading left singular vectors scaled by the
   square roots of the singular values are the extended observability matrix Γ;
4. C is the first block row of Γ and Ad solves the shift equation Γ↑ Ad = Γ↓ in least
   squares;
5. with Ad and C fixed the output is linear in Bd, D and the initial state, which are
   then found by one linear least squares over the whole record.

On noise-free data from a system of order n driven by a persistently exciting input
the result is exact up to rounding (a similarity transform of the truth).

A constant input (an offset: a constant force, a sensor bias through D) is not
persistently exciting and cannot enter the Hankel matrices; it is handled exactly
instead. Its contribution to the future outputs, the same in every column of the
Hankel matrices, is removed by centring every row of them (the state it drives keeps
its place in the range of Γ), and its B and D columns are then estimated in step 5
with the others. Pass ``offset=True`` to add such an input (u = 1, the last column),
or give the constant column in the data.

Errors are named, never raw numpy errors: an estimate of A with a pole outside the
unit circle makes the simulation in step 5 grow like |z|ᴺ; when that exceeds 1e250
over the record (near the overflow of double precision; e.g. |z| = 1.05 on 24 841
samples) step 5 is refused with the pole and what to change, rather than left to
overflow inside LAPACK. A milder unstable estimate is returned (look at ``poles``).

Oversampled records
-------------------
N4SID sees the dynamics through i samples of past and future. With data sampled far
above the band of interest (the slowest mode of interest spanning thousands of
samples) the default horizon sees a nearly constant signal and the singular values
no longer separate the modes from noise (look at ``singular_values``: no clear gap
after the order). Two remedies:

* decimate first (:func:`scipy.signal.decimate` on input and output, whose
  anti-alias filter keeps the band) to a sample rate of about ten times the highest
  frequency of interest, and use a horizon of about 20. The poles do not depend on
  the hold, so natural frequencies and damping ratios are unbiased; the filtered
  input is no longer held between samples, so the zero-order-hold ``d2c`` puts a
  phase error of about ω·dt/2 into the zeros (the frequency response), which a
  grey-box fit of a frequency response would see;
* or keep the rate and raise the horizon so that i·dt covers a quarter period of the
  slowest mode (the cost grows like i², and the record must hold 2(m + p)i + 2i
  samples).

Measured by ``benchmarks/n4sid_oversampling.py`` (two modes at 1 and 3 Hz, ζ = 2 % and
1 %, 1 % output noise, 60 periods, worst of 3 seeds): sampled at 30× the highest mode,
the default horizon misses the damping by 200 %, horizon 23 gets within 1 %; at 100×
and 300× the default fails outright, while decimating to 10× with horizon 20 gets the
frequencies within 1e-4 and the damping ratios within 0.2 % (README, "N4SID on
oversampled records").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg
import scipy.signal

from symid.data import BlackBox, IOData
from symid.errors import DataError

__all__ = ["DiscreteStateSpace", "fit_input_matrices", "n4sid"]

#: A singular value below this fraction of the largest is treated as zero: the data do
#: not hold that many states.
_RANK_TOL = 1e-12
#: Step 5 is refused when the estimated A grows the simulation by more than 10**_MAX_GROWTH over the record.
_MAX_GROWTH = 250.0


@dataclass(frozen=True)
class DiscreteStateSpace:
    """A discrete-time model x[k+1] = A x[k] + B u[k], y[k] = C x[k] + D u[k] with sample time dt.

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        The matrices, shapes (n, n), (n, m), (p, n), (p, m).
    dt : float
        Sample time in seconds.
    singular_values : numpy.ndarray
        N4SID: singular values of the oblique projection (the order is the number of
        clearly nonzero ones); empty for a model not estimated by :func:`n4sid`.
    horizon : int
        N4SID: block rows i of the past and future Hankel matrices (0 otherwise).
    x0 : numpy.ndarray
        N4SID: the estimated initial state.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float
    singular_values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    horizon: int = 0
    x0: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def n_states(self) -> int:
        """Order n."""
        return int(self.A.shape[0])

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of A (discrete-time poles)."""
        return np.linalg.eigvals(self.A)

    def frequency_response(self, w: Any) -> np.ndarray:
        """H(e^{jω dt}) = C (e^{jω dt} I − A)⁻¹ B + D at angular frequencies ``w`` (rad/s), shape (s, p, m)."""
        w = np.atleast_1d(np.asarray(w, dtype=float))
        z = np.exp(1j * w * self.dt)
        n = self.n_states
        X = np.linalg.solve(z[:, None, None] * np.eye(n) - self.A, np.broadcast_to(self.B.astype(complex),
                                                                                     (w.size, *self.B.shape)))
        return self.C @ X + self.D

    def to_continuous(self, *, band: Any = None) -> BlackBox:
        """The exact zero-order-hold continuous-time equivalent (:func:`symid.d2c`).

        ``band=(w_low, w_high)`` (rad/s) keeps only the modes whose natural frequency lies
        in the band, e.g. to drop a mode N4SID put at the Nyquist frequency (see :func:`symid.d2c`).
        """
        from symid.signal.zoh import d2c

        return d2c(self.A, self.B, self.C, self.D, self.dt, band=band)

    def summary(self) -> str:
        """Sizes, sample time, poles and (for N4SID) the leading singular values."""
        poles = np.sort_complex(self.poles)
        lines = ["DiscreteStateSpace", f"  states n  : {self.n_states}", f"  inputs m  : {self.B.shape[1]}",
                 f"  outputs p : {self.C.shape[0]}", f"  dt        : {self.dt:.6g} s",
                 f"  poles     : {', '.join(f'{z:.6g}' for z in poles)}"]
        if self.singular_values.size:
            sv = self.singular_values[: self.n_states + 3]
            lines.append(f"  N4SID singular values (horizon {self.horizon}): {', '.join(f'{v:.3e}' for v in sv)}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON."""
        return {"A": self.A.tolist(), "B": self.B.tolist(), "C": self.C.tolist(), "D": self.D.tolist(),
                "dt": self.dt, "singular_values": self.singular_values.tolist(), "horizon": self.horizon,
                "x0": self.x0.tolist()}


def _hankel(x: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """Block Hankel matrix with ``rows`` block rows: block row r holds x[r : r + cols]ᵀ."""
    return np.vstack([x[r:r + cols].T for r in range(rows)])


def _min_samples(i: int, order: int, m: int, p: int) -> int:
    """Samples needed for horizon i: j = N − 2i + 1 columns, at least 2(m + p)i + n of them."""
    return 2 * i - 1 + 2 * (m + p) * i + order


def _default_horizon(order: int, m: int, p: int, n_samples: int) -> int:
    """``max(n + 1, 2⌈n/p⌉)``, raised to 10 when the record is long enough (oversampled data need it)."""
    low = max(order + 1, 2 * math.ceil(order / p))
    i = max(low, 10)
    while i > low and n_samples < _min_samples(i, order, m, p):
        i -= 1
    return i


def _constant_inputs(u: np.ndarray) -> list[int]:
    """Columns of ``u`` that are constant and nonzero (offsets); a zero column is refused."""
    out = []
    for c in range(u.shape[1]):
        col = u[:, c]
        top = float(np.max(np.abs(col)))
        if top == 0.0:
            raise DataError(f"input {c} is zero throughout the record: it carries no information (drop it)")
        if float(np.ptp(col)) <= 1e-12 * top:
            out.append(c)
    if len(out) > 1:
        raise DataError(f"inputs {', '.join(map(str, out))} are all constant: their effects cannot be told apart; "
                        "keep one constant (offset) input")
    if len(out) == u.shape[1]:
        raise DataError("every input is constant (not persistently exciting): N4SID, which does not assume the "
                        "record starts at rest, cannot identify a model from it (an output-error fit from rest "
                        "still can: a step response)")
    return out


def _check(io: Any, order: Any, horizon: Any, m: int) -> tuple[int, int]:
    if not isinstance(io, IOData):
        raise DataError(f"n4sid needs input/output records as symid.IOData(u, y, dt); got {type(io).__name__}")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
        raise DataError(f"order must be a positive integer (the number of states); got {order!r}")
    order = int(order)
    p = io.n_outputs
    if horizon is None:
        horizon = _default_horizon(order, m, p, io.n_samples)
    if isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) or horizon < 1:
        raise DataError(f"horizon must be a positive integer (block rows of the Hankel matrices); got {horizon!r}")
    i = int(horizon)
    if p * i < order:
        raise DataError(f"horizon {i} with {p} output(s) can reveal at most {p * i} states, fewer than order {order}: "
                        f"use horizon >= {math.ceil(order / p)}")
    need = _min_samples(i, order, m, p)
    if io.n_samples < need:
        raise DataError(f"the record of N = {io.n_samples} samples is too short for order {order} with horizon {i}, "
                        f"{m} input(s) and {p} output(s): N4SID needs at least 2i − 1 + 2(m + p)i + n = {need} "
                        "samples; record longer, or lower the order or the horizon")
    return order, i


def _markov(A: np.ndarray, C: np.ndarray, N: int) -> np.ndarray:
    """``C A^k`` for k = 0..N−1, shape (N, p, n), by doubling: block [s, 2s) is block [0, s) times A^s."""
    p, n = C.shape
    M = np.empty((N, p, n))
    M[0] = C
    power, filled = A.copy(), 1  # power = A^filled
    with np.errstate(over="ignore", invalid="ignore"):
        while filled < N:
            k = min(filled, N - filled)
            M[filled:filled + k] = M[:k] @ power
            filled += k
            power = power @ power
    return M


def _b_d_x0(io: IOData, A: np.ndarray, C: np.ndarray, feedthrough: bool, *, u: np.ndarray | None = None
            ) -> tuple[np.ndarray, ...]:
    """Least squares for B, D and x0 with A and C fixed (the output is linear in them).

    ``y_k = Σ_{l<k} C A^{k−1−l} B u_l + D u_k + C A^k x0``: the regressor of ``B[r, c]``
    is the convolution of the Markov sequence ``C A^j e_r`` with input c, computed for
    every r and c at once by FFT (:func:`scipy.signal.fftconvolve`) on the sequence of
    :func:`_markov`; the regressor of x0 is that sequence itself. No per-sample Python loop.
    ``u`` replaces ``io.u`` (the inputs with an added offset column).
    """
    u = io.u if u is None else u
    y = io.y
    N, m = u.shape
    p, n = C.shape
    try:
        poles = np.linalg.eigvals(A)
    except np.linalg.LinAlgError:
        raise DataError("N4SID: the eigenvalues of the estimated A could not be computed") from None
    rho = float(np.max(np.abs(poles)))
    growth = (N - 1) * math.log10(rho) if rho > 0 else -np.inf
    if not np.isfinite(rho) or growth > _MAX_GROWTH:
        z = poles[np.argmax(np.abs(poles))]
        raise DataError(f"N4SID's estimate of A is unstable: pole z = {z:.6g} (|z| = {rho:.6g} > 1) grows the "
                        f"simulation by 10^{growth:.0f} over the {N} samples, so B, D and x0 cannot be fitted; the "
                        "data do not support a stable model of this order: lower the order, change the horizon, "
                        "decimate an oversampled record, or check the record (drift, an unstable or closed loop); "
                        "a system with a rigid-body mode or an integrator has a pole at z = 1, which N4SID can "
                        "place just outside the unit circle: harmless when the fit itself succeeds")
    M = _markov(A, C, N)  # (N, p, n)
    # rows_B[k, :, c, :] = Σ_{j<k} M_j u_{k-1-j}[c]  (zero at k = 0)
    conv = scipy.signal.fftconvolve(M.reshape(N, 1, p * n), u[:, :, None], axes=0)[: N - 1]  # (N-1, m, p*n)
    rows_B = np.zeros((N, p, m, n))
    rows_B[1:] = np.transpose(conv.reshape(N - 1, m, p, n), (0, 2, 1, 3))
    # y_k = Σ_c (C X_k[c]) B[:, c] + D u_k + C A^k x0 ; unknowns vec(B) (row-major: B[r, c] at r*m + c)
    JB = np.transpose(rows_B, (0, 1, 3, 2)).reshape(N * p, n * m)
    blocks = [JB]
    if feedthrough:
        JD = np.einsum("pq,kc->kpqc", np.eye(p), u).reshape(N * p, p * m)
        blocks.append(JD)
    blocks.append(M.reshape(N * p, n))
    J = np.hstack(blocks)
    if not np.all(np.isfinite(J)):
        raise DataError(f"N4SID: the simulation of the estimated model over the record is not finite (largest "
                        f"|pole| {rho:.6g}); lower the order or decimate the record")
    try:
        sol, *_ = np.linalg.lstsq(J, y.reshape(-1), rcond=None)
    except np.linalg.LinAlgError as exc:
        raise DataError(f"N4SID: the least squares for B, D and x0 failed ({exc}); largest |pole| {rho:.6g}") from None
    B = sol[: n * m].reshape(n, m)
    pos = n * m
    D = np.zeros((p, m))
    if feedthrough:
        D = sol[pos:pos + p * m].reshape(p, m)
        pos += p * m
    return B, D, sol[pos:]


def fit_input_matrices(io: IOData, A: Any, C: Any, *, feedthrough: bool = True) -> DiscreteStateSpace:
    """The discrete-time model with A and C given and B, D and x0 fitted to the record by least squares (the last
    step of :func:`n4sid`, the output being linear in them), at the record's sample time.

    Parameters
    ----------
    io : IOData
    A, C : array_like
        (n, n) and (p, n), at the sample time ``io.dt``.
    feedthrough : bool
        Fit D too (else D = 0).

    Returns
    -------
    DiscreteStateSpace
        With ``x0`` the fitted initial state.

    Raises
    ------
    DataError
        On an A whose simulation over the record would overflow (a pole far outside the unit circle), or a least
        squares that fails.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.signal.subspace import fit_input_matrices
    >>> u = np.random.default_rng(0).standard_normal(200)
    >>> x, y = 0.0, []
    >>> for uk in u:  # x[k+1] = 0.9 x[k] + 0.5 u[k], y = x + 0.1 u
    ...     y.append(x + 0.1 * uk)
    ...     x = 0.9 * x + 0.5 * uk
    >>> bb = fit_input_matrices(si.IOData(u, y, 1.0), [[0.9]], [[1.0]])
    >>> np.round([bb.B[0, 0], bb.D[0, 0]], 6).tolist()
    [0.5, 0.1]
    """
    A = np.atleast_2d(np.asarray(A, dtype=float))
    C = np.atleast_2d(np.asarray(C, dtype=float))
    B, D, x0 = _b_d_x0(io, A, C, feedthrough)
    return DiscreteStateSpace(A, B, C, D, float(io.dt), x0=np.asarray(x0, dtype=float))


def n4sid(io: IOData, order: int, *, horizon: int | None = None, feedthrough: bool = True,
          offset: bool = False, normalise: bool = True) -> DiscreteStateSpace:
    """Estimate a discrete-time state-space model of the given order from input/output records (N4SID).

    Parameters
    ----------
    io : IOData
        Input samples u (N, m), output samples y (N, p) and the sample time dt.
    order : int
        Number of states n.
    horizon : int, optional
        Block rows i of the past and future Hankel matrices; default
        ``max(n + 1, 2⌈n/p⌉, 10)`` (less than 10 when the record is too short for it).
        Larger values see more of the dynamics (oversampled records need them, see
        the module notes on decimation and horizon) but cost more.
    feedthrough : bool
        Estimate D (default); ``False`` fixes D = 0 (strictly proper, e.g. position
        outputs of a mechanical model), the offset input's column included.
    offset : bool
        Add a constant input u = 1 as the last input (default False): its B column is a
        constant force or disturbance, its D column (with ``feedthrough``) a constant
        output offset. A constant column already in ``io.u`` is handled the same way
        (module notes); at most one constant input.
    normalise : bool
        Run the algorithm on each input and output divided by its rms over the record, and
        scale the estimate back (default True), so that it does not depend on the units of
        any channel: the projections and the least squares of N4SID weigh the channels by
        their size, and an output in mK instead of K moved a new user's three-node thermal
        network's poles by 30 % (FRF error 0.2 % → 5 %). ``singular_values`` are then
        those of the normalised records. ``False``: the records as given.

    Returns
    -------
    DiscreteStateSpace
        (A, B, C, D) with ``dt = io.dt``, the singular values of the oblique projection
        and the estimated initial state; with ``offset=True``, B and D have one more
        column than ``io.u``.

    Raises
    ------
    DataError
        On a bad order or horizon, a record too short for them, an input that is not
        persistently exciting (or zero, or several constant inputs), data that hold
        fewer than ``order`` states (the ``order``-th singular value is zero: the order
        is too high for these data, or the black box would not be minimal), or an
        estimate of A so unstable that B, D and x0 cannot be fitted over the record
        (the pole is named). Never a raw numpy error.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> a = si.parameters("a", positive=True)
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]])
    >>> u = np.random.default_rng(0).standard_normal(200)
    >>> io = si.simulate_io(model, {"a": 2.0}, u, dt=0.1)
    >>> dss = si.n4sid(io, 1, feedthrough=False)
    >>> bool(np.isclose(dss.A[0, 0], np.exp(-0.2), rtol=1e-9))
    True
    >>> bool(np.isclose(dss.to_continuous().A[0, 0], -2.0, rtol=1e-8))
    True
    """
    if not isinstance(offset, (bool, np.bool_)):
        raise DataError(f"offset must be True or False; got {offset!r}")
    if not isinstance(io, IOData):
        raise DataError(f"n4sid needs input/output records as symid.IOData(u, y, dt); got {type(io).__name__}")
    if not isinstance(normalise, (bool, np.bool_)):
        raise DataError(f"normalise must be True or False; got {normalise!r}")
    if normalise:
        su, sy = _rms(io.u), _rms(io.y)
        if np.any(su != 1.0) or np.any(sy != 1.0):
            unit = IOData(io.u / su, io.y / sy, io.dt, time_unit=io.time_unit)
            dss = n4sid(unit, order, horizon=horizon, feedthrough=feedthrough, offset=offset, normalise=False)
            su = np.append(su, 1.0) if offset else su  # the offset input is 1 in any units
            return DiscreteStateSpace(A=dss.A, B=dss.B / su[None, :], C=sy[:, None] * dss.C,
                                      D=sy[:, None] * dss.D / su[None, :], dt=dss.dt,
                                      singular_values=dss.singular_values, horizon=dss.horizon, x0=dss.x0)
    u_all, y = io.u, io.y
    if offset:
        u_all = np.hstack([u_all, np.ones((io.n_samples, 1))])
    const = _constant_inputs(u_all)
    u = np.delete(u_all, const, axis=1)  # the inputs that enter the Hankel matrices
    m, p = u.shape[1], io.n_outputs
    n, i = _check(io, order, horizon, m)
    j = io.n_samples - 2 * i + 1
    U = _hankel(u, 2 * i, j)
    Y = _hankel(y, 2 * i, j)
    Up, Uf = U[: m * i], U[m * i:]
    Yp, Yf = Y[: p * i], Y[p * i:]
    H = np.vstack([Uf, Up, Yp, Yf])
    if const:  # a constant input adds the same vector to every column: centring the rows removes it exactly
        H = H - H.mean(axis=1, keepdims=True)
    H = H / math.sqrt(j)
    try:
        return _n4sid_core(H, io, None if u_all is io.u else u_all, n, i, m, p, feedthrough)
    except np.linalg.LinAlgError as exc:  # a last guard: every step above names its own failures
        raise DataError(f"N4SID failed in its linear algebra ({exc}); check the record for huge values or "
                        "lower the order") from None


def _rms(x: np.ndarray) -> np.ndarray:
    """Root mean square of each column; 1 where it is 0 or not finite (a zero input is refused later)."""
    r = np.sqrt(np.mean(np.asarray(x, dtype=float) ** 2, axis=0))
    return np.where(np.isfinite(r) & (r > 0), r, 1.0)


def _n4sid_core(H: np.ndarray, io: IOData, u_all: np.ndarray | None, n: int, i: int, m: int, p: int,
                feedthrough: bool) -> DiscreteStateSpace:
    """Steps 2–5 on the stacked (scaled) Hankel matrix H = [Uf; Up; Yp; Yf]."""
    L = scipy.linalg.qr(H.T, mode="r")[0][: H.shape[0]].T  # H = L Qᵀ, L lower triangular
    mu, mw = m * i, (m + p) * i
    Luu = L[:mu, :mu]
    if np.min(np.abs(np.diag(Luu))) <= 1e-10 * max(np.max(np.abs(np.diag(Luu))), 1e-300):
        raise DataError(f"the input is not persistently exciting of order {2 * i} (horizon {i}): its future block "
                        "Hankel matrix is rank deficient; use a richer input (e.g. white noise) or a smaller horizon")
    L_uw = L[: mu + mw, : mu + mw]
    L_y = L[mu + mw:, : mu + mw]
    coef = L_y @ np.linalg.pinv(L_uw)
    Lw = coef[:, mu:]
    O = Lw @ L[mu: mu + mw, : mu + mw]  # oblique projection Yf /_Uf Wp, in the Q basis
    Us, s, _ = np.linalg.svd(O, full_matrices=False)
    if s[0] <= 0 or not np.isfinite(s[0]):
        raise DataError("the outputs hold no response to the inputs (the oblique projection is zero)")
    if n > s.size or s[n - 1] <= _RANK_TOL * s[0]:
        k = int(np.sum(s > _RANK_TOL * s[0]))
        raise DataError(f"the data determine at most {k} state(s), fewer than order {n}: the order is too high for "
                        f"these data (singular values {', '.join(f'{v:.2e}' for v in s[: n + 1])}); a model of this "
                        f"order would not be minimal")
    G = Us[:, :n] * np.sqrt(s[:n])
    C = G[:p]
    A, *_ = np.linalg.lstsq(G[:-p], G[p:], rcond=None)
    B, D, x0 = _b_d_x0(io, A, C, feedthrough) if u_all is None else _b_d_x0(io, A, C, feedthrough, u=u_all)
    return DiscreteStateSpace(A=A, B=B, C=C, D=D, dt=io.dt, singular_values=s, horizon=i, x0=x0)
