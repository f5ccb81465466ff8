"""The sampled output of a state-space model and its exact derivatives with respect to θ, in numpy.

The output error's residual Jacobian, for the covariance of θ̂ and for Gauss–Newton steps,
without a symbolic graph: CasADi's Jacobian of 2500 samples of a 5-mass chain takes
12 s to build and cannot be interrupted; this recursion costs milliseconds per
evaluation.

Over a sample interval h with the input held (zero-order hold),

    x⁺ = Ad x + Bd u,   [[Ad, Bd], [0, I]] = expm(F h),   F = [[A, B], [0, 0]],

and the derivative of the exponential along dF = ∂F/∂θₖ is its Fréchet derivative
(:func:`scipy.linalg.expm_frechet`, Al-Mohy & Higham 2009), which gives ∂Ad/∂θₖ and
∂Bd/∂θₖ exactly. The sensitivities Sₖ = ∂x/∂θₖ then follow the same recursion,

    Sₖ⁺ = Ad Sₖ + (∂Ad/∂θₖ) x + (∂Bd/∂θₖ) u,     Sₖ(t₀) = ∂x(t₀)/∂θₖ,

and ∂ŷ/∂θₖ = C Sₖ + (∂C/∂θₖ) x + (∂D/∂θₖ) u. An estimated initial state is one more
column per state, with Sₖ(t₀) a unit vector and no forcing. With the input linear between
samples (first-order hold), x⁺ = Ad x + G1 u + G2 (u⁺ − u) from one larger block
exponential, differentiated the same way.

For a second-order model in first-order form (x = [q; q']), A = [[0, I], [−M⁻¹K, −M⁻¹V]]
and B = [0; M⁻¹B] are rational in θ: ∂(M⁻¹X)/∂θₖ = M⁻¹(∂X/∂θₖ − (∂M/∂θₖ) M⁻¹X).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.linalg import expm, expm_frechet

from symid.fit.timeseries.response import held_differences, interval_groups

__all__ = ["output_sensitivity", "state_space_derivatives"]


def state_space_derivatives(model: Any, theta: np.ndarray) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """((A, B, C, D), (dA, dB, dC, dD)) at θ, each dX of shape (l, rows, cols): ∂X/∂θₖ stacked over k.

    Examples
    --------
    The oscillator m q'' + c q' + k q = u, position output: ∂A/∂m holds k/m² and c/m².

    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.timeseries.sensitivity import state_space_derivatives
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> (A, B, C, D), (dA, dB, dC, dD) = state_space_derivatives(model, np.array([2.0, 1.0, 4.0]))
    >>> dA[0].tolist(), dB[0].tolist()
    ([[0.0, 0.0], [1.0, 0.25]], [[0.0], [-0.25]])
    """
    theta = np.asarray(theta, dtype=float).reshape(-1)
    maps = model.maps
    if "M" not in maps:
        mats = tuple(maps[k](theta) for k in "ABCD")
        return mats, tuple(np.asarray(maps[k].Xi, dtype=float) for k in "ABCD")
    A, B, C, D = model.state_space(theta)  # raises a ModelError where M(θ) is singular
    M, V, K, Bm, Cm = (maps[k](theta) for k in "MVKBC")
    dM, dV, dK, dB2, dC2 = (np.asarray(maps[k].Xi, dtype=float) for k in "MVKBC")
    l, n = theta.size, model.n_dof
    Minv = np.linalg.inv(M)
    MiK, MiV, MiB = Minv @ K, Minv @ V, Minv @ Bm

    def d_minv(dX: np.ndarray, MiX: np.ndarray) -> np.ndarray:  # ∂(M⁻¹X)/∂θₖ for every k
        return np.einsum("ij,kjl->kil", Minv, dX - dM @ MiX)

    dMiK, dMiV, dMiB = d_minv(dK, MiK), d_minv(dV, MiV), d_minv(dB2, MiB)
    dA = np.zeros((l, 2 * n, 2 * n))
    dA[:, n:, :n], dA[:, n:, n:] = -dMiK, -dMiV
    dB = np.zeros((l, 2 * n, Bm.shape[1]))
    dB[:, n:, :] = dMiB
    p = Cm.shape[0]
    dC = np.zeros((l, p, 2 * n))
    dD = np.zeros((l, p, Bm.shape[1]))
    for i, kind in enumerate(model.outputs):  # row by row: an output's kind is its own
        if kind == "position":
            dC[:, i, :n] = dC2[:, i]
        elif kind == "velocity":
            dC[:, i, n:] = dC2[:, i]
        else:  # acceleration: Cᵢ = −Cmᵢ [M⁻¹K, M⁻¹V], Dᵢ = Cmᵢ M⁻¹B
            dC[:, i, :n] = -(dC2[:, i] @ MiK + Cm[i] @ dMiK)
            dC[:, i, n:] = -(dC2[:, i] @ MiV + Cm[i] @ dMiV)
            dD[:, i] = dC2[:, i] @ MiB + Cm[i] @ dMiB
    return (A, B, C, D), (dA, dB, dC, dD)


def _zoh_derivatives(A: np.ndarray, B: np.ndarray, dA: np.ndarray, dB: np.ndarray, h: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(Ad, Bd, dAd, dBd) of the zero-order hold over h, dAd (l, n, n) and dBd (l, n, m)."""
    n, m = B.shape
    F = np.zeros((n + m, n + m))
    F[:n, :n], F[:n, n:] = A * h, B * h
    l = dA.shape[0]
    dAd, dBd = np.zeros((l, n, n)), np.zeros((l, n, m))
    Phi = None
    for k in range(l):
        if not (np.any(dA[k]) or np.any(dB[k])):
            continue
        dF = np.zeros_like(F)
        dF[:n, :n], dF[:n, n:] = dA[k] * h, dB[k] * h
        Phi, L = expm_frechet(F, dF, compute_expm=True, check_finite=False)
        dAd[k], dBd[k] = L[:n, :n], L[:n, n:]
    if Phi is None:  # no parameter in A or B: the exponential alone
        Phi = expm(F)
    return Phi[:n, :n], Phi[:n, n:], dAd, dBd


def _foh_derivatives(A: np.ndarray, B: np.ndarray, dA: np.ndarray, dB: np.ndarray, h: float
                     ) -> tuple[np.ndarray, ...]:
    """(Ad, G1, G2, dAd, dG1, dG2) of the first-order hold over h (the input linear between samples:
    x⁺ = Ad x + G1 u + G2 (u⁺ − u), :func:`symid.signal.simulate.foh_discretize`), the derivatives by the
    Fréchet derivative of the same block exponential ``expm([[A, B, 0], [0, 0, I/h], [0, 0, 0]] h)``."""
    n, m = B.shape
    F = np.zeros((n + 2 * m, n + 2 * m))
    F[:n, :n], F[:n, n:n + m], F[n:n + m, n + m:] = A * h, B * h, np.eye(m)
    l = dA.shape[0]
    dAd, dG1, dG2 = np.zeros((l, n, n)), np.zeros((l, n, m)), np.zeros((l, n, m))
    Phi = None
    for k in range(l):
        if not (np.any(dA[k]) or np.any(dB[k])):
            continue
        dF = np.zeros_like(F)
        dF[:n, :n], dF[:n, n:n + m] = dA[k] * h, dB[k] * h
        Phi, L = expm_frechet(F, dF, compute_expm=True, check_finite=False)
        dAd[k], dG1[k], dG2[k] = L[:n, :n], L[:n, n:n + m], L[:n, n + m:]
    if Phi is None:
        Phi = expm(F)
    return Phi[:n, :n], Phi[:n, n:n + m], Phi[:n, n + m:], dAd, dG1, dG2


def output_sensitivity(mats: tuple[np.ndarray, ...], dmats: tuple[np.ndarray, ...], t: np.ndarray, u: np.ndarray,
                       x0: np.ndarray, dx0: np.ndarray, hold: str = "zoh", held: np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    """ŷ (N, p) and ∂ŷ/∂v (N, p, k) on one record from x(t₀) = x0.

    Parameters
    ----------
    mats, dmats : tuple of ndarray
        (A, B, C, D) and their derivatives (dA, dB, dC, dD), each (l, rows, cols)
        (:func:`state_space_derivatives`).
    t, u : ndarray
        Sample times (N,) and inputs (N, m), the input held between samples (``hold="zoh"``) or linear
        between them (``"foh"``; with ``held``, a mask of the inputs, those held:
        :func:`symid.fit.timeseries.response.held_differences`).
    x0 : ndarray
        Initial state (n,).
    dx0 : ndarray
        ∂x(t₀)/∂v (n, k), k ≥ l: the first l columns belong to θ, any further ones to other
        unknowns that enter only through the initial state (an estimated x(t₀): unit vectors).

    Returns
    -------
    Y : ndarray (N, p)
    dY : ndarray (N, p, k)

    Examples
    --------
    Against a central difference on a one-state decay x' = −a x + u, y = x:

    >>> import numpy as np
    >>> from symid.fit.timeseries.sensitivity import output_sensitivity
    >>> t, u = np.linspace(0.0, 2.0, 21), np.ones((21, 1))
    >>> def out(a):
    ...     mats = (np.array([[-a]]), np.eye(1), np.eye(1), np.zeros((1, 1)))
    ...     dmats = (-np.ones((1, 1, 1)), np.zeros((1, 1, 1)), np.zeros((1, 1, 1)), np.zeros((1, 1, 1)))
    ...     return output_sensitivity(mats, dmats, t, u, np.zeros(1), np.zeros((1, 1)))
    >>> Y, dY = out(0.7)
    >>> fd = (out(0.7 + 1e-6)[0] - out(0.7 - 1e-6)[0]) / 2e-6
    >>> bool(np.allclose(dY[:, :, 0], fd, rtol=1e-6, atol=1e-9))
    True
    """
    A, B, C, D = mats
    dA, dB, dC, dD = dmats
    l = dA.shape[0]
    n = A.shape[0]
    k = dx0.shape[1]
    N = u.shape[0]
    reps, group = interval_groups(t)
    # the input's part of each step for every sample at once: Bd u (N−1, n) and ∂Bd/∂θ u (N−1, n·l); with the
    # input linear between samples, G1 u + G2 Δu and their derivatives
    Bu, dBu = np.zeros((N - 1, n)), np.zeros((N - 1, n * l))
    steps = []
    if hold == "foh":
        du = held_differences(u, held)
        for g, (Ad, G1, G2, dAd, dG1, dG2) in enumerate(_foh_derivatives(A, B, dA, dB, h) for h in reps):
            at = np.flatnonzero(group == g)
            Bu[at] = u[at] @ G1.T + du[at] @ G2.T
            dBu[at] = (np.einsum("knm,tm->tnk", dG1, u[at]) + np.einsum("knm,tm->tnk", dG2, du[at])
                       ).reshape(at.size, n * l)
            steps.append((Ad, dAd.transpose(1, 0, 2).reshape(n * l, n)))  # rows (state, θₖ)
    else:
        for g, (Ad, Bd, dAd, dBd) in enumerate(_zoh_derivatives(A, B, dA, dB, h) for h in reps):
            at = np.flatnonzero(group == g)
            Bu[at] = u[at] @ Bd.T
            dBu[at] = np.einsum("knm,tm->tnk", dBd, u[at]).reshape(at.size, n * l)
            steps.append((Ad, dAd.transpose(1, 0, 2).reshape(n * l, n)))
    # Z = [x | S] (n, 1 + k): one product with Ad moves the state and every sensitivity
    Zs = np.empty((N, n, 1 + k))
    Z = np.empty((n, 1 + k))
    Z[:, 0], Z[:, 1:] = np.asarray(x0, dtype=float).reshape(n), np.asarray(dx0, dtype=float).reshape(n, k)
    forcing = np.zeros((n, 1 + k))
    with np.errstate(over="ignore", invalid="ignore"):
        for i in range(N - 1):
            Zs[i] = Z
            Ad, dA2 = steps[group[i]]
            forcing[:, 0] = Bu[i]
            forcing[:, 1:1 + l] = (dA2 @ Z[:, 0] + dBu[i]).reshape(n, l)
            Z = Ad @ Z + forcing
        Zs[N - 1] = Z
        X, S = Zs[:, :, 0], Zs[:, :, 1:]
        Y = X @ C.T + u @ D.T
        dY = np.einsum("pn,tnk->tpk", C, S)
        dY[:, :, :l] += np.einsum("kpn,tn->tpk", dC, X) + np.einsum("kpm,tm->tpk", dD, u)
    return Y, dY
