"""CSV and NPZ reading and writing shared by the data containers (private).

NPZ files hold the container's arrays under their own names plus two tags, ``kind``
(the class name, a 0-d unicode array) and ``format_version`` (a 0-d integer array).
They are written through an open file handle, so the path is used exactly as given (no
``.npz`` is appended), and read with ``np.load(..., allow_pickle=False)``.

CSV files are plain UTF-8 text::

    # symid FrequencyData csv v1
    # n_outputs: 1
    # n_inputs: 1
    w,H[0][0].re,H[0][0].im
    0.5,1.2,-0.3
    ...

The first line names the kind and the format version, further ``# key: value`` lines
hold metadata (shapes, sample time), then one header line of column names and one row
per sample. Column names contain no commas (``H[0][1].re``), so no quoting is ever
needed. Floats are written with :func:`repr`, the shortest text that reads back to
the same float64, so a round trip is exact bit for bit.
"""

from __future__ import annotations

import os
import zipfile
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from symid.errors import DataError

__all__ = [
    "FORMAT_VERSION",
    "complex_from_parts",
    "expect_columns",
    "fmt",
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


def _load_npz(path: PathLike) -> dict[str, np.ndarray]:
    try:
        with np.load(path, allow_pickle=False) as npz:
            if not isinstance(npz, np.lib.npyio.NpzFile):  # pragma: no cover - np.load of a .npy
                raise DataError(f"{os.fspath(path)!r} is a single .npy array, not a symid .npz file")
            out = {}
            for key in npz.files:
                try:
                    out[key] = npz[key]
                except ValueError:
                    raise DataError(f"{os.fspath(path)!r}: array {key!r} needs pickling (object dtype); "
                                    f"symid files never do") from None
            return out
    except (zipfile.BadZipFile, EOFError, OSError) as exc:
        if isinstance(exc, FileNotFoundError | IsADirectoryError | PermissionError):
            raise
        raise DataError(f"{os.fspath(path)!r} is not a readable .npz file ({exc})") from None
    except ValueError as exc:
        raise DataError(f"{os.fspath(path)!r} is not a symid .npz file ({exc})") from None


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
    """Read a symid .npz file of ``kind``; every name in ``keys`` must be present."""
    contents = _load_npz(path)
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
    lines = [f"{_CSV_MAGIC}{kind} csv v{FORMAT_VERSION}"]
    lines += [f"# {k}: {v}" for k, v in meta.items()]
    lines.append(",".join(columns))
    lines += [",".join(r) for r in rows]
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")


def _parse_magic(line: str, path: PathLike) -> tuple[str, int]:
    parts = line.strip().split()
    # "# symid <Kind> csv v<version>"
    if len(parts) != 5 or parts[:2] != ["#", "symid"] or parts[3] != "csv" or not parts[4].startswith("v"):
        raise DataError(f"{os.fspath(path)!r} is not a symid CSV file: its first line should read "
                        f"'# symid <Kind> csv v{FORMAT_VERSION}', got {line.strip()[:80]!r}")
    try:
        version = int(parts[4][1:])
    except ValueError:
        raise DataError(f"{os.fspath(path)!r}: bad format version {parts[4]!r} on line 1") from None
    if version > FORMAT_VERSION or version < 1:
        raise DataError(f"{os.fspath(path)!r} has format version {version}; this symid reads "
                        f"version {FORMAT_VERSION} (upgrade symid?)")
    return parts[2], version


def _read_text(path: PathLike) -> list[str]:
    try:
        with open(path, encoding="utf-8") as fh:
            return fh.read().splitlines()
    except UnicodeDecodeError:
        raise DataError(f"{os.fspath(path)!r} is not a UTF-8 text file (a symid CSV was expected)") from None


def read_csv(path: PathLike, kind: str) -> tuple[dict[str, str], list[str], list[tuple[int, list[str]]]]:
    """Read a symid CSV file of ``kind``.

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
    found, _ = _parse_magic(lines[0], path)
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
    rows = []
    for j in range(i + 1, len(lines)):
        if not lines[j].strip():
            continue
        cells = [c.strip() for c in lines[j].split(",")]
        if len(cells) != len(columns):
            raise DataError(f"{os.fspath(path)!r}, line {j + 1}: {len(cells)} cells; the header has "
                            f"{len(columns)} columns")
        rows.append((j + 1, cells))
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


def meta_int(meta: Mapping[str, str], key: str, path: PathLike) -> int:
    """An integer metadata entry, required."""
    if key not in meta:
        raise DataError(f"{os.fspath(path)!r}: the metadata line '# {key}: ...' is missing")
    try:
        val = int(meta[key])
    except ValueError:
        raise DataError(f"{os.fspath(path)!r}: '# {key}' must be an integer; got {meta[key]!r}") from None
    if val < 1:
        raise DataError(f"{os.fspath(path)!r}: '# {key}' must be at least 1; got {val}")
    return val


def meta_float(meta: Mapping[str, str], key: str, path: PathLike) -> float:
    """A float metadata entry, required."""
    if key not in meta:
        raise DataError(f"{os.fspath(path)!r}: the metadata line '# {key}: ...' is missing")
    try:
        return float(meta[key])
    except ValueError:
        raise DataError(f"{os.fspath(path)!r}: '# {key}' must be a number; got {meta[key]!r}") from None


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
        return _npz_kind(_load_npz(path), path), "npz"
    lines = _read_text(path)
    if not lines:
        raise DataError(f"{os.fspath(path)!r} is empty; a symid CSV or NPZ file was expected")
    kind, _ = _parse_magic(lines[0], path)
    return kind, "csv"
