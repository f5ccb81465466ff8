"""CSV and NPZ reading and writing shared by the data containers (private).

NPZ files hold the container's arrays under their own names plus two tags, ``kind``
(the class name, a 0-d unicode array) and ``format_version`` (a 0-d integer array).
They are written through an open file handle, so the path is used exactly as given (no
``.npz`` is appended).

CSV files are plain UTF-8 text::

    # symid FrequencyData csv v2
    # n_outputs: 1
    # n_inputs: 1
    # n_rows: 2
    w,H[0][0].re,H[0][0].im
    0.5,1.2,-0.3
    2.0,0.2,-0.4
    # end

The first line names the kind and the format version, further ``# key: value`` lines
hold metadata (shapes, sample time, the number of data rows), then one header line of
column names, one row per sample, and the end marker. Column names contain no commas
(``H[0][1].re``), so no quoting is ever needed. Floats are written with :func:`repr`,
the shortest text that reads back to the same float64, so a round trip is exact bit for
bit. Version 1 files (no row count, no end marker) are still read, with a warning that
their completeness cannot be checked.

Nothing in a file is trusted before the bytes that back it:

* CSV: sizes declared in the metadata are plain positive integers, and the columns and
  rows they imply must be the columns and rows present before any array of that size
  is built; a version-2 file must hold exactly ``n_rows`` rows and end with ``# end``,
  so a file cut short is refused rather than loaded short.
* NPZ: the zip directory is read, not the members; only the members the container
  needs are decompressed, each after its ``.npy`` header has been read from the stream
  and checked (no object dtype, shape × item size = the member's declared size), and
  at most :func:`member_limit` bytes are ever read from one member (a zip bomb is
  refused from its declared sizes, and a member that lies about its size cannot make
  the reader go past the bytes its header promised). Pickles are never loaded.
"""

from __future__ import annotations

import os
import warnings
import zipfile
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from symid.errors import DataError

__all__ = [
    "CSV_VERSION",
    "FORMAT_VERSION",
    "complex_from_parts",
    "expect_columns",
    "expect_width",
    "fmt",
    "member_limit",
    "meta_float",
    "meta_int",
    "parse_float_rows",
    "peek_kind",
    "read_csv",
    "read_npz",
    "write_csv",
    "write_npz",
]

FORMAT_VERSION = 1
"""Version of the NPZ layout."""

CSV_VERSION = 2
"""Version of the CSV layout written (1 is still read)."""

_END = "# end"
_CSV_MAGIC = "# symid "

PathLike = str | os.PathLike


def fmt(x: float) -> str:
    """Shortest exact text of a float64 (``repr``)."""
    return repr(float(x))


def complex_from_parts(re: np.ndarray, im: np.ndarray) -> np.ndarray:
    """A complex array with exactly these real and imaginary parts (signed zeros kept)."""
    out = np.empty(np.shape(re), dtype=np.complex128)
    out.real = re
    out.imag = im
    return out


# -- NPZ -------------------------------------------------------------------------------

def write_npz(path: PathLike, kind: str, arrays: Mapping[str, np.ndarray]) -> None:
    """Write ``arrays`` plus the ``kind`` and ``format_version`` tags to ``path`` (exact name)."""
    payload = {"kind": np.array(kind), "format_version": np.array(FORMAT_VERSION, dtype=np.int64)}
    payload.update({k: np.asarray(v) for k, v in arrays.items()})
    with open(path, "wb") as fh:
        np.savez(fh, **payload)


MEMBER_FLOOR = 16 * 2**20
"""Bytes a member may always expand to, whatever its compressed size (16 MiB)."""

MEMBER_RATIO = 100
"""Largest expansion allowed beyond the floor: uncompressed ≤ 100 × compressed bytes."""


def member_limit(compressed: int) -> int:
    """Most bytes an NPZ member of ``compressed`` stored bytes may hold: max(16 MiB, 100 × compressed).

    Arrays symid writes are stored uncompressed (ratio 1); measured data compressed with
    ``numpy.savez_compressed`` shrink a few times; only a bomb expands by orders of
    magnitude.
    """
    return max(MEMBER_FLOOR, MEMBER_RATIO * int(compressed))


def _where(path: PathLike) -> str:
    return repr(os.fspath(path))


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, path: PathLike) -> np.ndarray:
    """One ``.npy`` member, its header checked against its declared size before anything is allocated."""
    name = info.filename.removesuffix(".npy")
    limit = member_limit(info.compress_size)
    if info.file_size > limit:
        raise DataError(f"{_where(path)}: array {name!r} declares {info.file_size} bytes from {info.compress_size} "
                        f"stored (limit {limit}): not a symid data file, or a damaged one")
    with zf.open(info) as fh:
        try:
            version = np.lib.format.read_magic(fh)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh, max_header_size=10_000)
            elif version in ((2, 0), (3, 0)):
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh, max_header_size=10_000)
            else:  # pragma: no cover - numpy writes 1.0 to 3.0
                raise ValueError(f"unknown .npy version {version}")
        except (ValueError, OSError, EOFError, SyntaxError) as exc:
            raise DataError(f"{_where(path)}: array {name!r} has no valid .npy header ({exc})") from None
        if dtype.hasobject:
            raise DataError(f"{_where(path)}: array {name!r} needs pickling (object dtype); symid files never do")
        count = 1
        for d in shape:
            count *= int(d)
        nbytes = count * dtype.itemsize
        header = fh.tell()
        if header + nbytes != info.file_size:
            raise DataError(f"{_where(path)}: array {name!r} declares shape {shape} of {dtype} ({nbytes} bytes) but "
                            f"the member holds {info.file_size - header} bytes: the file is damaged")
        data = fh.read(nbytes + 1)  # at most one byte more than promised, whatever the member holds
    if len(data) != nbytes:
        raise DataError(f"{_where(path)}: array {name!r} holds {len(data)} bytes, {nbytes} expected: the file is "
                        f"damaged")
    arr = np.frombuffer(data, dtype=dtype, count=count)
    return arr.reshape(shape, order="F" if fortran else "C").copy()


def _load_npz(path: PathLike, keys: Sequence[str] | None = None) -> dict[str, np.ndarray]:
    """The members ``keys`` (and the two tags) of an NPZ file; others are never decompressed."""
    try:
        with zipfile.ZipFile(path) as zf:
            infos = {i.filename.removesuffix(".npy"): i for i in zf.infolist() if i.filename.endswith(".npy")}
            wanted = list(infos) if keys is None else [k for k in ("kind", "format_version", *keys) if k in infos]
            return {k: _read_member(zf, infos[k], path) for k in dict.fromkeys(wanted)}
    except (zipfile.BadZipFile, EOFError, zipfile.LargeZipFile, NotImplementedError, RuntimeError) as exc:
        raise DataError(f"{_where(path)} is not a readable .npz file ({exc})") from None
    except OSError as exc:
        if isinstance(exc, FileNotFoundError | IsADirectoryError | PermissionError):
            raise
        raise DataError(f"{_where(path)} is not a readable .npz file ({exc})") from None


def _npz_kind(contents: Mapping[str, np.ndarray], path: PathLike) -> str:
    if "kind" not in contents or "format_version" not in contents:
        raise DataError(f"{os.fspath(path)!r} is not a symid data file: the 'kind' and 'format_version' "
                        f"entries are missing (found {', '.join(sorted(contents)) or 'nothing'})")
    kind = contents["kind"]
    if kind.dtype.kind != "U" or kind.ndim != 0:
        raise DataError(f"{os.fspath(path)!r}: 'kind' must be a text scalar; got {kind.dtype} {kind.shape}")
    version = contents["format_version"]
    if version.dtype.kind not in "iu" or version.ndim != 0:
        raise DataError(f"{os.fspath(path)!r}: 'format_version' must be an integer scalar")
    if int(version) > FORMAT_VERSION or int(version) < 1:
        raise DataError(f"{os.fspath(path)!r} has format version {int(version)}; this symid reads "
                        f"version {FORMAT_VERSION} (upgrade symid?)")
    return str(kind)


def read_npz(path: PathLike, kind: str, keys: Sequence[str]) -> dict[str, np.ndarray]:
    """Read a symid .npz file of ``kind``; every name in ``keys`` must be present (others are not read)."""
    contents = _load_npz(path, keys)
    found = _npz_kind(contents, path)
    if found != kind:
        raise DataError(f"{os.fspath(path)!r} holds {found}, not {kind}; use {found}.from_npz "
                        f"or symid.data.load")
    missing = [k for k in keys if k not in contents]
    if missing:
        raise DataError(f"{os.fspath(path)!r}: the {kind} file lacks the array(s) {', '.join(missing)}")
    return {k: contents[k] for k in keys}


# -- CSV -------------------------------------------------------------------------------

def write_csv(path: PathLike, kind: str, meta: Mapping[str, Any], columns: Sequence[str],
              rows: Sequence[Sequence[str]]) -> None:
    """Write a symid CSV file: magic line, ``# key: value`` metadata, header, rows of text cells."""
    lines = [f"{_CSV_MAGIC}{kind} csv v{CSV_VERSION}"]
    lines += [f"# {k}: {v}" for k, v in {**meta, "n_rows": len(rows)}.items()]
    lines.append(",".join(columns))
    lines += [",".join(r) for r in rows]
    lines.append(_END)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")


def _parse_magic(line: str, path: PathLike) -> tuple[str, int]:
    parts = line.strip().split()
    # "# symid <Kind> csv v<version>"
    if len(parts) != 5 or parts[:2] != ["#", "symid"] or parts[3] != "csv" or not parts[4].startswith("v"):
        raise DataError(f"{os.fspath(path)!r} is not a symid CSV file: its first line should read "
                        f"'# symid <Kind> csv v{CSV_VERSION}', got {line.strip()[:80]!r}")
    try:
        version = int(parts[4][1:])
    except ValueError:
        raise DataError(f"{os.fspath(path)!r}: bad format version {parts[4]!r} on line 1") from None
    if version > CSV_VERSION or version < 1:
        raise DataError(f"{os.fspath(path)!r} has format version {version}; this symid reads "
                        f"versions 1 to {CSV_VERSION} (upgrade symid?)")
    return parts[2], version


def _read_text(path: PathLike) -> list[str]:
    try:
        with open(path, encoding="utf-8") as fh:
            return fh.read().splitlines()
    except UnicodeDecodeError:
        raise DataError(f"{os.fspath(path)!r} is not a UTF-8 text file (a symid CSV was expected)") from None


def read_csv(path: PathLike, kind: str) -> tuple[dict[str, str], list[str], list[tuple[int, list[str]]]]:
    """Read a symid CSV file of ``kind``, refusing one that is cut short.

    Returns
    -------
    meta : dict of str
        The ``# key: value`` metadata.
    columns : list of str
        The header's column names.
    rows : list of (line number, cells)
        The data rows, one-based line numbers for messages; blank lines are skipped.
    """
    lines = _read_text(path)
    if not lines:
        raise DataError(f"{os.fspath(path)!r} is empty; a symid CSV file was expected")
    found, version = _parse_magic(lines[0], path)
    if found != kind:
        raise DataError(f"{os.fspath(path)!r} holds {found}, not {kind}; use {found}.from_csv "
                        f"or symid.data.load")
    meta: dict[str, str] = {}
    i = 1
    while i < len(lines) and lines[i].startswith("#"):
        body = lines[i][1:].strip()
        if ":" in body:
            key, _, value = body.partition(":")
            meta[key.strip()] = value.strip()
        i += 1
    if i >= len(lines):
        raise DataError(f"{os.fspath(path)!r}: the header line of column names is missing")
    columns = [c.strip() for c in lines[i].split(",")]
    body_lines = lines[i + 1:]
    if version >= 2:
        while body_lines and not body_lines[-1].strip():
            body_lines.pop()
        if not body_lines or body_lines[-1].strip() != _END:
            raise DataError(f"{os.fspath(path)!r} does not end with the line '{_END}': the file was cut short "
                            f"(or edited); it is refused rather than read incompletely")
        body_lines.pop()
    else:
        warnings.warn(f"{os.fspath(path)!r} is a version-1 symid CSV file: it carries no row count, so a file cut "
                      f"short cannot be told from a complete one; write it again to get version {CSV_VERSION}",
                      UserWarning, stacklevel=3)
    rows = []
    for j, text in enumerate(body_lines, start=i + 2):
        if not text.strip():
            continue
        if text.startswith("#"):
            raise DataError(f"{os.fspath(path)!r}, line {j}: a comment line among the data rows")
        cells = [c.strip() for c in text.split(",")]
        if len(cells) != len(columns):
            raise DataError(f"{os.fspath(path)!r}, line {j}: {len(cells)} cells; the header has "
                            f"{len(columns)} columns")
        rows.append((j, cells))
    if version >= 2:
        declared = meta_int(meta, "n_rows", path, at_most=len(rows) + 1)
        if declared != len(rows):
            raise DataError(f"{os.fspath(path)!r} declares {declared} data rows ('# n_rows') but holds "
                            f"{len(rows)}: the file is damaged")
    return meta, columns, rows


def parse_float_rows(rows: Sequence[tuple[int, list[str]]], path: PathLike, n_columns: int) -> np.ndarray:
    """The cells of ``rows`` as a float64 array of shape (len(rows), n_columns)."""
    out = np.empty((len(rows), n_columns), dtype=np.float64)
    for r, (line, cells) in enumerate(rows):
        for c, cell in enumerate(cells):
            try:
                out[r, c] = float(cell)
            except ValueError:
                raise DataError(f"{os.fspath(path)!r}, line {line}, column {c + 1}: {cell!r} is not a number") from None
    return out


def meta_int(meta: Mapping[str, str], key: str, path: PathLike, *, at_most: int | None = None) -> int:
    """A positive integer metadata entry, required, written as plain digits, at most ``at_most``.

    ``at_most`` is what the bytes present can back (e.g. the number of columns), so a
    header claiming more is refused before anything of that size is built.
    """
    if key not in meta:
        raise DataError(f"{os.fspath(path)!r}: the metadata line '# {key}: ...' is missing")
    text = meta[key]
    if not (text.isascii() and text.isdigit()) or len(text) > 12:
        raise DataError(f"{os.fspath(path)!r}: '# {key}' must be a positive integer written in digits; "
                        f"got {text[:40]!r}")
    val = int(text)
    if val < 1:
        raise DataError(f"{os.fspath(path)!r}: '# {key}' must be at least 1; got {val}")
    if at_most is not None and val > at_most:
        raise DataError(f"{os.fspath(path)!r}: '# {key}: {val}' is more than the file's contents can hold "
                        f"(at most {at_most}): the header does not match the data")
    return val


def meta_float(meta: Mapping[str, str], key: str, path: PathLike) -> float:
    """A float metadata entry, required."""
    if key not in meta:
        raise DataError(f"{os.fspath(path)!r}: the metadata line '# {key}: ...' is missing")
    try:
        return float(meta[key])
    except ValueError:
        raise DataError(f"{os.fspath(path)!r}: '# {key}' must be a number; got {meta[key]!r}") from None


def expect_width(columns: Sequence[str], expected: int, path: PathLike, rule: str) -> None:
    """Refuse a header whose number of columns is not what the metadata imply (checked before building names)."""
    if len(columns) != expected:
        raise DataError(f"{os.fspath(path)!r}: the metadata imply {expected} columns ({rule}) but the header has "
                        f"{len(columns)}: the header does not match the data")


def expect_columns(columns: Sequence[str], expected: Sequence[str], path: PathLike) -> None:
    """Raise unless the header matches ``expected`` exactly."""
    if list(columns) != list(expected):
        diff = next((k for k, (a, b) in enumerate(zip(columns, expected, strict=False)) if a != b),
                    min(len(columns), len(expected)))
        got = columns[diff] if diff < len(columns) else "(end of header)"
        want = expected[diff] if diff < len(expected) else "(end of header)"
        raise DataError(f"{os.fspath(path)!r}: unexpected CSV header: column {diff + 1} is {got!r}, "
                        f"expected {want!r} ({len(expected)} columns in all)")


def peek_kind(path: PathLike) -> tuple[str, str]:
    """The (kind, format) of a symid file: format is ``"npz"`` or ``"csv"``, sniffed from the content."""
    with open(path, "rb") as fh:
        head = fh.read(4)
    if head.startswith(b"PK"):
        return _npz_kind(_load_npz(path, ()), path), "npz"
    lines = _read_text(path)
    if not lines:
        raise DataError(f"{os.fspath(path)!r} is empty; a symid CSV or NPZ file was expected")
    kind, _ = _parse_magic(lines[0], path)
    return kind, "csv"
