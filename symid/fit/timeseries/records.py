"""Time-series data as the time-domain estimators take it: one or several records, checked against the model.

A record is a :class:`~symid.data.IOData` (uniform samples) or a
:class:`~symid.data.timeseries.TimeSeries` (any increasing sample times); several
experiments are a list or tuple of them, fitted with one θ (and, for a model with
``x0="estimate"``, one initial state each).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from symid.data import IOData, checks
from symid.data.timeseries import TimeSeries
from symid.errors import DataError, ModelError

__all__ = ["GAP_STEPS", "as_records", "band_limited", "is_time_series", "sampling_gap"]

GAP_STEPS = 10.0
"""A record sampled on an even grid (90 % of its steps the typical one) with a jump of more than this many steps is
said to have a gap: the input is taken as held (or linear) across it."""


def is_time_series(data: Any) -> bool:
    """Whether ``data`` is a record or a non-empty list/tuple of records (IOData or TimeSeries)."""
    if isinstance(data, (IOData, TimeSeries)):
        return True
    return (isinstance(data, (list, tuple)) and len(data) > 0
            and all(isinstance(d, (IOData, TimeSeries)) for d in data))


def as_records(model: Any, data: Any, *, estimate_x0: bool | None = None) -> tuple[TimeSeries, ...]:
    """The records as :class:`TimeSeries`, checked against the model's sizes.

    Raises
    ------
    DataError
        On data that are not time series, channel counts that do not match the model,
        an output channel that is zero in every record, or (``x0="estimate"``) a record
        too short to determine its initial state (``estimate_x0``, default: the model's ``x0``).
    ModelError
        For a model that is not a :class:`~symid.StateSpaceModel` or :class:`~symid.SecondOrderModel`.
    """
    from symid.model.secondorder import SecondOrderModel
    from symid.model.statespace import StateSpaceModel

    if not isinstance(model, (StateSpaceModel, SecondOrderModel)):
        raise ModelError(f"time-domain fitting needs a StateSpaceModel or SecondOrderModel; got "
                         f"{type(model).__name__}")
    if estimate_x0 is None:
        estimate_x0 = getattr(model, "initial_state_kind", "zero") == "estimate"
    if not is_time_series(data):
        raise DataError("time-domain fitting takes IOData, TimeSeries or a non-empty list of them (one per "
                        f"experiment); got {type(data).__name__}")
    items: Sequence[Any] = data if isinstance(data, (list, tuple)) else [data]
    out = []
    for e, rec in enumerate(items):
        ts = TimeSeries.from_iodata(rec) if isinstance(rec, IOData) else rec
        where = f"record {e}" if len(items) > 1 else "the record"
        if ts.n_inputs != model.n_inputs or ts.n_outputs != model.n_outputs:
            raise DataError(f"{where} has {ts.n_inputs} input(s) and {ts.n_outputs} output(s); the model has "
                            f"{model.n_inputs} input(s) and {model.n_outputs} output(s) "
                            "(a free response still needs u, all zero)")
        if estimate_x0 and ts.n_samples * ts.n_outputs - ts.n_missing <= model.n_states:
            raise DataError(f"{where} holds {ts.n_samples * ts.n_outputs - ts.n_missing} measured output value(s), "
                            f"too few to "
                            f"estimate its initial state of {model.n_states} values on top of θ: record longer, "
                            "or give x0 (known numbers or an expression in θ)")
        out.append(ts)
    units = sorted({getattr(ts, "time_unit", "s") for ts in out})
    if len(units) > 1:
        raise DataError(f"the records' times are in different units ({', '.join(units)}): one θ has one time unit; "
                        "rewrite the records in one unit")
    energy = sum(np.nansum(ts.y**2, axis=0) for ts in out)  # NaN: an output not measured at that time
    zero = np.flatnonzero(energy == 0)
    if zero.size:
        raise DataError(f"output {zero[0]} is zero in every record: there is nothing to fit it to")
    return tuple(out)


BAND_LIMITED_UPSAMPLE = 4
"""Points per sample interval at which ``hold="bandlimited"`` represents a sampled input (:func:`band_limited`)."""

BAND_LIMITED_EMPHASIS = 1.0 / 12.0
"""The 3-tap emphasis a of the points (:func:`band_limited`): 1/12 cancels linear interpolation's (ωh)²/12. A new
user's 2-DOF base-excited structure, sines up to half the Nyquist frequency, 1 % noise, 6 records: without it
(4 points per interval) the estimates were 1.5–4.4 standard errors off (rms; up to 7.5) and the truth's residual
coloured (median whiteness p 2e-4); with it 0.7–1.2 (up to 1.8), p 0.44, as with 16 points per interval and no
emphasis at four times the work; sines up to 0.8 of the Nyquist frequency: 0.9–1.1, as with 16 points."""


def band_limited(record: TimeSeries, where: str, factor: int | None = None, emphasis: float | None = None,
                 holds: tuple[str, ...] | None = None) -> TimeSeries:
    """The record with its input interpolated as a band-limited signal at ``factor`` points per sample interval.

    A measured input (a shaker's force, a road profile, anti-alias filtered) is band-limited: between its samples
    it is its band-limited (sinc) interpolation, not a held or a straight line. Linear interpolation between the
    samples attenuates it by about (ω dt)²/12 at frequency ω (a gain 2 % low at a fifth of the sampling rate).
    Here the band-limited interpolation is computed at ``factor`` points per interval
    (:func:`scipy.signal.resample_poly`, a Kaiser-windowed sinc, which passes through the samples), and the points
    are given the 3-tap emphasis (1 + 2a) u_k − a (u_{k−1} + u_{k+1}), a = ``emphasis`` (default
    :data:`BAND_LIMITED_EMPHASIS`), so that the simulation's linear interpolation between them, which attenuates by
    1 − (ωh)²/12 for h = dt/factor, is compensated to O((ωh)⁴). The output is measured at the
    record's own samples only: the points between them carry no output (NaN), so the misfit, the residual tests
    and the intervals count the same samples as before. Equally spaced samples only (a ``DataError`` naming the
    record otherwise); the first and last few samples' interpolation extends the input linearly (``padtype``).
    With ``holds`` (one of ``"zoh"``, ``"foh"``, ``"bandlimited"`` per input), only the band-limited inputs are
    interpolated so; at the points between samples a held input keeps its sample's value (the simulation then
    holds it: :func:`symid.fit.timeseries.response.held_differences`) and a linear one lies on the line.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data.timeseries import TimeSeries
    >>> from symid.fit.timeseries.records import band_limited
    >>> t = np.arange(64) * 0.1
    >>> rec = TimeSeries(t, np.sin(2.0 * t)[:, None], np.cos(t)[:, None])
    >>> fine = band_limited(rec, "the record", 4, emphasis=0.0)   # the interpolation alone
    >>> fine.n_samples, bool(np.allclose(fine.u[::4, 0], rec.u[:, 0], atol=1e-9)), int(np.isnan(fine.y).sum())
    (253, True, 189)
    """
    from scipy.signal import resample_poly

    factor = BAND_LIMITED_UPSAMPLE if factor is None else factor
    emphasis = BAND_LIMITED_EMPHASIS if emphasis is None else emphasis
    t = np.asarray(record.t, dtype=float)
    if t.size < 2:
        raise DataError(f"hold='bandlimited' needs at least 2 samples; {where} has {t.size}")
    step = np.diff(t)
    if not np.allclose(step, step[0], rtol=1e-6, atol=0.0):
        raise DataError(f"hold='bandlimited' interpolates equally spaced samples; the sample times of {where} are "
                        f"not (steps from {step.min():.6g} to {step.max():.6g}): use hold='foh' (linear between "
                        "samples) for uneven times")
    n = (t.size - 1) * factor + 1
    u = resample_poly(np.asarray(record.u, dtype=float), factor, 1, axis=0, padtype="line")[:n]
    u[::factor] = record.u  # the interpolation passes through the samples; exactly, not to the filter's rounding
    if emphasis:
        # linear interpolation between the points attenuates by sinc²(ωh/2) ≈ 1 − (ωh)²/12; the 3-tap emphasis
        # (1 + 2a) − 2a cos(ωh) with a = 1/12 cancels that term, leaving O((ωh)⁴)
        inner = u[1:-1] + emphasis * (2.0 * u[1:-1] - u[:-2] - u[2:])
        u = np.concatenate([u[:1], inner, u[-1:]])
    fine = t[0] + np.arange(n) * (step[0] / factor)
    for j, kind in enumerate(holds or ()):
        if kind == "zoh":  # each sample's value up to the next sample
            u[:, j] = np.concatenate([np.repeat(record.u[:-1, j], factor), record.u[-1:, j]])
        elif kind == "foh":
            u[:, j] = np.interp(fine, t, record.u[:, j])
    y = np.full((n, record.n_outputs), np.nan)
    y[::factor] = record.y
    return TimeSeries(fine, u, y, time_unit=record.time_unit)


def sampling_gap(records: Any) -> str | None:
    """A sentence naming the first record sampled on an even grid with a gap of more than :data:`GAP_STEPS` steps,
    else None. :class:`~symid.data.IOData` refuses such a record when it is read from a table (samples missing); a
    :class:`~symid.data.TimeSeries` takes it as it is, the input held or linear from the sample before the gap to the
    one after (a new user's room with 6 hours of a 5-minute log missing: the fit failed, told of a drift).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data.timeseries import TimeSeries
    >>> from symid.fit.timeseries.records import sampling_gap
    >>> t = np.concatenate([np.arange(100.0), 172.0 + np.arange(100.0)])
    >>> sampling_gap([TimeSeries(t, np.ones(200), np.ones(200))])[:72]
    'the record is sampled every 1 s but has a gap of 73 s (from 99 to 172 s,'
    """
    recs = list(records) if isinstance(records, (list, tuple)) else [records]
    for e, r in enumerate(recs):
        t = np.asarray(getattr(r, "t", ()), dtype=float)
        jump = checks.grid_jump(t)
        if jump is None:
            continue
        k, typical, _ = jump
        d = np.diff(t)
        if d[k] > GAP_STEPS * typical:
            unit = getattr(r, "time_unit", "s")
            which = f"record {e}" if len(recs) > 1 else "the record"
            return (f"{which} is sampled every {typical:.6g} {unit} but has a gap of {d[k]:.6g} {unit} (from "
                    f"{t[k]:.6g} to {t[k + 1]:.6g} {unit}, {d[k] / typical:.3g} steps): the input is taken as held "
                    f"(or linear) across it, and an input that changed inside it is wrong there. Split the record at "
                    f"the gap (a list of records, each with its own initial state) unless the input was truly "
                    f"constant there")
    return None
