"""Frequency-response data: the check against the model, and the misfit every FRF method is ranked by."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from symid.errors import DataError, ModelError
from symid.fit.base import Estimator
from symid.fit.frf.fisher import FrfFisher

__all__ = ["FrfEstimator", "check_frf", "relative_misfit", "relative_residuals"]


def check_frf(model: Any, data: Any) -> None:
    """Refuse a response of the wrong size, or too few frequencies for the parameters."""
    s, p, m = np.asarray(data.H).shape
    if (p, m) != (model.n_outputs, model.n_inputs):
        raise DataError(f"data H has {p} output(s) × {m} input(s) per frequency; the model has "
                        f"{model.n_outputs} output(s) × {model.n_inputs} input(s)")
    if not np.any(np.asarray(data.H)):
        raise DataError("the frequency response H is zero at every frequency: there is nothing to fit")
    equations = 2 * s * p * m
    if equations < model.n_parameters:
        need = math.ceil(model.n_parameters / (2 * p * m))
        raise DataError(f"{s} frequencies give {equations} real equations for {model.n_parameters} unknown "
                        f"parameters: at least {need} frequencies are needed")


def _model_response(model: Any, data: Any, theta: Any) -> np.ndarray | None:
    try:
        Hm = model.frequency_response(theta, data.w)
    except (ModelError, np.linalg.LinAlgError, FloatingPointError):
        return None
    return Hm if np.all(np.isfinite(Hm)) else None


def _relative(H: np.ndarray, Hm: np.ndarray) -> float:
    """Σ|H − Hm|² / Σ|H|², computed on H / max|H| so that neither sum under- or overflows."""
    scale = float(np.max(np.abs(H)))
    if scale == 0.0 or not np.isfinite(scale):
        return 0.0 if not np.any(Hm) else float("inf")
    den = float(np.sum(np.abs(H / scale) ** 2))
    return float(np.sum(np.abs((H - Hm) / scale) ** 2) / den)


def relative_misfit(model: Any, data: Any, theta: Any) -> float:
    """Relative squared misfit Σ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σ‖Hᵢ‖²_F of a frequency response.

    Returns ``inf`` when the model cannot be evaluated at θ (singular M, a pole on
    the imaginary axis, non-finite values).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.misfit import relative_misfit
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 5))
    >>> relative_misfit(model, frf, [2.0, 0.5, 3.0])
    0.0
    """
    Hm = _model_response(model, data, theta)
    return float("inf") if Hm is None else _relative(np.asarray(data.H), Hm)


def relative_residuals(model: Any, data: Any, theta: Any) -> np.ndarray | None:
    """(Hᵢ − H(ωᵢ, θ)) / |Hᵢ| entry by entry (0 where Hᵢ = 0), frequency first; ``None`` if not evaluable."""
    H = np.asarray(data.H)
    Hm = _model_response(model, data, theta)
    if Hm is None:
        return None
    mag = np.abs(H)
    return np.where(mag > 0, (H - Hm) / np.where(mag > 0, mag, 1.0), 0.0)


class FrfEstimator(Estimator, FrfFisher):
    """Base of the frequency-response methods: their data misfit (relative, squared), and its Fisher
    information for the uncertainty of θ̂ (:mod:`symid.fit.frf.fisher`)."""

    cost_kind: ClassVar[str] = "relative FRF misfit Σ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σ‖Hᵢ‖²_F"

    def misfit(self, theta: np.ndarray) -> float:
        """:func:`relative_misfit` of the model at θ."""
        return relative_misfit(self.model, self.data, theta)

    def residuals(self, theta: np.ndarray) -> np.ndarray | None:
        """:func:`relative_residuals` at θ."""
        return relative_residuals(self.model, self.data, theta)

    def n_data(self) -> int:
        """2·s·p·m real values."""
        return 2 * int(np.asarray(self.data.H).size)
