"""State-space realisations: minimality (PBH test) and the balanced realisation of a stable system."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

__all__ = ["balanced_realisation", "not_minimal"]

#: Relative tolerance of the PBH rank test.
PBH_TOL = 1e-9


def not_minimal(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> str | None:
    """What makes (A, B, C) non-minimal (PBH rank test at every eigenvalue), or ``None`` when it is minimal.

    Examples
    --------
    >>> import numpy as np
    >>> not_minimal(np.diag([-1.0, -2.0]), np.array([[1.0], [0.0]]), np.array([[1.0, 1.0]]))
    'the mode λ = -2 is not controllable from the inputs'
    """
    n = A.shape[0]
    scale = max(np.abs(A).max(), np.abs(B).max(), np.abs(C).max(), 1e-300)
    for lam in np.linalg.eigvals(A):
        Z = A - lam * np.eye(n)
        if np.linalg.svd(np.hstack([Z, B]), compute_uv=False)[-1] <= PBH_TOL * scale:
            return f"the mode λ = {lam:.4g} is not controllable from the inputs"
        if np.linalg.svd(np.vstack([Z, C]), compute_uv=False)[-1] <= PBH_TOL * scale:
            return f"the mode λ = {lam:.4g} is not observable from the outputs"
    return None


def balanced_realisation(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The balancing transform of a stable, minimal system (as MATLAB ``balreal``).

    Square-root method: Gramians Wc, Wo from the Lyapunov equations, Wc = L Lᵀ,
    Lᵀ Wo L = U Σ² Uᵀ, T⁻¹ = L U Σ^(-1/2). Both Gramians of (T A T⁻¹, T B, C T⁻¹) equal
    Σ = diag(Hankel singular values), in decreasing order. The sign of each balanced
    state makes the first clearly nonzero entry of its row of T B positive.

    Returns
    -------
    T, T_inv : numpy.ndarray
        The balanced system is (T A T⁻¹, T B, C T⁻¹).

    Examples
    --------
    >>> import numpy as np
    >>> A, B, C = np.array([[-1.0, 0.0], [1.0, -2.0]]), np.array([[1.0], [0.0]]), np.array([[0.0, 3.0]])
    >>> T, Ti = balanced_realisation(A, B, C)
    >>> Wc = sla.solve_continuous_lyapunov(T @ A @ Ti, -(T @ B) @ (T @ B).T)
    >>> bool(np.allclose(Wc, np.diag(np.diag(Wc)), atol=1e-12))
    True
    """
    Wc = sla.solve_continuous_lyapunov(A, -B @ B.T)
    Wo = sla.solve_continuous_lyapunov(A.T, -C.T @ C)
    L = np.linalg.cholesky((Wc + Wc.T) / 2)
    U, s2, _ = np.linalg.svd(L.T @ Wo @ L)
    Tinv = L @ U @ np.diag(s2**-0.25)
    T = np.linalg.inv(Tinv)
    TB = T @ B
    tol = 1e-12 * max(1.0, float(np.abs(TB).max()))
    signs = np.array([np.sign(row[np.flatnonzero(np.abs(row) > tol)[0]]) if np.any(np.abs(row) > tol) else 1.0
                      for row in TB])
    return signs[:, None] * T, Tinv * signs[None, :]
