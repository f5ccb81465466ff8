"""Outputs not measured at some sample times (NaN in a TimeSeries): left out of the output-error misfit.

The case that needs it (a new user's trial): an infusion that stops between two sparse blood samples. The
input switch must be a sample time of the record (the input is held between sample times), and no output is
measured there. Reference values: the model's truth (the data are simulated from it) and exact identities of
the misfit over the measured values.
"""

import numpy as np
import pytest

import symid as si
from symid.data import IOData, TimeSeries
from symid.fit.registry import prepare

K10, K12, K21, Q = si.parameters("k10 k12 k21 q", positive=True)
PK = si.StateSpaceModel(A=[[-K10 - K12, K21], [K12, -K21]], B=[[1], [0]], C=[[Q, 0]])  # q = 1/V
TRUTH = {"k10": 0.3, "k12": 0.5, "k21": 0.2, "q": 0.05}
SAMPLES = np.array([0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0])  # h
STOP = 0.75  # the infusion of 100 mg/h stops here, between two samples
START = {"k10": 0.1, "k12": 0.1, "k21": 0.1, "q": 0.02}


def infusion(noise=0.02, seed=0):
    """The record with the switch time as a row whose output is NaN; y from a 9 s grid (exact at the samples)."""
    t = np.sort(np.append(SAMPLES, STOP))
    fine = np.linspace(0.0, 24.0, 24 * 400 + 1)
    clean = si.simulate_io(PK, TRUTH, np.where(fine < STOP, 100.0, 0.0), fine[1] - fine[0])
    y = np.interp(t, fine, clean.y[:, 0]) * (1 + noise * np.random.default_rng(seed).standard_normal(t.size))
    y[t == STOP] = np.nan
    return TimeSeries(t, np.where(t < STOP, 100.0, 0.0), y, time_unit="h")


def test_a_time_series_takes_nan_outputs_and_keeps_them():
    rec = infusion()
    assert rec.n_missing == 1 and np.isnan(rec.y[2, 0])
    assert "1 missing" in rec.summary()
    assert rec == TimeSeries(rec.t, rec.u, rec.y, time_unit="h")  # NaN equals NaN in a record's equality


def test_a_record_with_missing_outputs_survives_npz(tmp_path):
    rec = infusion()
    rec.to_npz(tmp_path / "r.npz")
    assert TimeSeries.from_npz(tmp_path / "r.npz") == rec


@pytest.mark.parametrize(("u", "y", "match"), [
    ([1.0, np.nan, 0.0], [0.0, 1.0, 0.5], r"u\[1, 0\] is nan .* an output not measured there is NaN"),
    ([1.0, 0.0, 0.0], [0.0, np.inf, 0.5], r"y\[1, 0\] is inf .* or NaN where it was not measured"),
    ([1.0, 0.0, 0.0], [np.nan, np.nan, np.nan], r"y\[:, 0\] is NaN at every sample time"),
])
def test_what_cannot_be_missing_is_named(u, y, match):
    with pytest.raises(si.DataError, match=match):
        TimeSeries([0.0, 1.0, 2.0], u, y)


def test_a_uniform_record_with_a_missing_output_points_to_a_time_series():
    with pytest.raises(si.DataError, match=r"y\[1, 0\] = nan .* use a TimeSeries"):
        IOData([1.0, 0.0, 0.0], [0.0, np.nan, 0.5], 0.1)


def test_the_misfit_runs_over_the_measured_values_only():
    rec = infusion()
    est = prepare(PK, rec, "oe", {})
    theta = np.array([0.25, 0.6, 0.25, 0.04])
    seen = ~np.isnan(rec.y)
    filled = TimeSeries(rec.t, rec.u, np.where(seen, rec.y, 123.0), time_unit="h")  # any value in the gap
    yhat = prepare(PK, filled, "oe", {}).simulate(theta)[0]  # the simulation does not depend on y
    expected = np.sum((rec.y[seen] - yhat[seen]) ** 2) / np.sum(rec.y[seen] ** 2)
    np.testing.assert_allclose(est.misfit(theta), expected, rtol=1e-10)
    assert est.n_data() == 11 and est.n_missing == 1
    r, J = est.jacobian(theta)
    np.testing.assert_allclose(r @ r, expected, rtol=1e-10)
    assert np.all(J[~seen.T.reshape(-1)] == 0)  # a missing value moves nothing


@pytest.mark.parametrize("method", ["oe", "auto"])
def test_an_infusion_that_stops_between_samples_is_fitted(method):
    """2 % proportional noise, 11 samples over 24 h: the truth within the 95 % intervals, errors of a few %."""
    res = si.identify(PK, infusion(), method=method, x0=START)
    assert res.success
    err = np.abs(res.theta_vector / np.array(list(TRUTH.values())) - 1)
    assert np.all(err < 0.1)  # measured 0.2 - 5 % (k21 the largest)
    ci = res.uncertainty.intervals
    assert np.all((ci[:, 0] <= list(TRUTH.values())) & (list(TRUTH.values()) <= ci[:, 1]))


def test_a_variance_and_a_noise_level_need_no_value_where_the_output_is_missing():
    rec = infusion()
    var = (0.02 * rec.y) ** 2 + 1e-6  # from the measured values, as a user writes it: NaN where y is NaN
    res = si.identify(PK, rec, method="oe", x0=START, variance=var, noise_std=np.sqrt(var))
    assert res.success and np.all(np.isfinite(res.uncertainty.intervals))


def test_validation_scores_the_measured_values_and_says_so():
    rec = infusion(noise=0.0)
    v = si.validate(PK, TRUTH, rec, max_lag=3)
    np.testing.assert_allclose(v.fit_percent, 100.0, atol=1e-3)  # interpolated from a 9 s grid: exact to ~1e-6
    assert any("1 output value(s) not measured" in n for n in v.notes)
    assert np.isnan(v.y[0][2, 0])


def test_validation_of_a_short_record_by_default(tmp_path):
    """A clinical record of 12 rows: the default lag is a quarter of the 11 measured (2, said in a note; 25 needed
    longer records, a new user's trial), and the model's curve between the sparse samples is drawn from the same
    simulation (its values at the samples are the simulated ones)."""
    rec = infusion(noise=0.0)
    v = si.validate(PK, TRUTH, rec)
    assert v.lags[-1] == 2 and any("up to lag 2, a quarter of the shortest record (11 samples" in n for n in v.notes)
    with pytest.raises(si.DataError, match=r"max_lag = 11 needs records longer than 11 samples.*leave max_lag out"):
        si.validate(PK, TRUTH, rec, max_lag=11)
    t, y = v.t_fine[0], v.y_fine[0]
    assert t.size > 1000 and t[0] == rec.t[0] and t[-1] == rec.t[-1]
    at = np.searchsorted(t, rec.t)
    np.testing.assert_array_equal(t[at], rec.t)
    # the same system from the same state, in steps a q-th of each interval: equal to rounding (expm either way)
    np.testing.assert_allclose(y[at], v.y_sim[0], rtol=1e-9, atol=1e-12)
    # and between them the response an independent simulation on a 9 s grid gives (exact there for the held input;
    # linear interpolation between its points errs by ~1e-5 of the peak)
    fine = np.linspace(0.0, 24.0, 24 * 400 + 1)
    clean = si.simulate_io(PK, TRUTH, np.where(fine < STOP, 100.0, 0.0), fine[1] - fine[0])
    np.testing.assert_allclose(y[:, 0], np.interp(t, fine, clean.y[:, 0]), rtol=0, atol=1e-4 * clean.y.max())
    first, _ = v.plot(tmp_path / "pk")
    assert first.stat().st_size > 10_000


def test_methods_that_filter_every_sample_refuse_missing_outputs():
    m, c, k = si.parameters("m c k", positive=True)
    mck = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    io = si.simulate_io(mck, [1.0, 0.4, 4.0], np.random.default_rng(0).standard_normal(300), 0.05)
    y = io.y.copy()
    y[10] = np.nan
    rec = TimeSeries(io.t, io.u, y)
    for method in ("svf", "srivc"):
        with pytest.raises(si.DataError, match=rf"1 output value\(s\) are missing \(NaN\): method '{method}'"):
            si.identify(mck, rec, method=method)
    assert si.identify(mck, rec, method="oe", x0=[2.0, 1.0, 8.0]).success


def test_an_empty_output_cell_is_a_missing_value_in_a_time_series_table(tmp_path):
    path = tmp_path / "pk.csv"
    path.write_text("t,u,y\n0,100,0\n0.5,100,2.1\n0.75,0,\n1,0,1.9\n2,0,NaN\n4,0,0.9\n")
    columns = {"time": "t", "input": "u", "output": "y"}
    ts = TimeSeries.from_table(path, columns=columns, units={"time": "h"}, time_unit="h")
    assert ts.n_missing == 2 and np.isnan(ts.y[[2, 4], 0]).all()
    with pytest.raises(si.DataError, match=r"line 4, column 'y': the value is missing .* read the table as a "
                                           "TimeSeries"):
        IOData.from_table(path, columns=columns, units={"time": "h"})


def test_both_solvers_leave_the_missing_value_out_alike():
    """The CasADi graph (solver='ipopt') weighs the missing value 0 as the numpy residual (trf) does: the same
    least-squares estimate (measured 4e-11 apart)."""
    trf = si.identify(PK, infusion(), method="oe", x0=START)
    ipopt = si.identify(PK, infusion(), method="oe", solver="ipopt", x0=START)
    np.testing.assert_allclose(ipopt.theta_vector, trf.theta_vector, rtol=1e-6)


def test_without_the_switch_row_the_infusion_is_misplaced():
    """The same record without the row at the stop time: the input is held to the next sample (1 h instead of
    0.75 h), a third more drug than was given, and output error cannot fit it (measured: k12 = 114 for 0.5, the
    fit refused). The row with a NaN output is what places the switch."""
    rec = infusion()
    keep = ~np.isnan(rec.y[:, 0])
    dropped = TimeSeries(rec.t[keep], rec.u[keep], rec.y[keep], time_unit="h")
    res = si.identify(PK, dropped, method="oe", x0=START)
    err = np.abs(res.theta_vector / np.array(list(TRUTH.values())) - 1)
    assert not res.success and err.max() > 1.0
