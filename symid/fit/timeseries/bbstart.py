"""A start for output error read off a black box of the record: N4SID, its response mode by mode, a response fit.

Output error from a start a factor of a few off often ends in a local minimum (a mode of
the model beside the measured one leaves a misfit that barely changes until they meet),
while the frequency-response ``auto`` (:class:`symid.fit.frf.lm.AutoFRF`: continuation
over frequency, chain starts, restarts) reaches the structured parameters of a noise-free
frequency response from starts a decade off. This module gives the records to that
method through a black box:

1. **Black box.** N4SID of the model's order (:func:`symid.n4sid`; feedthrough only when
   the model has one at the start) on the one uniformly sampled record, with its default
   horizon and with the longer ones of ``HORIZONS``; the black box whose simulation from
   its own initial state predicts the samples best is kept. The default horizon (10 to
   20 block rows on these records) sees a fraction of the slowest mode's period on records
   sampled ten times per period of the fastest, and at 1 % noise leaves weakly observable
   modes misplaced: on the time-series population's 12 records (n = 2, 3, 5 of every
   class) its black boxes predicted the noisy samples with relative misfits up to 2.6e-3
   (3-mass chain with gains), 2.9e-3 (5-mass with gains) and 0.42 (5-mass chain), against
   the 1e-4 the noise explains; the best of the default and ``HORIZONS`` predicts every
   one of the 12 noisy records to 8.7e-5 … 1.01e-4 (the 5-mass chain's at horizon 120),
   and the noise-free ones to 2e-19 or better. A horizon is not tried where its Hankel
   matrices' LQ factor would cost more than ``HANKEL_WORK`` (records of many samples or
   channels), or where the record is too short for it. An input that leaves most of the
   band empty (a multisine up to 0.4 of the Nyquist frequency) makes N4SID's projection
   ill-conditioned, and noise then misplaces every mode. With ``decimate`` (``auto``'s
   ``black_box_decimation=True``) such a record is also tried decimated
   (:func:`input_decimation`: :func:`scipy.signal.decimate`'s zero-phase FIR filter, by
   up to ``DECIMATE_MAX``) for the modes, brought back to the record's own rate
   (:func:`_decimated_black_box`), and the black box predicting the record best is kept.
   It is not the default: the black box is far better (``tests/test_timeseries_bbstart.py``:
   a 2-mass chain's 1 %-noise record predicted to 4e-4 instead of 0.37), but on the
   time-series population driven by such a multisine (``benchmarks/timeseries_population.py
   --input multisine --methods auto,auto-decimate --sizes 2,3,5 --starts 2``,
   ``benchmarks/results/timeseries_multisine.json``, 17 min) ``auto`` met the success rule
   from 18 of 24 informed and 15 of 24 uninformed noisy starts with it, against 21 and 17 without:
   on chains its start led to near-fits the rule accepts a little above the least-squares
   misfit (a 2-mass chain's second mass at 1e-5 against 1.35, misfit 0.4 % above), every
   other class alike; noise-free starts alike (23 and 22 of 24). A new user's 4-storey
   frame (multisine to 0.4 of Nyquist, 2 % noise, 12 parameters, no start given) needs it:
   90 s and m1 4e7 times off without, a fit in 15 s within 1.7 % with. A poor black box
   (``POOR_BLACK_BOX``) on a band-limited input names the option in the start's note.
2. **Its continuous-time response, mode by mode.** With Ad = V Λ V⁻¹ (simple
   eigenvalues zᵢ), the zero-order-hold sampling of H(s) = D + Σᵢ ρᵢ / (s − sᵢ) has
   zᵢ = e^{sᵢ Δt} and Bd's modal rows (zᵢ − 1)/sᵢ times B's, so

       H(jω) = D + Σᵢ (Cd vᵢ)(wᵢᵀ Bd) · sᵢ / (zᵢ − 1) / (jω − sᵢ),   sᵢ = log(zᵢ) / Δt

   (principal logarithm; Δt in place of sᵢ/(zᵢ − 1) as sᵢ → 0). This is the exact
   continuous-time response of the sampled black box; unlike :func:`symid.d2c` it needs
   no real matrix logarithm, so a pole N4SID put on the negative real axis (a mode near
   the Nyquist frequency) costs nothing but that mode's accuracy.
3. **Structured fit.** The model is fitted to that response on 100 log-spaced lines from
   0.3 times the slowest to 3 times the fastest black-box mode by the frequency-response
   ``auto`` from the start (with the typical values ``scale``); its estimate is the start
   of an output-error pass. The response is a black box's, so it is judged like noisy
   data whose noise floor is the black box's own relative misfit on the samples (from its
   initial state): a fit within that floor is a fit. On noise-free records the floor is
   N4SID's rounding (2e-19 or better on the time-series population's 12 records), so only
   the model's own response fits; at 1 % noise it is about 1e-4 (step 1; with the default
   horizon alone it was up to 3e-3 for the chains with gains and 0.42 for the 5-mass
   chain, where N4SID misplaced weakly observable modes). A vector fit of the
   response is no yardstick here: it fits any black box's response exactly.
   Passes are counted, not timed, so the start does not depend on how busy the machine
   is (a share of the start's budget is only a safety): at most ``PASSES`` on noisy
   records, ``CLEAN_PASSES`` where the floor is below ``CLEAN_RECORD`` (the response is
   then the model's, and the passes go on until one reaches it: a noise-free 3-mass chain
   from a start a decade off came to near-fits at 2e-8 in ten passes before the eleventh
   reached the truth). Measured on the time-series population's records (n = 2, 3, 5, one
   informed and one uninformed start per problem and noise level, every pass logged, 45 s
   each, the floor not yet used): noise-free, the best misfit came at pass 0 in 25 of 30
   runs and by pass 4 in all; at 1 %, at pass 0 in 23 of 30 and by pass 3 in all but the
   four runs of the 5-mass chain and chain with gains, whose black boxes were poorest
   with the default horizon (passes 6 to 16). Before, a 15 s cap ended the fit, so a
   noisy record's start depended on the machine's load, and spent the whole 15 s there.

On noise-free records the response is the model's own, and the fit recovers θ; on noisy
ones N4SID can misplace a weakly observable mode, and the fit is only a start like any
other (the output-error pass decides, and :class:`~symid.fit.timeseries.auto.AutoOutputError`
runs a pass from the caller's start as well). Records N4SID cannot take (several records,
non-uniform sample times, an input that is not persistently exciting, too few samples, a
realisation that is not minimal) give no start, and say why.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from symid.data import FrequencyData, IOData
from symid.errors import SymidError
from symid.fit.frf.lm import AutoFRF
from symid.fit.result import StartOutcome

__all__ = ["DECIMATE_MAX", "INPUT_TAIL", "BlackBoxResponse", "BlackBoxStart", "black_box_response", "black_box_start",
           "input_decimation", "modal_response"]

LINES = 100
"""Frequency lines of the black box's response that the structured fit sees."""
PASSES = 8
"""Passes of the structured fit at most on noisy records (module notes, step 3)."""
CLEAN_PASSES = 31
"""Passes at most where the black box predicts the samples to ``CLEAN_RECORD`` (the frequency-response ``auto``'s own
count: the response is then the model's, and a pass stops the fit once it fits it to that level)."""
CLEAN_RECORD = 1e-6
"""A black box whose relative misfit on the samples is at most this has noise-free records (up to 0.1 % rms noise)."""
HORIZONS = (20, 40, 80, 120)
"""N4SID horizons tried beside the default (those above it); the black box predicting the samples best is kept."""
HANKEL_WORK = 2e9
"""A horizon i is tried only while N·(2(m + p)i)², the work of the LQ factor of its Hankel matrices, is at most this
(about a second)."""
BAND = (0.3, 3.0)
"""The lines span these multiples of the slowest and the fastest black-box mode (rad/s)."""
POOR_BLACK_BOX = 0.1
"""A black box whose misfit on the samples exceeds this (it predicts less than 90 % of the outputs' energy) is poor:
on a band-limited input the note then names ``black_box_decimation=True``."""
INPUT_TAIL = 1e-6
"""The input's band edge: the frequency below which all but this share of its power lies (module notes, step 1)."""
DECIMATE_MAX = 4
"""The largest decimation of a record whose input is band-limited (module notes, step 1)."""


@dataclass(frozen=True)
class BlackBoxStart:
    """The structured fit to a black box's response: ``theta`` (None when there is no start) and why."""

    theta: np.ndarray | None
    note: str
    misfit: float = math.nan
    """The structured fit's misfit to the black box's response (relative, squared)."""


def modal_response(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, dt: float,
                   w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Continuous-time response whose zero-order-hold sampling at ``dt`` is (A, B, C, D), mode by mode (module notes).

    Returns
    -------
    H : ndarray, shape (s, p, m)
        The response at ``w`` (rad/s).
    poles : ndarray, shape (n,)
        The continuous-time poles sᵢ = log(zᵢ)/Δt (principal logarithm).

    Raises
    ------
    numpy.linalg.LinAlgError
        When A's eigenvectors are singular (a defective A: repeated poles without a basis).

    Examples
    --------
    >>> import numpy as np, scipy.signal
    >>> from symid.fit.timeseries.bbstart import modal_response
    >>> A, B = np.array([[0.0, 1.0], [-4.0, -0.4]]), np.array([[0.0], [1.0]])
    >>> C, D = np.array([[1.0, 0.0]]), np.zeros((1, 1))
    >>> Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete((A, B, C, D), 0.1, method="zoh")
    >>> w = np.array([1.0, 2.0])
    >>> H, _ = modal_response(Ad, Bd, Cd, Dd, 0.1, w)
    >>> bool(np.allclose(H[:, 0, 0], 1 / ((1j * w) ** 2 + 0.4j * w + 4)))   # 1 / (s² + 0.4 s + 4)
    True
    """
    z, V = np.linalg.eig(np.asarray(A, dtype=float))
    W = np.linalg.inv(V)
    w = np.asarray(w, dtype=float)
    H = np.broadcast_to(np.asarray(D, dtype=complex), (w.size, *np.shape(D))).copy()
    CV, WB = np.asarray(C) @ V, W @ np.asarray(B)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(z.astype(complex)) / dt
        gain = np.where(np.abs(s) * dt > 1e-12, s / (z - 1), 1.0 / dt)
        for i in range(z.size):
            if z[i] == 0:  # s = −∞: its term s/(z − 1)/(jω − s) tends to 1/(1 − z) = 1 at every finite ω
                H += np.outer(CV[:, i], WB[i])[None]
            else:
                H += (np.outer(CV[:, i], WB[i]) * gain[i])[None] / (1j * w[:, None, None] - s[i])
    return H, s


class BlackBoxResponse(NamedTuple):
    """:func:`black_box_response`'s answer: the response (None when there is none), why not, how well the black box
    predicts the samples (its relative misfit on the record from its own initial state), N4SID's horizon and the
    decimation of the record it was estimated on (1: none)."""

    frf: FrequencyData | None
    note: str
    record_misfit: float = math.nan
    horizon: int = 0
    decimation: int = 1


def black_box_response(model: Any, data: Any, decimate: bool = False) -> BlackBoxResponse:
    """The continuous-time response of an N4SID black box of the model's order on ``LINES`` lines (module notes),
    or ``frf=None`` and why for records or models the route cannot take (never raises for those). ``decimate``: a
    record whose input is band-limited is also tried decimated (:func:`input_decimation`)."""
    from symid.fit.similarity.data import model_has_feedthrough

    if not isinstance(data, IOData):
        # one record of equally spaced times with every output measured is an IOData read as a TimeSeries (a new
        # user's heater log from from_table was told "N4SID takes one uniformly sampled record")
        dt = getattr(data, "uniform_dt", None)
        if dt is None or not np.all(np.isfinite(np.asarray(data.y))):
            several = isinstance(data, (list, tuple))
            return BlackBoxResponse(None, "no black-box start: N4SID takes one record of equally spaced samples with "
                                          "every output measured" + (f"; these are {len(data)} records" if several
                                                                     else ""))
        data = IOData(data.u, data.y, dt, time_unit=data.time_unit)
    try:
        dss, misfit, q = _best_black_box(data, model.n_states, model_has_feedthrough(model), decimate)
        _, poles = modal_response(dss.A, dss.B, dss.C, dss.D, dss.dt, np.zeros(0))
    except (SymidError, np.linalg.LinAlgError, ValueError) as exc:
        # its first clause: the advice after it is for a user of N4SID, not of this start (a new user's every
        # successful summary carried five lines on an unstable N4SID pole, "harmless when the fit succeeds")
        return BlackBoxResponse(None, f"no black-box start: {str(exc).split('; ')[0]}")
    size = np.abs(poles)
    size = size[np.isfinite(size) & (size > 0)]
    if size.size == 0:
        return BlackBoxResponse(None, "no black-box start: the black box has no mode of nonzero frequency")
    w = np.logspace(math.log10(BAND[0] * size.min()), math.log10(BAND[1] * size.max()), LINES)
    H, _ = modal_response(dss.A, dss.B, dss.C, dss.D, dss.dt, w)
    if not np.all(np.isfinite(H)) or not np.any(H != 0):
        return BlackBoxResponse(None, "no black-box start: the black box's response is zero or not finite")
    return BlackBoxResponse(FrequencyData(w, H), "", misfit, dss.horizon, q)


def _best_black_box(data: IOData, order: int, feedthrough: bool, decimate: bool = False) -> tuple[Any, float, int]:
    """N4SID at its default horizon and at the longer ``HORIZONS`` the record and ``HANKEL_WORK`` allow, on the record
    and (``decimate``), when its input is band-limited, on the record decimated (:func:`input_decimation`): the black
    box with the lowest misfit on the record's samples, that misfit and the decimation. Raises what the default
    horizon's N4SID raises on the record itself."""
    q = input_decimation(data) if decimate else 1
    try:
        best, best_misfit = _best_horizon(data, order, feedthrough)
    except (SymidError, np.linalg.LinAlgError, ValueError) as exc:
        if q == 1:
            raise
        first = exc  # the decimated record may still give one (an unstable estimate on the record)
        best, best_misfit = None, math.inf
    if q > 1:
        try:
            dss = _decimated_black_box(data, order, feedthrough, q)
            misfit = _record_misfit(dss, data)
        except (SymidError, np.linalg.LinAlgError, ValueError):
            if best is None:
                raise first from None
            return best, best_misfit, 1  # too short a record to filter, or N4SID refused it: the record's stands
        if misfit < best_misfit:
            return dss, misfit, q
    return best, best_misfit, 1


def _decimated_black_box(data: IOData, order: int, feedthrough: bool, q: int) -> Any:
    """N4SID on the record decimated by ``q`` (zero-phase FIR) for the modes, then back at the record's own sample
    time: A the principal q-th root of the coarse A (the band edge lies below 1/q of the Nyquist
    frequency, so no mode's angle wraps), the same C, and B, D, x0 fitted to the record itself by least squares.

    The coarse black box alone relates a filtered input to a filtered output; read as held between its samples
    (:func:`modal_response`), its response carries the hold's distortion at the coarse rate (a 2-mass chain's
    structured fit to it ended at misfit 5.9e-3, and output error from there in a local minimum), while the
    record's own input is held at its own rate.
    """
    from scipy.linalg import fractional_matrix_power
    from scipy.signal import decimate

    from symid.signal.subspace import fit_input_matrices

    u = decimate(np.asarray(data.u, dtype=float), q, ftype="fir", axis=0, zero_phase=True)
    y = decimate(np.asarray(data.y, dtype=float), q, ftype="fir", axis=0, zero_phase=True)
    coarse, _ = _best_horizon(IOData(u, y, data.dt * q, time_unit=data.time_unit), order, feedthrough)
    A = np.asarray(fractional_matrix_power(np.asarray(coarse.A, dtype=float), 1.0 / q))
    if not np.all(np.isfinite(A)) or np.max(np.abs(A.imag)) > 1e-9 * max(float(np.max(np.abs(A.real))), 1e-300):
        raise ValueError("the coarse black box has a pole on the negative real axis: no real root at the record's rate")
    out = fit_input_matrices(data, A.real, coarse.C, feedthrough=feedthrough)
    return dataclasses.replace(out, singular_values=coarse.singular_values, horizon=coarse.horizon)


def _best_horizon(data: IOData, order: int, feedthrough: bool) -> tuple[Any, float]:
    """N4SID at its default horizon and at the longer ``HORIZONS`` allowed: the best black box and its misfit."""
    from symid.signal.subspace import n4sid

    best = n4sid(data, order, feedthrough=feedthrough)
    best_misfit = _record_misfit(best, data)
    N, m, p = data.n_samples, np.shape(data.u)[1], np.shape(data.y)[1]
    for horizon in HORIZONS:
        if horizon <= best.horizon:
            continue
        if N * (2 * (m + p) * horizon) ** 2 > HANKEL_WORK:
            break
        try:
            dss = n4sid(data, order, feedthrough=feedthrough, horizon=horizon)
        except (SymidError, np.linalg.LinAlgError, ValueError):
            continue  # too short a record for this horizon, or an unstable estimate: the others stand
        misfit = _record_misfit(dss, data)
        if misfit < best_misfit:
            best, best_misfit = dss, misfit
    return best, best_misfit


def input_decimation(data: IOData) -> int:
    """How far to decimate a record whose input is band-limited before N4SID: 1 (not at all) unless all but
    :data:`INPUT_TAIL` of the input's power lies below half the Nyquist frequency; then the largest q ≤
    :data:`DECIMATE_MAX` that keeps that band edge within 0.9 of the new Nyquist frequency (the anti-alias filter of
    :func:`scipy.signal.decimate` cuts at 1).

    N4SID's oblique projection along the future inputs is ill-conditioned when the input leaves most of the band
    empty, and noise then misplaces every mode: a new user's 4-storey frame (a multisine over 1–20 Hz sampled at
    100 Hz, 2 % noise on two accelerometers) gave a black box predicting the samples to a relative misfit of 0.52,
    and time-series ``auto`` failed; decimated by 2 it fits (``tests/test_timeseries_bbstart.py``, which also has a
    2-mass chain's record predicted to 0.37 by the record's black box and 4e-4 by the decimated one).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.timeseries.bbstart import input_decimation
    >>> U = np.zeros(1001, complex)
    >>> U[20:401] = np.exp(2j * np.pi * np.random.default_rng(0).random(381))  # lines up to 0.4 of Nyquist
    >>> u = np.fft.irfft(U, 2000)
    >>> input_decimation(si.IOData(u, u, 0.01)), input_decimation(si.IOData(np.random.default_rng(1).standard_normal(
    ...     2000), u, 0.01))
    (2, 1)
    """
    u = np.asarray(data.u, dtype=float)
    u = u - u.mean(axis=0)
    power = np.sum(np.abs(np.fft.rfft(u, axis=0)) ** 2, axis=1)
    total = float(np.sum(power))
    if not total > 0 or power.size < 3:
        return 1
    share = np.cumsum(power) / total
    edge = max(int(np.searchsorted(share, 1.0 - INPUT_TAIL)), 1) / (power.size - 1)  # a fraction of Nyquist
    if edge >= 0.5:
        return 1
    return int(max(1, min(DECIMATE_MAX, math.floor(0.9 / edge))))


def _record_misfit(dss: Any, data: IOData) -> float:
    """The black box's relative misfit on the samples from its initial state (at most 1): Σ (ŷ − y)² / Σ y² over every
    output, as the response fit's misfit sums over every entry of the response."""
    u, y = np.asarray(data.u, dtype=float), np.asarray(data.y, dtype=float)
    x = np.asarray(dss.x0, dtype=float).reshape(-1) if np.size(dss.x0) else np.zeros(dss.A.shape[0])
    with np.errstate(all="ignore"):
        yb = _black_box_output(np.asarray(dss.A, dtype=float), np.asarray(dss.B, dtype=float),
                               np.asarray(dss.C, dtype=float), np.asarray(dss.D, dtype=float), u, x)
        power = float(np.sum(y**2))
        misfit = float(np.sum((yb - y) ** 2)) / power if power > 0 else math.inf
    return min(misfit, 1.0) if math.isfinite(misfit) else 1.0


MODAL_CONDITION = 1e6
"""Largest condition number of Ad's eigenvectors at which :func:`_black_box_output` runs mode by mode."""


def _black_box_output(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, u: np.ndarray,
                      x0: np.ndarray) -> np.ndarray:
    """y[k] = C x[k] + D u[k], x[k+1] = A x[k] + B u[k], x[0] = x0: mode by mode, each a first-order recursion run by
    :func:`scipy.signal.lfilter` (the loop over samples costs 1.25 s per 100 000; this, milliseconds), or sample by
    sample where the eigenvectors are ill-conditioned (beyond ``MODAL_CONDITION``) or not a basis."""
    from scipy.signal import lfilter

    lam, V = np.linalg.eig(A)
    if A.size and np.all(np.isfinite(lam)) and np.linalg.cond(V) <= MODAL_CONDITION:
        Vi = np.linalg.inv(V)
        drive = u @ (Vi @ B).T  # (N, n): each mode's input
        q0 = Vi @ x0
        q = np.empty(drive.shape, dtype=complex)
        for i, z in enumerate(lam):  # q[k+1] = z q[k] + drive[k]; the filter's state zi is q[0] (direct form II)
            q[:, i] = lfilter([0.0, 1.0], [1.0, -z], drive[:, i], zi=[q0[i]])[0]
        return (q @ (C @ V).T).real + u @ D.T
    x = x0.astype(float)
    out = np.empty((u.shape[0], C.shape[0]))
    for k in range(u.shape[0]):
        out[k] = C @ x + D @ u[k]
        x = A @ x + B @ u[k]
    return out


def black_box_start(model: Any, data: Any, x0: np.ndarray, *, scale: np.ndarray | None,
                    time_limit: float | None, passes: int | None = None,
                    response: BlackBoxResponse | None = None, decimate: bool = False) -> BlackBoxStart:
    """The frequency-response ``auto`` fit of the model to the N4SID black box's response (module notes).

    A pass fits when its misfit is within what the black box's own misfit on the samples
    explains; ``passes`` caps the passes (default ``PASSES`` on noisy records, ``CLEAN_PASSES``
    where the black box predicts the samples to ``CLEAN_RECORD``), ``time_limit`` is a
    safety. Never raises for records or models the route cannot take: the start is
    then None and ``note`` says why. ``response`` is :func:`black_box_response`'s answer
    when the caller has it already (it does not depend on the start; computed here otherwise).
    """
    response = black_box_response(model, data, decimate) if response is None else response
    frf, why, floor, horizon = response.frf, response.note, response.record_misfit, response.horizon
    if frf is None:
        return BlackBoxStart(None, why)
    if passes is None:
        passes = CLEAN_PASSES if floor <= CLEAN_RECORD else PASSES
    x0 = np.asarray(x0, dtype=float).reshape(-1)
    try:
        fit = _ResponseFit(model, frf, scale=scale, time_limit=time_limit, restarts=passes - 1)
        fit.noise_floor = max(floor, 0.0) if math.isfinite(floor) else None
        # on noisy records the response only has to be fitted to what the samples resolve: a fit exact at the 1e-10
        # level needs no passes looking for one to rounding (measured: 6 passes, 9.3 s of a 28 s start, on 4000
        # samples of a new user's flexible-shaft motor)
        fit._loose_fits_matter = floor <= CLEAN_RECORD
        fit.check_start(x0)
        out = fit.run(x0)
    except SymidError as exc:
        return BlackBoxStart(None, f"no black-box start: {exc}")
    if not np.all(np.isfinite(out.theta)):
        return BlackBoxStart(None, "no black-box start: the response fit did not end at finite values")
    if not out.cost < 1:  # a relative misfit of 1 is that of predicting zero: such a fit says nothing
        return BlackBoxStart(None, f"no black-box start: the model fitted the black box's response no better than "
                                   f"zero (misfit {out.cost:.2e})", float(out.cost))
    coarse = f", the record decimated by {response.decimation}" if response.decimation > 1 else ""
    hint = ""
    if not decimate and floor > POOR_BLACK_BOX and hasattr(data, "u") and input_decimation(data) > 1:
        hint = ("; the input leaves most of the band empty, where N4SID's projection is ill-conditioned: "
                "black_box_decimation=True estimates the black box on the record decimated")
    return BlackBoxStart(out.theta, f"the N4SID black box's response (horizon {horizon}{coarse}, misfit {floor:.1e} "
                                    f"on the samples) fitted to misfit {out.cost:.2e} "
                                    f"({out.wall_time:.1f} s, {1 + len(out.passes)} pass(es)){hint}",
                         float(out.cost))


class _ResponseFit(AutoFRF):
    """``auto`` on a black box's response (module notes, step 3): judged against the black box's own misfit on the
    samples (``noise_floor``), never against a vector fit of the response (which is a black box's, so one fits it
    exactly), and restarted to the count of passes (a minimum found again is no reason to stop there)."""

    def black_box(self) -> None:
        return None

    def _cleaner_than(self, best: StartOutcome) -> bool:
        return True
