"""Numeric LTI helpers the data layer may use without the symbolic models: frequency validation,
state-space matrices as a named tuple, and H(ω) = C (jωI − A)⁻¹ B + D."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from symid.errors import DataError, ModelError

__all__ = ["StateSpaceMatrices", "as_frequencies", "frequency_response_ss"]


def as_frequencies(w: Any, name: str = "w") -> np.ndarray:
    """Validate angular frequencies (rad/s): a finite, real 1-D array (a scalar becomes length 1)."""
    if w is None:
        raise DataError(f"{name} is missing (got None); give angular frequencies in rad/s")
    try:
        arr = np.asarray(w)
    except (TypeError, ValueError):
        raise DataError(f"{name} must be a 1-D sequence of numbers; got a ragged or non-numeric sequence") from None
    if np.iscomplexobj(arr):
        raise DataError(f"{name} must be real angular frequencies in rad/s; got complex values")
    try:
        arr = np.atleast_1d(arr.astype(float))
    except (TypeError, ValueError):
        raise DataError(f"{name} must hold numbers; got dtype {arr.dtype}") from None
    if arr.ndim != 1:
        raise DataError(f"{name} must be 1-D (one frequency per sample); got shape {arr.shape}")
    if arr.size == 0:
        raise DataError(f"{name} is empty")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{name} holds NaN or inf at index {int(np.flatnonzero(~np.isfinite(arr))[0])}")
    return arr



class StateSpaceMatrices(NamedTuple):
    """Numeric continuous-time state-space matrices (x' = A x + B u, y = C x + D u).

    A named tuple, so ``A, B, C, D = model.state_space(theta)`` unpacks it.

    Attributes
    ----------
    A : numpy.ndarray
        State matrix, shape (n, n).
    B : numpy.ndarray
        Input matrix, shape (n, m).
    C : numpy.ndarray
        Output matrix, shape (p, n).
    D : numpy.ndarray
        Feedthrough, shape (p, m).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray


def frequency_response_ss(ss: StateSpaceMatrices, w: np.ndarray) -> np.ndarray:
    """H(ω) = C (jωI − A)⁻¹ B + D for numeric matrices, shape (len(w), p, m)."""
    A, B, C, D = ss
    n = A.shape[0]
    Z = 1j * w[:, None, None] * np.eye(n) - A
    try:
        X = np.linalg.solve(Z, np.broadcast_to(B.astype(complex), (w.size, *B.shape)))
    except np.linalg.LinAlgError:
        bad = [float(x) for x in w if abs(np.linalg.det(1j * x * np.eye(n) - A)) < 1e-300]
        raise ModelError(f"jωI − A is singular at ω = {bad[:3]} (a pole on the imaginary axis)") from None
    return C @ X + D
