"""The sampled output of a state-space model on a record: exactly in numpy, and as a CasADi expression.

Between sample times the input is held (zero-order hold), so over an interval h the
state moves exactly by ``x⁺ = Ad(h) x + Bd(h) u`` with ``[[Ad, Bd], [0, I]] =
expm([[A, B], [0, 0]] h)``. Non-uniform sampling needs one exponential per distinct
interval (intervals equal to 1e-9 relative are grouped).

In numpy the exponential is :func:`scipy.linalg.expm` (Padé, scaling and squaring); the
CasADi form, which IPOPT differentiates exactly, is a degree-14 Taylor polynomial of
``M / 2^s`` followed by s squarings, with s chosen so that ``‖M‖₁ / 2^s ≤ 1/8`` at the θ
it is built for: the truncation error is then below (1/8)^15/15! ≈ 2e-26 relative.
The estimator rebuilds with a larger s when the estimate moves out of that range
(:func:`squarings`).

Before the Taylor polynomial the matrix is balanced by a diagonal similarity of powers of
two, ``diag(d, e)⁻¹ M diag(d, e)`` (states by LAPACK's ``gebal`` on ``A h``, every input
column to the size of the balanced ``A h``; :func:`balancing`), and the exponential is
scaled back: e^M = diag(d, e) e^{M̃} diag(d, e)⁻¹ exactly. Without it, the units of the
states and inputs set the norm: a time axis in microseconds puts entries 1e6 apart in
``A h`` of a second-order model ([q; q̇], q̇ = dq/dt), s grows from 4 to 19, and the
rounding of 19 squarings left IPOPT on the oe misfit short of its tolerance for 500
iterations (measured, tests/test_units_invariance.py).
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np
from scipy.linalg import matrix_balance

from symid.signal.simulate import foh_discretize, zoh_discretize

__all__ = ["balancing", "casadi_output", "held_differences", "interval_groups", "simulate_output", "squarings",
           "state_transitions"]

_TAYLOR_DEGREE = 14
_GROUP_RTOL = 1e-9


def interval_groups(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct sample intervals (to 1e-9 relative) and, per interval k → k+1, the index of its group."""
    h = np.diff(np.asarray(t, dtype=float))
    key = np.round(h / (h.max() * _GROUP_RTOL)).astype(np.int64)
    uniq, inverse = np.unique(key, return_inverse=True)
    reps = np.array([float(np.mean(h[inverse == g])) for g in range(uniq.size)])
    return reps, inverse.reshape(-1)


def balancing(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Powers of two (d per state, e per input) that balance ``[[A h, B h], [0, 0]]`` (ones where A or B is
    not finite).

    d is LAPACK's balancing of ``A h`` (``scipy.linalg.matrix_balance``, no permutation); e
    brings every column of the balanced ``B h`` to the 1-norm of the balanced ``A h`` (to 1/8
    where that is 0).

    Examples
    --------
    The oscillator 2 q̈ + 0.8 q̇ + 50 q = u sampled every 0.05 s, with time in seconds and in
    microseconds (x = [q, dq/dt], A = [[0, 1], [−k/m, −c/m]], B = [[0], [1/m]]): balanced,
    both need the same squarings.

    >>> import numpy as np
    >>> from symid.fit.timeseries.response import balancing, squarings
    >>> for a in (1.0, 1e-6):
    ...     A, B, h = np.array([[0.0, 1.0], [-25.0 * a**2, -0.4 * a]]), np.array([[0.0], [0.5 * a**2]]), 0.05 / a
    ...     print(squarings(A, B, h), squarings(A, B, h, balancing(A, B, h)))
    4 2
    19 2
    """
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    n, m = B.shape
    d, e = np.ones(n), np.ones(m)
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))) or n == 0:
        return d, e
    _, (d, _) = matrix_balance(A * h, permute=False, separate=True)
    Ab = A * h * d[None, :] / d[:, None]
    target = float(np.abs(Ab).sum(axis=0).max()) or 0.125
    cols = np.abs(B * h / d[:, None]).sum(axis=0)
    with np.errstate(divide="ignore"):
        e = np.where(cols > 0, 2.0 ** np.round(np.log2(target / np.where(cols > 0, cols, 1.0))), 1.0)
    return np.asarray(d, dtype=float), e


def squarings(A: np.ndarray, B: np.ndarray, h_max: float, balance: tuple[np.ndarray, np.ndarray] | None = None
              ) -> int:
    """s with ‖[[A, B], [0, 0]] h_max‖₁ / 2^s ≤ 1/8, balanced by ``balance`` = (d, e) when given
    (:func:`balancing`)."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    if balance is not None:
        g = np.concatenate([balance[0], balance[1]])
        M = M * g[None, :] / g[:, None]
    norm = float(np.abs(M).sum(axis=0).max()) * h_max
    return max(0, math.ceil(math.log2(8.0 * norm))) if norm > 0 else 0


def held_differences(u: np.ndarray, held: np.ndarray | None) -> np.ndarray:
    """u_{k+1} − u_k of every input, 0 for the inputs ``held`` marks: x⁺ = Ad x + G1 u + G2 (u⁺ − u) is then exact for
    those held between samples (G1 is the zero-order hold's input matrix) and the others linear.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.timeseries.response import held_differences
    >>> held_differences(np.array([[0.0, 1.0], [2.0, 4.0]]), np.array([True, False])).tolist()
    [[0.0, 3.0]]
    """
    du = np.diff(u, axis=0)
    if held is not None:
        du[:, np.asarray(held, dtype=bool)] = 0.0
    return du


def simulate_output(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, t: np.ndarray, u: np.ndarray,
                    x0: np.ndarray, hold: str = "zoh", held: np.ndarray | None = None) -> np.ndarray:
    """ŷ(t_k), shape (N, p), from x(t_0) = x0 (shape (n,)); exact for the input held between samples
    (``hold="zoh"``) or linear between them (``"foh"``; with ``held``, a mask of the inputs, those held) (scipy
    expm)."""
    reps, group = interval_groups(t)
    if hold == "foh":
        three = [foh_discretize(A, B, h) for h in reps]
        mats = [(Ad, None) for Ad, _, _ in three]
        du = held_differences(u, held)
        Bu = [u[:-1] @ G1.T + du @ G2.T for _, G1, G2 in three]
    else:
        mats = [zoh_discretize(A, B, h) for h in reps]
        Bu = [u[:-1] @ Bd.T for _, Bd in mats]
    N, n = u.shape[0], A.shape[0]
    X = np.empty((N, n))
    x = np.asarray(x0, dtype=float).reshape(n)
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(N):
            X[k] = x
            if k < N - 1:
                g = group[k]
                x = mats[g][0] @ x + Bu[g][k]
        return X @ C.T + u @ D.T


def state_transitions(A: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Φ(t_k, t_0) = e^{A (t_k − t_0)} for every sample, shape (N, n, n) (for the x0 least squares)."""
    reps, group = interval_groups(t)
    n = A.shape[0]
    Ads = [zoh_discretize(A, np.zeros((n, 1)), h)[0] for h in reps]
    out = np.empty((t.size, n, n))
    P = np.eye(n)
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(t.size):
            out[k] = P
            if k < t.size - 1:
                P = Ads[group[k]] @ P
    return out


def _expm_taylor(M: Any, s: int) -> Any:
    """e^M as CasADi expressions: Taylor polynomial of M / 2^s (Horner), squared s times."""
    size = M.shape[0]
    X = M / float(2**s)
    eye = ca.SX.eye(size)
    E = eye
    for k in range(_TAYLOR_DEGREE, 0, -1):
        E = eye + ca.mtimes(X, E) / k
    for _ in range(s):
        E = ca.mtimes(E, E)
    return E


def casadi_output(A: Any, B: Any, C: Any, D: Any, t: np.ndarray, u: np.ndarray, x0: Any, s_max: int,
                  balance: tuple[Any, Any] | None = None) -> Any:
    """ŷ(t_k) as an (N, p) CasADi SX expression in the symbols of A, B, C, D and x0.

    ``s_max`` squarings are used for the longest interval, fewer for shorter ones
    (the norm halves with the interval). ``balance`` = (d, e), numbers or CasADi symbols
    (columns n and m), balances the matrix before the exponential (:func:`balancing`).
    """
    n, m = A.shape[0], B.shape[1]
    reps, group = interval_groups(t)
    h_max = float(reps.max())
    if balance is not None:
        d, e = (ca.SX(ca.DM(np.asarray(v, dtype=float).reshape(-1, 1))) if isinstance(v, np.ndarray) else v
                for v in balance)
        state_in, input_in = ca.mtimes(1 / d, d.T), ca.mtimes(1 / d, e.T)  # M̃ = diag(d, e)⁻¹ M diag(d, e)
        state_out, input_out = ca.mtimes(d, (1 / d).T), ca.mtimes(d, (1 / e).T)
    mats = []
    for h in reps:
        s = max(0, s_max - math.floor(math.log2(h_max / h)))
        Ah, Bh = A * h, B * h
        if balance is not None:
            Ah, Bh = Ah * state_in, Bh * input_in
        E = _expm_taylor(ca.vertcat(ca.horzcat(Ah, Bh), ca.SX(m, n + m)), s)
        Ad, Bd = E[:n, :n], E[:n, n:]
        if balance is not None:
            Ad, Bd = Ad * state_out, Bd * input_out
        mats.append((Ad, Bd))
    free = not np.any(u)
    x = x0
    rows = []
    N = t.size
    for k in range(N):
        rows.append(ca.mtimes(C, x) + (0 if free else ca.mtimes(D, ca.DM(u[k]))))
        if k < N - 1:
            Ad, Bd = mats[group[k]]
            x = ca.mtimes(Ad, x) if free else ca.mtimes(Ad, x) + ca.mtimes(Bd, ca.DM(u[k]))
    return ca.horzcat(*rows).T
