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

from symid.data import IOData
from symid.data.timeseries import TimeSeries
from symid.errors import DataError, ModelError

__all__ = ["as_records", "is_time_series"]


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
