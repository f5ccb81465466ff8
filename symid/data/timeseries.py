"""Input/output samples at arbitrary (non-uniform) sample times."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np

from symid.data import _files, checks
from symid.data._base import DataContainer, naming_file
from symid.data.units import canonical_unit
from symid.errors import DataError

__all__ = ["TimeSeries"]


def _times(t: Any) -> np.ndarray:
    arr = checks.as_array(t, "t", complex_ok=False)
    if arr.ndim != 1:
        raise DataError(f"t must be a 1-D array of sample times; got shape {checks.shape_text(arr.shape)}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise DataError(f"t[{bad[0]}] is {arr[bad[0]]}; sample times must be finite (drop that sample)")
    step = np.diff(arr)
    dup = np.flatnonzero(step == 0)
    if dup.size:
        k = int(dup[0])
        raise DataError(f"t[{k}] and t[{k + 1}] are both {arr[k]:g}: duplicated sample time; average the two "
                        "samples or drop one")
    back = np.flatnonzero(step < 0)
    if back.size:
        k = int(back[0])
        raise DataError(f"t[{k + 1}] = {arr[k + 1]:g} comes before t[{k}] = {arr[k]:g}: sample times must increase; "
                        "sort the samples by time")
    return arr.astype(float)


def _channels(x: Any, name: str, N: int, *, missing_ok: bool = False) -> np.ndarray:
    """``x`` as (N, channels); NaN marks a missing value where ``missing_ok`` (the outputs), never ±inf."""
    arr = checks.as_array(x, name, complex_ok=False)
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2 or arr.shape[0] != N or arr.shape[1] < 1:
        raise DataError(f"{name} must have shape ({N}, channels) or ({N},), one row per sample time; "
                        f"got shape {checks.shape_text(arr.shape)}")
    bad = np.argwhere(np.isinf(arr) if missing_ok else ~np.isfinite(arr))
    if bad.size:
        k, j = (int(v) for v in bad[0])
        if missing_ok:
            raise DataError(f"{name}[{k}, {j}] is {arr[k, j]} (at t[{k}]); an output is a finite number, or NaN "
                            "where it was not measured")
        raise DataError(f"{name}[{k}, {j}] is {arr[k, j]} (at t[{k}]); samples must be finite: drop that sample "
                        "time or fill the gap" + (" (the input is known at every sample time; an output not "
                                                  "measured there is NaN)" if name == "u" else ""))
    if missing_ok:
        empty = np.flatnonzero(np.all(np.isnan(arr), axis=0))
        if empty.size:
            raise DataError(f"{name}[:, {empty[0]}] is NaN at every sample time: that output was never measured")
    return arr


@dataclass(frozen=True, init=False, eq=False, repr=False)
class TimeSeries(DataContainer):
    """Input/output samples u(t_k), y(t_k) at increasing times t_k, not necessarily equally spaced.

    The input is held constant from one sample time to the next (zero-order hold), as
    :class:`~symid.data.IOData` assumes for its uniform grid; ``y[k]`` is the output at
    ``t[k]``. A free response (no input) has ``u`` all zero. An output not measured at a
    sample time is NaN there: a time where only the input changes (an infusion that stops
    between two blood samples) is a row with the new input and NaN outputs. Output-error
    fitting (``method="oe"`` or ``"auto"``) leaves missing values out of its misfit.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times in the unit ``time_unit`` (seconds by default), finite and strictly
        increasing.
    u : array_like, shape (N, m) or (N,)
        Input samples; ``u[k]`` acts on [t_k, t_{k+1}).
    y : array_like, shape (N, p) or (N,)
        Output samples; NaN where an output was not measured (above).
    time_unit : str
        Unit of ``t`` (``"s"``, the default, ``"ms"``, ``"us"``, ``"min"``, ``"h"``,
        ``"d"``): the model's time unit. Reported by :meth:`summary`, kept in files.

    Raises
    ------
    DataError
        On NaN or inf in ``t`` or ``u``, inf in ``y`` or an output that is NaN at every
        time (naming the sample), duplicated or decreasing times (naming the pair), shapes
        that do not match ``t``, or fewer than two samples.

    Notes
    -----
    Written and read as NPZ files (``to_npz`` / ``from_npz``); a table (CSV, DataFrame,
    ``.mat``, dict of arrays) comes in through :meth:`from_table`; :meth:`from_iodata`
    converts a uniform record.

    Examples
    --------
    >>> from symid.data.timeseries import TimeSeries
    >>> ts = TimeSeries(t=[0.0, 0.5, 2.0], u=[0.0, 0.0, 0.0], y=[1.0, 0.7, 0.2])
    >>> ts.n_samples, ts.n_inputs, ts.uniform_dt is None
    (3, 1, True)
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    time_unit: str

    _kind: ClassVar[str] = "TimeSeries"
    _npz_keys: ClassVar[tuple[str, ...]] = ("t", "u", "y")

    def __init__(self, t: Any, u: Any, y: Any, time_unit: str = "s"):
        t_ = _times(t)
        if t_.size < 2:
            raise DataError(f"a time series needs at least 2 samples; got {t_.size}")
        u_ = _channels(u, "u", t_.size)
        y_ = _channels(y, "y", t_.size, missing_ok=True)
        object.__setattr__(self, "t", checks.frozen(t_))
        object.__setattr__(self, "u", checks.frozen(u_))
        object.__setattr__(self, "y", checks.frozen(y_))
        object.__setattr__(self, "time_unit", canonical_unit(time_unit, "time", "time_unit"))

    # -- the time unit: equality, pickling and files keep it ----------------------------------
    def _payload(self) -> dict[str, np.ndarray]:
        return {**super()._payload(), "time_unit": np.array(self.time_unit)}

    def __eq__(self, other: object) -> bool:
        return super().__eq__(other) and self.time_unit == other.time_unit  # type: ignore[union-attr]

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[type, tuple[Any, ...]]:
        return (type(self), (self.t, self.u, self.y, self.time_unit))

    @classmethod
    def from_npz(cls, path: _files.PathLike) -> Self:
        """Read data written by :meth:`to_npz` (a file without ``time_unit``, from older symid, is in seconds).

        Raises
        ------
        DataError
            If the file is not a symid TimeSeries NPZ file, is damaged or declares more
            than it can hold, or its arrays fail the constructor's checks.
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.
        """
        arrays = _files.read_npz(path, cls._kind, cls._npz_keys, optional=("time_unit",))
        with naming_file(path):
            unit = arrays.get("time_unit", np.array("s"))
            if unit.dtype.kind != "U" or unit.ndim != 0:
                raise DataError(f"'time_unit' must be a text scalar; got {unit.dtype} of shape {unit.shape}")
            return cls(arrays["t"], arrays["u"], arrays["y"], str(unit[()]))

    @classmethod
    def from_iodata(cls, io: Any) -> TimeSeries:
        """The same samples at times k·dt (in the record's time unit)."""
        return cls(io.t, io.u, io.y, io.time_unit)

    @classmethod
    def from_table(cls, table: Any, *, columns: dict[str, Any], units: dict[str, str] | None = None,
                   time_unit: str = "s", delimiter: str = ",") -> Self:
        """Read input/output samples at any increasing times from the user's own table.

        Parameters
        ----------
        table : str, os.PathLike, pandas.DataFrame or dict
            A plain CSV file, a MATLAB ``.mat`` file, a DataFrame or a dict of arrays
            (:mod:`symid.data.table`).
        columns : dict
            ``"time"``, ``"input"`` and ``"output"`` (a name or a list of names each).
        units : dict
            ``{"time": unit}``, the unit of the time column; required, never guessed.
        time_unit : str
            The record's time unit, to which the times are converted (default ``"s"``).
        delimiter : str
            Separator of a CSV file (default ``","``).

        Returns
        -------
        TimeSeries

        Raises
        ------
        DataError
            On a column the table does not hold, a unit missing or unknown, or values that
            fail the constructor's checks; the message gives a two-line example.

        Examples
        --------
        >>> from symid.data import TimeSeries
        >>> table = {"t_h": [0.0, 0.5, 2.0], "dose": [0.0, 0.0, 0.0], "c": [1.0, 0.7, 0.2]}
        >>> TimeSeries.from_table(table, columns={"time": "t_h", "input": "dose", "output": "c"},
        ...                       units={"time": "h"}, time_unit="h")
        TimeSeries(3 samples over 0…2 h, 1 input(s), 1 output(s))
        """
        from symid.data.table import series_from_table

        return series_from_table(table, columns=columns, units=units, time_unit=time_unit, uniform=False,
                                 delimiter=delimiter)

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return int(self.u.shape[1])

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return int(self.y.shape[1])

    @property
    def n_missing(self) -> int:
        """Number of output values not measured (NaN in ``y``)."""
        return int(np.count_nonzero(np.isnan(self.y)))

    @property
    def uniform_dt(self) -> float | None:
        """The sample time when the times are equally spaced (to 1e-12 relative), else ``None``."""
        step = np.diff(self.t)
        return float(step.mean()) if np.ptp(step) <= 1e-12 * step.mean() else None

    def __repr__(self) -> str:
        return (f"TimeSeries({self.n_samples} samples over {self.t[0]:g}…{self.t[-1]:g} {self.time_unit}, "
                f"{self.n_inputs} input(s), {self.n_outputs} output(s))")

    def summary(self) -> str:
        """Sizes, time span, spacing and the rms of every channel."""
        step = np.diff(self.t)
        return "\n".join([
            "TimeSeries",
            f"  samples N   : {self.n_samples} over {self.t[0]:.6g} … {self.t[-1]:.6g} {self.time_unit}",
            f"  spacing     : {step.min():.4g} … {step.max():.4g} {self.time_unit}",
            f"  inputs m    : {self.n_inputs}, rms {', '.join(f'{v:.4g}' for v in np.sqrt(np.mean(self.u**2, 0)))}",
            f"  outputs p   : {self.n_outputs}, rms {', '.join(f'{v:.4g}' for v in np.sqrt(np.nanmean(self.y**2, 0)))}"
            + (f" (over the measured values; {self.n_missing} missing)" if self.n_missing else ""),
        ])
