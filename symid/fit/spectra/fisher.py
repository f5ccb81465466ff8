"""The Fisher information of a spectral fit: residuals, exact Jacobian, relative noise.

The spectral misfit is Σᵢ wᵢ ‖Φyyᵢ − H Φuuᵢ Hᴴ‖²_F (wᵢ one constant, or 1/‖Φyyᵢ‖²_F per
frequency with IPOPT's ``weighting="frequency"``), or with ``weighting="variance"`` each
entry's own weight (:mod:`symid.fit.spectra.welch`). A Hermitian p × p spectrum holds p²
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
        """The weight of every packed entry: its frequency's, or its own (``entry_weights``, normalised as the
        misfit is)."""
        Phi = np.asarray(self.data.Phi_yy)
        s, p, _ = Phi.shape
        w = getattr(self, "entry_weights", None)
        if w is not None:
            total = float(np.sqrt(np.sum(w * np.abs(Phi) ** 2))) or 1.0
            return self._pack_magnitudes(np.sqrt(w)) / total
        return self._pack_magnitudes(np.broadcast_to(self._frequency_weights()[:, None, None], (s, p, p)))

    def jacobian(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """Weighted independent entries of Φyy − H Φuu Hᴴ and their Jacobian; with ``sensor_noise`` the white noise
        on each output is a nuisance unknown (a column of its own, its profiled value in the residual)."""
        Phi = np.asarray(self.data.Phi_yy)
        Pm, dP = spectra_sensitivity(self.model, theta, self.data.w, np.asarray(self.data.Phi_uu))
        wt = self._weights()
        J = -self._pack(dP) * wt[:, None]
        if getattr(self, "sensor_noise", False):
            from symid.fit.spectra.welch import profiled_sensor_noise

            s, p, _ = Phi.shape
            Pm = Pm + np.diag(profiled_sensor_noise(self.data, Pm, getattr(self, "entry_weights", None)))[None]
            unit = np.zeros((s, p, p, p))
            unit[:, np.arange(p), np.arange(p), np.arange(p)] = 1.0
            J = np.hstack([J, -self._pack(unit) * wt[:, None]])
        return self._pack(Phi - Pm) * wt, J

    def data_shift(self, theta: Any, dPhi: Any) -> np.ndarray:
        """How far the estimate θ moves, to first order (one Gauss–Newton step), when the data Φyy change by ``dPhi``
        (an array shaped like Φyy): the bias a systematic error of the spectra leaves in θ̂ (symid.fit.frf.leakage;
        as :meth:`symid.fit.frf.fisher.FrfFisher.data_shift`)."""
        _, J = self.jacobian(theta)
        step, *_ = np.linalg.lstsq(J, self._pack(np.asarray(dPhi)) * self._weights(), rcond=None)
        return -step[: np.asarray(theta).size]

    def residual_correlation(self, theta: Any) -> Any:
        """For spectra estimated by averaging windowed segments (:func:`symid.estimate_spectra`, or ``averages=``
        given): the correlation of the residual's entries, sparse, from the model's spectra at θ; None otherwise.

        A Welch estimate's entries at one line are not independent: Cov(Φ̂ab, Φ̂cd) = Φac Φdb / K and
        E[(Φ̂ab − Φab)(Φ̂cd − Φcd)] = Φad Φcb / K (a complex Wishart matrix); with one input the p² entries
        share one scatter. And lines k apart share the window's overlap: the correlation rₖ =
        |Σₙ w(n)² e^{−2πjkn/L}|² / (Σₙ w(n)²)² (Hann: r₁ = 4/9, r₂ = 1/36), where Φ changes little across
        them. Independent entries would count a record's information several times over: on the footbridge
        of :mod:`symid.fit.spectra.welch` the masses' intervals missed the truth by up to 4 standard errors.
        """
        import scipy.sparse

        from symid.fit.spectra.equations import _model_spectra_or_none

        made = getattr(self.data, "estimated_from", None) or {}
        if not made and getattr(self, "averages", None) is None:
            return None
        Pm = _model_spectra_or_none(self.model, self.data, theta, getattr(self, "entry_weights", None),
                                    getattr(self, "sensor_noise", False))
        if Pm is None:
            return None
        s, p, _ = Pm.shape
        # the packed coordinates of one line: (row a, column b, part: 0 real / 1 imaginary, factor)
        iu = np.triu_indices(p, 1)
        coords = ([(a, a, 0, 1.0) for a in range(p)] + [(a, b, 0, np.sqrt(2.0)) for a, b in zip(*iu, strict=True)]
                  + [(a, b, 1, np.sqrt(2.0)) for a, b in zip(*iu, strict=True)])
        a, b, part, fac = (np.array(c) for c in zip(*coords, strict=True))
        C = Pm[:, a[:, None], a[None, :]] * Pm[:, b[None, :], b[:, None]]   # Φac Φdb for x = (a, b), y = (c, d)
        P = Pm[:, a[:, None], b[None, :]] * Pm[:, a[None, :], b[:, None]]   # Φad Φcb
        re_u, re_v = (part == 0)[:, None], (part == 0)[None, :]
        G = np.where(re_u & re_v, (C + P).real, np.where(~re_u & ~re_v, (C - P).real,
                     np.where(~re_u & re_v, (C + P).imag, (P - C).imag))) / 2 * np.outer(fac, fac)
        d = np.sqrt(np.clip(np.einsum("sii->si", G), 0, None))
        denom = d[:, :, None] * d[:, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            R = np.where(denom > 0, G / np.where(denom > 0, denom, 1.0), 0.0)
        R[:, np.arange(p * p), np.arange(p * p)] = 1.0  # an entry the model gives no scatter: on its own
        # the packed index of (line i, coordinate c), as _pack orders them: every line's diagonal, then the real
        # parts above it, then the imaginary parts
        nup = iu[0].size
        line_of = np.arange(s)[:, None]
        idx = np.hstack([line_of * p + np.arange(p)[None, :], s * p + line_of * nup + np.arange(nup)[None, :],
                         s * (p + nup) + line_of * nup + np.arange(nup)[None, :]])
        rows, cols, vals = [], [], []

        def block(i: np.ndarray, j: np.ndarray, values: np.ndarray) -> None:
            rows.append(np.repeat(idx[i][:, :, None], p * p, axis=2).reshape(-1))
            cols.append(np.repeat(idx[j][:, None, :], p * p, axis=1).reshape(-1))
            vals.append(values.reshape(-1))

        block(np.arange(s), np.arange(s), R)
        nperseg, resolution, window = made.get("nperseg"), made.get("resolution"), made.get("window")
        if nperseg and resolution and window not in (None, "given"):
            import scipy.signal

            win = np.asarray(scipy.signal.get_window(window, int(nperseg)), dtype=float) ** 2
            n = np.arange(win.size)
            line = np.rint(np.asarray(self.data.w, dtype=float) / float(resolution)).astype(int)
            for k in range(1, 8):
                rk = abs(np.sum(win * np.exp(-2j * np.pi * k * n / win.size))) ** 2 / np.sum(win) ** 2
                if rk < 1e-4:
                    break
                i = np.flatnonzero(np.isin(line + k, line))
                j = np.searchsorted(line, line[i] + k)
                both = rk * 0.5 * (R[i] + R[j])
                block(i, j, both)
                block(j, i, np.swapaxes(both, 1, 2))
        N = s * p * p
        return scipy.sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                       shape=(N, N))

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
