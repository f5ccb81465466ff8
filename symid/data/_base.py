"""The common base of the data containers (private): equality, NPZ round trip, errors naming the file."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import ClassVar, Self

import numpy as np

from symid.data import _files
from symid.errors import DataError

__all__ = ["DataContainer", "naming_file"]


@contextmanager
def naming_file(path: _files.PathLike) -> Iterator[None]:
    """Prefix a :class:`DataError` raised while building a container from a file with the file name."""
    try:
        yield
    except DataError as exc:
        msg = str(exc)
        name = repr(os.fspath(path))
        if msg.startswith(name):
            raise
        raise DataError(f"{name}: {msg}") from None


class DataContainer:
    """Shared behaviour of the immutable data containers.

    Subclasses are frozen dataclasses whose fields are read-only numpy arrays (and, for
    :class:`~symid.data.IOData`, the float ``dt``). They define ``_kind`` (the tag stored
    in files) and ``_npz_keys`` (the arrays stored in an NPZ file, which are also the
    constructor's arguments, in order).
    """

    _kind: ClassVar[str]
    _npz_keys: ClassVar[tuple[str, ...]]
    stated_units: ClassVar[dict[str, tuple[tuple[str, str | None], ...]]] = {}
    """The input and output columns a CSV file was read with and the units its ``# units:`` comment states for
    them, ``{"input": ((column, unit), ...), "output": (...), "file": "'path'"}``, units as written (``None``
    for a column it states none for); ``{}`` for data not read from a CSV file. symid converts nothing by them:
    :func:`symid.identify` compares them with a model file's ``input_units`` and ``output_units``, and
    :func:`symid.validate` labels the channels by the columns. Set on the object read (not kept by a copy or a
    file)."""

    # -- equality: exact, array by array --------------------------------------------
    def _payload(self) -> dict[str, np.ndarray]:
        return {k: np.asarray(getattr(self, k)) for k in self._npz_keys}

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        mine, theirs = self._payload(), other._payload()  # type: ignore[attr-defined]
        return all(np.array_equal(mine[k], theirs[k], equal_nan=mine[k].dtype.kind in "fc")
                   for k in self._npz_keys)  # a missing value (NaN) equals a missing value

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[type, tuple[np.ndarray | float, ...]]:
        # pickle and copy rebuild through the constructor, so arrays come back read-only and checked
        return (type(self), tuple(getattr(self, k) for k in self._npz_keys))

    # -- NPZ ------------------------------------------------------------------------
    def to_npz(self, path: _files.PathLike) -> None:
        """Write the data to a NumPy ``.npz`` file at ``path`` (used exactly as given).

        The file holds the arrays under their attribute names plus the tags ``kind``
        (the class name) and ``format_version``. Reading it back with :meth:`from_npz`
        gives an equal object, bit for bit.
        """
        _files.write_npz(path, self._kind, self._payload())

    @classmethod
    def from_npz(cls, path: _files.PathLike) -> Self:
        """Read data written by :meth:`to_npz`.

        Only the arrays of this class and the two tags are decompressed, each after its
        declared size has been checked against its ``.npy`` header and against what the
        file's size can plausibly hold; pickles are never loaded (rules in the notes of
        ``symid.data._files``).

        Raises
        ------
        DataError
            If the file is not a symid NPZ file, holds another kind of data, is damaged
            or declares more than it can hold, or its arrays fail the constructor's
            checks.
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.
        """
        arrays = _files.read_npz(path, cls._kind, cls._npz_keys)
        with naming_file(path):
            return cls._from_npz_arrays(arrays)

    @classmethod
    def _from_npz_arrays(cls, arrays: dict[str, np.ndarray]) -> Self:
        return cls(**arrays)
