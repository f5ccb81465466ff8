"""Uncertainty of time-domain estimates (issue 15, item 3): Fisher information, standard errors, intervals.

Reference: for Gaussian output noise the least-squares estimate is asymptotically normal with
covariance F⁻¹ (Ljung, System Identification, 2nd ed., §9.2); a 95 % interval should hold the
truth in about 95 % of records. The Monte Carlo test counts that over 200 records.
"""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid.data.timeseries import TimeSeries
from symid.fit.timeseries.response import simulate_output
from symid.fit.uncertainty import fisher_uncertainty

TRUTH = {"k10": 0.2, "k12": 0.5, "k21": 0.15, "q": 0.05}
T_PK = np.array([0, 0.25, 0.5, 1, 1.5, 2, 3, 4, 6, 8, 10, 12, 16, 20, 24, 30, 36, 48.0])
START = {"k10": 0.1, "k12": 0.1, "k21": 0.1, "q": 0.1}


def pk_model():
    k10, k12, k21, q = si.parameters("k10 k12 k21 q", positive=True)
    return si.StateSpaceModel(A=[[-k10 - k12, k21], [k12, -k21]], B=[[0], [0]], C=[[q, 0]], x0=[100.0, 0.0])


def pk_noisy(model, rng, level=0.02):
    """Additive white noise of standard deviation level × std(y) (as si.simulate_io)."""
    A, B, C, D = model.state_space(TRUTH)
    y = simulate_output(A, B, C, D, T_PK, np.zeros((T_PK.size, 1)), model.initial_state(TRUTH))
    return TimeSeries(T_PK, np.zeros(T_PK.size), y + level * np.std(y) * rng.standard_normal(y.shape))


def test_single_dose_with_two_percent_noise_lies_within_its_intervals():
    """One record (seed 1). Not every record does: with seed 0, k10 lies 2.7 standard errors out, one of the
    ~5 % the Monte Carlo test below counts."""
    model = pk_model()
    res = si.identify(model, pk_noisy(model, np.random.default_rng(1)), method="oe", x0=START,
                      identifiability_check=False)
    unc = res.uncertainty
    assert res.success and unc is not None and not unc.near_singular
    for i, name in enumerate(res.parameter_names):
        lo, hi = unc.intervals[i]
        assert lo <= TRUTH[name] <= hi
        assert 0 < unc.standard_errors[i] < 0.1 * TRUTH[name]  # measured 0.3 % (q) to 3.4 % (k21)
    text = res.summary(TRUTH)
    assert "std. error" in text and "95 % interval" in text
    assert res.to_dict()["uncertainty"]["dof"] == T_PK.size - 4


def test_near_singular_fisher_information_is_flagged():
    """y = e^{-(a+b) t}: only a + b is determined; the weakest direction is (a − b)/√2."""
    a, b = si.parameters("a b", positive=True)
    model = si.StateSpaceModel(A=[[-a - b]], B=[[0]], C=[[1]], x0=[1.0])
    io = si.simulate_io(model, {"a": 0.3, "b": 0.2}, np.zeros(40), dt=0.1, noise=0.01, seed=1)
    res = si.identify(model, io, method="oe", x0=[0.2, 0.2], identifiability_check=False)
    unc = res.uncertainty
    assert unc.near_singular
    assert abs(abs(unc.weakest["a"]) - np.sqrt(0.5)) < 1e-3 and unc.weakest["a"] * unc.weakest["b"] < 0
    assert "NEAR-SINGULAR" in res.summary()
    # and beside success, not only below it (a new user's roof-only record: success, masses 4 times the truth)
    best = next(x for x in res.summary().splitlines() if x.startswith("best:"))
    assert res.success and "do not determine every parameter" in best
    determined = si.identify(model.with_known({"b": 0.2}), io, method="oe", x0=[0.2], identifiability_check=False)
    assert determined.success and "do not determine" not in determined.summary()


def test_fisher_uncertainty_matches_linear_regression():
    """A linear model: F⁻¹ σ̂² is the textbook (XᵀX)⁻¹ s² with s² = RSS / (N − k)."""
    rng = np.random.default_rng(3)
    X = rng.standard_normal((30, 3))
    y = X @ [1.0, -2.0, 0.5] + rng.standard_normal(30)
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ beta  # the least-squares residual (orthogonal to the columns of X)
    u = fisher_uncertainty(beta, ("a", "b", "c"), r, -X, np.zeros(30, int))
    np.testing.assert_allclose(u.covariance, np.linalg.inv(X.T @ X) * (r @ r) / 27, rtol=1e-10)


@pytest.mark.slow
def test_monte_carlo_coverage_of_95_percent_intervals():
    """200 records of the single-dose PK study with 2 % noise: every parameter's 95 % interval holds the
    truth in 90–98 % of them (issue 15 bound; binomial sd of the rate at 0.95 is 1.5 %)."""
    model = pk_model()
    rng = np.random.default_rng(2026)
    hits = np.zeros(4)
    n = 200
    for _ in range(n):
        res = si.identify(model, pk_noisy(model, rng), method="oe", x0=[TRUTH[k] for k in TRUTH],
                          identifiability_check=False)
        assert res.success
        lo, hi = res.uncertainty.intervals.T
        truth = np.array(list(TRUTH.values()))
        hits += (lo <= truth) & (truth <= hi)
    rate = hits / n
    print("coverage", dict(zip(TRUTH, rate.round(3).tolist(), strict=True)))
    assert np.all((rate >= 0.90) & (rate <= 0.98)), rate


def test_an_initial_position_the_output_cannot_see_is_not_a_near_singular_direction():
    """A new user's room (heat capacities as masses, conductances as dampers, K = 0, temperatures as velocities,
    the initial state estimated): the initial positions reach neither the output nor the dynamics, their columns
    of the Jacobian are zero, and every well-determined fit was flagged "NEAR-SINGULAR … practically
    non-identifiable" (condition 1e20 or inf). They are left out now: two nodes here, not flagged, and the
    intervals hold the truth (references: the values simulated)."""
    Ca, Cw, Haw, Hwo = si.parameters("Ca Cw Haw Hwo", positive=True)
    model = si.SecondOrderModel(M=[[Ca, 0], [0, Cw]], V=[[Haw, -Haw], [-Haw, Haw + Hwo]], K=[[0, 0], [0, 0]],
                                B=[[1], [0]], C=[[1, 0]], output="velocity")
    truth = {"Ca": 5e5, "Cw": 8e6, "Haw": 300.0, "Hwo": 80.0}
    u = np.where((np.arange(2000) // 97) % 2 == 0, 2000.0, 0.0)  # a heater switched on and off, 1-minute samples
    io = si.simulate_io(model, truth, u, 60.0, x0=[0.0, 0.0, 18.0, 17.5], noise_std=0.05, seed=3)
    res = si.identify(model, io, method="oe", x0=truth, initial_state="estimate", identifiability_check=False)
    unc = res.uncertainty
    assert res.success and not unc.near_singular, unc.summary()
    th = np.array([truth[n] for n in model.parameter_names])
    assert np.all((unc.intervals[:, 0] <= th) & (th <= unc.intervals[:, 1]))


def test_an_estimate_where_two_solutions_meet_is_said_to():
    """A new user's oral dose (absorption into a two-compartment model): with noise the least-squares estimate often
    lands where the flip-flop's two solutions meet (ka equal to a disposition rate), where no interval is finite, and
    the note named "the other solution", the estimate itself. Reference: the estimate's own disposition matrix,
    one of whose rates equals its ka at the fold (an exact property of the meeting point)."""
    import warnings

    ka, k10, k12, k21, q = si.parameters("ka k10 k12 k21 q", positive=True)
    model = si.StateSpaceModel(A=[[-ka, 0, 0], [ka, -k10 - k12, k21], [0, k12, -k21]], B=[[1], [0], [0]],
                               C=[[0, q, 0]])
    truth = {"ka": 0.6, "k10": 0.15, "k12": 0.3, "k21": 0.2, "q": 1 / 30}  # ka at the disposition rate 0.6
    t = np.array([0, 0.01, 0.25, 0.5, 1, 2, 3, 4, 6, 8, 12, 16, 20, 24.0])  # h; a 0.01 h bolus of 500 mg
    fine = np.linspace(0, 24, 24 * 1000 + 1)
    clean = si.simulate_io(model, truth, np.where(fine < 0.01, 5e4, 0.0), fine[1] - fine[0])
    y = np.interp(t, fine, clean.y[:, 0]) * (1 + 0.05 * np.random.default_rng(3).standard_normal(t.size))
    record = TimeSeries(t, np.where(t < 0.01, 5e4, 0.0), y, time_unit="h")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = si.identify(model, record, x0={"ka": 1.0, "k10": 0.1, "k12": 0.2, "k21": 0.3, "q": 0.05}, seed=0)
    th = res.theta
    rates = -np.linalg.eigvals([[-th["k10"] - th["k12"], th["k21"]], [th["k12"], -th["k21"]]])
    assert np.min(np.abs(rates - th["ka"])) < 1e-3 * th["ka"]  # at the meeting point
    assert "another solution coincides with it" in res.uncertainty.note
    assert "the other solution is" not in res.uncertainty.note
