"""Spectral data for a second-order model: the checks, the equations (5-6)/(5-8) and the misfit.

For a full set of sensors (C square, invertible and known) the relation (5-3)
Φyy = H Φuu Hᴴ with H = C X⁻¹ B and X(θ, ω) = −ω²M(θ) + jωV(θ) + K(θ) (5-7) is
equivalent to the quadratic matrix equalities of thesis (5-6)/(5-8)::

    X(θ, ωᵢ) Pᵢ X(θ, ωᵢ)ᴴ = Qᵢ,   Pᵢ = C⁻¹ Φyy(ωᵢ) C⁻ᴴ / |fᵢ|²,   Qᵢ = B Φuu(ωᵢ) Bᴴ,

where fᵢ = 1, jωᵢ or −ωᵢ² for position, velocity or acceleration outputs (y = fᵢ C q).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from symid.errors import DataError, ModelError
from symid.fit.base import Estimator
from symid.fit.spectra.fisher import SpectraFisher
from symid.model.secondorder import SecondOrderModel, output_factor

__all__ = ["VARIANCE_COST_KIND", "SpectraEstimator", "SpectralEquations", "check_spectral", "model_spectra",
           "spectral_equations", "spectral_misfit", "spectral_residuals"]


@dataclass(frozen=True)
class SpectralEquations:
    """The data of (5-8): Pᵢ, Qᵢ and the affine X(θ, ωᵢ) = X0ᵢ + Σₖ θₖ Xᵢₖ.

    Attributes
    ----------
    w : numpy.ndarray, shape (s,)
        Angular frequencies (rad/s).
    P : numpy.ndarray, shape (s, n, n)
        C⁻¹ Φyy C⁻ᴴ / |fᵢ|², Hermitian.
    Q : numpy.ndarray, shape (s, n, n)
        B Φuu Bᴴ, Hermitian.
    X0 : numpy.ndarray, shape (s, n, n)
        Constant part of X(θ, ωᵢ).
    Xc : numpy.ndarray, shape (s, n, n, l)
        Coefficient of each parameter in X(θ, ωᵢ).
    """

    w: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    X0: np.ndarray
    Xc: np.ndarray

    def X(self, theta: np.ndarray) -> np.ndarray:
        """X(θ, ωᵢ) for every frequency, shape (s, n, n)."""
        return self.X0 + self.Xc @ np.asarray(theta, dtype=float)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """‖X Pᵢ Xᴴ − Qᵢ‖_F per frequency."""
        X = self.X(theta)
        R = X @ self.P @ np.conj(np.swapaxes(X, 1, 2)) - self.Q
        return np.linalg.norm(R, axis=(1, 2))


def check_spectral(model: Any, data: Any) -> None:
    """Refuse a model that is not second order, or spectra of the wrong size or too few frequencies."""
    if not isinstance(model, SecondOrderModel):
        raise ModelError(f"spectral identification (thesis ch. 5) needs a SecondOrderModel; got "
                         f"{type(model).__name__}")
    p, m = data.n_outputs, data.n_inputs
    if (p, m) != (model.n_outputs, model.n_inputs):
        raise DataError(f"the spectra have {p} output(s) (Phi_yy {p}×{p}) and {m} input(s) (Phi_uu {m}×{m}); "
                        f"the model has {model.n_outputs} output(s) and {model.n_inputs} input(s)")
    if not np.any(np.asarray(data.Phi_yy)):
        raise DataError("the output spectrum Phi_yy is zero at every frequency: there is nothing to fit")
    if not np.any(np.asarray(data.Phi_uu)):
        raise DataError("the input spectrum Phi_uu is zero at every frequency: the outputs carry no information "
                        "about the model (Phi_yy = H Phi_uu H^H)")
    s, l = data.n_frequencies, model.n_parameters
    if s * p * p < l:  # a Hermitian p×p spectrum holds p² real numbers
        need = -(-l // (p * p))
        raise DataError(f"{s} frequencies give {s * p * p} real equations (p² = {p * p} per Hermitian p×p "
                        f"spectrum) for {l} unknown parameters: at least {need} frequencies are needed")


def spectral_equations(model: Any, data: Any) -> SpectralEquations:
    """Build (5-8) from a model and spectra, refusing what Algorithm 5.1 cannot treat.

    Parameters
    ----------
    model : SecondOrderModel
        With a known (parameter-free) square invertible C and a known B.
    data : SpectralData

    Returns
    -------
    SpectralEquations

    Raises
    ------
    ModelError
        Not a second-order model; C not square, singular or parameterised (the full
        sensor set of thesis §5-3/§5-5 is required); B parameterised.
    DataError
        Spectra of the wrong size, or too few frequencies.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[2]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], [1.0, 2.0, 3.0], Phi_uu=3.0)
    >>> from symid.fit.spectra.equations import spectral_equations
    >>> eq = spectral_equations(model, spec)
    >>> bool(np.allclose(eq.residuals([1.0, 0.5, 4.0]), 0))   # X P Xᴴ = Q at the truth
    True
    """
    check_spectral(model, data)
    maps = model.maps
    n, p = model.n_dof, model.n_outputs
    if not maps["C"].is_constant:
        raise ModelError("Algorithm 5.1 needs a full set of known sensors (thesis §5-5, Pᵢ = C⁻¹ Φyy C⁻ᴴ): "
                         "C must hold no parameter")
    if p != n:
        raise ModelError(f"Algorithm 5.1 needs a full set of sensors (thesis §5-3/§5-5, Pᵢ = C⁻¹ Φyy C⁻ᴴ): "
                         f"C must be square and invertible, p = n = {n}; this model has C of shape {p}×{n}")
    C = maps["C"].X0
    cond = np.linalg.cond(C)
    if not np.isfinite(cond) or cond > 1e12:
        raise ModelError(f"Algorithm 5.1 needs a full set of sensors (thesis §5-5, Pᵢ = C⁻¹ Φyy C⁻ᴴ): C must "
                         f"be invertible; this {n}×{n} C is singular (condition number {cond:.3g})")
    if not maps["B"].is_constant:
        raise ModelError("Algorithm 5.1 needs a known input matrix B (Qᵢ = B Φuu Bᴴ would be quadratic in θ): "
                         "B must hold no parameter")
    w = np.asarray(data.w, dtype=float)
    Ci = np.linalg.inv(C)
    f = output_factor(model, w)  # (s, p): Φyy = F C Z⁻¹ B Φuu Bᴴ Z⁻ᴴ Cᴴ Fᴴ, F = diag((jω)ᵈ) per output
    P = Ci @ (np.asarray(data.Phi_yy, dtype=complex) / (f[:, :, None] * f.conj()[:, None, :])) @ Ci.conj().T
    B = maps["B"].X0
    Q = B @ np.asarray(data.Phi_uu, dtype=complex) @ B.conj().T
    P = 0.5 * (P + np.conj(np.swapaxes(P, 1, 2)))
    Q = 0.5 * (Q + np.conj(np.swapaxes(Q, 1, 2)))
    coef = {k: np.moveaxis(maps[k].Xi, 0, -1) for k in "MVK"}  # (n, n, l)
    W = w[:, None, None]
    X0 = -(W**2) * maps["M"].X0 + 1j * W * maps["V"].X0 + maps["K"].X0
    Xc = (-(W[..., None] ** 2) * coef["M"] + 1j * W[..., None] * coef["V"] + coef["K"])
    return SpectralEquations(w, P, Q, X0, Xc)


def model_spectra(model: Any, theta: Any, w: Any, Phi_uu: np.ndarray) -> np.ndarray:
    """Φyy(ωᵢ) = H(ωᵢ, θ) Φuu(ωᵢ) H(ωᵢ, θ)ᴴ (thesis (5-3)), shape (s, p, p); Φuu of shape (s, m, m)."""
    H = np.asarray(model.frequency_response(theta, w))
    return H @ Phi_uu @ np.conj(np.swapaxes(H, 1, 2))


def _model_spectra_or_none(model: Any, data: Any, theta: Any, weights: Any = None,
                           sensor_noise: bool = False) -> np.ndarray | None:
    """H Φuu Hᴴ at θ (with ``sensor_noise``, plus the profiled white noise on each auto-spectrum), or None."""
    try:
        with np.errstate(all="ignore"):
            Pm = model_spectra(model, theta, data.w, np.asarray(data.Phi_uu))
    except (ModelError, np.linalg.LinAlgError, FloatingPointError):
        return None
    if not np.all(np.isfinite(Pm)):
        return None
    if sensor_noise:
        from symid.fit.spectra.welch import profiled_sensor_noise

        nu = profiled_sensor_noise(data, Pm, weights)
        Pm = Pm + np.diag(nu)[None, :, :]
    return Pm


def spectral_misfit(model: Any, data: Any, theta: Any, weights: Any = None, sensor_noise: bool = False) -> float:
    """Relative squared misfit Σᵢ‖Φyyᵢ − H Φuuᵢ Hᴴ‖²_F / Σᵢ‖Φyyᵢ‖²_F (the objective of (5-13), normalised).

    With ``weights`` (s, p, p) w, the weighted Σ w|Φyy − H Φuu Hᴴ|² / Σ w|Φyy|², entry by
    entry (:mod:`symid.fit.spectra.welch`); with ``sensor_noise``, the model's spectra
    plus the white noise on each output that fits best
    (:func:`~symid.fit.spectra.welch.profiled_sensor_noise`). Returns ``inf`` when the
    model cannot be evaluated at θ.

    Examples
    --------
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], [1.0, 2.0, 3.0], Phi_uu=1.0)
    >>> from symid.fit.spectra.equations import spectral_misfit
    >>> spectral_misfit(model, spec, [1.0, 0.5, 4.0]) < 1e-30
    True
    """
    Phi = np.asarray(data.Phi_yy)
    Pm = _model_spectra_or_none(model, data, theta, weights, sensor_noise)
    if Pm is None:
        return float("inf")
    scale = float(np.max(np.abs(Phi)))  # sums on Φ / max|Φ|: no under- or overflow
    if scale == 0.0:
        return 0.0 if not np.any(Pm) else float("inf")
    w = 1.0 if weights is None else np.asarray(weights, dtype=float)
    return float(np.sum(w * np.abs((Phi - Pm) / scale) ** 2) / np.sum(w * np.abs(Phi / scale) ** 2))


def spectral_residuals(model: Any, data: Any, theta: Any, weights: Any = None,
                       sensor_noise: bool = False) -> np.ndarray | None:
    """The residuals whose sum of squares is :func:`spectral_misfit`: (Φyyᵢ − H Φuuᵢ Hᴴ) / √Σ‖Φyyᵢ‖²_F (each
    entry times √w with ``weights``), frequency first; ``None`` if not evaluable. The success rule's whiteness
    test takes these (:func:`symid.fit.success.whiteness`)."""
    Phi = np.asarray(data.Phi_yy)
    Pm = _model_spectra_or_none(model, data, theta, weights, sensor_noise)
    if Pm is None:
        return None
    scale = float(np.max(np.abs(Phi))) or 1.0  # as in spectral_misfit: no under- or overflow
    w = 1.0 if weights is None else np.asarray(weights, dtype=float)
    return (Phi - Pm) / scale * np.sqrt(w) / (float(np.sqrt(np.sum(w * np.abs(Phi / scale) ** 2))) or 1.0)


VARIANCE_COST_KIND = ("relative spectral misfit weighted by the scatter, Σ w|Φyy − H Φuu Hᴴ|² / Σ w|Φyy|², "
                      "w = 1/(Φⱼⱼ Φₖₖ) of the model")
"""What the misfit measures with ``weighting="variance"`` (:mod:`symid.fit.spectra.welch`)."""


class SpectraEstimator(Estimator, SpectraFisher):
    """Base of the spectral methods: their data misfit (relative, squared, on Φyy), and its Fisher
    information for the uncertainty of θ̂ (:mod:`symid.fit.spectra.fisher`).

    ``entry_weights`` (s, p, p), when set (:meth:`set_entry_weights`), weighs each entry of the
    misfit (``weighting="variance"``, :mod:`symid.fit.spectra.welch`); with the number of
    averages behind Welch spectra known, the noise floor the fit is judged against follows
    (unless one is given)."""

    cost_kind = "relative spectral misfit Σ‖Φyyᵢ − H Φuuᵢ Hᴴ‖²_F / Σ‖Φyyᵢ‖²_F"
    entry_weights: np.ndarray | None = None
    averages: float | None = None
    sensor_noise: bool = False
    _given_floor: float | None = None
    _welch_floor: float | None = None

    @property  # type: ignore[override]
    def noise_floor(self) -> float | None:
        """The floor given (``noise_floor=``), else that of the Welch averages with ``weighting="variance"``."""
        return self._given_floor if self._given_floor is not None else self._welch_floor

    @noise_floor.setter
    def noise_floor(self, value: float | None) -> None:
        self._given_floor = value

    def set_entry_weights(self, weights: np.ndarray | None) -> None:
        """Weigh the misfit's entries by ``weights`` (s, p, p) (``None``: equally), its name and the Welch noise
        floor (with ``averages`` known) with them."""
        from symid.fit.spectra.welch import WELCH_FLOOR_MARGIN, welch_noise_floor

        self.entry_weights = None if weights is None else np.asarray(weights, dtype=float)
        self.cost_kind = type(self).cost_kind if weights is None else VARIANCE_COST_KIND  # type: ignore[misc]
        self._welch_floor = (None if weights is None or self.averages is None else
                             WELCH_FLOOR_MARGIN * welch_noise_floor(self.data, self.entry_weights, self.averages))

    def misfit(self, theta: np.ndarray) -> float:
        """:func:`spectral_misfit` of the model at θ."""
        return spectral_misfit(self.model, self.data, theta, self.entry_weights, self.sensor_noise)

    def residuals(self, theta: np.ndarray) -> np.ndarray | None:
        """:func:`spectral_residuals` at θ."""
        return spectral_residuals(self.model, self.data, theta, self.entry_weights, self.sensor_noise)

    def sensor_noise_at(self, theta: Any) -> np.ndarray | None:
        """With ``sensor_noise``: the white noise on each output's auto-spectrum that fits best at θ (p,); else
        None."""
        if not self.sensor_noise:
            return None
        from symid.fit.spectra.welch import profiled_sensor_noise

        Pm = _model_spectra_or_none(self.model, self.data, theta)
        return None if Pm is None else profiled_sensor_noise(self.data, Pm, self.entry_weights)

    def n_data(self) -> int:
        """s·p² real values (a Hermitian p×p spectrum per frequency)."""
        Phi = np.asarray(self.data.Phi_yy)
        return int(Phi.shape[0] * Phi.shape[1] ** 2)
