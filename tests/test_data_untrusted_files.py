"""A file's header is never trusted before its content (issue 12, item 3).

Hostile CSV and NPZ files are generated for every data class; each must be refused with a
:class:`DataError` (or, for a file that cannot be opened, the ``OSError`` a caller
expects) quickly and in bounded memory, whatever it declares; a file cut short is
refused, never loaded short. The rules are in the notes of ``symid/data/_files.py``.

Time and memory per case are bounded generously here (10 s, 200 MB traced by
:mod:`tracemalloc`, which numpy reports its array allocations to) for a shared machine;
the measured figures come from the slow study at the end, run with::

    pytest -m slow -s tests/test_data_untrusted_files.py
"""

from __future__ import annotations

import io
import json
import os
import re
import struct
import subprocess
import sys
import time
import tracemalloc
import warnings
import zipfile
import zlib
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np
import pytest

import symid as si
from symid.data import BlackBox, FrequencyData, IOData, SpectralData, _files, load
from symid.errors import DataError

SECONDS = 10.0  # generous: the slow study measures a few milliseconds per case
BYTES = 200 * 2**20

RNG = np.random.default_rng(7)
SAMPLES = {
    "FrequencyData": FrequencyData([0.5, 1.0, 2.0], RNG.standard_normal((3, 2, 1)) + 1j),
    "SpectralData": SpectralData([1.0, 2.0], [[[2.0, 0.5j], [-0.5j, 1.0]]] * 2, [1.0, 3.0]),
    "IOData": IOData(RNG.standard_normal((6, 2)), RNG.standard_normal(6), 0.1),
    "BlackBox": BlackBox([[0.0, 1.0], [-2.0, -0.5]], [0.0, 1.0], [[1.0, 0.0]], [[0.25]]),
}
KINDS = list(SAMPLES)
CLASSES = {kind: type(obj) for kind, obj in SAMPLES.items()}
SIZE_KEYS = {
    "FrequencyData": ("n_outputs", "n_inputs", "n_rows"),
    "SpectralData": ("n_outputs", "n_inputs", "n_rows"),
    "IOData": ("n_inputs", "n_outputs", "n_rows"),
    "BlackBox": ("n_states", "n_inputs", "n_outputs", "n_rows"),
}
BAD_SIZES = ["20000", "1e10", "-3", "0", "2.0", "0x10", "9" * 40, "10000000000", "\uff11", "", "two", "+2", "1 2"]


def _measured(call: Callable[[], Any]) -> tuple[BaseException | None, Any, float, int]:
    """(exception raised or None, result, seconds, peak traced bytes) of ``call()``."""
    tracemalloc.start()
    t0 = time.perf_counter()
    exc, result = None, None
    try:
        result = call()
    except Exception as caught:  # returned for the caller's assertions
        exc = caught
    finally:
        seconds = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return exc, result, seconds, peak


def _refused(call: Callable[[], Any], match: str | None = None, error: type[BaseException] = DataError) -> str:
    """Assert ``call()`` raises ``error`` (message matching ``match``) within the time and memory bounds."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a hostile version-2 file is refused, not read with a warning
        exc, result, seconds, peak = _measured(call)
    assert isinstance(exc, error), f"expected {error.__name__}, got {exc!r} (result {result!r})"
    if match is not None:
        assert re.search(match, str(exc)), str(exc)
    assert seconds < SECONDS, seconds
    assert peak < BYTES, peak
    return str(exc)


def _refused_by_both(path: os.PathLike, kind: str, fmt: str, match: str | None = None) -> None:
    """Refused by the class's own reader and by :func:`symid.data.load`."""
    _refused(lambda: getattr(CLASSES[kind], f"from_{fmt}")(path), match)
    _refused(lambda: load(path), match)


# -- CSV ---------------------------------------------------------------------------------------------

def _csv_text(kind: str, tmp_path) -> str:
    path = tmp_path / "sample.csv"
    SAMPLES[kind].to_csv(path)
    return path.read_text()


def _rows(text: str) -> tuple[list[str], int, int]:
    """The lines, the index of the first data row and the index of the end marker."""
    lines = text.splitlines(keepends=True)
    first = next(i for i, line in enumerate(lines) if not line.startswith("#")) + 1
    return lines, first, len(lines) - 1


def test_the_reported_case_a_102_byte_blackbox_claiming_20000_states(tmp_path):
    path = tmp_path / "bb.csv"
    path.write_text("# symid BlackBox csv v2\n# n_states: 20000\n# n_inputs: 1\n# n_outputs: 1\n# n_rows: 1\n"
                    "matrix,row,col,value\nA,0,0,1.0\n# end\n")
    _refused_by_both(path, "BlackBox", "csv", r"'# n_states: 20000' is more than the file's contents can hold")


@pytest.mark.parametrize("value", BAD_SIZES, ids=[repr(v) for v in BAD_SIZES])
@pytest.mark.parametrize("kind", KINDS)
def test_declared_sizes_must_be_plain_integers_backed_by_the_content(kind, value, tmp_path):
    text = _csv_text(kind, tmp_path)
    path = tmp_path / "x.csv"
    for key in SIZE_KEYS[kind]:
        damaged = re.sub(rf"^# {key}: .*$", f"# {key}: {value}", text, count=1, flags=re.M)
        assert damaged != text
        path.write_text(damaged, encoding="utf-8")
        message = _refused(lambda: CLASSES[kind].from_csv(path))
        assert f"'# {key}" in message and value[:12] in message, message  # names the key and the value


@pytest.mark.parametrize("kind", KINDS)
def test_sizes_that_disagree_with_the_columns_or_rows(kind, tmp_path):
    text = _csv_text(kind, tmp_path)
    path = tmp_path / "x.csv"
    key = SIZE_KEYS[kind][0]
    value = int(re.search(rf"^# {key}: (\d+)$", text, flags=re.M).group(1))
    for wrong in (value + 1, 3 * value + 2):
        path.write_text(text.replace(f"# {key}: {value}\n", f"# {key}: {wrong}\n"))
        _refused_by_both(path, kind, "csv", r"imply \d+ columns|entries, but holds|more than the file's contents")


def _replaced(lines: list[str], k: int, new: list[str]) -> list[str]:
    """``lines`` with line ``k`` replaced by the lines ``new`` (none to drop it)."""
    return [*lines[:k], *new, *lines[k + 1:]]


CSV_DAMAGE = {  # (lines, index of the first data row, index of the end marker) -> damaged lines; phrase
    # a file cut short, anywhere
    "last row missing": (lambda L, a, e: _replaced(L, e - 1, []), r"declares \d+ data rows \('# n_rows'\) but holds"),
    "first row missing": (lambda L, a, e: _replaced(L, a, []), r"declares \d+ data rows"),
    "end marker missing": (lambda L, a, e: L[:e], r"does not end with the line '# end'"),
    "cut inside the last row": (lambda L, a, e: [*L[:e - 1], L[e - 1][:3]], r"does not end with the line"),
    "only the header": (lambda L, a, e: [*L[:a], *L[e:]], r"'# n_rows: \d+' is more than the file's contents"),
    # more than declared
    "a row too many": (lambda L, a, e: _replaced(L, e - 1, [L[e - 1]] * 2), r"declares \d+ data rows"),
    "an extra column in one row": (lambda L, a, e: _replaced(L, a, [L[a].rstrip("\n") + ",1.0\n"]),
                                   r"line \d+: \d+ cells; the header has"),
    "an extra column everywhere": (lambda L, a, e: [*L[:a - 1], *(x.rstrip("\n") + ",1.0\n" for x in L[a - 1:e]),
                                                    *L[e:]], r"imply \d+ columns|unexpected CSV header"),
    "a cell missing": (lambda L, a, e: _replaced(L, a, [L[a].rsplit(",", 1)[0] + "\n"]), r"cells; the header has"),
    "text after the end marker": (lambda L, a, e: [*L, L[a]], r"does not end with the line '# end'"),
    # not what symid writes
    "a comment among the rows": (lambda L, a, e: _replaced(L, a, ["# note\n", L[a]]),
                                 r"a comment line among the data rows"),
    "metadata given twice": (lambda L, a, e: _replaced(L, 1, [L[1]] * 2), r"is given twice"),
    "row count missing": (lambda L, a, e: [x for x in L if not x.startswith("# n_rows")],
                          r"'# n_rows: \.\.\.' is missing"),
    "header missing": (lambda L, a, e: L[:a - 1], r"header line of column names is missing"),
    "unicode digit": (lambda L, a, e: _replaced(L, a, [re.sub(r"\d", "\u0660", L[a], count=1)]), r"must be ASCII"),
    "digit separator": (lambda L, a, e: _replaced(L, a, [L[a].replace(".", "_", 1)]), r"without '_'"),
    "a word for a number": (lambda L, a, e: _replaced(L, a, [L[a].replace(L[a].split(",")[-1], "abc\n")]),
                            r"is not a number|must be integers"),
    "NUL in a row": (lambda L, a, e: _replaced(L, a, [L[a].replace(",", ",\x00", 1)]),
                     r"is not a number|must be integers"),
    "newer version": (lambda L, a, e: _replaced(L, 0, [L[0].replace("v2", "v3")]), r"format version 3"),
    "version in words": (lambda L, a, e: _replaced(L, 0, [L[0].replace("v2", "vtwo")]), r"bad format version 'vtwo'"),
    "another kind": (lambda L, a, e: _replaced(L, 0, [L[0].replace("# symid ", "# symid Other")]), r"holds Other"),
}


@pytest.mark.parametrize("damage", list(CSV_DAMAGE))
@pytest.mark.parametrize("kind", KINDS)
def test_damaged_csv_files_are_refused(kind, damage, tmp_path):
    lines, first, end = _rows(_csv_text(kind, tmp_path))
    make, phrase = CSV_DAMAGE[damage]
    path = tmp_path / "x.csv"
    path.write_text("".join(make(lines, first, end)), encoding="utf-8")
    _refused(lambda: CLASSES[kind].from_csv(path), phrase)


@pytest.mark.parametrize("kind", KINDS)
def test_a_csv_cut_at_any_byte_is_refused(kind, tmp_path):
    raw = _csv_text(kind, tmp_path).encode()
    path = tmp_path / "cut.csv"
    for cut in range(len(raw) - 1):  # dropping only the final newline leaves the file complete
        path.write_bytes(raw[:cut])
        _refused(lambda: CLASSES[kind].from_csv(path))
    path.write_bytes(raw[:-1])
    assert CLASSES[kind].from_csv(path) == SAMPLES[kind]


def _as_version_1(text: str) -> str:
    lines = [x for x in text.splitlines(keepends=True) if not x.startswith(("# n_rows", "# end"))]
    return "".join(lines).replace("csv v2", "csv v1", 1)


@pytest.mark.parametrize("kind", ["FrequencyData", "SpectralData", "IOData"])
def test_version_1_files_are_read_with_a_warning_when_their_last_line_is_complete(kind, tmp_path):
    path = tmp_path / "old.csv"
    text = _as_version_1(_csv_text(kind, tmp_path))
    path.write_text(text)
    with pytest.warns(UserWarning, match="version-1 symid CSV file: it carries no row count"):
        assert CLASSES[kind].from_csv(path) == SAMPLES[kind]
    path.write_text(text[:-4])  # cut inside the last row: its last value would read short
    _refused(lambda: CLASSES[kind].from_csv(path), r"last line is incomplete \(no newline at the end\)")


def test_a_version_1_blackbox_is_checked_entry_by_entry_without_a_warning(tmp_path):
    path = tmp_path / "old.csv"
    text = _as_version_1(_csv_text("BlackBox", tmp_path))
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert BlackBox.from_csv(path) == SAMPLES["BlackBox"]
    path.write_text("".join(text.splitlines(keepends=True)[:-1]))  # the last entry lost at a line boundary
    _refused(lambda: BlackBox.from_csv(path), r"i\.e\. 9 entries, but holds 8 rows")


def _megabyte_lie(kind: str, tmp_path, body: Callable[[list[str], int, int], str]) -> os.PathLike:
    lines, first, end = _rows(_csv_text(kind, tmp_path))
    path = tmp_path / "big.csv"
    path.write_text(body(lines, first, end))
    assert 2**20 <= path.stat().st_size < 1.1e6
    return path


def test_a_megabyte_of_rows_under_a_header_declaring_a_few(tmp_path):
    # refused by read_csv, whatever the kind: BlackBox is the kind that allocated 16 GB for a 102-byte file
    path = _megabyte_lie("BlackBox", tmp_path, lambda L, a, e: "".join(L[:e]) + L[a] * (2**20 // len(L[a])) + L[e])
    _refused(lambda: BlackBox.from_csv(path), r"declares 9 data rows \('# n_rows'\) but holds \d{5}")


def test_a_megabyte_of_blank_lines(tmp_path):  # a million lines: 0.15 s under tracemalloc (7.5 s per-line loop)
    path = _megabyte_lie("FrequencyData", tmp_path, lambda L, a, e: "".join(L[:a]) + "\n" * 2**20 + L[e])
    _refused(lambda: FrequencyData.from_csv(path), r"'# n_rows: 3' is more than the file's contents can hold")


MEGABYTE_LIES = {
    "one row of half a million cells": (lambda L, a, e: "".join(L[:a]) + "1," * 2**19 + "\n" + L[e],
                                        r"524289 cells; the header has"),
    "one row of a million NULs": (lambda L, a, e: "".join(L[:a]) + "\x00" * 2**20 + "\n" + L[e],
                                  r"1 cells; the header has"),
    "a header of a million columns": (lambda L, a, e: "".join(L[:a - 1]) + "," * 2**20 + "\n" + "".join(L[a:]),
                                      r"the header has 1048577 columns"),
    "a row count of a million digits": (lambda L, a, e: re.sub(r"^# n_rows: \d+$", "# n_rows: " + "1" * 2**20,
                                                               "".join(L), flags=re.M),
                                        r"'# n_rows: 1{40}\.\.\. \(1048576 characters\)' is too large"),
    "a first line of a megabyte": (lambda L, a, e: "# symid " + "X" * 2**20 + " csv v2\n" + "".join(L[1:]),
                                   r"is not a symid CSV file|holds X{40}\.\.\. \(1048576 characters\)"),
}


@pytest.mark.parametrize("lie", list(MEGABYTE_LIES))
@pytest.mark.parametrize("kind", KINDS)
def test_megabyte_csv_files_that_lie(kind, lie, tmp_path):
    body, phrase = MEGABYTE_LIES[lie]
    path = _megabyte_lie(kind, tmp_path, body)
    message = _refused(lambda: CLASSES[kind].from_csv(path), phrase)
    assert len(message) < 500  # a hostile value is never echoed whole
    _refused(lambda: load(path), phrase)


# -- files that are not CSV or NPZ, or not files ----------------------------------------------------

JUNK = {
    "empty": b"",
    "zero bytes": bytes(2**20),
    "random bytes": np.random.default_rng(3).integers(0, 256, 2**20, dtype=np.uint8).tobytes(),
    "invalid UTF-8": b"# symid FrequencyData csv v2\n\xff\xfe\n",
    "UTF-16 text": "# symid FrequencyData csv v2\n".encode("utf-16"),
    "a .npy array": b"",  # filled in by the test (numpy.save)
    "a zip of text": b"",  # filled in by the test
    "an empty zip": b"PK\x05\x06" + bytes(18),
    "zip signature only": b"PK\x03\x04 this is not a zip",
}


@pytest.mark.parametrize("name", list(JUNK))
@pytest.mark.parametrize("fmt", ["csv", "npz"])
def test_junk_is_refused_by_every_reader(name, fmt, tmp_path):
    path = tmp_path / f"junk.{fmt}"
    if name == "a .npy array":
        with open(path, "wb") as fh:
            np.save(fh, np.ones(3))
    elif name == "a zip of text":
        with zipfile.ZipFile(path, "w") as zf:
            zf.writestr("readme.txt", "hello")
    else:
        path.write_bytes(JUNK[name])
    for cls in CLASSES.values():
        _refused(lambda cls=cls: getattr(cls, f"from_{fmt}")(path))
    _refused(lambda: load(path))


def test_the_wrong_format_is_named(tmp_path):
    csv, npz, npy = tmp_path / "a.csv", tmp_path / "a.npz", tmp_path / "a.npy"
    SAMPLES["IOData"].to_csv(csv)
    SAMPLES["IOData"].to_npz(npz)
    with open(npy, "wb") as fh:
        np.save(fh, np.ones(3))
    _refused(lambda: IOData.from_npz(csv), r"is a CSV file, not an \.npz file; use from_csv")
    _refused(lambda: IOData.from_csv(npz), r"is a zip \(NPZ\) file, not a CSV file; use from_npz")
    for reader in (IOData.from_npz, IOData.from_csv, load):
        _refused(lambda reader=reader: reader(npy), r"is a single \.npy array \(numpy\.save\)")


def test_paths_that_are_not_regular_files(tmp_path, monkeypatch):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)  # reading one would block: refused before it is opened
    for reader in (FrequencyData.from_csv, FrequencyData.from_npz, load):
        _refused(lambda reader=reader: reader(fifo), "is not a regular file")
        _refused(lambda reader=reader: reader("/dev/zero"), "is not a regular file")  # would never end
        _refused(lambda reader=reader: reader(tmp_path), error=IsADirectoryError)
        _refused(lambda reader=reader: reader(tmp_path / "missing"), error=FileNotFoundError)
        _refused(lambda reader=reader: reader("bad\x00name"), "is not a valid file name")
    path = tmp_path / "locked.csv"
    SAMPLES["FrequencyData"].to_csv(path)

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(_files, "open", refuse, raising=False)  # as root, chmod 000 does not stop a read
    for reader in (FrequencyData.from_csv, FrequencyData.from_npz, load):
        _refused(lambda reader=reader: reader(path), error=PermissionError)


# -- NPZ ----------------------------------------------------------------------------------------------

def _npy(arr: Any) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asarray(arr), allow_pickle=False)
    return buf.getvalue()


def _npy_header(shape: Any, descr: Any = "<f8", version: tuple[int, int] = (1, 0)) -> bytes:
    buf = io.BytesIO()
    header = {"descr": descr, "fortran_order": False, "shape": shape}
    if version == (1, 0):
        np.lib.format.write_array_header_1_0(buf, header)
    else:
        np.lib.format.write_array_header_2_0(buf, header)
    return buf.getvalue()


def _deflate(data: bytes) -> bytes:
    c = zlib.compressobj(9, zlib.DEFLATED, -15)
    return c.compress(data) + c.flush()


class _Entry(NamedTuple):
    name: str
    method: int
    compressed: bytes
    crc: int
    size: int  # declared uncompressed size
    flags: int = 0
    csize: int | None = None  # declared compressed size, if not len(compressed)


def _member(name: str, data: bytes, *, method: int = zipfile.ZIP_STORED, compressed: bytes | None = None,
            crc: int | None = None, size: int | None = None, flags: int = 0, csize: int | None = None) -> _Entry:
    """A zip entry holding ``data``, as :func:`_raw_zip` writes it; the keywords let it lie."""
    if compressed is None:
        compressed = _deflate(data) if method == zipfile.ZIP_DEFLATED else data
    return _Entry(name, method, compressed, zlib.crc32(data) if crc is None else crc,
                  len(data) if size is None else size, flags, csize)


def _raw_zip(path: os.PathLike, entries: list[_Entry]) -> None:
    """A zip archive written byte for byte (PKWARE APPNOTE 4.3.7, 4.3.12, 4.3.16): whatever sizes it is told."""
    local, central = bytearray(), bytearray()
    for name, method, data, crc, size, flags, csize in entries:
        raw = name.encode()
        head = (flags, method, 0, 0x21, crc, len(data) if csize is None else csize, size, len(raw))
        central += struct.pack("<IHH", 0x02014B50, 20, 20) + struct.pack("<HHHHIIIH", *head)
        central += struct.pack("<HHHHII", 0, 0, 0, 0, 0, len(local)) + raw
        local += struct.pack("<IH", 0x04034B50, 20) + struct.pack("<HHHHIIIH", *head) + struct.pack("<H", 0)
        local += raw + data
    end = struct.pack("<IHHHHIIH", 0x06054B50, 0, 0, len(entries), len(entries), len(central), len(local), 0)
    with open(path, "wb") as fh:
        fh.write(bytes(local + central + end))


def _entries(kind: str, replace: dict[str, _Entry] | None = None, extra: Sequence[_Entry] = ()) -> list[_Entry]:
    """The entries of a valid ``kind`` file, some replaced, some added."""
    obj = SAMPLES[kind]
    members = {"kind": _member("kind.npy", _npy(np.array(kind))),
               "format_version": _member("format_version.npy", _npy(np.array(1)))}
    members.update({k: _member(f"{k}.npy", _npy(getattr(obj, k))) for k in type(obj)._npz_keys})
    members.update(replace or {})
    return [*members.values(), *extra]


@pytest.mark.parametrize("kind", KINDS)
def test_the_raw_zip_writer_writes_valid_files(kind, tmp_path):
    path = tmp_path / "ok.npz"
    _raw_zip(path, _entries(kind))
    assert load(path) == SAMPLES[kind]  # the hostile files below differ from a valid one in one place
    _raw_zip(path, _entries(kind, {k: _member(f"{k}.npy", _npy(getattr(SAMPLES[kind], k)),
                                              method=zipfile.ZIP_DEFLATED) for k in type(SAMPLES[kind])._npz_keys}))
    assert load(path) == SAMPLES[kind]


HEADER_LIES = {
    "10^12 entries": (lambda: _npy_header((10**12,)) + bytes(64), r"declares shape \(1000000000000,\)"),
    "10^12 entries, size agreeing": (lambda: _npy_header((10**12,)), r"declares shape|bytes uncompressed"),
    "negative dimension": (lambda: _npy_header((-2, 4)) + bytes(64), r"none negative"),
    "four dimensions": (lambda: _npy_header((1, 1, 1, 1)) + bytes(8), r"at most 3\s+dimensions"),
    "object dtype": (lambda: _npy_header((2,), "|O") + bytes(16), r"object dtype, which needs pickling"),
    "structured dtype": (lambda: _npy_header((2,), [("a", "<f8")]) + bytes(16), r"structured dtype"),
    "zero-size items": (lambda: _npy_header((10**15,), "<U0"), r"zero-size items"),
    "huge items": (lambda: _npy_header((1,), "<U100000000") + bytes(8), r"declares shape \(1,\) of <U100000000"),
    "zero-size but huge": (lambda: _npy_header((0, 10**18)), r"more than the \d+ bytes allowed"),
    "fewer bytes than declared": (lambda: _npy_header((4,)) + bytes(16), r"declares shape \(4,\)"),
    "more bytes than declared": (lambda: _npy_header((1,)) + bytes(16), r"declares shape \(1,\)"),
    "not an npy": (lambda: b"not an npy file at all", r"no valid \.npy header"),
    "npy version 3": (lambda: b"\x93NUMPY\x03\x00" + _npy_header((1,))[8:] + bytes(8), r"format version 3\.0"),
    "npy header of 60 kB": (lambda: b"\x93NUMPY\x01\x00" + struct.pack("<H", 60000) + b" " * 60000,
                            r"\.npy header of 60000 bytes"),
    "npy v2 header of 4 GB": (lambda: b"\x93NUMPY\x02\x00" + struct.pack("<I", 2**32 - 1), r"\.npy header of"),
    "header not a dict": (lambda: b"\x93NUMPY\x01\x00" + struct.pack("<H", 16) + b"[1, 2, 3]       ",
                          r"no valid \.npy header"),
    "header nested deep": (lambda: b"\x93NUMPY\x01\x00" + struct.pack("<H", 600) + b"(" * 300 + b")" * 300,
                           r"no valid \.npy header"),
    "truncated header": (lambda: _npy_header((2,))[:20], r"truncated \.npy header|no valid"),
}


@pytest.mark.parametrize("lie", list(HEADER_LIES))
@pytest.mark.parametrize("kind", KINDS)
def test_npy_headers_are_checked_before_anything_is_read(kind, lie, tmp_path):
    make, phrase = HEADER_LIES[lie]
    key = type(SAMPLES[kind])._npz_keys[-1]
    path = tmp_path / "x.npz"
    for method in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        _raw_zip(path, _entries(kind, {key: _member(f"{key}.npy", make(), method=method)}))
        _refused_by_both(path, kind, "npz", rf"array '{key}' .*({phrase})")


def _lying_member(name: str, shape: tuple[int, ...], *, method: int, **lie: Any) -> _Entry:
    data = _npy(np.arange(float(np.prod(shape))).reshape(shape))
    return _member(name, data, method=method, **lie)


ZIP_LIES = {
    # (entry given the lie, phrase)
    # a deflated member is inflated 4 kB at a time, cut at the declared size: its CRC fails at once
    "file_size smaller than the data": (dict(size=200), r"its zip entry declares \d+ bytes of data|Bad CRC-32"),
    "file_size larger than the data": (dict(size=10**6), r"its zip entry declares|holds"),
    "file_size of 4 GB": (dict(size=2**32 - 1), r"more than the \d+ left|bytes uncompressed"),
    "compress_size of 4 GB": (dict(csize=2**32 - 1), r"compressed bytes in a file of"),
    "wrong CRC": (dict(crc=12345), r"Bad CRC-32"),
    "encrypted": (dict(flags=1), r"is encrypted"),
}


@pytest.mark.parametrize("lie", list(ZIP_LIES))
@pytest.mark.parametrize("method", [zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED], ids=["stored", "deflated"])
@pytest.mark.parametrize("kind", KINDS)
def test_zip_entries_that_lie_about_their_size(kind, method, lie, tmp_path):
    keyword, phrase = ZIP_LIES[lie]
    key = type(SAMPLES[kind])._npz_keys[0]
    path = tmp_path / "x.npz"
    _raw_zip(path, _entries(kind, {key: _lying_member(f"{key}.npy", (40,), method=method, **keyword)}))
    if method == zipfile.ZIP_STORED and lie.startswith("file_size"):
        phrase += r"|is stored uncompressed but declares"
    _refused_by_both(path, kind, "npz", phrase)


@pytest.mark.parametrize("method", [zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA], ids=["bzip2", "lzma"])
def test_members_whose_decompression_cannot_be_bounded_are_refused(method, tmp_path):
    path = tmp_path / "x.npz"
    with zipfile.ZipFile(path, "w", compression=method) as zf:
        for name, data in (("kind", np.array("IOData")), ("format_version", np.array(1)), ("u", np.ones(4)),
                           ("y", np.ones(4)), ("dt", np.array(0.1))):
            zf.writestr(f"{name}.npy", _npy(data))
    _refused_by_both(path, "IOData", "npz", r"is compressed with (bzip2|lzma)")


class _Bomb(NamedTuple):
    header: bytes  # .npy header of the 2**27 float64 zeros
    stream: bytes  # raw deflate stream of header + 1 GiB of zeros, about 1 MB
    crc: int
    zeros: bytes  # deflate of 16 MiB of zeros after a full flush, and the final block
    tail: bytes

    def entry(self, name: str, **lie: Any) -> _Entry:
        return _member(name, b"", method=zipfile.ZIP_DEFLATED, compressed=self.stream, crc=self.crc,
                       **{"size": len(self.header) + 2**30, **lie})

    def after(self, header: bytes) -> bytes:
        """A deflate stream of ``header`` followed by the same gigabyte of zeros."""
        c = zlib.compressobj(9, zlib.DEFLATED, -15)
        return c.compress(header) + c.flush(zlib.Z_FULL_FLUSH) + self.zeros * 64 + self.tail


@pytest.fixture(scope="module")
def gigabyte_bomb() -> _Bomb:
    """A float64 array of 1 GiB of zeros, compressed to about 1 MB, built in about 0.4 s.

    After a full flush the compressor starts afresh, so 16 MiB of zeros compress to the
    same bytes every time (zlib manual, ``Z_FULL_FLUSH``): they are compressed once.
    """
    header = _npy_header((2**27,))
    chunk = bytes(2**24)
    c = zlib.compressobj(9, zlib.DEFLATED, -15)
    head = c.compress(header) + c.flush(zlib.Z_FULL_FLUSH)
    zeros = c.compress(chunk) + c.flush(zlib.Z_FULL_FLUSH)
    tail = c.flush()
    crc = zlib.crc32(header)
    for _ in range(64):
        crc = zlib.crc32(chunk, crc)
    return _Bomb(header, head + zeros * 64 + tail, crc, zeros, tail)


@pytest.mark.parametrize("kind", KINDS)
def test_a_gigabyte_zip_bomb_is_refused_from_its_declared_size(kind, gigabyte_bomb, tmp_path):
    key = type(SAMPLES[kind])._npz_keys[0]
    path = tmp_path / "bomb.npz"
    _raw_zip(path, _entries(kind, {key: gigabyte_bomb.entry(f"{key}.npy")}))
    assert path.stat().st_size < 1.1e6
    _refused_by_both(path, kind, "npz", rf"its arrays declare \d+ bytes uncompressed \({key} "
                                        rf"{len(gigabyte_bomb.header) + 2**30}, .*\), more than the \d+ that this "
                                        rf"\d+-byte file may declare \(max\(1 MiB, 32 × its size\)")
    _raw_zip(path, _entries(kind, {"kind": gigabyte_bomb.entry("kind.npy")}))
    _refused_by_both(path, kind, "npz", r"array 'kind' declares \d+ bytes uncompressed; a tag is a scalar")


def test_a_bomb_that_declares_a_small_size_is_read_only_as_far_as_declared(gigabyte_bomb, tmp_path):
    small = _npy_header((3,))  # a stream of a header of 3 floats, then a gigabyte of zeros
    stream = gigabyte_bomb.after(small)
    path = tmp_path / "bomb.npz"
    for crc, phrase in [(gigabyte_bomb.crc, r"Bad CRC-32 for file 'w\.npy'"),  # the CRC of the whole stream
                        (zlib.crc32(small + bytes(24)), r"w\[0\] = 0\.0")]:  # the CRC of what is declared
        bomb = _member("w.npy", b"", method=zipfile.ZIP_DEFLATED, compressed=stream, crc=crc, size=len(small) + 24)
        _raw_zip(path, _entries("FrequencyData", {"w": bomb}))
        _refused(lambda: FrequencyData.from_npz(path), phrase)
        exc, _, seconds, peak = _measured(lambda: load(path))
        assert isinstance(exc, DataError) and seconds < SECONDS and peak < 8 * 2**20, (exc, seconds, peak)
    bomb = gigabyte_bomb.entry("w.npy", size=len(gigabyte_bomb.header) + 24)  # its header says 2**27 floats
    _raw_zip(path, _entries("FrequencyData", {"w": bomb}))
    _refused(lambda: FrequencyData.from_npz(path), r"declares shape \(134217728,\)|Bad CRC-32")


def test_members_symid_does_not_use_are_never_decompressed(gigabyte_bomb, tmp_path, monkeypatch):
    path = tmp_path / "extra.npz"
    _raw_zip(path, _entries("FrequencyData", extra=[gigabyte_bomb.entry("junk.npy"), _member("notes.txt", b"x" * 99)]))
    opened = []
    real_open = zipfile.ZipFile.open

    def spy(self: zipfile.ZipFile, name: Any, *args: Any, **kwargs: Any) -> Any:
        opened.append(getattr(name, "filename", name))
        return real_open(self, name, *args, **kwargs)

    monkeypatch.setattr(zipfile.ZipFile, "open", spy)
    for reader in (FrequencyData.from_npz, load):
        opened.clear()
        exc, frf, seconds, peak = _measured(lambda reader=reader: reader(path))
        assert exc is None and frf == SAMPLES["FrequencyData"]
        assert set(opened) == {"kind.npy", "format_version.npy", "w.npy", "H.npy"}, opened
        assert seconds < SECONDS and peak < 8 * 2**20, (seconds, peak)  # inflating the junk would take 1 GiB


def test_a_file_of_another_kind_is_refused_before_its_arrays_are_read(tmp_path, monkeypatch):
    path = tmp_path / "io.npz"
    SAMPLES["IOData"].to_npz(path)
    opened = []
    real_open = zipfile.ZipFile.open
    monkeypatch.setattr(zipfile.ZipFile, "open",
                        lambda self, name, *a, **k: opened.append(name.filename) or real_open(self, name, *a, **k))
    _refused(lambda: FrequencyData.from_npz(path), r"holds IOData, not FrequencyData")
    assert opened == ["format_version.npy", "kind.npy"]


TAG_DAMAGE = {
    "no tags": ({"kind": None, "format_version": None}, r"'kind' and 'format_version' entries are missing"),
    "version 99": ({"format_version": _npy(np.array(99))}, r"format version 99"),
    "version -1": ({"format_version": _npy(np.array(-1))}, r"format version -1"),
    "version text": ({"format_version": _npy(np.array("1"))}, r"'format_version' must be an integer scalar"),
    "version vector": ({"format_version": _npy(np.array([1, 1]))}, r"'format_version' must be an integer scalar"),
    "kind number": ({"kind": _npy(np.array(3.0))}, r"'kind' must be a text scalar"),
    "kind unknown": ({"kind": _npy(np.array("Banana"))}, r"holds Banana|unknown kind of data 'Banana'"),
    "kind of 1 MB": ({"kind": _npy(np.array("x" * 2**18))}, r"a tag is a scalar of at most"),
}


@pytest.mark.parametrize("damage", list(TAG_DAMAGE))
def test_damaged_tags(damage, tmp_path):
    change, phrase = TAG_DAMAGE[damage]
    replace = {k: _member(f"{k}.npy", v) for k, v in change.items() if v is not None}
    entries = [e for e in _entries("IOData", replace) if e.name.removesuffix(".npy") not in
               [k for k, v in change.items() if v is None]]
    path = tmp_path / "x.npz"
    _raw_zip(path, entries)
    _refused_by_both(path, "IOData", "npz", phrase)


def test_a_member_given_twice_is_refused(tmp_path):
    path = tmp_path / "x.npz"
    entries = _entries("IOData")
    _raw_zip(path, [*entries, _member("u.npy", _npy(np.zeros(6)))])
    _refused_by_both(path, "IOData", "npz", r"holds two members named 'u\.npy'")


@pytest.mark.parametrize("kind", KINDS)
def test_an_npz_cut_or_damaged_anywhere_is_refused(kind, tmp_path):
    path = tmp_path / "x.npz"
    SAMPLES[kind].to_npz(path)
    raw = path.read_bytes()
    for cut in range(0, len(raw), 5):
        path.write_bytes(raw[:cut])
        _refused(lambda: load(path))
    rng = np.random.default_rng(11)
    for at in rng.integers(0, len(raw), 200):  # one byte changed: refused, or read back unchanged
        damaged = bytearray(raw)
        damaged[at] ^= 1 + int(rng.integers(255))
        path.write_bytes(bytes(damaged))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            exc, result, seconds, peak = _measured(lambda: load(path))
        assert (isinstance(exc, DataError) or result == SAMPLES[kind]) and seconds < SECONDS and peak < BYTES, exc


def test_the_npz_budget():
    assert _files.npz_budget(0) == 2**20
    assert _files.npz_budget(10**6) == 32 * 10**6
    assert _files.npz_budget(10**12) == 4 * 2**30


def test_measured_data_compress_far_less_than_the_budget_allows():
    # the zoo's data sets (symid/zoo.py), saved as numpy.savez_compressed would: ratios measured 0.2 to 1.7
    for name in ("truss8", "msd3_psd", "msd3_similarity", "random5"):
        data = si.load_model(name).data()
        arrays = {k: np.asarray(getattr(data, k)) for k in type(data)._npz_keys}
        buf = io.BytesIO()
        np.savez_compressed(buf, **arrays)
        ratio = sum(a.nbytes for a in arrays.values()) / len(buf.getvalue())
        assert ratio < _files.NPZ_RATIO / 10, (name, ratio)


def test_round_trips_stay_exact_and_quiet(tmp_path):
    rng = np.random.default_rng(0)
    frf = FrequencyData(np.sort(rng.uniform(0.1, 10, 50)), rng.standard_normal((50, 2, 3)) + 1j)
    for obj in (frf, *SAMPLES.values()):
        for fmt in ("csv", "npz"):
            path = tmp_path / f"x.{fmt}"
            getattr(obj, f"to_{fmt}")(path)
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                assert load(path) == obj
                assert getattr(type(obj), f"from_{fmt}")(path) == obj
    path = tmp_path / "compressed.npz"  # numpy.savez_compressed of the same arrays is read too
    np.savez_compressed(path, kind=np.array("FrequencyData"), format_version=np.array(1), w=frf.w, H=frf.H)
    assert load(path) == frf


# -- measured study: time and peak resident memory per file, each in a fresh process ------------------

_PROBE = """
import json, sys, time, tracemalloc, warnings
warnings.simplefilter("ignore")
import symid.data as sd

def run():
    try:
        sd.load(sys.argv[1])
        return "accepted"
    except Exception as exc:
        return type(exc).__name__

def status(key):  # KiB
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith(key + ":"))

with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")  # resets VmHWM, the peak resident size, to the current one (Linux >= 4.0, proc(5))
before = status("VmRSS")
t0 = time.perf_counter()
outcome = run()
seconds = time.perf_counter() - t0
after = status("VmHWM")
tracemalloc.start()
run()
traced = tracemalloc.get_traced_memory()[1] // 1024
print(json.dumps({"outcome": outcome, "seconds": seconds, "rss_kib": after, "grown_kib": after - before,
                  "traced_kib": traced}))
"""


def _study_files(tmp_path, bomb: _Bomb) -> dict[str, os.PathLike]:
    """Files under 1 MB: the worst of the cases above, and the largest a reader accepts."""
    files = {}

    def put(name: str, content: bytes | str) -> None:
        files[name] = tmp_path / name.replace(" ", "_")
        if isinstance(content, str):
            content = content.encode()
        files[name].write_bytes(content)

    put("blackbox csv, n_states 20000 (102 B)", "# symid BlackBox csv v2\n# n_states: 20000\n# n_inputs: 1\n"
        "# n_outputs: 1\n# n_rows: 1\nmatrix,row,col,value\nA,0,0,1.0\n# end\n")
    put("blackbox csv v1, n_states 20000", "# symid BlackBox csv v1\n# n_states: 20000\n# n_inputs: 1\n"
        "# n_outputs: 1\nmatrix,row,col,value\nA,0,0,1.0\n")
    put("frf csv, n_inputs 1e10", "# symid FrequencyData csv v2\n# n_outputs: 1\n# n_inputs: 1e10\n# n_rows: 1\n"
        "w,H[0][0].re,H[0][0].im\n1.0,0.0,0.0\n# end\n")
    put("spectra csv, sizes 10^12-1", "# symid SpectralData csv v2\n# n_outputs: 999999999999\n"
        "# n_inputs: 999999999999\n# n_rows: 1\nw\n1.0\n# end\n")
    rows = "".join(f"{k + 1}.0,{np.sin(k).item()!r},{np.cos(k).item()!r}\n" for k in range(22_000))  # 0.95 MB
    put("frf csv 1 MB, n_rows off by one", f"# symid FrequencyData csv v2\n# n_outputs: 1\n# n_inputs: 1\n"
        f"# n_rows: {rows.count(chr(10)) + 1}\nw,H[0][0].re,H[0][0].im\n{rows}# end\n")
    put("frf csv 1 MB, accepted", f"# symid FrequencyData csv v2\n# n_outputs: 1\n# n_inputs: 1\n"
        f"# n_rows: {rows.count(chr(10))}\nw,H[0][0].re,H[0][0].im\n{rows}# end\n")
    entries = "".join(f"{m},{i},{j},{np.sin(i + j).item()!r}\n" for m, n1, n2 in (("A", 170, 170), ("B", 170, 1),
                                                                          ("C", 1, 170), ("D", 1, 1))
                      for i in range(n1) for j in range(n2))
    put("blackbox csv 0.9 MB (n = 170), accepted", f"# symid BlackBox csv v2\n# n_states: 170\n# n_inputs: 1\n"
        f"# n_outputs: 1\n# n_rows: {entries.count(chr(10))}\nmatrix,row,col,value\n{entries}# end\n")
    put("io csv, 1 MB of cells in one row", "# symid IOData csv v2\n# dt: 0.1\n# n_inputs: 1\n# n_outputs: 1\n"
        "# n_rows: 1\nu[0],y[0]\n" + "1," * 2**19 + "\n# end\n")
    put("frf csv, 1 MB of blank lines", "# symid FrequencyData csv v2\n# n_outputs: 1\n# n_inputs: 1\n# n_rows: 1\n"
        "w,H[0][0].re,H[0][0].im\n" + "\n" * 2**20 + "# end\n")
    put("1 MB of random bytes", np.random.default_rng(3).integers(0, 256, 2**20, dtype=np.uint8).tobytes())
    for name, key, lie in (("npz, w of 10^12 entries", "w", _npy_header((10**12,)) + bytes(64)),
                           ("npz, object dtype", "w", _npy_header((2,), "|O") + bytes(16))):
        files[name] = tmp_path / f"{key}{len(files)}.npz"
        _raw_zip(files[name], _entries("FrequencyData", {key: _member(f"{key}.npy", lie)}))
    small = _npy_header((3, 1, 1), "<c16")
    for name, replace, extra in (
            ("npz bomb 1 GiB as H (1 MB)", {"H": bomb.entry("H.npy")}, []),
            ("npz bomb 1 GiB declared as 48 B", {"H": _member("H.npy", b"", method=zipfile.ZIP_DEFLATED,
                                                              compressed=bomb.after(small), crc=bomb.crc,
                                                              size=len(small) + 48)}, []),
            ("npz bomb 1 GiB unused, accepted", {}, [bomb.entry("junk.npy")])):
        files[name] = tmp_path / f"bomb{len(files)}.npz"
        _raw_zip(files[name], _entries("FrequencyData", replace, extra))
    n = 1_900_000  # IOData of 30 MB deflated to about 1 MB (ratio 31: the largest a file under 1 MB may hold)
    u, y = np.zeros((n, 1)), np.zeros((n, 1))
    u[::20], y[::20] = 1.0, RNG.standard_normal((len(u[::20]), 1))
    files["npz 30 MB deflated to 1 MB, accepted"] = tmp_path / "dense.npz"
    np.savez_compressed(files["npz 30 MB deflated to 1 MB, accepted"], kind=np.array("IOData"),
                        format_version=np.array(1), u=u, y=y, dt=np.array(0.1))
    u[::20] = 0.0  # the same with fewer random values: ratio above 32
    files["npz ratio above 32, refused"] = tmp_path / "sparse.npz"
    np.savez_compressed(files["npz ratio above 32, refused"], kind=np.array("IOData"), format_version=np.array(1),
                        u=u, y=y[:, :] * (np.arange(n)[:, None] % 40 == 0), dt=np.array(0.1))
    return files


@pytest.mark.slow
def test_study_every_file_under_a_megabyte_takes_under_a_second_and_200_mb(tmp_path, gigabyte_bomb):
    files = _study_files(tmp_path, gigabyte_bomb)
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    print("\nseconds: time to accept or refuse; peak RSS: of the process while reading (the import included); "
          "grown: that less the RSS before reading; traced: tracemalloc peak of a second read (numpy included)")
    print(f"{'file':44s} {'bytes':>9s} {'outcome':>10s} {'seconds':>8s} {'peak RSS':>9s} {'grown':>8s} {'traced':>8s}")
    worst = {"seconds": 0.0, "grown_kib": 0, "traced_kib": 0}
    for name, path in files.items():
        size = os.path.getsize(path)
        assert size < 1.1e6, name
        run = subprocess.run([sys.executable, "-c", _PROBE, str(path)], capture_output=True, text=True, env=env,
                             timeout=120, check=True)
        got = json.loads(run.stdout)
        print(f"{name:44s} {size:9d} {got['outcome']:>10s} {got['seconds']:8.3f} {got['rss_kib'] / 1024:7.1f}MB "
              f"{got['grown_kib'] / 1024:6.1f}MB {got['traced_kib'] / 1024:6.1f}MB")
        assert got["outcome"] in ("accepted", "DataError"), (name, got)
        assert got["outcome"] == "accepted" if "accepted" in name else got["outcome"] == "DataError", (name, got)
        assert got["seconds"] < SECONDS and max(got["grown_kib"], got["traced_kib"]) < BYTES / 1024, (name, got)
        worst = {k: max(worst[k], got[k]) for k in worst}
    print(f"worst: {worst['seconds']:.3f} s, {worst['grown_kib'] / 1024:.1f} MB resident grown, "
          f"{worst['traced_kib'] / 1024:.1f} MB traced")
