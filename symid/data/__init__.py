"""Data containers of symid: frequency responses, spectra, input/output series, black boxes.

Every container is an immutable dataclass holding read-only numpy arrays, validated at
construction (any problem raises :class:`symid.errors.DataError` naming the array), and
reads and writes CSV (``to_csv`` / ``from_csv``) and NPZ (``to_npz`` / ``from_npz``)
files exactly. :func:`load` reads any symid data file, whichever kind it holds.
Measurements made elsewhere (plain CSV, MATLAB ``.mat``, pandas DataFrames) come in
through ``from_table`` or :func:`read_data`, their columns and units declared
(:mod:`symid.data.table`, :mod:`symid.data.units`).
"""

from __future__ import annotations

from symid.data._files import PathLike, peek_kind
from symid.data.blackbox import BlackBox
from symid.data.frequency import FrequencyData
from symid.data.iodata import IOData
from symid.data.spectral import SpectralData
from symid.data.table import read_data
from symid.data.timeseries import TimeSeries
from symid.errors import DataError

__all__ = ["BlackBox", "FrequencyData", "IOData", "SpectralData", "TimeSeries", "load", "read_data"]

_KINDS = {cls._kind: cls for cls in (FrequencyData, SpectralData, IOData, BlackBox, TimeSeries)}


def load(path: PathLike) -> FrequencyData | SpectralData | IOData | BlackBox:
    """Read a symid data file of any kind, CSV or NPZ (told apart by content, not by name).

    Parameters
    ----------
    path : str or os.PathLike
        A file written by one of the containers' ``to_csv`` or ``to_npz``.

    Returns
    -------
    FrequencyData or SpectralData or IOData or BlackBox
        Whatever the file holds.

    Raises
    ------
    DataError
        If the file is not a symid data file or its contents are invalid.

    Examples
    --------
    >>> import os, tempfile
    >>> from symid.data import IOData, load
    >>> path = os.path.join(tempfile.mkdtemp(), "io.npz")
    >>> IOData([0.0, 1.0], [0.0, 0.5], dt=0.1).to_npz(path)
    >>> load(path)
    IOData(2 samples, dt = 0.1 s, 1 input(s), 1 output(s))
    """
    kind, fmt = peek_kind(path)
    if kind not in _KINDS:
        raise DataError(f"{str(path)!r} holds an unknown kind of data {kind!r}; "
                        f"known kinds are {', '.join(_KINDS)}")
    cls = _KINDS[kind]
    if fmt == "csv" and not hasattr(cls, "from_csv"):
        raise DataError(f"{str(path)!r}: {kind} files are NPZ only")
    return cls.from_npz(path) if fmt == "npz" else cls.from_csv(path)
