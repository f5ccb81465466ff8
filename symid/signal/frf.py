"""Frequency responses from measured input/output records: H1 and H2 (Welch), periodic averaging, coherence.

Two ways in, chosen by ``period``:

**Random (non-periodic) excitation** — Welch's averaged cross spectra
(:func:`scipy.signal.csd`, segments of ``nperseg`` samples, a window, half overlap).
With S[a, b] = E[X_a conj(X_b)] averaged over the segments,

* H1 = Syu Suu⁻¹ (least squares; unbiased for noise on the outputs only),
* H2 = Syy_ii / conj(Syu_i) per output i, single input (unbiased for noise on the input only),

and the multiple coherence of output i with all the inputs,
γᵢ² = Syu_i Suu⁻¹ Syu_iᴴ / Syy_ii (the ordinary coherence for one input). The variance
of each entry is the first-order formula of the frequency-domain regression (Bendat &
Piersol, *Random Data*, 4th ed., §9.2; Pintelon & Schoukens, *System Identification:
A Frequency Domain Approach*, 2nd ed., §2.5): with the residual spectrum
(1 − γᵢ²) Syy_ii left by the m inputs,

    var Ĥ1_ij = (1 − γᵢ²) Syy_ii [Suu⁻¹]_jj / (n_eff − m),

n_eff being the number of independent averages that K half-overlapping windowed
segments are worth (Welch 1967: n_eff = K / (1 + 2 Σⱼ (1 − j/K) ρⱼ²), ρⱼ the overlap
correlation of the window at a shift of j steps; 0.947 K for K ≫ 1 with a Hann window)
and n_eff − m instead of n_eff correcting for the m degrees of freedom spent on
H1. For H2 the same first-order value at the H2 estimate,
(1 − γ²) |Ĥ2|² / (γ² (n_eff − 1)), valid where the coherence is close to one.
The variance is that of the noise only: a window also smooths the response over its
resolution (leakage), a bias that is largest at lightly damped resonances, where it
shows as dips of the coherence (on the F-16 ground vibration test, Welch with
8192-sample Hann segments drops the coherence to 0.56 at the 7.3 Hz mode, where the
periodic estimate of the same record keeps it above 0.999). Longer segments or periodic
excitation remove it.

**Periodic excitation** (a multisine; ``period`` samples per period) — every period is
transformed separately, the first ``transient_periods`` are dropped (the transient),
and the spectra of the remaining P periods are averaged, Ū = mean U_k, Ȳ = mean Y_k.
The estimate is Ĥ = Ȳ Ū⁺ (Ȳ / Ū for one input): with one record per input (m records
of independent excitations, given as a list of :class:`~symid.IOData`) Ū is square.
The noise is estimated from the periods themselves (Pintelon & Schoukens §2.4,
"nonparametric noise model"): the per-period residuals E_k = Y_k − Ĥ U_k hold the
output noise and the input noise seen through H; their sample variance over the
periods (P − 1 degrees of freedom) gives, to first order,

    var Ĥ_ij = Σ_e σ²_E[i, e] |Ū⁺[e, j]|² / P

(for one input, (σ²_Y + |H|² σ²_U − 2 Re(H̄ σ²_YU)) / (P |Ū|²)). No window is used: a
whole number of periods of a periodic signal has no leakage. With P = 1 there is no
variance (``variance=None``).

Variance convention: ``E|Ĥ − H|²``, real and imaginary parts together (each holds
half of it for circular complex noise), the convention of :class:`~symid.FrequencyData`.

Which lines are kept: the lines inside ``band`` (every line above DC and below the
Nyquist frequency when it is not given), less the lines where the input is not
excited — where the smallest singular value of the averaged input spectrum (Ū, or
√Suu for Welch) is below ``min_excitation`` times the largest over all lines (1e-3,
−60 dB, by default): there the ratio of spectra is noise over noise (the skipped
lines of an odd multisine, the lines above a band-limited excitation). The returned
frequencies say which lines were kept; ``min_excitation=0`` keeps every line with a
nonzero input. A band with no excited line is a :class:`~symid.errors.DataError`.

The measured ratio is the continuous-time response H(jω) at the lines when input and
output were both sampled from band-limited signals (anti-alias filters on both
channels, the usual measurement set-up); a record simulated with a zero-order hold
(:func:`symid.simulate_io`) has instead the sampled response H_d(e^{jω dt}), which
differs from H(jω) by the hold (about ω dt/2 in phase).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal

from symid.data import FrequencyData, IOData
from symid.errors import DataError, DataWarning

__all__ = ["effective_averages", "estimate_coherence", "estimate_frf"]

_ESTIMATORS = ("h1", "h2")
_DETRENDS = ("constant", "linear", False)


@dataclass(frozen=True)
class _Estimate:
    """Everything one analysis computes; the public functions return parts of it."""

    w: np.ndarray
    H: np.ndarray
    variance: np.ndarray | None
    coherence: np.ndarray
    variance_dof: float | None = None
    """Real degrees of freedom of the variance estimate (2 per complex one)."""
    input_separation: float = 1.0
    """Median over the lines of the smallest eigenvalue of the inputs' normalised spectral matrix (:func:`_separation`):
    1 for uncorrelated inputs, 0 for inputs that are one signal at every line."""
    nperseg: int | None = None
    """Welch: samples per segment (None for the periodic estimate, which has no window)."""


COLLINEAR_INPUTS = 1e-2
"""Below this median separation of the inputs (for two inputs, 1 − |γ₁₂|: an input coherence above 0.98) the
estimate warns: each input's column has at least 1/separation times the variance it would have with uncorrelated
inputs, and with inputs that are one signal (one the derivative or a copy of the other) it is arbitrary."""


def _separation(Suu: np.ndarray) -> float:
    """Median over the lines of λ_min(D^{-1/2} Suu D^{-1/2}), D = diag(Suu): how far the inputs are from being one
    signal (1 with one input)."""
    if Suu.shape[1] < 2 or Suu.shape[0] == 0:
        return 1.0
    d = np.sqrt(np.real(np.diagonal(Suu, axis1=1, axis2=2)))
    with np.errstate(divide="ignore", invalid="ignore"):
        C = Suu / (d[:, :, None] * d[:, None, :])
    C = 0.5 * (C + np.conj(np.swapaxes(C, 1, 2)))
    lam = np.linalg.eigvalsh(np.where(np.isfinite(C), C, 0.0))[:, 0]
    return float(np.median(np.clip(lam, 0.0, None)))


# -- arguments ----------------------------------------------------------------------------

def _records(data: Any) -> list[IOData]:
    if isinstance(data, IOData):
        return [data]
    if isinstance(data, (list, tuple)) and data and all(isinstance(d, IOData) for d in data):
        recs = list(data)
        first = recs[0]
        for k, r in enumerate(recs[1:], start=1):
            if (r.n_inputs, r.n_outputs) != (first.n_inputs, first.n_outputs):
                raise DataError(f"record {k} has {r.n_inputs} input(s) and {r.n_outputs} output(s); record 0 has "
                                f"{first.n_inputs} and {first.n_outputs}: all records must have the same channels")
            if not np.isclose(r.dt, first.dt, rtol=1e-12, atol=0):
                raise DataError(f"record {k} has dt = {r.dt!r} s, record 0 has dt = {first.dt!r} s: all records "
                                "must share one sample time")
        return recs
    raise DataError("estimate_frf needs input/output records: a symid.IOData(u, y, dt) or a non-empty list of them "
                    f"(one per experiment); got {type(data).__name__}")


def _count(x: Any, name: str, *, low: int) -> int:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer)) or x < low:
        raise DataError(f"{name} must be an integer >= {low}; got {x!r}")
    return int(x)


def _band(band: Any, nyquist: float) -> tuple[float, float]:
    if band is None:
        return 0.0, nyquist
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise DataError(f"band must be a pair (w_low, w_high) of numbers in rad/s; got {band!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
        raise DataError(f"band must be (w_low, w_high) in rad/s with 0 <= w_low < w_high, both finite; got {band!r}")
    if lo >= nyquist:
        raise DataError(f"band {band!r} rad/s lies above the Nyquist frequency π/dt = {nyquist:.6g} rad/s: the "
                        "record holds no information there")
    if hi > nyquist * (1 + 1e-12):
        warnings.warn(f"band {band!r} rad/s reaches above the Nyquist frequency π/dt = {nyquist:.6g} rad/s: only "
                      "the lines below it are used", UserWarning, stacklevel=5)
    return lo, hi


def _min_excitation(x: Any) -> float:
    try:
        val = float(x)
    except (TypeError, ValueError):
        raise DataError(f"min_excitation must be a number in [0, 1); got {x!r}") from None
    if not (0 <= val < 1):
        raise DataError(f"min_excitation must be in [0, 1) (relative input amplitude); got {x!r}")
    return val


def _check_window(window: Any, nperseg: int) -> None:
    try:
        scipy.signal.get_window(window, nperseg)
    except (TypeError, ValueError) as exc:
        raise DataError(f"window {window!r} is not a window scipy.signal.get_window knows ({exc}); "
                        "use e.g. 'hann', 'hamming' or ('tukey', 0.25)") from None


# -- line selection --------------------------------------------------------------------------

def _keep_lines(w: np.ndarray, level: np.ndarray, band: tuple[float, float], min_excitation: float,
                what: str, largest: np.ndarray | None = None) -> np.ndarray:
    """Indices of the lines in ``band`` whose input level (smallest singular value) is high enough; ``largest``,
    the largest singular value, tells inputs that are one signal from inputs that are zero."""
    in_band = (w >= band[0]) & (w <= band[1])
    if not np.any(in_band):
        raise DataError(f"no {what} lies in band [{band[0]:.6g}, {band[1]:.6g}] rad/s (lines from {w[0]:.6g} to "
                        f"{w[-1]:.6g} rad/s, spacing {w[1] - w[0] if w.size > 1 else w[0]:.6g} rad/s)")
    top = float(np.max(level)) if level.size else 0.0
    if not top > 0:
        if largest is not None and np.max(largest) > 0:
            raise DataError("the inputs are one signal at every line (one is a copy, a scaled copy or a "
                            "filtered version of another, e.g. its derivative): the response to each cannot be told "
                            "apart. Excite them independently, or model them as one input")
        raise DataError("the input is zero at every frequency: there is no excitation to estimate a response from")
    excited = level >= min_excitation * top
    if min_excitation == 0:
        excited = level > 0
    keep = np.flatnonzero(in_band & excited)
    if keep.size == 0:
        raise DataError(f"the input is not excited at any {what} in band [{band[0]:.6g}, {band[1]:.6g}] rad/s "
                        f"(every line is below min_excitation = {min_excitation:g} times the strongest line, at "
                        f"{w[int(np.argmax(level))]:.6g} rad/s)")
    return keep


def _multiple_coherence(Suu: np.ndarray, Syu: np.ndarray, Syy_diag: np.ndarray) -> np.ndarray:
    """γᵢ² = Syu_i Suu⁻¹ Syu_iᴴ / Syy_ii, shape (s, p), clipped to [0, 1] against rounding."""
    X = np.linalg.solve(Suu, np.conj(np.swapaxes(Syu, 1, 2)))  # Suu⁻¹ Syuᴴ, (s, m, p)
    num = np.real(np.einsum("spm,smp->sp", Syu, X))
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(Syy_diag > 0, num / np.where(Syy_diag > 0, Syy_diag, 1.0), 0.0)
    return np.clip(g, 0.0, 1.0)


# -- Welch ----------------------------------------------------------------------------------

def effective_averages(window: Any, nperseg: int, noverlap: int, n_segments: int) -> float:
    """Number of independent averages that ``n_segments`` overlapping windowed segments are worth (Welch 1967).

    n_eff = K / (1 + 2 Σⱼ₌₁^{K−1} (1 − j/K) ρⱼ²) with ρⱼ = Σₙ w[n] w[n + jS] / Σₙ w[n]², S = nperseg − noverlap.

    Examples
    --------
    >>> from symid.signal.frf import effective_averages
    >>> round(effective_averages("hann", 256, 128, 1000) / 1000, 3)   # Hann, half overlap
    0.947
    >>> effective_averages("boxcar", 256, 0, 10)                      # no overlap: K
    10.0
    """
    win = np.asarray(scipy.signal.get_window(window, nperseg), dtype=float)
    step = nperseg - noverlap
    energy = float(np.sum(win**2))
    total = 0.0
    for j in range(1, n_segments):
        shift = j * step
        if shift >= nperseg:
            break
        rho = float(np.sum(win[: nperseg - shift] * win[shift:])) / energy
        total += (1 - j / n_segments) * rho**2
    return float(n_segments / (1 + 2 * total))


def _welch(recs: list[IOData], estimator: str, nperseg: Any, window: Any, detrend: Any, band: Any,
           min_excitation: float) -> _Estimate:
    if detrend not in _DETRENDS:
        raise DataError(f"detrend must be 'constant', 'linear' or False; got {detrend!r}")
    m, dt = recs[0].n_inputs, recs[0].dt
    N = min(r.n_samples for r in recs)
    if nperseg is None:
        nperseg = 2 ** int(np.floor(np.log2(max(N / 8, 8))))
    nperseg = _count(nperseg, "nperseg", low=8)
    if nperseg > N:
        raise DataError(f"nperseg = {nperseg} is longer than the record ({N} samples); use nperseg <= {N}")
    _check_window(window, nperseg)
    noverlap = nperseg // 2
    S = None
    K_total, n_eff = 0, 0.0
    for r in recs:
        x = np.hstack([r.u, r.y])
        f, Sr = scipy.signal.csd(x[:, :, None], x[:, None, :], fs=1.0 / dt, window=window, nperseg=nperseg,
                                 noverlap=noverlap, detrend=detrend, scaling="density", axis=0)
        Sr = np.conj(Sr)  # csd(a, b) = E[conj(A) B], here E[conj(X_a) X_b]; S[f, a, b] = E[X_a conj(X_b)]
        K = (r.n_samples - noverlap) // (nperseg - noverlap)
        S = Sr * K if S is None else S + Sr * K
        K_total += K
        n_eff += effective_averages(window, nperseg, noverlap, K)
    S = S / K_total
    first = 2 if detrend is not False else 1  # the detrend biases the lowest bin (see estimate_spectra)
    inner = slice(first, f.size - 1 if nperseg % 2 == 0 else f.size)
    w_all = 2 * np.pi * f[inner]
    S = S[inner]
    Suu, Syu, Syy = S[:, :m, :m], S[:, m:, :m], S[:, m:, m:]
    Suu = 0.5 * (Suu + np.conj(np.swapaxes(Suu, 1, 2)))
    lam = np.linalg.eigvalsh(Suu)
    keep = _keep_lines(w_all, np.sqrt(np.clip(lam[:, 0], 0, None)), _band(band, np.pi / dt), min_excitation,
                       "Welch bin", largest=np.sqrt(np.clip(lam[:, -1], 0, None)))
    w, Suu, Syu, Syy = w_all[keep], Suu[keep], Syu[keep], Syy[keep]
    syy = np.real(np.diagonal(Syy, axis1=1, axis2=2))  # (s, p)
    coh = _multiple_coherence(Suu, Syu, syy)
    dof = n_eff - m
    if dof <= 0:
        raise DataError(f"{K_total} Welch segment(s) (worth {n_eff:.2f} independent averages) cannot separate "
                        f"{m} input(s): use a shorter nperseg or a longer record")
    Suu_inv = np.linalg.inv(Suu)
    if estimator == "h1":
        H = np.swapaxes(np.linalg.solve(np.swapaxes(Suu, 1, 2), np.swapaxes(Syu, 1, 2)), 1, 2)  # Syu Suu⁻¹
        var = (1 - coh)[:, :, None] * syy[:, :, None] * np.real(np.diagonal(Suu_inv, axis1=1, axis2=2))[:, None, :]
        var = var / dof
    else:
        if m != 1:
            raise DataError(f"the H2 estimator is defined here for one input; these records have {m} inputs: use "
                            "estimator='h1', or periodic excitation (period=)")
        cross = Syu[:, :, 0]
        zero = np.flatnonzero(np.any(np.abs(cross) == 0, axis=1))
        if zero.size:
            raise DataError(f"the cross spectrum is zero at ω = {w[zero[0]]:.6g} rad/s (coherence 0): H2 = Syy / "
                            "conj(Syu) does not exist there; use estimator='h1' or narrow the band")
        H = (syy / np.conj(cross))[:, :, None]
        with np.errstate(divide="ignore"):
            rel = np.where(coh > 0, (1 - coh) / np.where(coh > 0, coh, 1.0), np.inf)
        if not np.all(np.isfinite(rel)):
            i = int(np.flatnonzero(~np.all(np.isfinite(rel), axis=1))[0])
            raise DataError(f"the coherence is zero at ω = {w[i]:.6g} rad/s: the H2 estimate and its variance do not "
                            "exist there; use estimator='h1' or narrow the band")
        var = (rel * np.abs(H[:, :, 0]) ** 2 / (n_eff - 1))[:, :, None]
    return _Estimate(w, H, var, coh, 2.0 * float(dof if estimator == "h1" else n_eff - 1), _separation(Suu),
                     nperseg=nperseg)


# -- periodic ------------------------------------------------------------------------------

PERIODIC_DRIFT = 0.05
"""With ``period=``, an output whose mean moves over the periods used by more than this fraction of its periodic
part's rms (and by more than 4 standard deviations of the noise's) is said not to be periodic yet
(:func:`_not_periodic`)."""


def _not_periodic(y: np.ndarray, k: int, detrended: bool) -> str | None:
    """A sentence when an output's mean over each period (``y`` (P, period, p), record ``k``) moves by more than
    :data:`PERIODIC_DRIFT` of the rms of its average period from the first period used to the last: a transient
    longer than the periods skipped (a slow or rigid-body mode) or a drift, which the averaged spectra take for
    response at every line while the period-to-period variance does not see it (a new user's drive: the motor
    angle's period means 0.25, 0.62, 0.87, 1.03 rad, its response 10-30 times off at every line, the plotted band
    tight)."""
    P, L = y.shape[0], y.shape[1]
    if P < 2:
        return None
    means = y.mean(axis=1)  # (P, p)
    periodic = y.mean(axis=0)
    rms = np.sqrt(np.mean((periodic - periodic.mean(axis=0)) ** 2, axis=0))
    move = np.abs(means[-1] - means[0])
    # beyond what the noise moves a period's mean: σ/√L per period for white noise of the spread σ between periods
    spread = np.sqrt(np.sum((y - periodic) ** 2, axis=(0, 1)) / ((P - 1) * L))
    noise = 4.0 * np.sqrt(2.0) * spread / np.sqrt(L)
    bad = np.flatnonzero((move > PERIODIC_DRIFT * np.where(rms > 0, rms, np.inf)) & (move > noise))
    if not bad.size:
        return None
    j = int(bad[np.argmax(move[bad] / rms[bad])])
    where = f"record {k}, " if k else ""
    path = ", ".join(f"{v:.4g}" for v in means[:, j][:6]) + (", …" if P > 6 else "")
    fix = ("" if detrended else ", or detrend='linear' (a line fitted over the periods used is taken off each "
                                "input and output first)")
    return (f"{where}output {j} is not periodic over the periods used: its mean per period moves ({path}), "
            f"{move[j] / rms[j]:.3g} times the rms of its periodic part: a transient longer than the periods skipped "
            f"(a slow or rigid-body mode) or a drift, which every line takes for response while the variance between "
            f"periods does not see it. Skip more periods (transient_periods=), record more{fix}")


def _periodic(recs: list[IOData], period: Any, transient_periods: Any, band: Any, min_excitation: float,
              estimator: str, detrend: Any = "constant") -> _Estimate:
    if estimator != "h1":
        raise DataError(f"estimator={estimator!r} is a Welch estimator; with period= the spectra of the periods are "
                        "averaged (errors-in-variables consistent: Ĥ = mean Y / mean U); leave estimator out")
    period = _count(period, "period", low=2)
    skip = _count(transient_periods, "transient_periods", low=0)
    m, p, dt = recs[0].n_inputs, recs[0].n_outputs, recs[0].dt
    E = len(recs)
    if E < m:
        raise DataError(f"{m} inputs need at least {m} records with independent periodic excitations (one "
                        f"experiment per input, given as a list of IOData) to separate them at each line; got {E}")
    Us, Ys = [], []
    for k, r in enumerate(recs):
        N = r.n_samples
        if N % period:
            raise DataError(f"record {k} has N = {N} samples, not a whole number of periods of {period} samples "
                            f"(N / period = {N / period:.4g}): trim the record to {N // period * period} samples "
                            "(whole periods) or check the period")
        n_per = N // period
        if skip >= n_per:
            raise DataError(f"transient_periods = {skip} drops every one of the {n_per} periods of record {k}")
        u, y = r.u[skip * period:], r.y[skip * period:]
        if detrend == "linear":  # a line over the periods used off each input and output (DC is dropped anyway)
            ramp = np.column_stack([np.ones(u.shape[0]), np.arange(u.shape[0], dtype=float)])
            u = u - ramp @ np.linalg.lstsq(ramp, u, rcond=None)[0]
            y = y - ramp @ np.linalg.lstsq(ramp, y, rcond=None)[0]
        u = u.reshape(n_per - skip, period, m)
        y = y.reshape(n_per - skip, period, p)
        if (text := _not_periodic(y, k, detrend == "linear")) is not None:
            warnings.warn(text, DataWarning, stacklevel=4)
        Us.append(np.fft.rfft(u, axis=1))
        Ys.append(np.fft.rfft(y, axis=1))
    P = min(U.shape[0] for U in Us)
    if any(U.shape[0] != P for U in Us):
        raise DataError(f"the records hold different numbers of periods after the transient "
                        f"({', '.join(str(U.shape[0]) for U in Us)}); give records of equal length")
    U = np.stack(Us, axis=-1)  # (P, F, m, E)
    Y = np.stack(Ys, axis=-1)  # (P, F, p, E)
    F = U.shape[1]
    lines = np.arange(1, F - 1 if period % 2 == 0 else F)  # without DC and Nyquist
    w_all = 2 * np.pi * lines / (period * dt)
    U, Y = U[:, lines], Y[:, lines]
    Ubar, Ybar = U.mean(axis=0), Y.mean(axis=0)  # (s, m, E), (s, p, E)
    sv = np.linalg.svd(Ubar, compute_uv=False)  # (s, min(m, E))
    keep = _keep_lines(w_all, sv[:, -1] if m <= E else np.zeros(len(lines)), _band(band, np.pi / dt),
                       min_excitation, "line", largest=sv[:, 0] if m <= E else None)
    w, U, Y, Ubar, Ybar = w_all[keep], U[:, keep], Y[:, keep], Ubar[keep], Ybar[keep]
    Upinv = np.linalg.pinv(Ubar)  # (s, E, m)
    H = Ybar @ Upinv  # (s, p, m)
    var = None
    if P >= 2:
        R = Y - H[None] @ U  # per-period residuals (P, s, p, E)
        R = R - R.mean(axis=0)
        sig2 = np.sum(np.abs(R) ** 2, axis=0) / (P - 1)  # (s, p, E)
        var = np.einsum("spe,sej->spj", sig2, np.abs(Upinv) ** 2) / P
    # coherence over all periods of all records (rectangular "segments")
    Uk = np.moveaxis(U, -1, 1).reshape(-1, *U.shape[1:3])  # (P·E, s, m)
    Yk = np.moveaxis(Y, -1, 1).reshape(-1, *Y.shape[1:3])
    Suu = np.einsum("ksa,ksb->sab", Uk, np.conj(Uk))
    Syu = np.einsum("ksa,ksb->sab", Yk, np.conj(Uk))
    syy = np.sum(np.abs(Yk) ** 2, axis=0)
    coh = _multiple_coherence(Suu, Syu, syy) if P * E >= m else np.zeros_like(syy)
    return _Estimate(w, H, var, coh, None if var is None else 2.0 * (P - 1), _separation(Suu))


def _analyse(data: Any, estimator: Any, period: Any, transient_periods: Any, nperseg: Any, window: Any,
             detrend: Any, band: Any, min_excitation: Any) -> _Estimate:
    recs = _records(data)
    if estimator not in _ESTIMATORS:
        raise DataError(f"estimator must be one of {', '.join(map(repr, _ESTIMATORS))}; got {estimator!r}")
    level = _min_excitation(min_excitation)
    if period is None:
        if transient_periods:
            raise DataError("transient_periods applies to periodic excitation: give period= (samples per period)")
        return _welch(recs, estimator, nperseg, window, detrend, band, level)
    if nperseg is not None:
        raise DataError("nperseg is a Welch option; with period= every period is one segment: leave nperseg out")
    if detrend not in _DETRENDS:
        raise DataError(f"detrend must be 'constant', 'linear' or False; got {detrend!r}")
    return _periodic(recs, period, transient_periods, band, level, estimator, detrend)


def _hold_factor(w: np.ndarray, dt: float) -> np.ndarray:
    """The zero-order hold's response at ω, (1 − e^{−jω dt}) / (jω dt) = e^{−jω dt/2} sinc(ω dt / 2): what a held
    input puts between a continuous-time H(jω) and the response from the sampled input to the sampled output
    (the first term of that response's alias sum).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.signal.frf import _hold_factor
    >>> w, dt = np.array([1.0, 100.0]), 0.01
    >>> bool(np.allclose(_hold_factor(w, dt), (1 - np.exp(-1j * w * dt)) / (1j * w * dt), rtol=1e-12))
    True
    """
    return np.exp(-0.5j * w * dt) * np.sinc(w * dt / (2 * np.pi))


def estimate_frf(data: IOData | Sequence[IOData], *, estimator: str = "h1", period: int | None = None,
                 transient_periods: int = 0, nperseg: int | None = None, window: Any = "hann",
                 detrend: str | bool = "constant", band: Any = None, min_excitation: float = 1e-3,
                 hold: str | None = None) -> FrequencyData:
    """Frequency response H(ω) with its per-line noise variance, from measured input/output records.

    Random excitation is averaged over Welch segments (H1 or H2); periodic excitation
    (a multisine) over whole periods, with the noise variance of every line estimated
    from the spread between periods. The module notes give the formulas and sources.

    Parameters
    ----------
    data : IOData or list of IOData
        The record (u of shape (N, m), y of shape (N, p), dt), or several records of the
        same channels and sample time (independent experiments, averaged together;
        with ``period=`` and m inputs, at least m records of independent excitations).
    estimator : {"h1", "h2"}
        Welch estimator: ``"h1"`` = Syu Suu⁻¹ (noise on the outputs; default),
        ``"h2"`` = Syy / conj(Syu) (noise on the input; one input only). Not used
        with ``period=``.
    period : int, optional
        Samples per period of a periodic excitation. The records must hold a whole
        number of periods. Default: random excitation (Welch).
    transient_periods : int
        Periodic excitation: how many leading periods to drop (they hold the transient
        from the start of the excitation). Default 0.
    nperseg : int, optional
        Welch: samples per segment (resolution 2π/(nperseg·dt) rad/s). Default: the
        largest power of two ≤ N/8 (about 15 half-overlapping segments).
    window : str or tuple
        Welch: the segment window (:func:`scipy.signal.get_window`; default ``"hann"``).
    detrend : {"constant", "linear", False}
        Welch: removed from each segment (default ``"constant"``); with a detrend the
        lowest bin above DC is dropped, as in :func:`symid.estimate_spectra`. With
        ``period=``: ``"linear"`` takes a line fitted over the periods used off each input
        and output (the others change nothing: DC is not used). An output whose mean moves
        over the periods used is not periodic yet, and a ``DataWarning`` says so.
    band : (float, float), optional
        Keep the lines with ω in [w_low, w_high] rad/s. A band wholly above the Nyquist
        frequency π/dt is refused; one reaching above it warns.
    min_excitation : float
        Lines where the input's amplitude (smallest singular value over inputs) is below
        this fraction of its strongest line are left out (not excited; see the module
        notes); 0 keeps every line with a nonzero input. Default 1e-3 (−60 dB).
    hold : {None, "foh", "bandlimited", "zoh"}
        ``None`` (default), ``"foh"`` or ``"bandlimited"`` (as ``si.identify`` names a sampled
        input): Ĥ is the
        response from the sampled input to the sampled output, which is the continuous-time
        H(jω) when the input was sampled, not held (see the notes); nothing is corrected.
        ``"zoh"``: the input was held between samples (a DAC, a digital
        controller, :func:`symid.simulate_io`): Ĥ (and its variance) is divided by the
        hold's response e^{−jω dt/2} sinc(ω dt/2), so that a continuous-time model fits it.
        What stays is the aliasing of the response above the Nyquist frequency, small where
        |H| falls fast: one mass in position, a held multisine up to half the Nyquist
        frequency, the median error against H(jω) 36 % → 0.1 % (2.1 % at the top line;
        ``tests/test_estimate_frf.py``). For an output with a direct feedthrough
        (acceleration) the aliases dominate and the correction can leave Ĥ further from
        H(jω) than none: fit such a record as samples (``si.identify(model, io)``).

    Returns
    -------
    FrequencyData
        ω (rad/s), H (s, p, m) and ``variance`` (s, p, m): ``E|Ĥ − H|²`` per entry
        (``None`` for periodic excitation with a single period), with ``variance_dof`` the
        real degrees of freedom of that estimate: 2(P − 1) from P periods, 2(n_eff − m)
        from Welch averages (2(n_eff − 1) for H2). A fit weighted by it allows for them.

    Raises
    ------
    DataError
        On records that are not IOData or disagree in channels or sample time; a period
        that does not divide a record's length, or a transient that takes every period;
        fewer periodic records than inputs; an unknown estimator, window or detrend; a
        segment longer than the record; a band with no line or no excited line, or wholly
        above the Nyquist frequency; H2 with several inputs, or at a line of zero
        coherence.

    Warns
    -----
    DataWarning
        When the inputs are nearly one signal (:data:`COLLINEAR_INPUTS`: for two inputs, a
        coherence above 0.98 between them at the median line), so that the response to
        each cannot be told apart: the warning says how much that multiplies each
        column's variance. An input derived from another (its derivative, a scaled copy)
        is not a separate input. And when ``band`` reaches above the Nyquist frequency.

    Notes
    -----
    Ĥ is the response from the sampled input to the sampled output. Where the input
    is held between samples (a DAC, or :func:`symid.simulate_io`, which holds it), that
    is the response of the zero-order-hold discretisation of the system, not its
    continuous-time H(jω): the hold delays the input by half a sample on average, and an
    output with a direct feedthrough (acceleration) is sampled as the input jumps. On a
    1-DOF oscillator measured in acceleration (resonance 10 Hz, sampled at 100 Hz, a
    held multisine 0.5–30 Hz), Ĥ differs from H(jω) by 20 % at the median line, 300 %
    at 1 Hz, and a continuous-time model fitted to it is biased. ``hold="zoh"`` removes
    the hold's own response (delay and sinc); the aliases remain, large for an output
    with a direct feedthrough. Or fit such records as samples (``si.identify(model,
    io)``, output error, which models the hold exactly), or measure an input that is not
    held (band-limited, anti-alias filtered), as real acquisition systems do, and keep
    to a band well below the Nyquist frequency.

    See Also
    --------
    estimate_coherence : the coherence at the same lines.
    symid.plots.frf_estimate_plot : |H| with its confidence band, and the coherence.

    Examples
    --------
    A multisine through a first-order filter, 6 periods, the first dropped:

    >>> import numpy as np
    >>> import scipy.signal
    >>> import symid as si
    >>> rng = np.random.default_rng(0)
    >>> period, k = 256, np.arange(1, 40)
    >>> U = np.zeros(period // 2 + 1, complex)
    >>> U[k] = np.exp(2j * np.pi * rng.random(k.size))
    >>> u = np.tile(np.fft.irfft(U, period), 6)
    >>> y = scipy.signal.lfilter([0.2], [1, -0.8], u) + 1e-6 * rng.standard_normal(u.size)
    >>> io = si.IOData(u, y, dt=0.01)
    >>> frf = si.estimate_frf(io, period=period, transient_periods=1, band=(0, 2 * np.pi * 39 / 2.56))
    >>> frf.n_frequencies, frf.variance.shape
    (39, (39, 1, 1))
    >>> z = np.exp(1j * frf.w * 0.01)                  # the filter's exact response at the lines
    >>> bool(np.allclose(frf.H[:, 0, 0], 0.2 / (1 - 0.8 / z), rtol=1e-3))
    True
    """
    if hold not in (None, "foh", "bandlimited", "zoh"):
        raise DataError(f"hold must be None, 'foh' or 'bandlimited' (the input sampled) or 'zoh' (held between "
                        f"samples); got {hold!r}")
    est = _analyse(data, estimator, period, transient_periods, nperseg, window, detrend, band, min_excitation)
    if est.input_separation < COLLINEAR_INPUTS:
        # a new user's road input and its derivative as two inputs: coherence 0.99993 between them, each column of Ĥ
        # 190 % to 10⁴ % off with no word said (the output's coherence with the two was 0.9999)
        sep = est.input_separation
        warnings.warn(f"the {est.H.shape[2]} inputs are nearly one signal (median over the lines of the smallest "
                      f"eigenvalue of their normalised spectral matrix {sep:.2g}; for two inputs, a coherence of "
                      f"{(1 - sep) ** 2:.5f} between them): the response to each cannot be told apart, and each "
                      f"column of Ĥ has at least {1 / max(sep, 1e-300):.2g} times the variance it would have with "
                      "uncorrelated inputs (arbitrary where they are one signal). Excite the inputs independently; "
                      "if one input is derived from another (its derivative, a scaled copy), it is not a separate "
                      "input: model the pair as one", DataWarning, stacklevel=2)
    dt = _records(data)[0].dt
    if hold != "zoh":
        out = FrequencyData(est.w, est.H, est.variance, est.variance_dof)
    else:
        factor = _hold_factor(est.w, dt)[:, None, None]
        variance = None if est.variance is None else est.variance / np.abs(factor) ** 2
        out = FrequencyData(est.w, est.H / factor, variance, est.variance_dof)
    made = {"dt": float(dt), "hold": hold}
    if est.nperseg is not None:  # a windowed estimate: its resolution smooths lightly damped modes (fit/frf/leakage)
        made.update(nperseg=int(est.nperseg), window=window if isinstance(window, (str, tuple)) else "given",
                    resolution=2 * np.pi / (est.nperseg * float(dt)),
                    samples=int(min(r.n_samples for r in _records(data))))
    object.__setattr__(out, "estimated_from", made)  # metadata, not a field
    return out


def estimate_coherence(data: IOData | Sequence[IOData], *, estimator: str = "h1", period: int | None = None,
                       transient_periods: int = 0, nperseg: int | None = None, window: Any = "hann",
                       detrend: str | bool = "constant", band: Any = None, min_excitation: float = 1e-3
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The multiple coherence of each output with the inputs, at the lines :func:`estimate_frf` keeps.

    Takes exactly the arguments of :func:`estimate_frf` (same averaging, same lines).
    The coherence γᵢ²(ω) ∈ [0, 1] is the fraction of output i's power that the inputs
    explain linearly: 1 for a noise-free linear system, lower with noise, nonlinearity
    or leakage. For one input it is the ordinary coherence |Syu|² / (Suu Syy). With
    ``period=`` it is computed over the kept periods (rectangular segments).

    Parameters
    ----------
    data : IOData or list of IOData
        As :func:`estimate_frf`.
    estimator, period, transient_periods, nperseg, window, detrend, band, min_excitation
        As :func:`estimate_frf` (the estimator does not change the coherence, only
        which arguments are accepted).

    Returns
    -------
    w : numpy.ndarray, shape (s,)
        Angular frequencies (rad/s), those of ``estimate_frf(data, ...)``.
    coherence : numpy.ndarray, shape (s, p)
        γᵢ² per line and output.

    Raises
    ------
    DataError
        As :func:`estimate_frf`.

    Examples
    --------
    >>> import numpy as np
    >>> import scipy.signal
    >>> import symid as si
    >>> rng = np.random.default_rng(1)
    >>> u = rng.standard_normal(20_000)
    >>> y = scipy.signal.lfilter([0.5, 0.3], [1.0], u)
    >>> w, coh = si.estimate_coherence(si.IOData(u, y, dt=0.001), nperseg=256)
    >>> coh.shape, bool(coh.min() > 0.999)
    ((126, 1), True)
    """
    est = _analyse(data, estimator, period, transient_periods, nperseg, window, detrend, band, min_excitation)
    return est.w.copy(), est.coherence
