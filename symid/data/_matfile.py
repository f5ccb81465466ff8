"""MATLAB ``.mat`` files read as data (private): numeric variables only, every size checked first.

:func:`scipy.io.loadmat` reads MATLAB's level-5 format (what ``save`` writes by default,
compressed or not; ``-v7.3`` files are HDF5 and are refused with advice). It never
unpickles anything, but it trusts the sizes a file declares: a compressed variable can
expand a thousandfold. So before it runs:

1. the file must be a regular file with a level-5 header (``MATLAB 5.0 MAT-file``, byte
   order mark ``IM`` or ``MI``);
2. every top-level element is walked: an uncompressed one must fit in the bytes left in
   the file, and a compressed one is inflated as a stream, 1 MiB at a time and then
   discarded, counting its bytes; the total must fit the budget
   ``min(4 GiB, max(1 MiB, 32 × file size))`` of :func:`symid.data._files.npz_budget`
   (the same rule as NPZ files; measured MATLAB data compress by less than 2);
3. :func:`scipy.io.whosmat` lists the variables; those asked for must exist and be
   numeric (``double``, ``single``, integers; not cell, struct, object, char, sparse,
   logical or function handles) with at most 2 dimensions;
4. only those variables are read (``variable_names=``), and each result is checked
   again to be a real or complex numeric array.
"""

from __future__ import annotations

import os
import struct
import zlib
from collections.abc import Sequence

import numpy as np

from symid.data import _files
from symid.errors import DataError

__all__ = ["read_mat_variables"]

_HEADER = 128
_MI_COMPRESSED = 15
_MI_MATRIX = 14
_NUMERIC = {"double", "single", "int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64"}
_CHUNK = 2**20


def _where(path: _files.PathLike) -> str:
    return repr(os.fspath(path))


def _walk(fh, size: int, path: _files.PathLike) -> None:
    """Check every element's declared size against the file and the decompression budget."""
    head = fh.read(_HEADER)
    if len(head) < _HEADER:
        raise DataError(f"{_where(path)} is too short for a MATLAB .mat file")
    if head.startswith(b"\x89HDF") or head[:116].find(b"MATLAB 7.3") >= 0:
        raise DataError(f"{_where(path)} is a MATLAB v7.3 (HDF5) file; save it with save(..., '-v7') or export "
                        "a CSV file")
    if not head.startswith(b"MATLAB 5.0 MAT-file"):
        raise DataError(f"{_where(path)} is not a MATLAB level-5 .mat file (save(..., '-v7') writes one); "
                        "MATLAB v4 files are not read")
    order = head[126:128]
    if order not in (b"IM", b"MI"):
        raise DataError(f"{_where(path)}: bad byte-order mark in the .mat header; the file is damaged")
    endian = "<" if order == b"IM" else ">"
    budget = _files.npz_budget(size)
    expanded = 0
    pos = _HEADER
    while pos < size:
        fh.seek(pos)
        tag = fh.read(8)
        if len(tag) < 8:
            raise DataError(f"{_where(path)}: truncated element at byte {pos}; the file is damaged")
        mdtype, nbytes = struct.unpack(endian + "II", tag)
        if mdtype >> 16:  # a small-data element (only valid inside variables)
            raise DataError(f"{_where(path)}: unexpected element at byte {pos}; the file is damaged")
        start = pos + 8
        if nbytes > size - start:
            raise DataError(f"{_where(path)}: an element at byte {pos} declares {nbytes} bytes, more than the "
                            f"{size - start} left in the file; the file is damaged")
        if mdtype == _MI_COMPRESSED:
            inflate = zlib.decompressobj()
            left = nbytes
            while left > 0 or inflate.unconsumed_tail:
                chunk = inflate.unconsumed_tail or fh.read(min(_CHUNK, left))
                if not inflate.unconsumed_tail:
                    left -= len(chunk)
                    if not chunk:
                        break
                try:
                    out = inflate.decompress(chunk, _CHUNK)
                except zlib.error as exc:
                    raise DataError(f"{_where(path)}: a compressed variable is damaged ({exc})") from None
                expanded += len(out)
                if expanded > budget:
                    raise DataError(f"{_where(path)}: its variables expand to more than {budget} bytes, the most "
                                    f"this {size}-byte file may declare (max(1 MiB, {_files.NPZ_RATIO} × its size), "
                                    f"at most 4 GiB; a zip bomb?)")
                if inflate.eof:
                    break
            pos = start + nbytes
        else:
            if mdtype != _MI_MATRIX:
                raise DataError(f"{_where(path)}: unexpected element type {mdtype} at byte {pos}; the file is "
                                "damaged or not a MATLAB data file")
            expanded += nbytes
            if expanded > budget:
                raise DataError(f"{_where(path)}: its variables declare more than {budget} bytes")
            pos = start + nbytes


def read_mat_variables(path: _files.PathLike, names: Sequence[str]) -> dict[str, np.ndarray]:
    """The named numeric variables of a level-5 ``.mat`` file, each a float or complex array of ≤ 2 dimensions.

    Raises
    ------
    DataError
        If the file is not a level-5 .mat file, is damaged, declares more than its size
        can back, lacks a variable, or a variable is not a numeric array.
    """
    import scipy.io

    with _files._open_regular(path) as fh:
        size = os.fstat(fh.fileno()).st_size
        _walk(fh, size, path)
    try:
        listed = scipy.io.whosmat(os.fspath(path))
    except Exception as exc:  # scipy raises ValueError, TypeError, MatReadError ... on a damaged file
        raise DataError(f"{_where(path)} is not a readable .mat file ({type(exc).__name__}: "
                        f"{str(exc)[:100]})") from None
    info = {name: (shape, cls) for name, shape, cls in listed}
    missing = [n for n in names if n not in info]
    if missing:
        have = ", ".join(f"{n} {tuple(s)}" for n, (s, _) in list(info.items())[:20])
        raise DataError(f"{_where(path)} has no variable {', '.join(map(repr, missing))}; it holds: {have or 'none'}")
    for n in names:
        shape, cls = info[n]
        if cls not in _NUMERIC:
            raise DataError(f"{_where(path)}: variable {n!r} is a MATLAB {cls}, not a numeric array; symid reads "
                            "double, single and integer arrays")
        if len(shape) > 2:
            raise DataError(f"{_where(path)}: variable {n!r} has {len(shape)} dimensions {tuple(shape)}; symid "
                            "reads vectors and 2-D arrays (samples × channels)")
    try:
        loaded = scipy.io.loadmat(os.fspath(path), variable_names=list(names), squeeze_me=False,
                                  struct_as_record=True, mat_dtype=False, chars_as_strings=False)
    except Exception as exc:
        raise DataError(f"{_where(path)} could not be read ({type(exc).__name__}: {str(exc)[:100]})") from None
    out = {}
    for n in names:
        arr = loaded.get(n)
        if not isinstance(arr, np.ndarray) or arr.dtype.kind not in "iufc" or arr.ndim > 2:
            raise DataError(f"{_where(path)}: variable {n!r} did not read as a numeric array")
        out[n] = arr.astype(np.complex128 if arr.dtype.kind == "c" else np.float64)
    return out
