"""Typical parameter values from time series: the frequency response of the records, then dimensional analysis.

A user who fits samples without a start still has the records: their frequency response
says at which frequencies the system answers and how strongly, and that is all the
dimensional analysis of :func:`symid.fit.frf.scale.typical_scale` needs (the band centre
and the response level). So the records are turned into a frequency response
(:func:`symid.estimate_frf`, Welch's H1 with its default segments, the lines where the
input is excited, below half the Nyquist frequency where the zero-order hold and
aliasing bend it little) and the typical values are read off it as for measured
frequency responses. The estimate is coarse (its resolution smooths lightly damped modes, and the
zero-order hold bends it near the Nyquist frequency), which does not matter here: the
result is an order of magnitude to draw starts around, never a start itself (fitting
that estimate as a start for output error was measured and not kept, see
:mod:`symid.fit.timeseries.auto`).

There are none (``None``; the starts are then N(0, 1) draws, as before) for records with
non-uniform sample times, records whose input is zero (free responses: nothing to divide
by), or records too short or unexcited for a frequency response.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symid.data import FrequencyData, IOData
from symid.data.timeseries import TimeSeries
from symid.errors import DataError, ModelError

__all__ = ["typical_scale"]

_HOLD_BAND = 0.5  # lines up to this fraction of the Nyquist frequency π/dt take part in the dimensional analysis


def _uniform(record: Any) -> IOData | None:
    """The record as an IOData, or None when its samples are not uniform or its input is zero."""
    if isinstance(record, TimeSeries):
        dt = record.uniform_dt
        if dt is None or record.n_missing:
            return None
        record = IOData(u=record.u, y=record.y, dt=dt, time_unit=record.time_unit)
    if not isinstance(record, IOData) or not np.any(record.u):
        return None
    return record


def typical_scale(model: Any, data: Any) -> np.ndarray | None:
    """Typical magnitude of every parameter from time series (module docstring), or ``None``.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : IOData, TimeSeries, or a list of them
        With several records, those of the most common sample time with an excited
        input are averaged into one frequency response.

    Returns
    -------
    numpy.ndarray or None
        One positive value per parameter, in ``parameter_names`` order.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.timeseries.scale import typical_scale
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> u = np.random.default_rng(0).standard_normal(4000)
    >>> io = si.simulate_io(model, [20.0, 40.0, 5e5], u, dt=2e-3)      # 158 rad/s
    >>> scale = typical_scale(model, io)
    >>> bool(np.all(np.abs(np.log10(scale / [20.0, 40.0, 5e5])) < 1))  # each within a factor 10
    True
    """
    from symid.fit.frf.scale import typical_scale as frf_typical_scale
    from symid.signal.frf import estimate_frf

    records = list(data) if isinstance(data, (list, tuple)) else [data]
    usable = [r for r in (_uniform(r) for r in records) if r is not None]
    if not usable:
        return None
    dts = [r.dt for r in usable]
    common = max(set(dts), key=dts.count)
    same = [r for r in usable if r.dt == common and r.u.shape[1] == usable[0].u.shape[1]
            and r.y.shape[1] == usable[0].y.shape[1]]
    try:
        frf = estimate_frf(same if len(same) > 1 else same[0])
    except DataError:
        return None
    if frf.w.size < 3 or not np.any(np.abs(frf.H) > 0):
        return None
    # near the Nyquist frequency π/dt the samples' response is not the model's: the zero-order hold scales it by
    # sinc(ω dt / 2) (0.64 at π/dt) and aliasing folds the rest back; below π/(2 dt) the hold's factor is above
    # 0.9. Measured on the 2-mass chain of benchmarks/timeseries_population.py (acceleration output, 8 times low
    # at π/dt): its springs came out 1.7 and 1.2 decades off with every line, 1.0 and 0.5 with these
    w = np.asarray(frf.w, dtype=float)
    keep = w <= _HOLD_BAND * np.pi / common
    if np.count_nonzero(keep) < 3:
        return None
    frf = FrequencyData(w=w[keep], H=np.asarray(frf.H)[keep])
    try:
        scale = frf_typical_scale(model, frf)
    except (ModelError, ValueError, np.linalg.LinAlgError):
        return None
    scale = np.asarray(scale, dtype=float)
    if scale.size != model.n_parameters or not np.all(np.isfinite(scale)) or np.any(scale <= 0):
        return None
    return scale
