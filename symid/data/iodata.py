"""Sampled input/output time series with a uniform sample time."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np

from symid.data import _files, checks
from symid.data._base import DataContainer, naming_file
from symid.data.units import canonical_unit
from symid.errors import DataError

__all__ = ["IOData"]


def _signal(x: Any, name: str, width: str) -> np.ndarray:
    arr = checks.as_array(x, name, complex_ok=False)
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    elif arr.ndim != 2:
        raise DataError(f"{name} must have shape (N, {width}) (one row per sample), or (N,) for a single "
                        f"channel; got shape {checks.shape_text(arr.shape)}")
    if arr.shape[1] < 1:
        raise DataError(f"{name} must have at least one channel; got shape {checks.shape_text(arr.shape)}")
    try:
        checks.check_finite(arr, name)
    except DataError as exc:
        if name != "y" or np.isinf(arr).any():
            raise
        # an output not measured at some sample times: say where that is allowed
        raise DataError(f"{exc}; for outputs not measured at some sample times use a TimeSeries "
                        "(TimeSeries(io.t, io.u, y)), where NaN marks a missing value") from None
    return arr


@dataclass(frozen=True, init=False, eq=False, repr=False)
class IOData(DataContainer):
    """Input/output samples u[k], y[k] at times t_k = k·dt, k = 0..N−1.

    Parameters
    ----------
    u : array_like, shape (N, m) or (N,)
        Input samples, one row per sample; a 1-D array is a single input.
    y : array_like, shape (N, p) or (N,)
        Output samples, one row per sample; a 1-D array is a single output.
    dt : float
        Sample time, finite and > 0, in ``time_unit``.
    time_unit : str
        Unit of ``dt`` and of the times (``"s"``, the default, ``"ms"``, ``"us"``,
        ``"min"``, ``"h"``, ``"d"``): the model's time unit, since rates and frequencies
        estimated from the record are per this unit. Reported by :meth:`summary`, kept in files.

    Raises
    ------
    DataError
        On NaN or inf, wrong shapes, ``u`` and ``y`` of different lengths, fewer than
        two samples, more channels than samples, or a ``dt`` that is not a finite
        positive number.

    Notes
    -----
    A 2-D array is always read as (samples, channels), never transposed silently: an
    array with more channels than samples, such as (2, 5000), is refused as probably
    transposed.

    CSV layout (see :meth:`to_csv`)::

        # symid IOData csv v2
        # dt: 0.01
        # time_unit: s
        # n_inputs: m
        # n_outputs: p
        # n_rows: N
        u[0],...,u[m-1],y[0],...,y[p-1]
        <one row per sample>
        # end

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data import IOData
    >>> io = IOData(u=np.ones(5), y=np.arange(5.0), dt=0.1)
    >>> io.u.shape, io.n_samples, io.n_outputs
    ((5, 1), 5, 1)
    >>> io.t
    array([0. , 0.1, 0.2, 0.3, 0.4])
    """

    u: np.ndarray
    y: np.ndarray
    dt: float
    time_unit: str

    _kind: ClassVar[str] = "IOData"
    _npz_keys: ClassVar[tuple[str, ...]] = ("u", "y", "dt")

    def __init__(self, u: Any, y: Any, dt: Any = None, time_unit: str = "s"):
        u_ = _signal(u, "u", "m")
        y_ = _signal(y, "y", "p")
        if u_.shape[0] != y_.shape[0]:
            raise DataError(f"u and y must have the same number of samples N: u has {u_.shape[0]} "
                            f"(shape {checks.shape_text(u_.shape)}), y has {y_.shape[0]} "
                            f"(shape {checks.shape_text(y_.shape)})")
        for label, arr in (("u", u_), ("y", y_)):
            # one row of as many values in both: a signal each, written as a row (one sample of several channels
            # would be too short either way)
            if arr.shape[0] == 1 and u_.shape[1] == y_.shape[1] >= 2:
                raise DataError(f"{label} has shape {checks.shape_text(arr.shape)}: {arr.shape[1]} channels but only "
                                f"{arr.shape[0]} sample; arrays are (samples, channels), one row per sample "
                                f"(pass {label}.T, or a 1-D array, if you have one row per channel)")
        if u_.shape[0] < 2:
            raise DataError(f"u and y must hold at least 2 samples (rows); got N = {u_.shape[0]}")
        for label, arr in (("u", u_), ("y", y_)):
            if arr.shape[1] > arr.shape[0]:
                raise DataError(f"{label} has shape {checks.shape_text(arr.shape)}: {arr.shape[1]} channels but only "
                                f"{arr.shape[0]} samples; arrays are (samples, channels), one row per sample "
                                f"(pass {label}.T if you have one row per channel)")
        if dt is None:
            raise DataError("dt is missing: IOData(u, y, dt) needs the sample time in seconds")
        dt_ = checks.check_positive_scalar(dt, "dt")
        object.__setattr__(self, "u", checks.frozen(u_))
        object.__setattr__(self, "y", checks.frozen(y_))
        object.__setattr__(self, "dt", dt_)
        object.__setattr__(self, "time_unit", _time_unit(time_unit))

    # -- the time unit: equality, pickling and files keep it ----------------------------------
    def _payload(self) -> dict[str, np.ndarray]:
        return {**super()._payload(), "time_unit": np.array(self.time_unit)}

    def __eq__(self, other: object) -> bool:
        return super().__eq__(other) and self.time_unit == other.time_unit  # type: ignore[union-attr]

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[type, tuple[Any, ...]]:
        return (type(self), (self.u, self.y, self.dt, self.time_unit))

    @classmethod
    def from_npz(cls, path: _files.PathLike) -> Self:
        """Read data written by :meth:`to_npz` (a file without ``time_unit``, from older symid, is in seconds).

        Raises
        ------
        DataError
            If the file is not a symid IOData NPZ file, is damaged or declares more than
            it can hold, or its arrays fail the constructor's checks.
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.
        """
        arrays = _files.read_npz(path, cls._kind, cls._npz_keys, optional=("time_unit",))
        with naming_file(path):
            unit = arrays.get("time_unit", np.array("s"))
            if unit.dtype.kind != "U" or unit.ndim != 0:
                raise DataError(f"'time_unit' must be a text scalar; got {unit.dtype} of shape {unit.shape}")
            return cls(arrays["u"], arrays["y"], arrays["dt"], str(unit[()]))

    @classmethod
    def from_table(cls, table: Any, *, columns: dict[str, Any], units: dict[str, str] | None = None,
                   dt: float | None = None, time_unit: str = "s", delimiter: str = ",") -> Self:
        """Read an equally spaced input/output record from the user's own table, its columns and units declared.

        Parameters
        ----------
        table : str, os.PathLike, pandas.DataFrame or dict
            A plain CSV file, a MATLAB ``.mat`` file, a DataFrame or a dict of arrays
            (:mod:`symid.data.table`).
        columns : dict
            ``"input"`` and ``"output"``: a column name or a list of names (a 2-D
            variable of a .mat file or dict is several channels); ``"time"``: the sample
            times, unless ``dt`` is given.
        units : dict
            ``{"time": unit}``, the unit of the time column or of ``dt`` (``"s"``,
            ``"ms"``, ``"us"``, ``"min"``, ``"h"``, ``"d"``); required, never guessed.
        dt : float, optional
            Sample time, when the table has no time column.
        time_unit : str
            The record's time unit, to which the times are converted (default ``"s"``).
        delimiter : str
            Separator of a CSV file (default ``","``).

        Returns
        -------
        IOData
            Times that are not equally spaced (beyond 0.1 % of a sample of jitter, or
            beyond the rounding of the digits they are written with, up to 10 % of a
            sample) are refused: read them with :meth:`TimeSeries.from_table
            <symid.data.TimeSeries.from_table>`.

        Raises
        ------
        DataError
            On a column the table does not hold, a unit missing or unknown, uneven
            times, or values that fail the constructor's checks; the message gives a
            two-line example.

        Examples
        --------
        >>> from symid.data import IOData
        >>> table = {"t": [0.0, 0.5, 1.0, 1.5], "u": [1.0, 1.0, 0.0, 0.0], "y": [0.0, 0.4, 0.6, 0.5]}
        >>> io = IOData.from_table(table, columns={"time": "t", "input": "u", "output": "y"}, units={"time": "min"})
        >>> io.dt, io.time_unit
        (30.0, 's')
        """
        from symid.data.table import series_from_table

        return series_from_table(table, columns=columns, units=units, dt=dt, time_unit=time_unit, uniform=True,
                                 delimiter=delimiter)

    # -- properties -----------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.u.shape[0])

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return int(self.u.shape[1])

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return int(self.y.shape[1])

    @property
    def t(self) -> np.ndarray:
        """Sample times k·dt, k = 0..N−1 (a new array)."""
        return np.arange(self.n_samples) * self.dt

    @property
    def duration(self) -> float:
        """Time span of the record, (N − 1)·dt."""
        return (self.n_samples - 1) * self.dt

    # -- text -----------------------------------------------------------------------
    def __repr__(self) -> str:
        return (f"IOData({self.n_samples} samples, dt = {self.dt:.4g} {self.time_unit}, "
                f"{self.n_inputs} input(s), {self.n_outputs} output(s))")

    def summary(self) -> str:
        """A short readable description: sizes, sample time, rms of every channel."""
        rms_u = np.sqrt(np.mean(self.u**2, axis=0))
        rms_y = np.sqrt(np.mean(self.y**2, axis=0))
        return "\n".join([
            "IOData",
            f"  samples N   : {self.n_samples}",
            f"  dt          : {self.dt:.6g} {self.time_unit} (duration {self.duration:.6g} {self.time_unit})",
            f"  inputs m    : {self.n_inputs}, rms {', '.join(f'{v:.4g}' for v in rms_u)}",
            f"  outputs p   : {self.n_outputs}, rms {', '.join(f'{v:.4g}' for v in rms_y)}",
        ])

    # -- CSV ------------------------------------------------------------------------
    @staticmethod
    def _columns(m: int, p: int) -> list[str]:
        return [f"u[{j}]" for j in range(m)] + [f"y[{i}]" for i in range(p)]

    def to_csv(self, path: _files.PathLike) -> None:
        """Write the data as CSV text (layout in the class notes); the round trip is exact."""
        table = np.hstack([self.u, self.y])
        rows = [[_files.fmt(x) for x in row] for row in table.tolist()]
        meta = {"dt": _files.fmt(self.dt), "time_unit": self.time_unit, "n_inputs": self.n_inputs,
                "n_outputs": self.n_outputs}
        _files.write_csv(path, self._kind, meta, self._columns(self.n_inputs, self.n_outputs), rows)

    @classmethod
    def from_csv(cls, path: _files.PathLike) -> Self:
        """Read a file written by :meth:`to_csv`.

        Raises
        ------
        DataError
            If the file is not a symid IOData CSV file, was cut short, declares
            sizes that its rows and columns do not match, or its contents fail the
            constructor's checks (rules in the notes of ``symid.data._files``).
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.

        Warns
        -----
        UserWarning
            For a version-1 file, whose completeness cannot be checked.
        """
        meta, columns, rows = _files.read_csv(path, cls._kind, meta_keys=("dt", "time_unit", "n_inputs", "n_outputs"))
        m = _files.meta_int(meta, "n_inputs", path, at_most=len(columns))
        p = _files.meta_int(meta, "n_outputs", path, at_most=len(columns))
        _files.expect_width(columns, m + p, path, "n_inputs + n_outputs")
        dt = _files.meta_float(meta, "dt", path)
        _files.expect_columns(columns, cls._columns(m, p), path)
        table = _files.parse_float_rows(rows, path, len(columns))
        with naming_file(path):
            return cls(table[:, :m], table[:, m:], dt, meta.get("time_unit", "s"))


def _time_unit(unit: Any) -> str:
    """A canonical time unit name (``"s"``, ``"ms"``, ...)."""
    return canonical_unit(unit, "time", "time_unit")
