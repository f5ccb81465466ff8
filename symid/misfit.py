"""The data misfit every method is ranked by, whatever it optimises internally."""

from __future__ import annotations

from typing import Any

import numpy as np

from symid.errors import ModelError

__all__ = ["relative_misfit", "relative_parameter_error"]


def relative_misfit(model: Any, data: Any, theta: Any) -> float:
    """Relative squared misfit Σ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σ‖Hᵢ‖²_F of a frequency response.

    Returns ``inf`` when the model cannot be evaluated at θ (singular M, a pole on
    the imaginary axis, non-finite values).
    """
    H = np.asarray(data.H)
    try:
        Hm = model.frequency_response(theta, data.w)
    except (ModelError, np.linalg.LinAlgError, FloatingPointError):
        return float("inf")
    if not np.all(np.isfinite(Hm)):
        return float("inf")
    den = float(np.sum(np.abs(H) ** 2))
    return float(np.sum(np.abs(H - Hm) ** 2) / (den if den > 0 else 1.0))


def relative_parameter_error(theta: np.ndarray, truth: np.ndarray) -> float:
    """‖θ − θ*‖₂ / ‖θ*‖₂ (absolute error when θ* = 0)."""
    theta = np.asarray(theta, dtype=float)
    truth = np.asarray(truth, dtype=float)
    den = float(np.linalg.norm(truth))
    return float(np.linalg.norm(theta - truth) / (den if den > 0 else 1.0))
