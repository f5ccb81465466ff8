"""A white residual counts only where the whiteness test could have refused it (symid.fit.success).

Reference: a single-bolus two-compartment decay (k10 = 0.3, k12 = 0.8, k21 = 0.2 per hour, q = 0.05 per mg), sampled
noise-free at 15 times over 48 h (tests/test_timeseries_auto.py). Its residuals are carried by a few early samples:
the lag-one statistic can reach at most 1.8 to 3.2 there (computed below), so it called white the residual of
estimates up to 100 % off (k21 doubled: misfit 8.5e-3, statistic 2.5 ≤ 3), and every such estimate was a success.
One Gauss–Newton step from each predicts a misfit 98 % to 100 % lower (measured; the limit is 50 %).
"""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid.data.timeseries import TimeSeries
from symid.fit.success import WHITENESS_POWER, fit_test, whiteness, whiteness_reach
from symid.fit.timeseries.oe import OutputError
from symid.fit.timeseries.response import simulate_output

TRUTH = np.array([0.3, 0.8, 0.2, 0.05])  # k10, k12, k21, q
TIMES = np.array([0, 0.25, 0.5, 1, 1.5, 2, 3, 4, 6, 8, 12, 16, 24, 36, 48.0])


def _bolus() -> OutputError:
    k10, k12, k21, q = si.parameters("k10 k12 k21 q", positive=True)
    model = si.StateSpaceModel(A=[[-k10 - k12, k21], [k12, -k21]], B=[[0], [0]], C=[[q, 0]], x0=[500.0, 0.0])
    A, B, C, D = model.state_space(TRUTH)
    y = simulate_output(A, B, C, D, TIMES, np.zeros((TIMES.size, 1)), model.initial_state(TRUTH))
    return OutputError(model, TimeSeries(TIMES, np.zeros(TIMES.size), y))


def _judge(est: OutputError, theta: np.ndarray):
    return est.outcome(theta, theta, finished=True, status="test", message="test", iterations=0, wall_time=0.0)


def test_the_reach_is_what_the_smoothest_residual_of_these_sizes_gives():
    r = np.linspace(1.0, 2.0, 15)  # one sign throughout: the statistic reaches its bound
    assert whiteness(r) == pytest.approx(whiteness_reach(r), rel=1e-12)
    assert whiteness_reach(np.ones(15)) == pytest.approx(np.sqrt(14), rel=1e-12)  # 14 equal products
    assert whiteness_reach(np.ones(15, complex)) == pytest.approx(np.sqrt(28), rel=1e-12)
    assert whiteness_reach(np.ones(2)) == 0.0 and whiteness_reach(np.zeros(20)) == 0.0
    # noise: E|p| = 2/π and E p² = 1 per product, so the reach is about √(0.405 (s − 1)), 12.7 for 400 samples
    noise = np.random.default_rng(0).standard_normal(400)
    assert 10.0 < whiteness_reach(noise) < 16.0


@pytest.mark.parametrize("which, factor", [(2, 2.0), (3, 1.05), (1, 1.05)])
def test_a_wrong_estimate_of_a_short_record_is_no_success(which, factor):
    est = _bolus()
    theta = TRUTH.copy()
    theta[which] *= factor
    out = _judge(est, theta)
    res = est.residuals(theta)
    assert 1e-10 < out.cost <= 1e-2 and whiteness(res) <= 3.0  # what the rule before accepted
    assert whiteness_reach(res) < WHITENESS_POWER
    assert not out.success and "Gauss–Newton" in out.fit
    assert est.local_gain(theta) > 0.95
    assert _judge(est, TRUTH).success  # the truth: an exact fit


def test_a_short_residual_counts_when_a_black_box_a_gauss_newton_step_or_a_noise_floor_backs_it():
    r = np.random.default_rng(1).standard_normal(15) * 1e-2
    cost = float(np.sum(r**2))
    args = {"n_data": 15, "n_parameters": 2, "residuals": r}
    assert whiteness(r) <= 3.0 and whiteness_reach(r) < WHITENESS_POWER
    assert not fit_test(cost, **args).fits  # nothing to back a weak test: noise_floor= is asked for
    assert "noise_floor=" in fit_test(cost, **args).text
    assert fit_test(cost, **args, local_gain=lambda: 0.1).fits  # a minimum of the misfit: counts, said to be weak
    assert fit_test(cost, **args, local_gain=lambda: 0.1).rule == "weak whiteness"
    assert not fit_test(cost, **args, local_gain=lambda: 0.9).fits  # one step removes 90 %: no minimum
    assert fit_test(cost, **args, black_box=lambda: (cost, 3)).fits  # b = 3 ≤ N/2 and as good as the fit
    assert not fit_test(cost, **args, black_box=lambda: (cost / 10, 3)).fits  # the data are cleaner than this fit
    assert not fit_test(cost, **args, black_box=lambda: (cost, 9)).fits  # b > N/2: no black box to compare with
    assert fit_test(cost, **args, black_box=lambda: (cost, 9), local_gain=lambda: 0.1).fits  # then the step decides
    assert fit_test(cost, **args, noise_floor=cost).fits  # the noise level given: rule 2 decides


def test_a_long_noisy_record_is_still_judged_by_its_whiteness():
    # the one-mass oscillator of tests/test_oe_progress.py, 200 samples, 1 % noise, fitted from 30-50 % off
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    u = np.random.default_rng(0).standard_normal(200)
    io = si.simulate_io(model, [2.0, 0.8, 50.0], u, 0.05, noise=0.01, seed=2)
    est = OutputError(model, io)
    out = est.run(np.array([3.0, 0.48, 65.0]))
    assert out.success and "white residual" in out.fit
    assert whiteness_reach(est.residuals(out.theta)) > WHITENESS_POWER  # 9.0: about √(0.405 × 199)
