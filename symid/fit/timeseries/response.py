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
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from symid.signal.simulate import zoh_discretize

__all__ = ["casadi_output", "interval_groups", "simulate_output", "squarings", "state_transitions"]

_TAYLOR_DEGREE = 14
_GROUP_RTOL = 1e-9


def interval_groups(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct sample intervals (to 1e-9 relative) and, per interval k → k+1, the index of its group."""
    h = np.diff(np.asarray(t, dtype=float))
    key = np.round(h / (h.max() * _GROUP_RTOL)).astype(np.int64)
    uniq, inverse = np.unique(key, return_inverse=True)
    reps = np.array([float(np.mean(h[inverse == g])) for g in range(uniq.size)])
    return reps, inverse.reshape(-1)


def squarings(A: np.ndarray, B: np.ndarray, h_max: float) -> int:
    """s with ‖[[A, B], [0, 0]] h_max‖₁ / 2^s ≤ 1/8."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    norm = float(np.abs(M).sum(axis=0).max()) * h_max
    return max(0, math.ceil(math.log2(8.0 * norm))) if norm > 0 else 0


def simulate_output(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, t: np.ndarray, u: np.ndarray,
                    x0: np.ndarray) -> np.ndarray:
    """ŷ(t_k), shape (N, p), from x(t_0) = x0 (shape (n,)); exact zero-order hold (scipy expm)."""
    reps, group = interval_groups(t)
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


def casadi_output(A: Any, B: Any, C: Any, D: Any, t: np.ndarray, u: np.ndarray, x0: Any, s_max: int) -> Any:
    """ŷ(t_k) as an (N, p) CasADi SX expression in the symbols of A, B, C, D and x0.

    ``s_max`` squarings are used for the longest interval, fewer for shorter ones
    (the norm halves with the interval).
    """
    n, m = A.shape[0], B.shape[1]
    reps, group = interval_groups(t)
    h_max = float(reps.max())
    mats = []
    for h in reps:
        s = max(0, s_max - math.floor(math.log2(h_max / h)))
        M = ca.vertcat(ca.horzcat(A * h, B * h), ca.SX(m, n + m))
        E = _expm_taylor(M, s)
        mats.append((E[:n, :n], E[:n, n:]))
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
