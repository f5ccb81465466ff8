"""Exact derivatives of a model's frequency response and spectra with respect to θ, from the affine maps.

Every matrix of a symid model is affine in θ, X(θ) = X0 + Σₖ θₖ Xₖ, so the derivatives
need no finite differences. With R(ω) = (jωI − A)⁻¹ for a state-space model,

    H = C R B + D,    ∂H/∂θₖ = Cₖ R B + C R Aₖ R B + C R Bₖ + Dₖ,

and with Z(ω) = K − ω²M + jωV and f(ω) = 1, jω or −ω² (position, velocity,
acceleration output) for a second-order model,

    H = f C Z⁻¹ B,    ∂H/∂θₖ = f (Cₖ Z⁻¹ B − C Z⁻¹ (Kₖ − ω²Mₖ + jωVₖ) Z⁻¹ B + C Z⁻¹ Bₖ).

The output spectrum Φyy = H Φuu Hᴴ (thesis (5-3)) then has
∂Φyy/∂θₖ = ∂H Φuu Hᴴ + H Φuu ∂Hᴴ.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symid.errors import ModelError
from symid.model.secondorder import output_factor

__all__ = ["frf_sensitivity", "spectra_sensitivity"]


def _coef(amap: Any) -> np.ndarray:
    """Coefficients Xₖ of an affine map as an array (l, r, c)."""
    return np.asarray(amap.Xi, dtype=float)


def _flat(amap: Any) -> np.ndarray:
    """Coefficients Xₖ of an affine map flattened to (r·c, l)."""
    xi = _coef(amap)
    return xi.reshape(xi.shape[0], -1).T


def _outer(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """(s, p, m, n·r) array of left[s, p, n]·right[s, r, m], so that ``_outer(L, R) @ _flat(X)`` is L Xₖ R."""
    s, p = left.shape[:2]
    m = right.shape[2]
    return (left[:, :, None, :, None] * np.swapaxes(right, 1, 2)[:, None, :, None, :]).reshape(s, p, m, -1)


def _left(coef: np.ndarray, right: np.ndarray) -> np.ndarray:
    """(s, p, m, l) array of Σₙ coef[k, p, n]·right[s, n, m] (Cₖ R), as one matrix product."""
    l, p, n = coef.shape
    out = coef.reshape(l * p, n) @ right  # (s, l·p, m)
    return out.reshape(right.shape[0], l, p, -1).transpose(0, 2, 3, 1)


def _right(left: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """(s, p, m, l) array of Σₙ left[s, p, n]·coef[k, n, m] (L Bₖ), as one matrix product."""
    l, n, m = coef.shape
    out = left @ coef.transpose(1, 0, 2).reshape(n, l * m)  # (s, p, l·m)
    return out.reshape(left.shape[0], left.shape[1], l, m).transpose(0, 1, 3, 2)


def frf_sensitivity(model: Any, theta: Any, w: Any) -> tuple[np.ndarray, np.ndarray]:
    """H(ωᵢ, θ) and its exact derivative with respect to θ.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    theta : dict or sequence of float
    w : array_like, shape (s,)
        Angular frequencies (rad/s).

    Returns
    -------
    H : numpy.ndarray, shape (s, p, m)
    dH : numpy.ndarray, shape (s, p, m, l)
        ∂H/∂θₖ in the last axis.

    Raises
    ------
    ModelError
        When the response cannot be evaluated (a pole at one of the frequencies).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.sensitivity import frf_sensitivity
    >>> a = si.parameters("a")
    >>> H, dH = frf_sensitivity(si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]]), [2.0], [1.0])
    >>> bool(np.isclose(dH[0, 0, 0, 0], -1 / (1j + 2.0) ** 2, rtol=1e-14))    # d/da 1/(jω + a)
    True
    """
    from symid.model.secondorder import SecondOrderModel

    th = model.theta_vector(theta)
    w = np.asarray(w, dtype=float).reshape(-1)
    maps = model.maps
    mats = model.matrices(th)
    try:
        if isinstance(model, SecondOrderModel):
            M, V, K, B, C = (mats[k] for k in "MVKBC")
            W = w[:, None, None]
            Z = K - W**2 * M + 1j * W * V
            m_in = B.shape[1]
            if np.array_equal(M, M.T) and np.array_equal(V, V.T) and np.array_equal(K, K.T):
                # Z is symmetric (a mechanical model): Zᵀ = Z, so Z⁻¹B and Z⁻ᵀCᵀ come from one solve
                rhs = np.concatenate([B, C.T], axis=1).astype(complex)
                sol = np.linalg.solve(Z, np.broadcast_to(rhs, (w.size, *rhs.shape)))
                ZB, CZ = sol[:, :, :m_in], np.swapaxes(sol[:, :, m_in:], 1, 2)
            else:
                ZB = np.linalg.solve(Z, np.broadcast_to(B.astype(complex), (w.size, *B.shape)))
                CZ = np.swapaxes(np.linalg.solve(np.swapaxes(Z, 1, 2),
                                                 np.broadcast_to(C.T.astype(complex), (w.size, *C.T.shape))), 1, 2)
            G = C @ ZB
            # C Z⁻¹ Xₖ Z⁻¹ B for X = K, M, V: the outer products (C Z⁻¹)ₚₙ (Z⁻¹ B)ᵣₘ against the coefficients
            # flattened over (n, r): one matrix product for the three, never an (s, l, n, n) array
            l = th.size
            KMV = _outer(CZ, ZB) @ np.concatenate([_flat(maps["K"]), _flat(maps["M"]), _flat(maps["V"])], axis=1)
            wc = w[:, None, None, None]
            dG = -KMV[..., :l] + wc**2 * KMV[..., l:2 * l] - 1j * wc * KMV[..., 2 * l:]
            if not maps["C"].is_constant:  # gains in C (most models measure a known combination of states)
                dG = dG + _left(_coef(maps["C"]), ZB)
            if not maps["B"].is_constant:
                dG = dG + _right(CZ, _coef(maps["B"]))
            f = output_factor(model, w)  # (s, p): each output row times (jω)ᵈ
            return f[:, :, None] * G, f[:, :, None, None] * dG
        A, B, C, D = (mats[k] for k in "ABCD")
        n = A.shape[0]
        Zs = 1j * w[:, None, None] * np.eye(n) - A
        RB = np.linalg.solve(Zs, np.broadcast_to(B.astype(complex), (w.size, *B.shape)))
        CR = np.swapaxes(np.linalg.solve(np.swapaxes(Zs, 1, 2),
                                         np.broadcast_to(C.T.astype(complex), (w.size, *C.T.shape))), 1, 2)
        H = C @ RB + D
        dH = _outer(CR, RB) @ _flat(maps["A"])
        if not maps["C"].is_constant:
            dH = dH + _left(_coef(maps["C"]), RB)
        if not maps["B"].is_constant:
            dH = dH + _right(CR, _coef(maps["B"]))
        if "D" in maps:
            dH = dH + np.moveaxis(_coef(maps["D"]), 0, -1)[None]
        return H, dH
    except np.linalg.LinAlgError:
        raise ModelError("the frequency response has a pole at one of the frequencies: no derivative there") from None


def spectra_sensitivity(model: Any, theta: Any, w: Any, Phi_uu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Φyy(ωᵢ, θ) = H Φuu Hᴴ and its exact derivative with respect to θ.

    Returns
    -------
    Phi : numpy.ndarray, shape (s, p, p)
    dPhi : numpy.ndarray, shape (s, p, p, l)

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.sensitivity import spectra_sensitivity
    >>> a = si.parameters("a")
    >>> P, dP = spectra_sensitivity(si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]]), [2.0], [1.0], np.ones((1, 1, 1)))
    >>> bool(np.isclose(dP[0, 0, 0, 0], -2 * 2.0 / (1 + 2.0**2) ** 2, rtol=1e-14))    # d/da 1/(ω² + a²)
    True
    """
    H, dH = frf_sensitivity(model, theta, w)
    Puu = np.asarray(Phi_uu, dtype=complex)
    HP = H @ Puu  # (s, p, m)
    Phi = HP @ np.conj(np.swapaxes(H, 1, 2))
    term = np.einsum("spmk,smr,sqr->spqk", dH, Puu, np.conj(H))
    return Phi, term + np.conj(np.swapaxes(term, 1, 2))
