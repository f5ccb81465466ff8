"""Power spectral densities from sampled records (Welch), in the convention of ``simulate_spectra``.

Convention
----------
symid's spectra are two-sided densities per unit of angular frequency divided by 2π::

    Φxy(ω) = ∫ Rxy(τ) e^{−jωτ} dτ,   Rxy(τ) = E[x(t + τ) y(t)ᴴ],   E[x xᴴ] = (1/2π) ∫ Φxx(ω) dω,

so that y = H u gives Φyy(ω) = H(jω) Φuu(ω) H(jω)ᴴ, the relation (5-3) that
:func:`symid.simulate_spectra` evaluates, and a continuous-time white noise of intensity
φ (E[u(t) u(s)] = φ δ(t − s)) has Φuu = φ. In terms of scipy's ``welch``/``csd`` with
``fs = 1/dt`` and ``scaling="density"``: Φ(ω) at ω = 2πf is the two-sided density per Hz,
half the one-sided value scipy returns by default. A sampled white sequence of variance
σ² at sample time dt has Φ = σ² dt: to excite a model with white noise of intensity φ,
draw samples of variance φ/dt (held by a zero-order hold their spectrum is
φ·sinc²(ω dt/2), flat to 1 % below ω ≈ 0.35/dt).

Cross spectra follow from scipy's ``csd(x, y) = E[conj(X) Y]``:
Φyy[a, b] = E[Y_a conj(Y_b)] = csd(y_b, y_a).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.signal

from symid.data import IOData, SpectralData, checks
from symid.errors import DataError

__all__ = ["estimate_spectra"]


def _cross_spectra(x: np.ndarray, fs: float, nperseg: int, window: Any, detrend: str | bool
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies (Hz) and two-sided density matrices S[f, a, b] = E[X_a conj(X_b)] per Hz."""
    f, S = scipy.signal.csd(x[:, None, :], x[:, :, None], fs=fs, window=window, nperseg=nperseg,
                            detrend=detrend, scaling="density", axis=0, return_onesided=True)
    S = S / 2.0  # one-sided → two-sided (DC and Nyquist are dropped below); axis 0 is frequency
    return f, 0.5 * (S + np.conj(np.swapaxes(S, 1, 2)))


_PSD_RTOL = 1e-10
"""A given Φuu(ω) may have eigenvalues down to −1e-10 × its largest |eigenvalue| (rounding)."""
_DETRENDS = ("constant", "linear", False)


def _callable_values(fn: Callable[[float], Any], w: np.ndarray) -> list[np.ndarray]:
    vals = []
    for wi in w:
        try:
            v = np.asarray(fn(float(wi)), dtype=complex)
        except (TypeError, ValueError) as exc:
            raise DataError(f"Phi_uu({float(wi):.6g}) must return a number or an (m, m) array of numbers; "
                            f"calling it gave {type(exc).__name__}: {exc}") from None
        vals.append(v)
    return vals


def _given_input(Phi_uu: Any, w: np.ndarray, m: int | None) -> np.ndarray:
    """A given input spectrum as (s, m, m): scalar, (m, m) matrix, or callable of ω; checked PSD."""
    if callable(Phi_uu):
        vals = _callable_values(Phi_uu, w)
        for wi, v in zip(w, vals, strict=True):
            if not np.all(np.isfinite(v)):
                raise DataError(f"Phi_uu must be finite: Phi_uu({float(wi):.6g}) = {v.tolist()!r}")
        out = np.stack([v * np.eye(m or 1) if v.ndim == 0 else v for v in vals])
    else:
        arr = checks.as_array(Phi_uu, "Phi_uu", complex_ok=True)
        checks.check_finite(arr.reshape(-1), "Phi_uu")
        if arr.ndim == 0:
            arr = arr * np.eye(m or 1)
        if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
            raise DataError(f"Phi_uu must be a scalar (white noise intensity), a square (m, m) matrix or a "
                            f"callable of ω; got shape {checks.shape_text(arr.shape)}")
        out = np.broadcast_to(arr, (w.size, *arr.shape)).copy()
    if out.ndim != 3 or out.shape[1] != out.shape[2] or (m is not None and out.shape[1] != m):
        want = "square matrices" if m is None else f"{m}×{m} matrices (one row per input of u)"
        raise DataError(f"Phi_uu must give {want}; got shape {checks.shape_text(out.shape[1:])}")
    checks.check_finite(out, "Phi_uu")
    checks.check_hermitian(out, "Phi_uu")
    lam = np.linalg.eigvalsh(0.5 * (out + np.conj(np.swapaxes(out, 1, 2))))
    bad = np.flatnonzero(lam[:, 0] < -_PSD_RTOL * np.maximum(np.abs(lam).max(axis=1), np.finfo(float).tiny))
    if bad.size:
        i = int(bad[0])
        raise DataError(f"Phi_uu must be positive semidefinite (a spectral density, e.g. a white-noise intensity "
                        f"φ > 0): at ω = {w[i]:.6g} rad/s its smallest eigenvalue is {lam[i, 0]:.6g} "
                        f"({bad.size} of {w.size} frequencies negative)")
    return out


def _band(band: Any) -> tuple[float, float]:
    """(w_low, w_high) as floats, 0 ≤ w_low < w_high, or a DataError."""
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise DataError(f"band must be a pair (w_low, w_high) of numbers in rad/s; got {band!r}") from None
    if not (0 <= lo < hi):
        raise DataError(f"band must be (w_low, w_high) in rad/s with 0 <= w_low < w_high; got {band!r}")
    return lo, hi


def _positive_int(x: Any, name: str) -> int:
    """An integer ≥ 1 given as an int or an integral float; a DataError naming ``name`` otherwise."""
    if isinstance(x, bool | str) or not isinstance(x, int | float | np.integer | np.floating) \
            or not np.isfinite(x) or int(x) != x or x < 1:
        raise DataError(f"{name} must be a positive integer; got {x!r}")
    return int(x)


def _select(w: np.ndarray, band: Any, n_frequencies: int | None) -> np.ndarray:
    """Indices of the kept bins: inside ``band``, then at most ``n_frequencies`` nearly log-spaced."""
    keep = np.arange(w.size)
    if band is not None:
        lo, hi = _band(band)
        keep = keep[(w >= lo) & (w <= hi)]
        if keep.size and np.isfinite(hi) and hi > w[-1] * (1 + 1e-12):
            warnings.warn(f"band {band!r} rad/s reaches above the highest Welch bin ({w[-1]:.6g} rad/s, below "
                          "the Nyquist frequency π/dt): only the bins up to it are used", stacklevel=3)
    if keep.size == 0:
        raise DataError(f"no Welch frequency bin lies in band {band!r} rad/s (bins from {w[0]:.4g} to "
                        f"{w[-1]:.4g} rad/s, spacing {w[1] - w[0] if w.size > 1 else w[0]:.4g} rad/s)")
    if n_frequencies is not None:
        n_frequencies = _positive_int(n_frequencies, "n_frequencies")
        if n_frequencies < keep.size:
            targets = np.geomspace(w[keep[0]], w[keep[-1]], n_frequencies)
            pos = np.unique(np.abs(np.log(w[keep])[None, :] - np.log(targets)[:, None]).argmin(axis=1))
            keep = keep[pos]
    return keep


def _check_window(window: Any, nperseg: int) -> None:
    try:
        scipy.signal.get_window(window, nperseg)
    except (TypeError, ValueError) as exc:
        raise DataError(f"window {window!r} is not a window scipy.signal.get_window knows ({exc}); "
                        "use e.g. 'hann', 'hamming' or ('tukey', 0.25)") from None


def estimate_spectra(data: Any, *, dt: float | None = None, Phi_uu: Any = None, nperseg: int | None = None,
                     window: Any = "hann", detrend: str | bool = "constant", band: Any = None,
                     n_frequencies: int | None = None) -> SpectralData:
    """Output (and input) spectral density matrices from sampled records by Welch's method.

    Parameters
    ----------
    data : IOData or array_like of shape (N, p) or (N,)
        Measured input and output (:class:`~symid.IOData`), or the outputs alone
        (output-only data, e.g. ambient excitation), one row per sample.
    dt : float, optional
        Sample time in seconds; required for an output array, taken from ``IOData``.
    Phi_uu : float, array_like (m, m) or callable, optional
        The input spectrum when it is known rather than measured: a scalar φ for white
        noise of intensity φ (Φuu = φ, see the module notes: samples of variance φ/dt),
        an (m, m) matrix (e.g. ``φ * np.eye(m)`` for m independent white inputs), or a
        callable ``f(ω)`` returning a scalar or an (m, m) matrix. Required for output-only
        data; with ``IOData`` it replaces the estimate from the measured input.
    nperseg : int, optional
        Samples per Welch segment (frequency resolution 2π/(nperseg·dt) rad/s). Default:
        the largest power of two ≤ N/8, so that about 15 half-overlapping segments are
        averaged (relative standard deviation of each bin ≈ 1/√15).
    window : str or tuple
        Passed to :func:`scipy.signal.csd` (default ``"hann"``).
    detrend : {"constant", "linear", False}
        Removed from each segment (default ``"constant"``, its mean). With a detrend
        the lowest bin above DC is dropped: the detrend biases it low (white noise,
        Hann window: by about 1/6).
    band : (float, float), optional
        Keep the bins with ω in [w_low, w_high] rad/s.
    n_frequencies : int, optional
        Keep at most this many bins, nearest to log-spaced frequencies over the band.

    Returns
    -------
    SpectralData
        ω = 2πf of the Welch bins without f = 0, the Nyquist bin and (with a detrend)
        the first bin, Φyy (s, p, p) and
        Φuu (s, m, m), both Hermitian, two-sided per the module's convention.

    Raises
    ------
    DataError
        Output-only data without ``dt`` or ``Phi_uu``; a ``dt`` that contradicts the
        ``IOData``; an input spectrum of the wrong size, not finite, not Hermitian or
        not positive semidefinite; a segment longer than the record; an unknown window
        or detrend; a malformed or empty band.

    Examples
    --------
    White noise of variance σ² = 4 sampled at dt = 0.01 s has the flat spectrum σ² dt = 0.04:

    >>> import numpy as np
    >>> import symid as si
    >>> u = 2.0 * np.random.default_rng(0).standard_normal(200_000)
    >>> spec = si.estimate_spectra(si.IOData(u, u, 0.01), nperseg=256)
    >>> round(float(np.mean(spec.Phi_uu.real)), 3)
    0.04
    """
    if detrend not in _DETRENDS:  # (False == 0: a 0 is read as False)
        raise DataError(f"detrend must be 'constant', 'linear' or False; got {detrend!r}")
    if isinstance(data, IOData):
        if dt is not None and not np.isclose(checks.check_positive_scalar(dt, "dt"), data.dt, rtol=1e-12, atol=0):
            raise DataError(f"dt = {dt!r} contradicts the IOData's sample time {data.dt!r}; leave dt out")
        y, u, dt_ = np.asarray(data.y, dtype=float), np.asarray(data.u, dtype=float), float(data.dt)
    else:
        arr = checks.as_array(data, "outputs", complex_ok=False)
        if arr.ndim == 1:
            arr = arr.reshape(-1, 1)
        if arr.ndim != 2 or arr.shape[0] < arr.shape[1]:
            raise DataError(f"outputs must have shape (N, p), one row per sample; got shape "
                            f"{checks.shape_text(arr.shape)}")
        checks.check_finite(arr, "outputs")
        if dt is None:
            raise DataError("output-only data need the sample time: pass dt= (seconds)")
        if Phi_uu is None:
            raise DataError("output-only data need the input spectrum: pass Phi_uu= (e.g. the intensity φ of a "
                            "white-noise input)")
        y, u, dt_ = arr, None, checks.check_positive_scalar(dt, "dt")
    N = y.shape[0]
    if N < 8:
        raise DataError(f"the record has N = {N} samples; Welch's method needs at least 8")
    given = nperseg
    if nperseg is None:
        nperseg = 2 ** int(np.floor(np.log2(max(N / 8, 8))))
    try:
        nperseg = _positive_int(nperseg, "nperseg")
    except DataError:
        nperseg = 0  # reported below with the allowed range
    if not 8 <= nperseg <= N:
        raise DataError(f"nperseg must be an integer between 8 and the record length N = {N}; got {given!r}")
    _check_window(window, nperseg)
    f, Syy = _cross_spectra(y, 1.0 / dt_, nperseg, window, detrend)
    # without DC and Nyquist; with a detrend, also without bin 1: removing each segment's mean
    # (or line) removes about 1/6 of its power through the window's main lobe (0.83 σ²dt measured
    # for white noise with a Hann window), and shifts the phase of the cross spectra there
    first = 2 if detrend is not False else 1
    inner = slice(first, f.size - 1 if nperseg % 2 == 0 else f.size)
    w_all = 2 * np.pi * f[inner]
    keep = _select(w_all, band, n_frequencies)
    w = w_all[keep]
    Phi_yy = Syy[inner][keep]
    if Phi_uu is None:
        Phi_u = _cross_spectra(u, 1.0 / dt_, nperseg, window, detrend)[1][inner][keep]
    else:
        Phi_u = _given_input(Phi_uu, w, None if u is None else u.shape[1])
    out = SpectralData(w, Phi_yy, Phi_u)
    # a windowed estimate: its resolution smooths lightly damped modes (symid.fit.frf.leakage)
    object.__setattr__(out, "estimated_from", {"dt": float(dt_), "nperseg": int(nperseg),
                                               "window": window if isinstance(window, (str, tuple)) else "given",
                                               "resolution": 2 * np.pi / (nperseg * float(dt_)), "samples": int(N),
                                               "noverlap": int(nperseg) // 2,
                                               "input": "measured" if Phi_uu is None else "given"})
    return out
