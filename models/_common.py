"""Helpers shared by the zoo files: symmetric parameterisations and black-box data.

Private to the zoo (the leading underscore keeps it out of ``symid.list_models()``).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

import symid as si

__all__ = [
    "balanced_realisation",
    "blackbox_data",
    "random_similarity",
    "similar_to",
    "symmetric_by_diagonals",
    "symmetric_truth",
]


def _diagonal_order(n: int) -> list[tuple[int, int]]:
    """Upper-triangular positions (i, j), i <= j, diagonal by diagonal, top to bottom."""
    return [(i, i + d) for d in range(n) for i in range(n - d)]


def symmetric_by_diagonals(n: int, prefix: str = "theta", start: int = 1) -> tuple[sp.Matrix, list[sp.Symbol]]:
    """A fully parameterised symmetric n x n matrix, numbered as thesis (4-16) and (7-20) do.

    The main diagonal gets ``prefix{start}`` ... ``prefix{start+n-1}``, the first
    super-diagonal the next n-1 indices (top to bottom), and so on up to the corner
    (1, n). Diagonal symbols are declared positive (a positive definite matrix has a
    positive diagonal), off-diagonal symbols real.

    Parameters
    ----------
    n : int
        Size of the matrix.
    prefix : str, optional
        Name prefix of the parameters.
    start : int, optional
        Index of the first parameter.

    Returns
    -------
    matrix : sympy.Matrix
        The symmetric matrix of symbols.
    symbols : list of sympy.Symbol
        Its n(n+1)/2 parameters in index order.
    """
    positions = _diagonal_order(n)
    names = [f"{prefix}{start + k}" for k in range(len(positions))]
    diag = si.parameters(names[:n], positive=True)
    diag = [diag] if n == 1 else list(diag)
    off = [] if n == 1 else si.parameters(names[n:])
    off = [off] if isinstance(off, sp.Symbol) else list(off)
    symbols = diag + off
    mat = sp.zeros(n, n)
    for (i, j), s in zip(positions, symbols, strict=True):
        mat[i, j] = s
        mat[j, i] = s
    return mat, symbols


def symmetric_truth(value: np.ndarray, prefix: str = "theta", start: int = 1) -> dict[str, float]:
    """The true values of :func:`symmetric_by_diagonals` parameters for a numeric symmetric matrix."""
    value = np.asarray(value, dtype=float)
    return {f"{prefix}{start + k}": float(value[i, j]) for k, (i, j) in enumerate(_diagonal_order(value.shape[0]))}


def balanced_realisation(A, B, C) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Balanced realisation (T A T⁻¹, T B, C T⁻¹) of a stable, minimal system (MATLAB ``balreal``).

    The transform is :func:`symid.signal.realisation.balanced_realisation` (square-root method,
    both Gramians equal to diag(Hankel singular values), sign of each state fixed by the
    first clearly nonzero entry of its row of T B).
    """
    from symid.signal.realisation import balanced_realisation as balancing  # lazy: scipy only when a recipe runs

    A, B, C = (np.asarray(X, dtype=float) for X in (A, B, C))
    T, Tinv = balancing(A, B, C)
    return T @ A @ Tinv, T @ B, C @ Tinv


def similar_to(A, B, C, A_ref, B_ref, C_ref) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The similarity transform of (A, B, C) closest to a reference triplet.

    Solves the linear least-squares problem
    ``min_T ‖T A − A_ref T‖² + ‖T B − B_ref‖² + ‖C − C_ref T‖²`` and returns
    ``(T A T⁻¹, T B, C T⁻¹)``: exactly similar to (A, B, C), as close to the reference
    (e.g. a printed, noisy N4SID estimate) as a similarity transform allows.
    """
    A, B, C, A_ref, B_ref, C_ref = (np.asarray(X, dtype=float) for X in (A, B, C, A_ref, B_ref, C_ref))
    n = A.shape[0]
    eye = np.eye(n)
    # vec(T X) = (Xᵀ ⊗ I) vec(T), vec(Y T) = (I ⊗ Y) vec(T), column-major vec.
    lhs = np.vstack([np.kron(A.T, eye) - np.kron(eye, A_ref), np.kron(B.T, eye), np.kron(eye, C_ref)])
    rhs = np.concatenate([np.zeros(n * n), B_ref.ravel(order="F"), C.ravel(order="F")])
    T = np.linalg.lstsq(lhs, rhs, rcond=None)[0].reshape(n, n, order="F")
    Tinv = np.linalg.inv(T)
    return T @ A @ Tinv, T @ B, C @ Tinv


def random_similarity(A, B, C, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A seeded, well-conditioned random similarity transform of (A, B, C).

    ``T = Q₁ diag(d) Q₂`` with Q₁, Q₂ orthogonal (QR of standard Gaussian matrices)
    and d uniform in [0.5, 2], so cond(T) <= 4; drawn with ``numpy.random.default_rng(seed)``.
    """
    A, B, C = (np.asarray(X, dtype=float) for X in (A, B, C))
    n = A.shape[0]
    rng = np.random.default_rng(seed)
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    T = Q1 @ np.diag(rng.uniform(0.5, 2.0, n)) @ Q2
    Tinv = np.linalg.inv(T)
    return T @ A @ Tinv, T @ B, C @ Tinv


def blackbox_data(A, B, C, noise: float | None = None, seed: int | None = None):
    """A :class:`symid.data.BlackBox`, optionally perturbed by relative noise.

    With ``noise`` each matrix X gets ``noise · rms(X) · N(0, 1)`` added to every entry
    (zeros included, so the perturbation does not leak structure), drawn with
    ``numpy.random.default_rng(seed)``.
    """
    from symid.data import BlackBox

    mats = [np.asarray(X, dtype=float) for X in (A, B, C)]
    if noise:
        rng = np.random.default_rng(seed)
        mats = [X + noise * np.sqrt(np.mean(X**2)) * rng.standard_normal(X.shape) for X in mats]
    return BlackBox(*mats)
