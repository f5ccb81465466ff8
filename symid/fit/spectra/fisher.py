"""The Fisher information of a spectral fit: residuals, exact Jacobian, relative noise.

The spectral misfit is Σᵢ wᵢ ‖Φyyᵢ − H Φuuᵢ Hᴴ‖²_F (wᵢ one constant, or 1/‖Φyyᵢ‖²_F per
frequency with IPOPT's ``weighting="frequency"``). A Hermitian p × p spectrum holds p²
real numbers: the diagonal (real) and the real and imaginary parts above it, the latter
counted twice in the Frobenius norm (weight √2 in the residual vector). The Jacobian is
exact from the affine maps (:func:`symid.fit.sensitivity.spectra_sensitivity`).
Estimated from the residuals, the noise is **relative** to the measured auto-spectra:
E|eᵢⱼ|² = ε² Φyyᵢᵢ Φyyⱼⱼ (real on the diagonal, each part half of it above), as a Welch
estimate's is (ε² = 1/K for K averaged segments; :meth:`SpectraFisher.noise_shape`); for
spectra of rank one (a single input) that is ε² |Φyyᵢⱼ|², the model
``si.simulate_spectra(..., noise=ε)`` follows; ``noise_std=`` gives it per frequency or
entry instead.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from symid.fit.sensitivity import spectra_sensitivity
from symid.fit.uncertainty import FisherInformation, broadcast_noise

__all__ = ["SpectraFisher"]


class SpectraFisher(FisherInformation):
    """:class:`~symid.fit.uncertainty.FisherInformation` of the spectral misfit (mixed into ``SpectraEstimator``).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], np.linspace(0.5, 3, 30), Phi_uu=1.0, noise=0.01, seed=0)
    >>> res = si.identify(model, spec, method="ipopt", x0=[1.0, 0.5, 4.0])
    >>> res.uncertainty.noise_units, bool(np.all(res.uncertainty.standard_errors < 0.02))
    ('relative', True)
    """

    noise_units: ClassVar[str] = "relative"
    model: Any
    data: Any
    options: dict[str, Any]
    method: ClassVar[str]

    def _frequency_weights(self) -> np.ndarray:
        """√wᵢ per frequency, as the method's misfit weighs it."""
        Phi = np.asarray(self.data.Phi_yy)
        per = np.linalg.norm(Phi, axis=(1, 2))
        if getattr(self, "options", {}).get("weighting") == "frequency":
            return 1.0 / np.where(per > 0, per, 1.0)
        return np.full(per.size, 1.0 / (float(np.linalg.norm(per)) or 1.0))

    def _pack(self, X: np.ndarray) -> np.ndarray:
        """Independent real entries of Hermitian (s, p, p, ...) arrays: diagonal, then √2 Re and √2 Im above it."""
        p = X.shape[1]
        iu = np.triu_indices(p, 1)
        idx = np.arange(p)
        up = X[:, iu[0], iu[1]]
        parts = [X[:, idx, idx].real, np.sqrt(2.0) * up.real, np.sqrt(2.0) * up.imag]
        return np.concatenate([q.reshape(q.shape[0] * q.shape[1], *q.shape[2:]) for q in parts])

    def _weights(self) -> np.ndarray:
        """The frequency weight of every packed entry."""
        s, p, _ = np.asarray(self.data.Phi_yy).shape
        return self._pack_magnitudes(np.broadcast_to(self._frequency_weights()[:, None, None], (s, p, p)))

    def jacobian(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """Weighted independent entries of Φyy − H Φuu Hᴴ and their Jacobian."""
        Phi = np.asarray(self.data.Phi_yy)
        Pm, dP = spectra_sensitivity(self.model, theta, self.data.w, np.asarray(self.data.Phi_uu))
        wt = self._weights()
        return self._pack(Phi - Pm) * wt, -self._pack(dP) * wt[:, None]

    def data_shift(self, theta: Any, dPhi: Any) -> np.ndarray:
        """How far the estimate θ moves, to first order (one Gauss–Newton step), when the data Φyy change by ``dPhi``
        (an array shaped like Φyy): the bias a systematic error of the spectra leaves in θ̂ (symid.fit.frf.leakage;
        as :meth:`symid.fit.frf.fisher.FrfFisher.data_shift`)."""
        _, J = self.jacobian(theta)
        step, *_ = np.linalg.lstsq(J, self._pack(np.asarray(dPhi)) * self._weights(), rcond=None)
        return -step[: np.asarray(theta).size]

    def residual_channels(self) -> np.ndarray:
        """One channel: a relative noise level shared by every entry."""
        return np.zeros(self._weights().size, dtype=int)

    def noise_shape(self, theta: Any) -> np.ndarray:
        """√(Φyyᵢᵢ Φyyⱼⱼ) of the data × the weight (the √2 of the parts above the diagonal cancels their half).

        A spectrum averaged over K segments (Welch) has Var Φ̂ᵢⱼ ≈ Φᵢᵢ Φⱼⱼ / K, the auto-spectra
        being those measured, sensor noise included: where that noise is all the data hold (the
        lines far above a structure's modes, a position falling as ω⁻⁴ against a flat noise
        floor), the model's own |Φᵢⱼ(θ)| is orders of magnitude smaller, and a noise level
        relative to it came out at 1.6e6 % for a new user's building (2 % sensor noise, SI
        units), its standard errors 1e4 times the estimates. For a single input (or any
        spectrum of rank one) and data that follow the model, √(Φᵢᵢ Φⱼⱼ) = |Φᵢⱼ|: the same shape.
        """
        Phi = np.asarray(self.data.Phi_yy)
        auto = np.abs(np.real(np.diagonal(Phi, axis1=1, axis2=2)))  # (s, p)
        mag = np.sqrt(auto[:, :, None] * auto[:, None, :])
        return self._pack_magnitudes(mag) * self._weights()

    def _pack_magnitudes(self, mag: np.ndarray) -> np.ndarray:
        """Per independent entry, the std of that real number for E|eᵢⱼ|² = magᵢⱼ², over the √2 weight above."""
        p = mag.shape[1]
        iu = np.triu_indices(p, 1)
        idx = np.arange(p)
        up = mag[:, iu[0], iu[1]]
        return np.concatenate([mag[:, idx, idx].reshape(-1), up.reshape(-1), up.reshape(-1)])

    def given_noise(self, noise_std: Any) -> tuple[np.ndarray, np.ndarray]:
        """``noise_std``: a number, one per frequency (s,), or (s, p, p); E|eᵢⱼ|² = std² for each entry."""
        Phi = np.asarray(self.data.Phi_yy)
        arr = broadcast_noise(noise_std, Phi.shape, f"the output spectrum Phi_yy (s, p, p) = {Phi.shape}")
        return self._pack_magnitudes(arr) * self._weights(), arr.reshape(-1)

    def uncertainty_note(self) -> str:
        """Said for the methods that do not minimise the spectral misfit (``auto`` does: its passes and its polish are
        IPOPT on (5-13); a new user's successful fit read that it did not)."""
        if self.method == "auto" or (self.method == "ipopt"
                                     and getattr(self, "options", {}).get("objective", "output") == "output"):
            return ""
        return (f"method {self.method!r} does not minimise the spectral misfit (5-13); this is the covariance of "
                "the least-squares estimate, evaluated at its θ̂ (polish=True reaches that estimate)")
