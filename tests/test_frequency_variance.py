"""FrequencyData's optional per-line noise variance: validation, files, pickling, selection."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from symid.data import FrequencyData, load
from symid.errors import DataError

W = np.array([1.0, 2.0, 3.0, 5.0])


def _mimo():
    rng = np.random.default_rng(0)
    H = rng.standard_normal((4, 2, 3)) + 1j * rng.standard_normal((4, 2, 3))
    return FrequencyData(W, H, variance=rng.uniform(0, 1e-3, (4, 2, 3)))


def test_siso_variance_is_stored_like_h():
    f = FrequencyData(W, np.ones(4), variance=[0.1, 0.2, 0.0, 0.3])
    assert f.variance.shape == (4, 1, 1)
    assert not f.variance.flags.writeable
    assert FrequencyData(W, np.ones(4)).variance is None


@pytest.mark.parametrize("fmt", ["csv", "npz"])
@pytest.mark.parametrize("with_variance", [True, False])
def test_file_round_trip_keeps_the_variance_bit_for_bit(tmp_path, fmt, with_variance):
    f = _mimo() if with_variance else FrequencyData(W, _mimo().H)
    path = tmp_path / f"frf.{fmt}"
    (f.to_csv if fmt == "csv" else f.to_npz)(path)
    back = load(path)
    assert back == f
    if with_variance:
        assert np.array_equal(back.variance, f.variance)
    else:
        assert back.variance is None


def test_equality_pickle_copy_and_selection_keep_the_variance():
    f = _mimo()
    assert f != FrequencyData(f.w, f.H)  # a noise model is part of the data
    assert pickle.loads(pickle.dumps(f)) == f
    assert copy.deepcopy(f) == f
    sel = f[1:3]
    assert np.array_equal(sel.variance, f.variance[1:3]) and np.array_equal(sel.H, f.H[1:3])
    mask = f[np.array([True, False, True, True])]
    assert np.array_equal(mask.w, W[[0, 2, 3]]) and np.array_equal(mask.variance, f.variance[[0, 2, 3]])
    assert f[[0, 3]].n_frequencies == 2
    assert "noise std" in f.summary()


@pytest.mark.parametrize(("variance", "match"), [
    ([0.1, -1e-9, 0.0, 0.0], "must be >= 0"),
    ([0.1, 0.2], "shape of H"),
    ([0.1j, 0, 0, 0], "must be real"),
    ([np.nan, 0, 0, 0], "must be finite"),
    ([np.inf, 0, 0, 0], "must be finite"),
    (["a", "b", "c", "d"], "must hold numbers"),
])
def test_bad_variance_is_refused_by_name(variance, match):
    with pytest.raises(DataError, match=match):
        FrequencyData(W, np.ones(4), variance=variance)


@pytest.mark.parametrize("index", [slice(4, 9), [2, 0], "a", 1.5, None])
def test_bad_selection_is_a_data_error(index):
    with pytest.raises(DataError):
        _mimo()[index]


def test_csv_with_a_variance_column_missing_is_refused(tmp_path):
    path = tmp_path / "frf.csv"
    FrequencyData(W, np.ones(4), variance=np.ones(4)).to_csv(path)
    text = path.read_text().replace(",var[0][0]", ",var[0][1]")
    path.write_text(text)
    with pytest.raises(DataError, match="unexpected CSV header"):
        FrequencyData.from_csv(path)


@pytest.mark.parametrize("fmt", ["csv", "npz"])
def test_the_variances_degrees_of_freedom_travel_with_it(tmp_path, fmt):
    """variance_dof (an estimated variance's degrees of freedom): files, pickling, copies and selection keep it;
    equality sees it; the summary says it."""
    f = FrequencyData(_mimo().w, _mimo().H, _mimo().variance, variance_dof=14)
    path = tmp_path / f"frf.{fmt}"
    (f.to_csv if fmt == "csv" else f.to_npz)(path)
    back = load(path)
    assert back == f and back.variance_dof == 14.0
    assert pickle.loads(pickle.dumps(f)).variance_dof == 14.0 and copy.deepcopy(f).variance_dof == 14.0
    assert f[1:3].variance_dof == 14.0
    assert f != _mimo()  # the same arrays, a variance known exactly
    assert "estimated with 14 degrees of freedom" in f.summary()


@pytest.mark.parametrize(("dof", "variance", "match"), [
    (0, np.ones(4), r"variance_dof must be a finite number > 0"),
    (np.nan, np.ones(4), r"variance_dof must be a finite number > 0"),
    ("14", np.ones(4), r"variance_dof must be a finite number > 0"),
    (14, None, r"variance_dof is given without a variance"),
])
def test_bad_degrees_of_freedom_are_refused_by_name(dof, variance, match):
    with pytest.raises(DataError, match=match):
        FrequencyData(W, np.ones(4), variance, variance_dof=dof)
