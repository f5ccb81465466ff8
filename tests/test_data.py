"""Data containers: validation at construction, immutability, exact CSV and NPZ round trips."""

from __future__ import annotations

import copy
import dataclasses
import os
import pickle
import tempfile

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import symid as si
from symid.data import BlackBox, FrequencyData, IOData, SpectralData, load
from symid.errors import DataError

RNG = np.random.default_rng(1234)
W = np.array([0.5, 1.0, 1.5, 2.0])
H_MIMO = RNG.standard_normal((4, 2, 3)) + 1j * RNG.standard_normal((4, 2, 3))


def _hermitian(s: int, k: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((s, k, k)) + 1j * rng.standard_normal((s, k, k))
    return X @ np.conj(np.swapaxes(X, 1, 2))  # Hermitian positive semidefinite


PYY = _hermitian(4, 2, 1)
PUU = _hermitian(4, 3, 2)
U = RNG.standard_normal((50, 2))
Y = RNG.standard_normal((50, 3))
A = np.array([[0.0, 1.0], [-2.0, -0.5]])
B = np.array([[0.0, 1.0], [1.0, 0.0]])
C = np.array([[1.0, 0.0]])
D = np.array([[0.0, 0.25]])


def _with(arr: np.ndarray, index: tuple[int, ...], value: complex) -> np.ndarray:
    out = np.array(arr, copy=True)
    out[index] = value
    return out


def _non_hermitian() -> np.ndarray:
    P = PYY.copy()
    P[2, 0, 1] += 0.3
    return P


# -- validation ---------------------------------------------------------------------------

INVALID = [
    # FrequencyData
    ("FRF NaN in H", lambda: FrequencyData(W, _with(H_MIMO, (1, 0, 0), np.nan)), "H must be finite: H[1, 0, 0]"),
    ("FRF inf in H", lambda: FrequencyData(W, _with(H_MIMO, (3, 1, 2), np.inf)), "H must be finite"),
    ("FRF NaN in w", lambda: FrequencyData(_with(W, (2,), np.nan), H_MIMO), "w must be finite: w[2]"),
    ("FRF inf in w", lambda: FrequencyData(_with(W, (3,), np.inf), H_MIMO), "w must be finite"),
    ("FRF w unsorted", lambda: FrequencyData([0.5, 1.5, 1.0, 2.0], H_MIMO), "(unsorted)"),
    ("FRF w duplicate", lambda: FrequencyData([0.5, 1.0, 1.0, 2.0], H_MIMO),
     "w[2] = 1.0 is not greater than w[1] = 1.0 (duplicate)"),
    ("FRF w zero", lambda: FrequencyData([0.0, 1.0, 1.5, 2.0], H_MIMO), "w[0] = 0.0"),
    ("FRF w negative", lambda: FrequencyData([-1.0, 1.0, 1.5, 2.0], H_MIMO), "must be positive"),
    ("FRF w 2-D", lambda: FrequencyData(W.reshape(2, 2), H_MIMO), "w must be 1-D"),
    ("FRF w empty", lambda: FrequencyData([], np.zeros((0, 1, 1))), "w is empty"),
    ("FRF w complex", lambda: FrequencyData(W + 0j, H_MIMO), "w must be real"),
    ("FRF H 2-D", lambda: FrequencyData(W, np.ones((4, 2))), "H must have shape (s, p, m)"),
    ("FRF H 4-D", lambda: FrequencyData(W, np.ones((4, 1, 1, 1))), "got shape (4, 1, 1, 1)"),
    ("FRF length mismatch", lambda: FrequencyData(W, H_MIMO[:3]), "H has 3 frequencies"),
    ("FRF SISO length mismatch", lambda: FrequencyData(W, np.ones(5)), "but w has 4"),
    ("FRF no inputs", lambda: FrequencyData(W, np.ones((4, 1, 0))), "at least one output and one input"),
    ("FRF strings", lambda: FrequencyData(W, np.array(["a", "b", "c", "d"])), "H must hold numbers"),
    ("FRF ragged", lambda: FrequencyData(W, [[1, 2], [3]]), "ragged"),
    ("FRF bool", lambda: FrequencyData(W, np.ones(4, dtype=bool)), "booleans"),
    ("FRF None", lambda: FrequencyData(W, None), "H is missing"),
    # SpectralData
    ("spec NaN Phi_yy", lambda: SpectralData(W, _with(PYY, (0, 1, 1), np.nan), PUU), "Phi_yy must be finite"),
    ("spec inf Phi_uu", lambda: SpectralData(W, PYY, _with(PUU, (1, 0, 0), np.inf)), "Phi_uu must be finite"),
    ("spec non-Hermitian Phi_yy", lambda: SpectralData(W, _non_hermitian(), PUU),
     "Phi_yy[2] is not Hermitian: max |Φ − Φᴴ| = 0.3"),
    ("spec non-Hermitian Phi_uu", lambda: SpectralData(W, PYY, PUU + 1j * np.eye(3)), "Phi_uu[0] is not Hermitian"),
    ("spec not square", lambda: SpectralData(W, np.ones((4, 2, 3)), PUU), "Phi_yy must hold square matrices"),
    ("spec 2-D", lambda: SpectralData(W, np.ones((4, 2)), PUU), "Phi_yy must have shape (s, p, p)"),
    ("spec length mismatch", lambda: SpectralData(W, PYY[:2], PUU), "Phi_yy has 2 frequencies"),
    ("spec Phi_uu length", lambda: SpectralData(W, PYY, np.ones(3)), "Phi_uu has 3 frequencies"),
    ("spec w duplicate", lambda: SpectralData([1.0, 1.0, 2.0, 3.0], PYY, PUU), "(duplicate)"),
    ("spec w non-positive", lambda: SpectralData([-1.0, 1.0, 2.0, 3.0], PYY, PUU), "must be positive"),
    # IOData
    ("IO NaN u", lambda: IOData(_with(U, (7, 1), np.nan), Y, 0.1), "u must be finite: u[7, 1]"),
    ("IO inf y", lambda: IOData(U, _with(Y, (3, 2), -np.inf), 0.1), "y must be finite: y[3, 2]"),
    ("IO length mismatch", lambda: IOData(U, Y[:-1], 0.1), "u has 50"),
    ("IO u 3-D", lambda: IOData(U[:, :, None], Y, 0.1), "u must have shape (N, m)"),
    ("IO y 3-D", lambda: IOData(U, Y[:, :, None], 0.1), "y must have shape (N, p)"),
    ("IO one sample", lambda: IOData(U[:1], Y[:1], 0.1), "at least 2 samples"),
    # a new user's row of 50 values was told only "got N = 1": now named as one channel written as a row
    ("IO row instead of column", lambda: IOData(np.ones((1, 50)), np.ones((1, 50)), 0.1),
     "u has shape (1, 50): 50 channels but only 1 sample; arrays are (samples, channels)"),
    ("IO transposed", lambda: IOData(U.T, Y.T[:2], 0.1), "u has shape (2, 50): 50 channels but only 2 samples"),
    ("IO y transposed", lambda: IOData(U[:3], Y.T, 0.1), "y has shape (3, 50): 50 channels but only 3 samples"),
    ("IO complex u", lambda: IOData(U + 1j, Y, 0.1), "u must be real"),
    ("IO dt zero", lambda: IOData(U, Y, 0.0), "dt must be a finite number > 0"),
    ("IO dt negative", lambda: IOData(U, Y, -0.1), "dt must be a finite number > 0"),
    ("IO dt nan", lambda: IOData(U, Y, np.nan), "dt must be"),
    ("IO dt inf", lambda: IOData(U, Y, np.inf), "dt must be"),
    ("IO dt vector", lambda: IOData(U, Y, [0.1, 0.2]), "dt must be a scalar"),
    ("IO dt string", lambda: IOData(U, Y, "0.1"), "dt must hold numbers"),
    # BlackBox
    ("BB A not square", lambda: BlackBox(np.ones((2, 3)), B, C), "A must be a square matrix"),
    ("BB A 1-D", lambda: BlackBox(np.ones(2), B, C), "A must be a square matrix"),
    ("BB B rows", lambda: BlackBox(A, np.ones((3, 1)), C), "B must have shape (n, m) = (2, m)"),
    ("BB C cols", lambda: BlackBox(A, B, np.ones((1, 3))), "C must have shape (p, n) = (p, 2)"),
    ("BB D shape", lambda: BlackBox(A, B, C, np.ones((2, 2))), "D must have shape (p, m) = (1, 2)"),
    ("BB D scalar MIMO", lambda: BlackBox(A, B, C, 1.0), "D must have shape (p, m) = (1, 2)"),
    ("BB NaN A", lambda: BlackBox(_with(A, (1, 0), np.nan), B, C), "A must be finite: A[1, 0]"),
    ("BB inf D", lambda: BlackBox(A, B, C, _with(D, (0, 1), np.inf)), "D must be finite"),
    ("BB complex A", lambda: BlackBox(A + 0j, B, C), "A must be real"),
    ("BB bad tuple", lambda: BlackBox.from_state_space((A, B)), "expects a 4-tuple"),
]


@pytest.mark.parametrize(("label", "make", "phrase"), INVALID, ids=[c[0] for c in INVALID])
def test_invalid_input_raises_data_error_naming_the_problem(label, make, phrase):
    with pytest.raises(DataError) as info:
        make()
    assert phrase in str(info.value), str(info.value)
    assert isinstance(info.value, ValueError)


def test_hermitian_check_does_not_overflow_on_huge_spectra():
    skew = np.array([[1.0, 2.0], [0.0, 1.0]])
    with pytest.raises(DataError, match=r"Phi_yy\[0\] is not Hermitian"):
        SpectralData(W, 1e200 * np.broadcast_to(skew, (4, 2, 2)), np.ones(4))  # ||Φ||_F² would overflow
    SpectralData(W, 1e300 * np.broadcast_to(skew + skew.T, (4, 2, 2)), np.ones(4))


def test_hermitian_tolerance_is_relative_to_the_norm():
    big = PYY * 1e12
    big[:, 0, 1] += 1e-2  # 1e-14 relative to entries of order 1e12: accepted
    SpectralData(W, big, PUU)
    with pytest.raises(DataError, match="not Hermitian"):
        SpectralData(W, PYY * 1e-12 + np.array([[0, 1e-18], [0, 0]]), PUU)


# -- conveniences, immutability, text -------------------------------------------------------

def test_siso_conveniences():
    frf = FrequencyData(W, np.ones(4))
    assert frf.H.shape == (4, 1, 1) and frf.H.dtype == np.complex128
    spec = SpectralData(W, np.ones(4), 2 * np.ones(4))
    assert spec.Phi_yy.shape == (4, 1, 1) and spec.Phi_uu.shape == (4, 1, 1)
    io = IOData(np.arange(5), np.arange(5.0), dt=1)
    assert io.u.shape == (5, 1) and io.u.dtype == np.float64 and io.dt == 1.0
    bb = BlackBox(A, [0, 1], [1, 0], 0.5)
    assert (bb.B.shape, bb.C.shape, bb.D.shape) == ((2, 1), (1, 2), (1, 1))
    assert FrequencyData(3.0, [1j]).n_frequencies == 1


def test_properties():
    frf = FrequencyData(W, H_MIMO)
    assert (frf.n_frequencies, frf.n_outputs, frf.n_inputs, frf.shape) == (4, 2, 3, (4, 2, 3))
    spec = SpectralData(W, PYY, PUU)
    assert (spec.n_frequencies, spec.n_outputs, spec.n_inputs) == (4, 2, 3)
    io = IOData(U, Y, 0.1)
    assert (io.n_samples, io.n_inputs, io.n_outputs) == (50, 2, 3)
    np.testing.assert_allclose(io.t[:3], [0.0, 0.1, 0.2], rtol=0, atol=1e-15)
    assert io.duration == pytest.approx(4.9, rel=1e-12)
    bb = BlackBox(A, B, C, D)
    assert (bb.n_states, bb.n_inputs, bb.n_outputs) == (2, 2, 1)
    np.testing.assert_allclose(np.sort_complex(bb.poles), np.sort_complex(np.linalg.eigvals(A)), rtol=1e-12)


def test_containers_are_immutable_and_copy_their_inputs():
    H = H_MIMO.copy()
    frf = FrequencyData(W, H)
    H[0, 0, 0] = 99.0
    assert frf.H[0, 0, 0] != 99.0
    with pytest.raises(ValueError, match="read-only"):
        frf.H[0, 0, 0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        frf.w = W  # type: ignore[misc]
    io = IOData(U, Y, 0.1)
    for arr in (io.u, io.y, SpectralData(W, PYY, PUU).Phi_uu, BlackBox(A, B, C).A):
        assert not arr.flags.writeable


def test_blackbox_from_state_space_and_frequency_response():
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]], output="acceleration")
    theta = {"m": 2.0, "c": 0.3, "k": 5.0}
    ss = model.state_space(theta)
    bb1, bb2 = BlackBox.from_state_space(ss), BlackBox(*ss)
    assert bb1 == bb2
    np.testing.assert_allclose(bb1.frequency_response(W), model.frequency_response(theta, W), rtol=1e-12)
    back = bb1.state_space()
    assert isinstance(back, si.StateSpaceMatrices) and back.D.flags.writeable
    np.testing.assert_array_equal(back.D, ss.D)


@pytest.mark.parametrize("obj", [FrequencyData(W, H_MIMO), IOData(U, Y, 0.1)], ids=["frf", "io"])
def test_pickle_and_copy_keep_arrays_read_only(obj):
    for back in (pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj), copy.copy(obj)):
        assert back == obj
        assert not np.asarray(getattr(back, type(obj)._npz_keys[0])).flags.writeable


def test_equality_is_exact_and_typed():
    frf = FrequencyData(W, H_MIMO)
    assert frf == FrequencyData(W.tolist(), H_MIMO)
    assert frf != FrequencyData(W, H_MIMO + 1e-15)
    assert frf != SpectralData(W, PYY, PUU)
    assert IOData(U, Y, 0.1) != IOData(U, Y, 0.2)


@pytest.mark.parametrize("obj", [
    FrequencyData(W, H_MIMO), SpectralData(W, PYY, PUU), IOData(U, Y, 0.1), BlackBox(A, B, C, D)],
    ids=["frf", "spectra", "io", "blackbox"])
def test_repr_and_summary(obj):
    assert type(obj).__name__ in repr(obj)
    assert type(obj).__name__ in obj.summary()


# -- files ------------------------------------------------------------------------------------

ALL_KINDS = [
    FrequencyData(W, H_MIMO),
    FrequencyData(W, 1 / (1j * W + 1)),
    SpectralData(W, PYY, PUU),
    IOData(U, Y, 0.1),
    IOData(np.linspace(0, 1, 7), np.sin(np.linspace(0, 1, 7)), 1 / 3),
    BlackBox(A, B, C, D),
    BlackBox(A * np.pi, [0.1, 1 / 3], [1e-300, -0.0]),
]
KIND_IDS = ["frf-mimo", "frf-siso", "spectra", "io-mimo", "io-siso", "blackbox", "blackbox-siso"]


@pytest.mark.parametrize("obj", ALL_KINDS, ids=KIND_IDS)
@pytest.mark.parametrize("fmt", ["csv", "npz"])
def test_file_round_trip_is_exact(obj, fmt, tmp_path):
    path = tmp_path / f"data.{fmt}"
    getattr(obj, f"to_{fmt}")(path)
    back = getattr(type(obj), f"from_{fmt}")(path)
    assert back == obj
    for name in type(obj)._npz_keys:
        a, b = np.asarray(getattr(obj, name)), np.asarray(getattr(back, name))
        assert a.dtype == b.dtype and a.shape == b.shape
        assert a.tobytes() == b.tobytes()  # bit for bit, signed zeros included
    assert load(path) == obj
    assert load(str(path)) == obj


def test_npz_keeps_the_given_name_and_loads_without_pickle(tmp_path):
    path = tmp_path / "frf.data"  # no .npz suffix: not appended
    FrequencyData(W, H_MIMO).to_npz(path)
    assert path.exists() and not (tmp_path / "frf.data.npz").exists()
    with np.load(path, allow_pickle=False) as npz:
        assert str(npz["kind"]) == "FrequencyData" and int(npz["format_version"]) == 1
        assert set(npz.files) == {"kind", "format_version", "w", "H"}
    assert load(path) == FrequencyData(W, H_MIMO)


def test_csv_layout_is_documented_text(tmp_path):
    path = tmp_path / "io.csv"
    IOData([[1.0, 2.0], [3.0, 4.0]], [0.1, 0.2], dt=0.01).to_csv(path)
    assert path.read_text().splitlines() == [
        "# symid IOData csv v2",
        "# dt: 0.01",
        "# time_unit: s",
        "# n_inputs: 2",
        "# n_outputs: 1",
        "# n_rows: 2",
        "u[0],u[1],y[0]",
        "1.0,2.0,0.1",
        "3.0,4.0,0.2",
        "# end",
    ]
    path = tmp_path / "spec.csv"
    SpectralData([1.0], [[[2.0]]], [[[1.0, complex(0, 0.5)], [complex(0, -0.5), 1.0]]]).to_csv(path)
    assert path.read_text().splitlines()[4:] == [
        "w,Phi_yy[0][0].re,Phi_yy[0][0].im,Phi_uu[0][0].re,Phi_uu[0][0].im,Phi_uu[0][1].re,Phi_uu[0][1].im,"
        "Phi_uu[1][0].re,Phi_uu[1][0].im,Phi_uu[1][1].re,Phi_uu[1][1].im",
        "1.0,2.0,0.0,1.0,0.0,0.0,0.5,0.0,-0.5,1.0,0.0",
        "# end",
    ]


@pytest.mark.parametrize("fmt", ["csv", "npz"])
def test_loading_the_wrong_kind_names_the_kind(fmt, tmp_path):
    path = tmp_path / f"x.{fmt}"
    getattr(IOData(U, Y, 0.1), f"to_{fmt}")(path)
    with pytest.raises(DataError, match="holds IOData, not FrequencyData"):
        getattr(FrequencyData, f"from_{fmt}")(path)


def test_npz_without_tags_or_with_objects_is_refused(tmp_path):
    plain = tmp_path / "plain.npz"
    np.savez(plain, w=W, H=H_MIMO)
    with pytest.raises(DataError, match="'kind' and 'format_version' entries are missing"):
        FrequencyData.from_npz(plain)
    objs = tmp_path / "objs.npz"
    np.savez(objs, kind=np.array("FrequencyData"), format_version=np.array(1), w=W,
             H=np.array([1, "a"], dtype=object))
    with pytest.raises(DataError, match="pickling"):
        FrequencyData.from_npz(objs)
    newer = tmp_path / "newer.npz"
    np.savez(newer, kind=np.array("FrequencyData"), format_version=np.array(99), w=W, H=H_MIMO)
    with pytest.raises(DataError, match="format version 99"):
        FrequencyData.from_npz(newer)
    missing = tmp_path / "missing.npz"
    np.savez(missing, kind=np.array("FrequencyData"), format_version=np.array(1), w=W)
    with pytest.raises(DataError, match="lacks the array"):
        FrequencyData.from_npz(missing)


def test_invalid_contents_of_a_file_name_the_file_and_the_array(tmp_path):
    path = tmp_path / "bad.npz"
    np.savez(path, kind=np.array("FrequencyData"), format_version=np.array(1), w=[2.0, 1.0], H=[1.0, 2.0])
    with pytest.raises(DataError, match=r"bad\.npz'.*w must be strictly increasing"):
        FrequencyData.from_npz(path)


CSV_DAMAGE = [
    ("not symid", lambda t: "hello,world\n1,2\n", "is not a symid CSV file"),
    ("empty", lambda t: "", "is empty"),
    ("cell", lambda t: t.replace("0.5,", "abc,", 1), "is not a number"),
    ("short row", lambda t: t.replace("\n2.0,3.0,0.0\n", "\n2.0,3.0\n"), "cells; the header has"),
    ("cut at a line", lambda t: "\n".join(t.splitlines()[:-2]) + "\n", "does not end with the line '# end'"),
    ("row missing", lambda t: t.replace("2.0,3.0,0.0\n", "", 1), "declares 3 data rows"),
    ("row count", lambda t: t.replace("# n_rows: 3", "# n_rows: 2"), "declares 2 data rows"),
    ("row count huge", lambda t: t.replace("# n_rows: 3", "# n_rows: 20000000"), "more than the file's contents"),
    ("sizes too large", lambda t: t.replace("# n_inputs: 1", "# n_inputs: 20000"), "more than the file's contents"),
    ("sizes inconsistent", lambda t: t.replace("# n_outputs: 1", "# n_outputs: 2"), "imply 5 columns"),
    ("float size", lambda t: t.replace("# n_inputs: 1", "# n_inputs: 1e10"), "written in digits"),
    ("negative size", lambda t: t.replace("# n_inputs: 1", "# n_inputs: -3"), "written in digits"),
    ("header", lambda t: t.replace("H[0][0].im", "H[0][0].imag"), "unexpected CSV header"),
    ("meta", lambda t: t.replace("# n_inputs: 1\n", ""), "'# n_inputs: ...' is missing"),
    ("meta int", lambda t: t.replace("# n_inputs: 1", "# n_inputs: one"), "positive integer written in digits"),
    ("version", lambda t: t.replace("csv v2", "csv v7"), "format version 7"),
    ("duplicate w", lambda t: t.replace("\n1.0,", "\n0.5,"), "(duplicate)"),
    ("header missing", lambda t: "\n".join(t.splitlines()[:3]) + "\n", "header line of column names is missing"),
]


@pytest.mark.parametrize(("label", "damage", "phrase"), CSV_DAMAGE, ids=[c[0] for c in CSV_DAMAGE])
def test_damaged_csv_raises_data_error(label, damage, phrase, tmp_path):
    path = tmp_path / "frf.csv"
    FrequencyData([0.5, 1.0, 2.0], [1.0, 2.0 + 1j, 3.0]).to_csv(path)
    path.write_text(damage(path.read_text()))
    with pytest.raises(DataError) as info:
        FrequencyData.from_csv(path)
    assert phrase in str(info.value), str(info.value)


BB_DAMAGE = [
    ("unknown matrix", lambda t: t.replace("\nD,0,0", "\nE,0,0"), "unknown matrix 'E'"),
    ("out of range", lambda t: t.replace("\nD,0,0", "\nD,5,0"), "outside D's shape"),
    ("twice", lambda t: t.replace("\nD,0,0", "\nA,0,0"), "A[0,0] appears twice"),
    ("missing", lambda t: t.replace(t.splitlines()[-2] + "\n", "").replace("# n_rows: 9", "# n_rows: 8"),
     "9 entries, but holds 8 rows"),
    ("huge n", lambda t: t.replace("# n_states: 2", "# n_states: 20000"), "more than the file's contents"),
    ("not int", lambda t: t.replace("\nD,0,0", "\nD,x,0"), "must be integers"),
]


@pytest.mark.parametrize(("label", "damage", "phrase"), BB_DAMAGE, ids=[c[0] for c in BB_DAMAGE])
def test_damaged_blackbox_csv(label, damage, phrase, tmp_path):
    path = tmp_path / "bb.csv"
    BlackBox(A, [0, 1], [1, 0]).to_csv(path)
    path.write_text(damage(path.read_text()))
    with pytest.raises(DataError) as info:
        BlackBox.from_csv(path)
    assert phrase in str(info.value), str(info.value)


def test_load_refuses_foreign_files(tmp_path):
    path = tmp_path / "junk.bin"
    path.write_bytes(b"PK\x03\x04 this is not a zip")
    with pytest.raises(DataError, match=r"not a readable \.npz file"):
        load(path)
    path.write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(DataError, match="not a UTF-8 text file"):
        load(path)
    path.write_text("# symid Banana csv v1\nx\n1\n")
    with pytest.raises(DataError, match="unknown kind of data 'Banana'"):
        load(path)
    with pytest.raises(FileNotFoundError):
        load(tmp_path / "nope.csv")


# -- property-based round trip ----------------------------------------------------------------

_finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
_positive = st.floats(min_value=1e-300, max_value=1e300, allow_nan=False, allow_infinity=False)


@st.composite
def _frequency_data(draw):
    w = sorted(draw(st.lists(_positive, min_size=1, max_size=6, unique=True)))
    p, m = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    re = draw(hnp.arrays(np.float64, (len(w), p, m), elements=_finite))
    im = draw(hnp.arrays(np.float64, (len(w), p, m), elements=_finite))
    H = np.empty(re.shape, dtype=complex)
    H.real, H.imag = re, im
    return FrequencyData(np.array(w), H)


@st.composite
def _io_data(draw):
    N, m, p = draw(st.integers(3, 8)), draw(st.integers(1, 3)), draw(st.integers(1, 3))  # N >= channels
    u = draw(hnp.arrays(np.float64, (N, m), elements=_finite))
    y = draw(hnp.arrays(np.float64, (N, p), elements=_finite))
    return IOData(u, y, draw(_positive))


@st.composite
def _spectral_data(draw):
    w = sorted(draw(st.lists(_positive, min_size=1, max_size=4, unique=True)))
    p, m = draw(st.integers(1, 3)), draw(st.integers(1, 2))
    bounded = st.floats(min_value=-1e150, max_value=1e150, allow_nan=False)  # X + Xᴴ stays finite
    parts = [draw(hnp.arrays(np.float64, (len(w), k, k), elements=bounded)) for k in (p, p, m, m)]
    Xy, Xu = parts[0] + 1j * parts[1], parts[2] + 1j * parts[3]

    def spectrum(X):  # Hermitian, and its diagonal a power (≥ 0): SpectralData refuses a negative one
        S = X + np.conj(np.swapaxes(X, 1, 2))
        k = np.arange(S.shape[1])
        S[:, k, k] = np.abs(S[:, k, k].real)
        return S

    return SpectralData(np.array(w), spectrum(Xy), spectrum(Xu))


@st.composite
def _black_box(draw):
    n, m, p = draw(st.integers(1, 3)), draw(st.integers(1, 2)), draw(st.integers(1, 2))
    mats = [draw(hnp.arrays(np.float64, shp, elements=_finite)) for shp in ((n, n), (n, m), (p, n), (p, m))]
    return BlackBox(*mats)


@settings(max_examples=60, deadline=None)
@given(obj=st.one_of(_frequency_data(), _io_data(), _spectral_data(), _black_box()),
       fmt=st.sampled_from(["csv", "npz"]))
def test_round_trip_property(obj, fmt):
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, f"data.{fmt}")
        getattr(obj, f"to_{fmt}")(path)
        back = load(path)
    assert type(back) is type(obj)
    for name in type(obj)._npz_keys:
        assert np.asarray(getattr(back, name)).tobytes() == np.asarray(getattr(obj, name)).tobytes()


def test_iodata_without_dt_names_it():
    with pytest.raises(DataError, match=r"dt is missing: IOData\(u, y, dt\) needs the sample time"):
        IOData(np.ones(5), np.ones(5))
