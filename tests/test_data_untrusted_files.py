"""A file's header is never trusted before its content (issue 12 item 3): every file is accepted or refused
quickly and in bounded memory, whatever it declares; a file cut short is refused, never loaded short."""

from __future__ import annotations

import io
import time
import tracemalloc
import warnings
import zipfile

import numpy as np
import pytest

import symid as si
from symid.data import load
from symid.errors import DataError

# bounds asserted per file: generous for a shared 2-core machine (measured: a few ms and < 1 MB each)
SECONDS, BYTES = 1.0, 200 * 2**20


def _refused_quickly(path, reader=load, match=None):
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        with pytest.raises(DataError, match=match):
            reader(path)
    finally:
        elapsed = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert elapsed < SECONDS, elapsed
    assert peak < BYTES, peak


def _npy(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asarray(arr), allow_pickle=False)
    return buf.getvalue()


def _npy_header(shape, dtype="<f8") -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": dtype, "fortran_order": False, "shape": shape})
    return buf.getvalue()


def _tags(zf, kind="FrequencyData"):
    zf.writestr("kind.npy", _npy(np.array(kind)))
    zf.writestr("format_version.npy", _npy(np.array(1)))


# -- CSV ---------------------------------------------------------------------------------------

def test_a_102_byte_blackbox_csv_claiming_20000_states(tmp_path):
    path = tmp_path / "bb.csv"
    path.write_text("# symid BlackBox csv v2\n# n_states: 20000\n# n_inputs: 1\n# n_outputs: 1\n# n_rows: 1\n"
                    "matrix,row,col,value\nA,0,0,1.0\n# end\n")
    _refused_quickly(path, match="more than the file's contents")


@pytest.mark.parametrize("value", ["1e10", "20000", "-1", "0", "2.0", "0x10", "9" * 40, "１"])
@pytest.mark.parametrize("kind", ["FrequencyData", "SpectralData", "IOData"])
def test_declared_sizes_are_checked_against_the_columns(tmp_path, kind, value):
    data = {"FrequencyData": si.FrequencyData([1.0, 2.0], [1.0, 2.0j]),
            "SpectralData": si.SpectralData([1.0, 2.0], [1.0, 2.0], [1.0, 1.0]),
            "IOData": si.IOData([1.0, 2.0], [0.5, 0.1], 0.1)}[kind]
    path = tmp_path / "x.csv"
    data.to_csv(path)
    path.write_text(path.read_text().replace("# n_inputs: 1", f"# n_inputs: {value}"))
    _refused_quickly(path)


def test_a_csv_cut_at_a_line_boundary_is_refused(tmp_path):
    path = tmp_path / "frf.csv"
    si.FrequencyData([0.5, 1.0, 2.0], [1.0, 2.0, 3.0]).to_csv(path)
    lines = path.read_text().splitlines(keepends=True)
    for cut in range(len(lines) - 1, 5, -1):  # every cut after the header: the last rows and/or the end marker
        path.write_text("".join(lines[:cut]))
        _refused_quickly(path, match="does not end with the line")


def test_version_1_files_are_read_with_a_warning(tmp_path):
    path = tmp_path / "old.csv"
    path.write_text("# symid FrequencyData csv v1\n# n_outputs: 1\n# n_inputs: 1\nw,H[0][0].re,H[0][0].im\n"
                    "0.5,1.0,0.0\n2.0,0.5,0.5\n")
    with pytest.warns(UserWarning, match="version-1 symid CSV file"):
        frf = load(path)
    np.testing.assert_array_equal(frf.H.ravel(), [1.0, 0.5 + 0.5j])


@pytest.mark.parametrize("content", [b"", b"\x00" * 100, b"\xff\xfe\x00binary", b"# symid FrequencyData csv v2\n",
                                     "# symid FrequencyData csv v2\n# n_rows: 1\nw\n\u00e9\n# end\n".encode()])
def test_junk_files_are_refused(tmp_path, content):
    path = tmp_path / "junk"
    path.write_bytes(content)
    _refused_quickly(path)


def test_a_directory_or_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(IsADirectoryError):
        load(tmp_path)
    with pytest.raises(FileNotFoundError):
        load(tmp_path / "missing.npz")


# -- NPZ ---------------------------------------------------------------------------------------

def test_npz_header_claiming_10_to_the_12_entries(tmp_path):
    path = tmp_path / "big.npz"
    with zipfile.ZipFile(path, "w") as zf:
        _tags(zf)
        zf.writestr("w.npy", _npy_header((10**12,)) + b"\x00" * 64)
        zf.writestr("H.npy", _npy(np.ones((2, 1, 1), dtype=complex)))
    _refused_quickly(path, match=r"declares shape \(1000000000000,\)")


def test_npz_bomb_is_refused_from_its_declared_size(tmp_path):
    path = tmp_path / "bomb.npz"
    n = 8 * 2**20  # 64 MiB of zeros deflate to ~64 KiB: more than 100 times the stored bytes and over 16 MiB
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        _tags(zf)
        zf.writestr("w.npy", _npy(np.array([1.0, 2.0])))
        with zf.open("H.npy", "w", force_zip64=True) as fh:
            fh.write(_npy_header((n,), "<f8"))
            zero = bytes(2**20)
            for _ in range(8 * 8):
                fh.write(zero)
    assert path.stat().st_size < 1_000_000
    _refused_quickly(path, match="declares .* bytes from")


def test_members_symid_does_not_use_are_never_decompressed(tmp_path):
    path = tmp_path / "extra.npz"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        _tags(zf)
        zf.writestr("w.npy", _npy(np.array([1.0, 2.0])))
        zf.writestr("H.npy", _npy(np.array([[[1.0 + 0j]], [[0.5j]]])))
        with zf.open("junk.npy", "w", force_zip64=True) as fh:  # a bomb under a name symid does not read
            zero = bytes(2**20)
            for _ in range(64):
                fh.write(zero)
    tracemalloc.start()
    t0 = time.perf_counter()
    frf = load(path)
    elapsed, peak = time.perf_counter() - t0, tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert frf.H.shape == (2, 1, 1) and elapsed < SECONDS and peak < 10 * 2**20


def test_npz_object_members_and_short_members_are_refused(tmp_path):
    path = tmp_path / "obj.npz"
    with zipfile.ZipFile(path, "w") as zf:
        _tags(zf)
        zf.writestr("w.npy", _npy_header((2,), "|O") + b"\x00" * 16)
        zf.writestr("H.npy", _npy(np.ones((2, 1, 1), dtype=complex)))
    _refused_quickly(path, match="pickling")
    path = tmp_path / "short.npz"
    with zipfile.ZipFile(path, "w") as zf:
        _tags(zf)
        zf.writestr("w.npy", _npy_header((4,)) + b"\x00" * 16)  # 2 of the 4 floats promised
        zf.writestr("H.npy", _npy(np.ones((4, 1, 1), dtype=complex)))
    _refused_quickly(path, match="declares shape")
    path = tmp_path / "noheader.npz"
    with zipfile.ZipFile(path, "w") as zf:
        _tags(zf)
        zf.writestr("w.npy", b"not an npy file at all")
        zf.writestr("H.npy", _npy(np.ones((4, 1, 1), dtype=complex)))
    _refused_quickly(path, match="no valid .npy header")


def test_a_truncated_npz_is_refused(tmp_path):
    path = tmp_path / "frf.npz"
    si.FrequencyData([0.5, 1.0, 2.0], [1.0, 2.0, 3.0]).to_npz(path)
    raw = path.read_bytes()
    for cut in (len(raw) // 3, len(raw) // 2, len(raw) - 10):
        path.write_bytes(raw[:cut])
        _refused_quickly(path)


def test_round_trips_stay_exact(tmp_path):
    rng = np.random.default_rng(0)
    frf = si.FrequencyData(np.sort(rng.uniform(0.1, 10, 50)), rng.standard_normal((50, 2, 3)) + 1j)
    for fmt in ("csv", "npz"):
        path = tmp_path / f"frf.{fmt}"
        getattr(frf, f"to_{fmt}")(path)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert load(path) == frf
