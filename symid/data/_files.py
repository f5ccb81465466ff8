"""CSV and NPZ reading and writing shared by the data containers (private).

NPZ files hold the container's arrays under their own names plus two tags, ``kind``
(the class name, a 0-d unicode array) and ``format_version`` (a 0-d integer array).
They are written with :func:`numpy.savez` (members stored, not compressed) through an
open file handle, so the path is used exactly as given (no ``.npz`` is appended).

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
bit.

Nothing in a file is trusted before the bytes that back it
----------------------------------------------------------
Only regular files are read: a directory raises :class:`IsADirectoryError`, a missing
file :class:`FileNotFoundError`, an unreadable one :class:`PermissionError` (the
``OSError`` a caller expects); a device, pipe or socket is a :class:`DataError`.

CSV
    Sizes in the metadata must be positive integers in plain decimal digits (at most
    12 of them); ``1e10``, ``-3``, ``2.0``, ``0x10`` or ``１`` are refused. The columns
    the sizes imply are compared with the header's column count, and the entries they
    imply with the number of rows present, before any array of that size is built.
    Data lines must be ASCII (no Unicode digits or spaces) without ``_`` (which
    :func:`float` would read as a digit separator).

    Version 2 (what symid writes) must hold exactly ``n_rows`` data rows and end
    with the line ``# end``: a file cut anywhere, at a line boundary or inside a
    line, is refused rather than loaded short. Version 1 files
    (no row count, no end marker) are still read when their last line is complete
    (the file ends with a newline, as every file symid wrote does); because rows lost
    from the end of such a file cannot be detected, reading a version-1
    FrequencyData, SpectralData or IOData file warns (:class:`UserWarning`, write it
    again to upgrade). A version-1 BlackBox file does not warn: every entry of its
    matrices is checked to be present.

NPZ
    The zip directory is read, never the members' contents wholesale: only the members
    the container needs are opened (plus the two tags, read first, so a file of
    another kind is refused before its arrays are touched); other members are never
    decompressed. Before any array is read, the uncompressed sizes its members declare
    must together fit :func:`npz_budget`. For each member: it must be stored or
    deflated (what :func:`numpy.savez` and :func:`numpy.savez_compressed` write; bzip2
    and lzma, whose decompressors :mod:`zipfile` does not bound, are refused) and not
    encrypted; its ``.npy`` header (at most 4096 bytes, format 1.0 or 2.0) is read from
    the stream and checked — no object, structured or zero-size item dtype, at most 3
    dimensions, none negative — and its shape × item size plus the header must equal
    the uncompressed size the zip directory declares. Then the array is allocated and
    filled 1 MiB at a time from the member; :mod:`zipfile` never returns more than the
    declared size and checks the CRC there, so a member lying about its size cannot
    make the reader allocate more than it declared. Pickles are never loaded.

    The budget is ``min(4 GiB, max(1 MiB, 32 × the file's size))`` bytes. Files symid
    writes are stored (ratio 1); the zoo's data sets saved with
    :func:`numpy.savez_compressed` shrink by 1.7 at most (float64 measurements barely
    compress; tests/test_data_untrusted_files.py checks it), so a ratio beyond 32 is a
    bomb or a degenerate file (e.g. all zeros), which reads once saved uncompressed
    (``to_npz``). A file under 1 MB thus decompresses to at most 32 MB (measured: 87 MB
    traced and 90 MB resident for the largest such file accepted, the container's own
    copies included; see the slow study in that test file); the 4 GiB ceiling bounds
    what any file, however large, can make the reader allocate.
"""

from __future__ import annotations

import errno
import io
import math
import os
import stat
import struct
import warnings
import zipfile
import zlib
from collections.abc import Mapping, Sequence
from typing import IO, Any

import numpy as np

from symid.errors import DataError

__all__ = [
    "CSV_VERSION",
    "FORMAT_VERSION",
    "NPZ_CEILING",
    "NPZ_FLOOR",
    "NPZ_RATIO",
    "complex_from_parts",
    "expect_columns",
    "expect_width",
    "fmt",
    "meta_float",
    "meta_int",
    "npz_budget",
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
"""Version of the CSV layout written (1 is still read, see the module notes)."""

NPZ_RATIO = 32
"""Most bytes the members read from an NPZ file may declare, per byte of the file."""

NPZ_FLOOR = 2**20
"""Bytes the members read from any NPZ file may always declare (1 MiB), however small the file."""

NPZ_CEILING = 4 * 2**30
"""Most bytes the members read from any NPZ file may declare (4 GiB), however large the file."""

_END = "# end"
_CSV_MAGIC = "# symid "
_NPY_MAGIC = b"\x93NUMPY"
_NPY_MAX_HEADER = 4096
_NPY_MAX_NDIM = 3
_MAX_META_DIGITS = 12
_TAG_BYTES = 4096  # a tag member (kind, format_version) is a short scalar
_CHUNK = 2**20  # bytes decompressed at a time
_ZIP_METHODS = {9: "deflate64", 12: "bzip2", 14: "lzma", 93: "zstandard"}
_ZIP_SIGNATURES = (b"PK\x03\x04", b"PK\x05\x06", b"PK\x07\x08")  # a member, an empty archive, a spanned one

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


def _where(path: PathLike) -> str:
    return repr(os.fspath(path))


def _clip(text: str, limit: int = 40) -> str:
    """``text`` cut to ``limit`` characters: a hostile value is never echoed whole."""
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def _show(text: str, limit: int = 40) -> str:
    """``repr`` of ``text``, cut to ``limit`` characters."""
    return repr(text) if len(text) <= limit else f"{text[:limit]!r}... ({len(text)} characters)"


def _open_regular(path: PathLike) -> IO[bytes]:
    """Open ``path`` for binary reading if it is a regular file.

    A directory raises :class:`IsADirectoryError`, as :func:`open` would; a device,
    pipe or socket (``/dev/zero``, a FIFO) is refused before it is opened, as reading
    one may never end or block.
    """
    name = os.fspath(path)  # TypeError for what is not a path (an int would be taken as a file descriptor)
    try:
        mode = os.stat(name).st_mode
    except ValueError:  # an embedded NUL
        raise DataError(f"{_where(path)} is not a valid file name") from None
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), name)
    if not stat.S_ISREG(mode):
        raise DataError(f"{_where(path)} is not a regular file (a device, pipe or socket); "
                        f"a symid data file was expected")
    fh = open(name, "rb")  # returned to the caller, who closes it
    if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):  # replaced between stat and open
        fh.close()
        raise DataError(f"{_where(path)} is not a regular file; a symid data file was expected")
    return fh


# -- NPZ -------------------------------------------------------------------------------

def write_npz(path: PathLike, kind: str, arrays: Mapping[str, np.ndarray]) -> None:
    """Write ``arrays`` plus the ``kind`` and ``format_version`` tags to ``path`` (exact name)."""
    payload = {"kind": np.array(kind), "format_version": np.array(FORMAT_VERSION, dtype=np.int64)}
    payload.update({k: np.asarray(v) for k, v in arrays.items()})
    with open(path, "wb") as fh:
        np.savez(fh, **payload)


def npz_budget(file_size: int) -> int:
    """Most bytes the members read from an NPZ file of ``file_size`` bytes may declare in all.

    ``min(NPZ_CEILING, max(NPZ_FLOOR, NPZ_RATIO * file_size))``: 1 MiB for any file,
    32 bytes per byte of the file beyond that, never more than 4 GiB.

    Examples
    --------
    >>> from symid.data._files import npz_budget
    >>> npz_budget(1000) == 2**20, npz_budget(10**6) == 32 * 10**6
    (True, True)
    """
    return min(NPZ_CEILING, max(NPZ_FLOOR, NPZ_RATIO * int(file_size)))


class _NpzReader:
    """The members of one open NPZ file, read one at a time under a byte budget."""

    def __init__(self, zf: zipfile.ZipFile, path: PathLike, file_size: int):
        self.zf = zf
        self.path = path
        self.file_size = file_size
        self.budget = npz_budget(file_size)
        self.left = self.budget
        self.members: dict[str, zipfile.ZipInfo] = {}
        for info in zf.infolist():
            name = info.filename.removesuffix(".npy")
            if info.filename.endswith(".npy") and name in self.members:
                raise DataError(f"{_where(path)} holds two members named {info.filename!r}: the file is damaged "
                                f"or not a symid file")
            if info.filename.endswith(".npy"):
                self.members[name] = info

    def _fail(self, name: str, what: str) -> DataError:
        return DataError(f"{_where(self.path)}: array {name!r} {what}: the file is damaged or not a symid file")

    def _check_entry(self, name: str, info: zipfile.ZipInfo, limit: int | None) -> int:
        """The zip directory's claims about a member, checked before it is opened; returns its byte cap."""
        if info.flag_bits & 0x1:
            raise self._fail(name, "is encrypted")
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            method = _ZIP_METHODS.get(info.compress_type, f"zip method {info.compress_type}")
            raise self._fail(name, f"is compressed with {method} (symid reads stored or deflated members, as "
                                   f"numpy.savez and savez_compressed write)")
        if info.compress_size > self.file_size:
            raise self._fail(name, f"declares {info.compress_size} compressed bytes in a file of {self.file_size}")
        if info.compress_type == zipfile.ZIP_STORED and info.compress_size != info.file_size:
            raise self._fail(name, f"is stored uncompressed but declares {info.file_size} bytes in "
                                   f"{info.compress_size}")
        if limit is not None and info.file_size > limit:
            raise self._fail(name, f"declares {info.file_size} bytes uncompressed; a tag is a scalar of at most "
                                   f"{limit}")
        return self.left if limit is None else min(limit, self.left)

    def _header(self, name: str, fh: IO[bytes]) -> tuple[int, tuple[int, ...], bool, np.dtype]:
        """The ``.npy`` header of a member stream: (bytes it takes, shape, fortran order, dtype)."""
        magic = fh.read(len(_NPY_MAGIC) + 2)
        if len(magic) != len(_NPY_MAGIC) + 2 or not magic.startswith(_NPY_MAGIC):
            raise self._fail(name, "has no valid .npy header (wrong magic string)")
        version = (magic[-2], magic[-1])
        if version not in ((1, 0), (2, 0)):
            raise self._fail(name, f"has .npy format version {version[0]}.{version[1]} (symid reads 1.0 and 2.0)")
        length_format = "<H" if version == (1, 0) else "<I"
        prefix = fh.read(struct.calcsize(length_format))
        if len(prefix) != struct.calcsize(length_format):
            raise self._fail(name, "has a truncated .npy header")
        (length,) = struct.unpack(length_format, prefix)
        if length > _NPY_MAX_HEADER:
            raise self._fail(name, f"declares a .npy header of {length} bytes (symid's are under "
                                   f"{_NPY_MAX_HEADER})")
        text = fh.read(length)
        if len(text) != length:
            raise self._fail(name, "has a truncated .npy header")
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # numpy's note about headers written by Python 2
                shape, fortran, dtype = read(io.BytesIO(prefix + text), max_header_size=_NPY_MAX_HEADER)
        except (ValueError, SyntaxError, TypeError, RecursionError) as exc:
            raise self._fail(name, f"has no valid .npy header ({str(exc)[:100]})") from None
        return len(magic) + len(prefix) + length, tuple(shape), bool(fortran), dtype

    def reserve(self, names: Sequence[str]) -> None:
        """Refuse, before reading any of them, arrays that together declare more than the budget left."""
        total = sum(self.members[k].file_size for k in names)
        if total > self.left:
            sizes = ", ".join(f"{k} {self.members[k].file_size}" for k in names)
            raise DataError(f"{_where(self.path)}: its arrays declare {total} bytes uncompressed ({sizes}), more than "
                            f"the {self.left} that this {self.file_size}-byte file may declare (max(1 MiB, "
                            f"{NPZ_RATIO} × its size), at most 4 GiB; a zip bomb?): the file is damaged or not a symid "
                            f"file")

    def read(self, name: str, limit: int | None = None) -> np.ndarray:
        """The array ``name``, after every check: a tag with its ``limit``, an array once :meth:`reserve` d."""
        info = self.members[name]
        cap = self._check_entry(name, info, limit)
        with self.zf.open(info) as fh:
            header, shape, fortran, dtype = self._header(name, fh)
            if dtype.hasobject:
                raise self._fail(name, "has object dtype, which needs pickling; symid files never do")
            if dtype.fields is not None or dtype.subdtype is not None or dtype.kind == "V":
                raise self._fail(name, f"has structured dtype {dtype}")
            if dtype.itemsize == 0:
                raise self._fail(name, f"has dtype {dtype} of zero-size items")
            if len(shape) > _NPY_MAX_NDIM or any(d < 0 for d in shape):
                raise self._fail(name, f"declares shape {shape} (symid arrays have at most {_NPY_MAX_NDIM} "
                                       f"dimensions, none negative)")
            if math.prod(max(d, 1) for d in shape) * dtype.itemsize > cap:  # even a zero-size array's dimensions
                raise self._fail(name, f"declares shape {shape} of {dtype}, more than the {cap} bytes allowed")
            nbytes = math.prod(shape) * dtype.itemsize
            if header + nbytes != info.file_size:
                raise self._fail(name, f"declares shape {shape} of {dtype} ({nbytes} bytes) in its .npy header, "
                                       f"but its zip entry declares {info.file_size - header} bytes of data")
            self.left -= info.file_size
            arr = np.empty(math.prod(shape), dtype=dtype)
            raw = arr.view(np.uint8)
            done = 0
            while done < nbytes:  # in chunks, straight into the array: no second copy of the member
                chunk = fh.read(min(_CHUNK, nbytes - done))
                if not chunk:
                    break
                raw[done:done + len(chunk)] = np.frombuffer(chunk, dtype=np.uint8)
                done += len(chunk)
            if done != nbytes or fh.read(1):  # zipfile stops at the declared size and checks the CRC there
                raise self._fail(name, f"holds {done} bytes of data or more; its header declares {nbytes}")
        return arr.reshape(shape, order="F" if fortran else "C")

    def kind(self) -> str:
        """The ``kind`` tag, after the ``format_version`` tag is checked."""
        if "kind" not in self.members or "format_version" not in self.members:
            found = sorted(self.members)
            listed = ", ".join(_clip(n) for n in found[:10])
            listed += f" and {len(found) - 10} more" if len(found) > 10 else ""
            raise DataError(f"{_where(self.path)} is not a symid data file: the 'kind' and 'format_version' "
                            f"entries are missing (found {listed or 'nothing'})")
        version = self.read("format_version", _TAG_BYTES)
        if version.dtype.kind not in "iu" or version.ndim != 0:
            raise DataError(f"{_where(self.path)}: 'format_version' must be an integer scalar; got "
                            f"{version.dtype} of shape {version.shape}")
        if int(version) > FORMAT_VERSION or int(version) < 1:
            raise DataError(f"{_where(self.path)} has format version {int(version)}; this symid reads "
                            f"version {FORMAT_VERSION} (upgrade symid?)")
        kind = self.read("kind", _TAG_BYTES)
        if kind.dtype.kind != "U" or kind.ndim != 0:
            raise DataError(f"{_where(self.path)}: 'kind' must be a text scalar; got {kind.dtype} of shape "
                            f"{kind.shape}")
        return str(kind[()])


# what zipfile, zlib and struct raise on a damaged archive (an OSError here is a bad seek or read, not access)
_ZIP_ERRORS = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, EOFError, OSError, OverflowError, struct.error,
               NotImplementedError, RuntimeError, ValueError, KeyError)


def _with_npz(path: PathLike, use: Any) -> Any:
    """Call ``use(reader)`` on an :class:`_NpzReader` of the file at ``path``, mapping zip failures to DataError."""
    with _open_regular(path) as fh:
        size = os.fstat(fh.fileno()).st_size
        head = fh.read(len(_NPY_MAGIC))
        if head == _NPY_MAGIC:
            raise DataError(f"{_where(path)} is a single .npy array (numpy.save), not a symid .npz file")
        if head.startswith(_CSV_MAGIC.encode()[:6]):
            raise DataError(f"{_where(path)} is a CSV file, not an .npz file; use from_csv or symid.data.load")
        try:
            fh.seek(0)
            with zipfile.ZipFile(fh) as zf:
                return use(_NpzReader(zf, path, size))
        except DataError:
            raise
        except _ZIP_ERRORS as exc:
            raise DataError(f"{_where(path)} is not a readable .npz file ({type(exc).__name__}: "
                            f"{str(exc)[:100]}): the file is damaged or not a symid file") from None


def read_npz(path: PathLike, kind: str, keys: Sequence[str], *, optional: Sequence[str] = ()
             ) -> dict[str, np.ndarray]:
    """Read the arrays ``keys`` of a symid .npz file of ``kind``, and those of ``optional`` it holds
    (other members are not read).

    Raises
    ------
    DataError
        If the file is not a symid NPZ file of ``kind``, lacks one of ``keys``, or a
        member fails a check of the module notes.
    FileNotFoundError, IsADirectoryError, PermissionError
        If the file cannot be opened.
    """
    def use(reader: _NpzReader) -> dict[str, np.ndarray]:
        found = reader.kind()
        if found != kind:
            raise DataError(f"{_where(path)} holds {_clip(found)}, not {kind}; use "
                            f"{_clip(found)}.from_npz or symid.data.load")
        missing = [k for k in keys if k not in reader.members]
        if missing:
            raise DataError(f"{_where(path)}: the {kind} file lacks the array(s) {', '.join(missing)}")
        wanted = [*keys, *(k for k in optional if k in reader.members)]
        reader.reserve(wanted)
        return {k: reader.read(k) for k in wanted}

    return _with_npz(path, use)


# -- CSV -------------------------------------------------------------------------------

def write_csv(path: PathLike, kind: str, meta: Mapping[str, Any], columns: Sequence[str],
              rows: Sequence[Sequence[str]]) -> None:
    """Write a symid CSV file: magic line, ``# key: value`` metadata, header, rows, end marker."""
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
        raise DataError(f"{_where(path)} is not a symid CSV file: its first line should read "
                        f"'# symid <Kind> csv v{CSV_VERSION}', got {_show(line.strip(), 80)}")
    digits = parts[4][1:]
    if not (digits.isascii() and digits.isdigit()) or len(digits) > 3:
        raise DataError(f"{_where(path)}: bad format version {_show(parts[4])} on line 1")
    version = int(digits)
    if version > CSV_VERSION or version < 1:
        raise DataError(f"{_where(path)} has format version {version}; this symid reads "
                        f"versions 1 to {CSV_VERSION} (upgrade symid?)")
    return parts[2], version


def _read_text(path: PathLike) -> str:
    with _open_regular(path) as fh:
        raw = fh.read()
    if raw.startswith(_ZIP_SIGNATURES):
        raise DataError(f"{_where(path)} is a zip (NPZ) file, not a CSV file; use from_npz or symid.data.load")
    if raw.startswith(_NPY_MAGIC):
        raise DataError(f"{_where(path)} is a single .npy array (numpy.save), not a symid CSV file")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataError(f"{_where(path)} is not a UTF-8 text file (byte {exc.start} is not UTF-8); a symid CSV "
                        f"file was expected") from None


def read_csv(path: PathLike, kind: str, *, complete_by_content: bool = False, meta_keys: Sequence[str] | None = None
             ) -> tuple[dict[str, str], list[str], list[tuple[int, str]]]:
    """Read a symid CSV file of ``kind``, refusing one that is cut short (rules in the module notes).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    kind : str
        The class name expected on the first line.
    complete_by_content : bool
        Whether the caller checks itself that no row is missing (BlackBox: every entry
        once); a version-1 file then reads without a warning.
    meta_keys : sequence of str, optional
        The metadata keys the kind has (``n_rows`` besides); any other ``# key: value``
        line is refused, never ignored (``# units: Hz`` would otherwise pass unread).

    Returns
    -------
    meta : dict of str
        The ``# key: value`` metadata.
    columns : list of str
        The header's column names.
    rows : list of (line number, text)
        The data rows, one-based line numbers for messages, each with exactly
        ``len(columns)`` comma-separated cells; blank lines are skipped.
    """
    text = _read_text(path)
    lines = text.splitlines()
    if not lines:
        raise DataError(f"{_where(path)} is empty; a symid CSV file was expected")
    found, version = _parse_magic(lines[0], path)
    if found != kind:
        raise DataError(f"{_where(path)} holds {_clip(found)}, not {kind}; use {_clip(found)}.from_csv "
                        f"or symid.data.load")
    meta: dict[str, str] = {}
    i = 1
    while i < len(lines) and lines[i].startswith("#"):
        body = lines[i][1:].strip()
        if ":" in body:
            key, _, value = body.partition(":")
            if key.strip() in meta:
                raise DataError(f"{_where(path)}, line {i + 1}: the metadata '# {_clip(key.strip())}' "
                                f"is given twice")
            if meta_keys is not None and key.strip() not in (*meta_keys, "n_rows"):
                raise DataError(f"{_where(path)}, line {i + 1}: unknown metadata '# {_clip(key.strip())}': a symid "
                                f"{kind} file carries {', '.join((*meta_keys, 'n_rows'))} and nothing else, so this "
                                f"line would be ignored; remove it (frequencies here are rad/s), or read a table "
                                f"of your own with {kind}.from_table(..., columns=..., units=...)")
            meta[key.strip()] = value.strip()
        i += 1
    if i >= len(lines):
        raise DataError(f"{_where(path)}: the header line of column names is missing")
    columns = [c.strip() for c in lines[i].split(",")]
    last = len(lines)
    if version >= 2:
        while last > i + 1 and not lines[last - 1].strip():
            last -= 1
        if last == i + 1 or lines[last - 1].strip() != _END:
            raise DataError(f"{_where(path)} does not end with the line '{_END}': the file was cut short "
                            f"(or edited); it is refused rather than read incompletely")
        last -= 1
    elif not text.endswith(("\n", "\r")):
        raise DataError(f"{_where(path)}: its last line is incomplete (no newline at the end): the file was cut "
                        f"short; it is refused rather than read incompletely")
    elif not complete_by_content:
        warnings.warn(f"{_where(path)} is a version-1 symid CSV file: it carries no row count, so a file that "
                      f"lost rows at its end cannot be told from a complete one; write it again (to_csv) to get "
                      f"version {CSV_VERSION}", UserWarning, stacklevel=3)
    rows = []
    # the non-blank lines, found without a Python object per blank line: a file of a million blank lines took
    # 7.5 s in a per-line loop under tracemalloc (its integers), the test's bound being 10 s
    data = lines[i + 1:last]
    filled = np.flatnonzero(np.fromiter(map(bool, map(str.strip, data)), dtype=bool, count=len(data)))
    for j in (filled + i + 1).tolist():
        line = lines[j]
        if line.startswith("#"):
            raise DataError(f"{_where(path)}, line {j + 1}: a comment line among the data rows")
        if not line.isascii() or "_" in line:
            raise DataError(f"{_where(path)}, line {j + 1}: data must be ASCII numbers without '_'; "
                            f"got {_show(line)}")
        cells = line.count(",") + 1
        if cells != len(columns):
            raise DataError(f"{_where(path)}, line {j + 1}: {cells} cells; the header has {len(columns)} columns")
        rows.append((j + 1, line))
    if version >= 2:
        declared = meta_int(meta, "n_rows", path, at_most=len(rows) + 1)
        if declared != len(rows):
            raise DataError(f"{_where(path)} declares {declared} data rows ('# n_rows') but holds "
                            f"{len(rows)}: the file is damaged")
    return meta, columns, rows


def parse_float_rows(rows: Sequence[tuple[int, str]], path: PathLike, n_columns: int) -> np.ndarray:
    """The cells of ``rows`` (as :func:`read_csv` returns them) as a float64 array (len(rows), n_columns)."""
    out = np.empty((len(rows), n_columns), dtype=np.float64)
    for r, (line, text) in enumerate(rows):
        for c, cell in enumerate(text.split(",")):
            try:
                out[r, c] = float(cell)
            except ValueError:
                raise DataError(f"{_where(path)}, line {line}, column {c + 1}: {_show(cell.strip())} is not a "
                                f"number") from None
    return out


def meta_int(meta: Mapping[str, str], key: str, path: PathLike, *, at_most: int | None = None) -> int:
    """A positive integer metadata entry, required, written in plain digits, at most ``at_most``.

    ``at_most`` is what the bytes present can back (e.g. the number of columns), so a
    header claiming more is refused before anything of that size is built.
    """
    if key not in meta:
        raise DataError(f"{_where(path)}: the metadata line '# {key}: ...' is missing")
    text = meta[key]
    if not (text.isascii() and text.isdigit()):
        raise DataError(f"{_where(path)}: '# {key}' must be a positive integer written in digits; "
                        f"got {_show(text)}")
    if len(text) > _MAX_META_DIGITS:
        raise DataError(f"{_where(path)}: '# {key}: {_clip(text)}' is too large (more than "
                        f"{_MAX_META_DIGITS} digits): the file is damaged or not a symid file")
    val = int(text)
    if val < 1:
        raise DataError(f"{_where(path)}: '# {key}' must be at least 1; got {val}")
    if at_most is not None and val > at_most:
        raise DataError(f"{_where(path)}: '# {key}: {val}' is more than the file's contents can hold "
                        f"(at most {at_most}): the header does not match the data")
    return val


def meta_float(meta: Mapping[str, str], key: str, path: PathLike) -> float:
    """A float metadata entry, required (range checks are the constructor's)."""
    if key not in meta:
        raise DataError(f"{_where(path)}: the metadata line '# {key}: ...' is missing")
    text = meta[key]
    try:
        if not text.isascii() or "_" in text:
            raise ValueError(text)
        return float(text)
    except ValueError:
        raise DataError(f"{_where(path)}: '# {key}' must be a number; got {_show(text)}") from None


def expect_width(columns: Sequence[str], expected: int, path: PathLike, rule: str) -> None:
    """Refuse a header whose number of columns is not what the metadata imply (checked before building names)."""
    if len(columns) != expected:
        raise DataError(f"{_where(path)}: the metadata imply {expected} columns ({rule}) but the header has "
                        f"{len(columns)}: the header does not match the data")


def expect_columns(columns: Sequence[str], expected: Sequence[str], path: PathLike) -> None:
    """Raise unless the header matches ``expected`` exactly."""
    if list(columns) != list(expected):
        diff = next((k for k, (a, b) in enumerate(zip(columns, expected, strict=False)) if a != b),
                    min(len(columns), len(expected)))
        got = _show(columns[diff]) if diff < len(columns) else "(end of header)"
        want = expected[diff] if diff < len(expected) else "(end of header)"
        raise DataError(f"{_where(path)}: unexpected CSV header: column {diff + 1} is {got}, "
                        f"expected {want!r} ({len(expected)} columns in all)")


def peek_kind(path: PathLike) -> tuple[str, str]:
    """The (kind, format) of a symid file: format is ``"npz"`` or ``"csv"``, sniffed from the content.

    Only the first line of a CSV file and the two tags of an NPZ file are read.
    """
    with _open_regular(path) as fh:
        head = fh.read(256)
    if not head:
        raise DataError(f"{_where(path)} is empty; a symid CSV or NPZ file was expected")
    if head.startswith(_ZIP_SIGNATURES):
        return _with_npz(path, _NpzReader.kind), "npz"
    if head.startswith(_NPY_MAGIC):
        raise DataError(f"{_where(path)} is a single .npy array (numpy.save), not a symid CSV or NPZ file")
    first = head.split(b"\n", 1)[0]
    try:
        # a first line longer than what was read is no symid magic line: never mind a character cut in two
        line = first.decode("utf-8", errors="strict" if len(first) < len(head) or len(head) < 256 else "replace")
    except UnicodeDecodeError:
        raise DataError(f"{_where(path)} is not a UTF-8 text file, nor a zip (NPZ) file; a symid CSV or NPZ "
                        f"file was expected") from None
    kind, _ = _parse_magic(line, path)
    return kind, "csv"
