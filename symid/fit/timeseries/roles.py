"""Are a record's input and output columns the wrong way round? What a failed time-series fit's NEXT line names.

A test signal (a PRBS, steps, a valve switched between positions) takes a few levels; a
measured response takes as many values as it has samples (noise alone makes them
differ). A record whose outputs hold a test signal's few levels while its inputs vary
like measurements was most likely read with the roles swapped (a new user's two-tank
record, `--columns input=h2_m,T1_K output=valve_pct,heater_kW`: 120 s of restarts, misfit
0.989, and advice about starts and noise). The check only looks at the columns, so it
runs only on a fit that failed, and it is a question in the NEXT line, never a refusal:
an output of a few levels can be real (a quantised sensor on a short record), which is
why it asks for at most ``MAX_LEVELS`` levels over at least ``MIN_SAMPLES`` samples and
inputs that vary in most samples.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["MAX_LEVELS", "MEASURED_SHARE", "MIN_SAMPLES", "swapped_roles"]

MAX_LEVELS = 8
"""At most this many distinct values make an output look like a test signal."""
MIN_SAMPLES = 50
"""Over at least this many samples (fewer say little about levels)."""
MEASURED_SHARE = 0.25
"""An input looks measured when at least this share of its samples are distinct values."""


def _levels(column: np.ndarray) -> int:
    values = column[np.isfinite(column)]
    return int(np.unique(values).size)


def swapped_roles(data: Any) -> str | None:
    """A sentence for the NEXT line when the outputs look like test signals and the inputs like measurements
    (module notes), else None.

    Parameters
    ----------
    data : IOData, TimeSeries or a list of them

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> rng = np.random.default_rng(0)
    >>> prbs = np.repeat(rng.integers(0, 2, 20), 10).astype(float)        # two levels, held
    >>> level = np.cumsum(prbs) * 0.01 + 0.01 * rng.standard_normal(200)  # a measured response
    >>> swapped_roles(si.IOData(level, prbs, 1.0))[:46]
    'output 0 takes only 2 values over 200 samples '
    >>> swapped_roles(si.IOData(prbs, level, 1.0)) is None
    True
    """
    records = data if isinstance(data, (list, tuple)) else [data]
    if not records or not all(hasattr(r, "u") and hasattr(r, "y") for r in records):
        return None
    u = np.vstack([np.asarray(r.u, dtype=float) for r in records])
    y = np.vstack([np.asarray(r.y, dtype=float) for r in records])
    if y.shape[0] < MIN_SAMPLES:
        return None
    stated = getattr(records[0], "stated_units", None) or {}

    def name(role: str, i: int) -> str:
        columns = stated.get(role, ())
        return f"{role} {columns[i][0]!r}" if i < len(columns) and columns[i][0] else f"{role} {i}"

    levelled = [(j, _levels(y[:, j])) for j in range(y.shape[1])]
    levelled = [(j, n) for j, n in levelled if 2 <= n <= MAX_LEVELS]
    measured = [i for i in range(u.shape[1])
                if _levels(u[:, i]) >= MEASURED_SHARE * np.count_nonzero(np.isfinite(u[:, i]))]
    if not levelled or not measured:
        return None
    j, n = levelled[0]
    i = measured[0]
    return (f"{name('output', j)} takes only {n} values over {y.shape[0]} samples (a test signal's levels) while "
            f"{name('input', i)} varies in most samples, as a measured response does: are the input and output "
            f"columns swapped? (columns={{\"input\": ..., \"output\": ...}}; --columns input=... output=...)")
