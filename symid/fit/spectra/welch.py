"""Weights and noise floor for output spectra estimated by averaging segments (Welch).

A spectrum averaged over K segments scatters in proportion to its own level: to first
order Var Φ̂ⱼₖ = Φⱼⱼ Φₖₖ / K (the diagonal real; the real and imaginary parts above it
share the variance; a complex Wishart matrix with K degrees of freedom, Percival & Walden
1993, §6.7). The unweighted misfit (5-13) then lets the few lines at the resonances, the
noisiest in absolute terms, carry the whole fit. A new user's 3-storey footbridge (three
accelerometers, ambient forces on every floor, 20 min at 100 Hz, Welch segments of 8192
samples, about 28 averages, 902 lines over 1–12 Hz): with equal weights the estimate was
the least-squares one (IPOPT from the truth ends there too) with masses and springs about
10 % off and the dampers up to 42 %, at a misfit of 0.0195 that the success rule refused.
Over 8 records of that footbridge with 3 % sensor noise (``OMP_NUM_THREADS=1
.venv/bin/python benchmarks/psd_welch_weights.py``) the standard deviations of the masses
and springs were 3.0–8.1 % with equal weights and 0.5–0.8 % with each entry weighted by
1/(Φⱼⱼ Φₖₖ) (``auto``), the dampers' 8.4–68 % against 3.0–8.6 %.

The weights come from the model's own spectra at the estimate (:func:`variance_weights`),
iterated a few times from weights of the measured auto-spectra: weights from the measured
values correlate with their noise and bias the fit (as a frequency response's relative
weights do, :mod:`symid.fit.frf.misfit`). Where the model's auto-spectrum falls below
the measured one's local level by more than noise explains (sensor noise the model does
not hold, far above a position's modes), that level is taken instead, so that such lines
do not carry the fit either; ``auto`` also fits that noise beside the model
(``sensor_noise``, :func:`profiled_sensor_noise`: at 30 % sensor noise the fits without it
failed on 8 of 8 records, masses and springs 5–16 % off, with it succeeded on 8 of 8 within
1 %). A full whitening by Φ(θ)⁻¹ (the Whittle likelihood's
weighting) was tried and not kept: the sensor noise the model does not hold then sits in
the spectra's smallest eigen-directions, which it weighs most, and the footbridge's
masses and springs came out 9–11 % low.

With the number of averages known (the spectra estimated by :func:`symid.estimate_spectra`
from output records with a given input spectrum, or ``averages=`` given), the weighted
misfit that noise alone leaves is known as well: s·p²/K_eff over Σ w|Φ̂|², with K_eff the
averages the overlapping segments are worth (:func:`symid.signal.frf.effective_averages`).
The success rule judges the fit against it (:func:`welch_noise_floor`), times
:data:`WELCH_FLOOR_MARGIN`: a Wishart matrix's entries are correlated (coherent outputs
share one scatter), the window's smoothing of the peaks adds a bias the noise does not
(:mod:`symid.fit.frf.leakage`), and with tens of averages the scatter is not Gaussian.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.ndimage

from symid.signal.frf import effective_averages

__all__ = ["LOCAL_LINES", "VARIANCE_ROUNDS", "WELCH_FLOOR_MARGIN", "data_weights", "profiled_sensor_noise",
           "spectra_averages", "variance_weights", "welch_noise_floor"]

WELCH_FLOOR_MARGIN = 1.1
"""The weighted misfit may lie this many times above the Welch noise floor (module notes; the χ² bound of the success
rule comes on top, about 1.05 for a thousand lines). The fits that reach the truth lie at 0.77–0.97 times the floor
on 6 records of the frame of ``tests/test_spectra_welch_weights.py`` and at 0.97–1.006 on 6 of the footbridge of
``benchmarks/psd_welch_weights.py`` (3 % and 30 % sensor noise); a new user's 4-storey frame (two accelerometers)
was accepted at a local minimum 1.19 times the floor, a mass 10⁴ times its value, with the margin 1.5."""

VARIANCE_ROUNDS = 3
"""Solves reweighted at the estimate after the first (fewer when the estimate moves by under 1e-6 of itself); on the
footbridge of the module notes the second round moved the estimate by under 0.2 % and the third by under 1e-5."""

LOCAL_LINES = 9
"""The measured auto-spectrum's local level is its running median over this many lines (module notes)."""


def _auto(Phi: np.ndarray) -> np.ndarray:
    """The auto-spectra Φⱼⱼ of (s, p, p) spectra as (s, p), real and ≥ 0."""
    return np.abs(np.real(np.diagonal(np.asarray(Phi), axis1=1, axis2=2)))


def _local_level(Phi_yy: np.ndarray) -> np.ndarray:
    """The measured auto-spectra's running median over :data:`LOCAL_LINES` lines, (s, p)."""
    auto = _auto(Phi_yy)
    size = min(LOCAL_LINES, auto.shape[0])
    return scipy.ndimage.median_filter(auto, size=(size, 1), mode="nearest")


def _from_auto(auto: np.ndarray) -> np.ndarray:
    """Weights 1/(aⱼ aₖ) of (s, p) auto-spectra a, scaled to mean 1 (a zero level gets the largest weight)."""
    top = float(np.max(auto)) if auto.size else 0.0
    a = np.maximum(auto, 1e-12 * top if top > 0 else 1.0)
    w = 1.0 / (a[:, :, None] * a[:, None, :])
    return w / float(np.mean(w))


def data_weights(data: Any) -> np.ndarray:
    """Weights 1/(Φ̂ⱼⱼ Φ̂ₖₖ) of the measured auto-spectra, each taken at its local level (the running median over
    :data:`LOCAL_LINES` lines, less correlated with each line's own scatter), shape (s, p, p), mean 1: the weights
    before there is an estimate."""
    return _from_auto(_local_level(np.asarray(data.Phi_yy)))


def variance_weights(model: Any, data: Any, theta: Any, averages: float | None = None) -> np.ndarray | None:
    """Weights 1/(Φⱼⱼ Φₖₖ) of the model's spectra at θ, shape (s, p, p), mean 1; where the measured local level
    lies above the model's by more than noise explains (a factor 1 + 6/√K, K the averages, else 3), that level
    (module notes). ``None`` where the model cannot be evaluated at θ.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.spectra.welch import variance_weights
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.2, 4.0], [1.0, 2.0, 3.0], Phi_uu=1.0)
    >>> w = variance_weights(model, spec, [1.0, 0.2, 4.0])[:, 0, 0]
    >>> np.round(w / w[0], 4).tolist()          # 1/|H|⁴: the resonance at 2 rad/s weighs least
    [1.0, 0.0003, 7.8698]
    """
    from symid.fit.spectra.equations import model_spectra

    try:
        with np.errstate(all="ignore"):
            Pm = model_spectra(model, theta, data.w, np.asarray(data.Phi_uu))
    except (ArithmeticError, ValueError, np.linalg.LinAlgError):
        return None
    if not np.all(np.isfinite(Pm)):
        return None
    auto = _auto(Pm)
    factor = 3.0 if averages is None else 1.0 + 6.0 / np.sqrt(max(float(averages), 1.0))
    level = _local_level(np.asarray(data.Phi_yy))
    return _from_auto(np.where(level > factor * auto, level, auto))


def spectra_averages(data: Any) -> float | None:
    """The independent averages K_eff behind spectra :func:`symid.estimate_spectra` estimated from output records with
    a given input spectrum (``estimated_from``); ``None`` otherwise: spectra from a file or a simulation, or with a
    measured input, whose estimated Φuu scatters with the outputs."""
    made = getattr(data, "estimated_from", None) or {}
    if made.get("input") != "given":
        return None
    N, nperseg, window = made.get("samples"), made.get("nperseg"), made.get("window")
    if not N or not nperseg or window in (None, "given"):
        return None
    noverlap = int(made.get("noverlap", int(nperseg) // 2))
    K = (int(N) - noverlap) // (int(nperseg) - noverlap)
    return effective_averages(window, int(nperseg), noverlap, K) if K >= 1 else None


def welch_noise_floor(data: Any, weights: np.ndarray, averages: float) -> float:
    """The weighted relative misfit Σ w|Φ̂ − Φ|² / Σ w|Φ̂|² that the scatter of K averages leaves at the true
    parameters, for weights w = 1/(Φⱼⱼ Φₖₖ): s·p²/K over Σ w|Φ̂|² (module notes).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data import SpectralData
    >>> from symid.fit.spectra.welch import welch_noise_floor
    >>> spec = SpectralData([1.0, 2.0], [[[2.0]], [[8.0]]], np.ones(2))
    >>> welch_noise_floor(spec, np.array([[[1 / 4]], [[1 / 64]]]), averages=25.0)   # one lag per line: 1/K
    0.04
    """
    Phi = np.asarray(data.Phi_yy)
    total = float(np.sum(weights * np.abs(Phi) ** 2))
    return float(np.sum(weights * _auto(Phi)[:, :, None] * _auto(Phi)[:, None, :]) / total / averages) \
        if total > 0 else float("inf")


def profiled_sensor_noise(data: Any, Pm: np.ndarray, weights: np.ndarray | None) -> np.ndarray:
    """The white sensor noise νⱼ ≥ 0 on each output's auto-spectrum that fits Φyy best beside the model's spectra
    ``Pm`` (s, p, p) in the misfit's weights: νⱼ = max(0, Σᵢ wᵢⱼⱼ (Φ̂ᵢⱼⱼ − Pmᵢⱼⱼ) / Σᵢ wᵢⱼⱼ), exact since νⱼ
    enters the diagonal entry (j, j) alone (module notes of :mod:`symid.fit.spectra.equations`).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data import SpectralData
    >>> from symid.fit.spectra.welch import profiled_sensor_noise
    >>> model = np.array([[[4.0]], [[1.0]], [[0.25]]])
    >>> spec = SpectralData([1.0, 2.0, 3.0], model + 0.5, np.ones(3))      # a floor of 0.5 beside the model
    >>> profiled_sensor_noise(spec, model, None).tolist()
    [0.5]
    """
    Phi = np.asarray(data.Phi_yy)
    diff = np.real(np.diagonal(Phi - Pm, axis1=1, axis2=2))  # (s, p)
    w = np.ones(diff.shape) if weights is None else np.diagonal(np.asarray(weights), axis1=1, axis2=2)
    total = w.sum(axis=0)
    return np.maximum(0.0, (w * diff).sum(axis=0) / np.where(total > 0, total, 1.0))
