"""Does a windowed estimate of the response smooth the fitted resonances? A note after a fit of a Welch estimate.

:func:`symid.estimate_frf` without ``period=`` averages windowed segments of ``nperseg``
samples (Welch), whose lines lie Δω = 2π/(nperseg·dt) apart. For a random input with a
flat spectrum the H1 estimate is then, beside its noise, the response smoothed by the
window's spectral kernel |W(δ)|² (a Hann window: about ±2 lines), a bias its variance
does not hold. Across a lightly damped mode's half-power bandwidth 2ζωₙ there may be only
a few lines, and the fit takes the smoothed resonance for a more damped one: a new
user's 3-storey frame on a shake table (200 Hz, 60 s, the default segments of 1024
samples, 0.3–3.6 lines across the modes' bandwidths) got c3 11.6 % high, 5.2 standard
errors, with ``success``; with ``nperseg=4096`` every interval held the truth.

How much it matters depends on the noise: with equal weights and no noise a lone
oscillator's damper comes out 52 % high at one line across the bandwidth, 5–6 % at four,
1.3–1.6 % at eight; weighted by the estimate's own variance, which the leakage inflates
at the peak (the coherence drops there), 1.6–3 % at one line
(``OMP_NUM_THREADS=1 .venv/bin/python benchmarks/frf_leakage.py``). So the test is the
bias itself, in the estimate's own standard errors: the fitted response is smoothed by
the window's kernel (:func:`smoothed_response`, which reproduces a Welch estimate's peak
to within a few % of its height: 0.42 against 0.43, 0.65 against 0.68, 0.85 against 0.87
of the true peak at 0.26, 1 and 2 lines across the bandwidth), and one Gauss–Newton step
in the fit's own weighting says how far that change of the data moves each parameter
(:meth:`~symid.fit.frf.fisher.FrfFisher.data_shift`). Beyond :data:`LEAKAGE_SHIFT`
standard errors the note names those parameters, the mode with the fewest lines across
its bandwidth and a segment length that shrinks the bias. On the shake-table frame: with
the default 1024 samples, c3, k3 and k1 are named, 4.1, 3.5 and 3 standard errors (c3 was
5.2 and k1 2.1 off the truth, their intervals missing it); with 4096, where every
interval held it, nothing is said. On the oscillator with 2 % output noise and records of
12 000 samples (the benchmark's part (c), 8 records per row): where the damper's interval
held the truth in 0–3 of 8 records the note was given in 8 of 8, where it held in 7–8 of
8 the note was given in 0, 5 and 8 of 8 (a median bias of 0.86 and 1.63 standard errors
for the last two), and every fit from one line across the bandwidth on was a ``success``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.signal

from symid.fit.modes import estimate_poles

__all__ = ["KERNEL_LINES", "LEAKAGE_SHIFT", "leakage_note", "smoothed_response", "smoothed_spectra"]

LEAKAGE_SHIFT = 1.0
"""The window's smoothing of the fitted response is named when it moves some parameter, to first order, by more than
this many of its standard errors (a 95 % interval shifted by one holds the truth 83 % of the time)."""

KERNEL_LINES = 4
"""The smoothing kernel is sampled over ±this many lines (a Hann window's holds 99.99 % of its weight within ±3)."""

_STEPS = 4  # kernel samples per line


def _kernel(window: Any, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """(offsets in lines, weights summing to 1): the window's power spectrum |W(δ)|² sampled at δ."""
    win = np.asarray(scipy.signal.get_window(window, nperseg), dtype=float)
    offsets = np.linspace(-KERNEL_LINES, KERNEL_LINES, 2 * KERNEL_LINES * _STEPS + 1)
    phase = np.exp(-2j * np.pi * np.outer(offsets, np.arange(nperseg)) / nperseg)
    weights = np.abs(phase @ win) ** 2
    return offsets, weights / weights.sum()


def _across_kernel(model: Any, theta: Any, w: Any, nperseg: int, dt: float, window: Any
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(the kernel's weights (k,), the response at each line's k offsets (s, k, p, m)): what both smoothings share."""
    w = np.asarray(w, dtype=float)
    offsets, weights = _kernel(window, int(nperseg))
    at = w[:, None] + offsets[None, :] * (2 * np.pi / (int(nperseg) * float(dt)))
    H = np.asarray(model.frequency_response(theta, np.abs(at).ravel()))
    H = H.reshape(*at.shape, *H.shape[1:])
    return weights, np.where((at < 0)[:, :, None, None], np.conj(H), H)  # H(−ω) = conj H(ω) for a real system


def smoothed_response(model: Any, theta: Any, w: Any, nperseg: int, dt: float, window: Any = "hann") -> np.ndarray:
    """The model's response at ``w`` as a Welch H1 estimate with a flat input spectrum sees it: smoothed by the
    window's power spectrum over ±:data:`KERNEL_LINES` lines of 2π/(nperseg·dt) (module notes).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.leakage import smoothed_response
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> theta, w = [1.0, 0.2, 100.0], np.array([5.0, 10.0])                 # 10 rad/s, ζ 1 %
    >>> exact = model.frequency_response(theta, w)[:, 0, 0]
    >>> smooth = smoothed_response(model, theta, w, nperseg=256, dt=0.05)[:, 0, 0]   # lines 0.49 rad/s apart
    >>> np.round(np.abs(smooth / exact), 3).tolist()                              # the peak flattened
    [1.003, 0.339]
    """
    weights, H = _across_kernel(model, theta, w, nperseg, dt, window)
    return np.einsum("j,sjpm->spm", weights, H)


def smoothed_spectra(model: Any, theta: Any, w: Any, Phi_uu: Any, nperseg: int, dt: float,
                     window: Any = "hann") -> np.ndarray:
    """The model's output spectra H Φuu Hᴴ at ``w`` as a Welch estimate sees them: each line's Φuu (taken flat
    across the kernel) through the response at the kernel's offsets, weighted by the window's power spectrum."""
    weights, H = _across_kernel(model, theta, w, nperseg, dt, window)
    P = np.asarray(Phi_uu, dtype=complex)
    Phi = np.einsum("sjpm,smn,sjqn->sjpq", H, P, np.conj(H))
    return np.einsum("j,sjpq->spq", weights, Phi)


def _fewest_lines(model: Any, theta: Any, w: np.ndarray, step: float) -> tuple[float, float, float] | None:
    """(lines across the half-power bandwidth, ωₙ, ζ) of the underdamped mode inside the band with the fewest."""
    poles = estimate_poles(model, theta)
    if poles is None:
        return None
    best = None
    for p in poles:
        wn = abs(p)
        if p.imag <= 0 or -p.real >= p.imag or not w.min() <= wn <= w.max():
            continue
        lines = 2.0 * -p.real / step
        if best is None or lines < best[0]:
            best = (lines, wn, -p.real / wn)
    return best


def leakage_note(estimator: Any, data: Any, theta: Any, standard_errors: Any) -> dict[str, Any] | None:
    """``{"text", "shifts", "lines", "frequency", "zeta", "nperseg", "suggested"}`` when the window's smoothing of
    the fitted response moves some parameter by more than :data:`LEAKAGE_SHIFT` of its standard errors (module
    notes); else None (also for a response not estimated by Welch segments).

    Parameters
    ----------
    estimator : FrfEstimator
        The fit's estimator (its model, data, weights and Jacobian).
    data : FrequencyData
        The user's, with the ``estimated_from`` metadata of :func:`symid.estimate_frf`.
    theta : array_like
        The estimate.
    standard_errors : array_like
        Its standard errors.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> truth = [1.0, 1.2566, 3947.8]                                        # 10 Hz, ζ 1 %
    >>> u = np.random.default_rng(0).standard_normal(8192)
    >>> io = si.simulate_io(model, truth, u, 0.005, noise=0.02, seed=1)      # 200 Hz, 41 s
    >>> frf = si.estimate_frf(io, nperseg=512, hold="zoh")                  # lines 0.39 Hz apart
    >>> res = si.identify(model, frf, x0=truth, identifiability_check=False)   # calls leakage_note
    >>> note = res.options["leakage"]
    >>> round(note["lines"], 1), note["suggested"], sorted(note["shifts"], key=note["shifts"].get)[-1]
    (0.6, 2048, 'c')
    """
    made = getattr(data, "estimated_from", None) or {}
    nperseg, dt, window = made.get("nperseg"), made.get("dt"), made.get("window")
    if not nperseg or not dt or window in (None, "given") or not hasattr(estimator, "data_shift"):
        return None
    model, w = estimator.model, np.asarray(estimator.data.w, dtype=float)
    se = np.asarray(standard_errors, dtype=float)
    try:
        if hasattr(estimator.data, "Phi_yy"):  # output spectra: H Φuu Hᴴ smoothed alike
            P = np.asarray(estimator.data.Phi_uu)
            H = np.asarray(model.frequency_response(theta, w))
            dX = smoothed_spectra(model, theta, w, P, nperseg, dt, window) - H @ P @ np.conj(np.swapaxes(H, 1, 2))
        else:
            dX = smoothed_response(model, theta, w, nperseg, dt, window) - np.asarray(model.frequency_response(theta,
                                                                                                             w))
        shift = np.abs(estimator.data_shift(theta, dX)) / se
    except Exception:  # an estimate where the model cannot be evaluated: nothing to say
        return None
    shift = np.where(np.isfinite(shift), shift, 0.0)
    if not shift.max() > LEAKAGE_SHIFT:
        return None
    step = 2 * np.pi / (int(nperseg) * float(dt))
    mode = _fewest_lines(model, theta, w, step)
    # in its standard errors the bias falls about 1.5-1.6 times per doubling of the segments (the bias as the square
    # of their length, while the noise of fewer averages grows): measured on the oscillator of the example
    factor = 2 ** max(1, math.ceil(math.log2(float(shift.max()) / LEAKAGE_SHIFT) / 0.65))
    suggested = int(nperseg) * factor
    names = list(model.parameter_names)
    worst = [names[i] for i in np.argsort(-shift)[:3] if shift[i] > LEAKAGE_SHIFT]
    moved = ", ".join(f"{n} {shift[names.index(n)]:.2g}" for n in worst)
    where = ""
    if mode is not None:
        lines, wn, zeta = mode
        where = (f"; the mode at {wn / (2 * np.pi):.4g} Hz (ζ {zeta:.3g}) has {lines:.2g} line(s) across its "
                 f"half-power bandwidth")
    record = made.get("samples")
    longer = f"; the records have {record} samples, so a longer record" if record and suggested > record // 2 else ""
    spectra = hasattr(estimator.data, "Phi_yy")
    what = "spectra were estimated" if spectra else "response was estimated"
    how = "si.estimate_spectra" if spectra else "si.estimate_frf"
    periodic = "" if spectra else (" or with periodic excitation (estimate_frf(period=...)), whose lines have no "
                                   "window")
    text = (f"the {what} by Welch segments of {nperseg} samples ({how}; lines "
            f"{step / (2 * np.pi):.3g} Hz apart){where}: the window smooths the resonances, and the fit takes that "
            f"for the model's (more damping), a bias of about {moved} standard errors that the intervals do not "
            f"include. Estimate them with longer segments (nperseg={suggested}{longer}){periodic}")
    return {"text": text, "shifts": dict(zip(names, shift.tolist(), strict=True)),
            "lines": None if mode is None else float(mode[0]), "frequency": None if mode is None else float(mode[1]),
            "zeta": None if mode is None else float(mode[2]), "nperseg": int(nperseg), "suggested": suggested}
