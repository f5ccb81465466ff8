"""Output error with ``solver="trf"``: trust-region least squares on the numpy sensitivities (symid/fit/timeseries).

References: the parameters the records are simulated from (noise-free: the exact fit), and IPOPT's estimate
(``solver="ipopt"``) on the same noisy records, the least-squares minimum both reach.
"""

import itertools
import warnings

import numpy as np
import pytest

import symid as si
from symid.fit.timeseries.auto import AutoOutputError
from symid.fit.timeseries.oe import OutputError

TRUTH = np.array([2.0, 0.8, 50.0])
START = TRUTH * np.array([1.5, 0.6, 1.3])
DT = 0.05


def oscillator(factors=None):
    factors = np.ones(3) if factors is None else np.asarray(factors)
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[factors[0] * m]], V=[[factors[1] * c]], K=[[factors[2] * k]], B=[[1]], C=[[1]],
                               parameters=[m, c, k])


def record(noise=None, x0=None, n=300, seed=0):
    u = np.random.default_rng(seed).standard_normal(n)
    return si.simulate_io(oscillator(), TRUTH, u, DT, noise=noise, seed=seed + 1, x0=x0)


def test_trf_reaches_the_truth_of_noise_free_samples():
    out = OutputError(oscillator(), record(), solver="trf").run(START)
    assert out.success and out.message.startswith("trf:")
    np.testing.assert_allclose(out.theta, TRUTH, rtol=1e-8)  # the exact fit of samples of the model itself


def test_trf_and_ipopt_reach_the_same_least_squares_estimate_on_noisy_samples():
    io = record(noise=0.02)
    trf = OutputError(oscillator(), io, solver="trf").run(START)
    ipopt = OutputError(oscillator(), io, solver="ipopt").run(START)
    assert trf.success and ipopt.success
    assert np.max(np.abs(trf.theta / TRUTH - 1)) > 1e-4  # the noise moved the estimate: a real comparison
    np.testing.assert_allclose(trf.theta, ipopt.theta, rtol=1e-6)
    assert trf.cost <= ipopt.cost * (1 + 1e-9)


def test_trf_estimates_the_initial_states_of_several_records():
    records = [record(x0=[0.3, -1.0], seed=1), record(x0=[-0.2, 0.5], n=200, seed=2)]
    est = OutputError(oscillator(), records, initial_state="estimate", solver="trf")
    out = est.run(START)
    assert out.success
    np.testing.assert_allclose(out.theta, TRUTH, rtol=1e-8)
    x0s = est.initial_states(out.theta)
    np.testing.assert_allclose(x0s[0], [0.3, -1.0], rtol=1e-7)
    np.testing.assert_allclose(x0s[1], [-0.2, 0.5], rtol=1e-7)


def test_trf_estimate_follows_the_units():
    """Parameters declared in units 1e-5 … 1e6 apart, time in ms, outputs × 1e5, initial state estimated: the
    estimate is the same estimate converted (the unknowns are log-parameters relative to the start)."""
    io = record(noise=0.01, x0=[0.3, -1.0])
    ref = OutputError(oscillator(), io, initial_state="estimate", solver="trf").run(START)
    f = 10.0 ** np.array([-5.0, 4.0, 6.0])
    alpha, beta = 1e-3, 1e5  # time in units 1e3 times smaller; outputs 1e5 times larger
    T = np.array([alpha**-2, alpha**-1, 1.0]) / beta / f  # m, c, k of the same physics in the new units
    io_u = si.IOData(io.u, io.y * beta, DT / alpha)
    out = OutputError(oscillator(f), io_u, initial_state="estimate", solver="trf").run(START * T)
    assert ref.success and out.success
    np.testing.assert_allclose(out.theta / T, ref.theta, rtol=1e-6)


def test_trf_keeps_to_its_time_limit_and_stops_on_the_callback():
    io = record(n=3000)
    est = OutputError(oscillator(), io, solver="trf", time_limit=0.2, max_iter=10**6, tol=1e-15)
    out = est.run(TRUTH * 30)
    # the budget plus at most one evaluation (a few ms here) and the outcome's test
    assert out.status == "time_limit" and not out.finished and out.wall_time < 3.0
    seen = []
    stopper = OutputError(oscillator(), record(), solver="trf", callback=lambda info: seen.append(info) or True)
    out = stopper.run(START)
    assert out.status == "stopped" and len(seen) == 1
    np.testing.assert_allclose(seen[0].theta, START, rtol=1e-12)  # the first evaluation: the start itself


def test_trf_verbose_prints_a_line_per_evaluation_that_lowers_the_misfit(capsys):
    seen = []
    out = OutputError(oscillator(), record(noise=0.01), verbose=True, callback=seen.append).run(START)
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(seen) >= 3 and all(line.startswith("trf    iteration") for line in lines)
    misfits = [i.objective for i in seen]
    assert all(b < a for a, b in itertools.pairwise(misfits))  # each one lower
    assert misfits[-1] == pytest.approx(out.cost, rel=1e-9)
    assert seen[0].theta == pytest.approx(START, rel=1e-12)


def test_a_start_where_the_model_cannot_be_simulated_is_said_so():
    # an unstable start whose response overflows the record (found on a generated 3-state network, where trf
    # reported SciPy's "gtol" at the start: a zero gradient of the refused residual)
    a, b = si.parameters("a b")
    model = si.StateSpaceModel(A=[[a, b], [0, -1]], B=[[0], [1]], C=[[1, 0]])
    io = si.simulate_io(model, {"a": -1.0, "b": 1.0}, np.random.default_rng(0).standard_normal(400), dt=1.0)
    out = OutputError(model, io).run(np.array([2000.0, 1.0]))  # e^{2000 t}: not finite after the first sample
    assert out.status == "invalid_start" and not out.success and not out.finished
    assert "not finite" in out.message


def test_a_budget_spent_before_the_first_evaluation_is_a_time_limit_not_an_invalid_start():
    out = OutputError(oscillator(), record(), time_limit=1e-9).run(START)  # found by a new user: "invalid_start"
    assert out.status == "time_limit" and not out.finished
    np.testing.assert_array_equal(out.theta, START)


def test_steps_that_all_overflow_leave_the_start_and_say_so():
    # found by a new user: an unstable start (e^{~7.7 t} over 40 s) evaluated, every step from it overflowed, and trf
    # returned NaN parameters under SciPy's "gtol"; now the start, with a status and message saying why
    a, b, g = si.parameters("a b g")
    model = si.StateSpaceModel(A=[[0, 1], [-a, -b]], B=[[0], [g]], C=[[1, 0]])
    u = np.repeat(np.random.default_rng(3).standard_normal(100), 8)
    io = si.simulate_io(model, {"a": 4.0, "b": 0.6, "g": 2.0}, u, dt=0.05, noise=0.01, seed=1)
    start = np.array([-20.0, -5.0, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # and nothing from numpy or SciPy is printed
        out = OutputError(model, io).run(start)
    assert np.all(np.isfinite(out.theta)) and not out.success and not out.finished
    # measured: one finite evaluation (the start), every step from it refused
    np.testing.assert_array_equal(out.theta, start)
    assert out.status == "no_step" and "every step from the start was refused" in out.message


def test_an_unknown_solver_and_a_hessian_trf_does_not_use_are_named():
    with pytest.raises(si.OptionError, match="solver"):
        OutputError(oscillator(), record(), solver="lbfgs")
    with pytest.raises(si.OptionError, match="hessian='exact' is IPOPT's"):
        OutputError(oscillator(), record(), solver="trf", hessian="exact")


def test_auto_runs_its_passes_with_trf():
    est = AutoOutputError(oscillator(), record(), solver="trf", black_box_start=False)
    out = est.run(START)
    assert out.success
    assert any(f"best pass: {why}" in out.message for why in ("gtol", "ftol", "xtol", "ftol_xtol"))  # trf's own
    np.testing.assert_allclose(out.theta, TRUTH, rtol=1e-8)
