"""FRF ``ls`` and time-series ``svf`` and ``srivc`` talk and stop (issue 14, item 6): time_limit=, callback=, verbose=.

Problems (all fixed seeds):

- ``ls``: the 2-DOF mass-damper of thesis (4-19) with a full set of sensors (C = I), 1 % noise and its
  per-line variance, so the noise-weighted iteration runs (5 solves, measured; one solve per iteration);
- ``svf``: the one-mass oscillator m q̈ + c q̇ + k q = u (m = 2, c = 0.8, k = 50) at 0.05 s, 5 % output noise:
  least squares and 5 instrumental-variable steps (6 iterations, measured);
- ``srivc``: the same oscillator, 400 samples, 1 % noise; with ``tol=1e-300`` it never converges and runs to
  ``max_iter`` (2000 iterations took 2.3 s, about 1 ms each, measured).

Two kinds of budget test. With a callback that sleeps ``NAP`` seconds every iteration cannot end on its own rule
within ``BUDGET`` (ls needs 5 naps, svf 6, srivc 50): the budget is what stops it, on any machine. Every method
checks its clock after each iteration, so a start overruns its budget by at most one iteration (one nap plus
milliseconds of work) and the outcome's misfit: ``OVERRUN`` = 2 s leaves room for a loaded 2-core machine, as
tests/test_similarity_progress.py. Without a callback, a tiny budget (1 ms) stops ls and svf after at most two
iterations (the first ends past 1 ms, or the second does: a noise-weighted solve or an IV step takes 10+ ms) where
the run without a budget needs 5 or 6, so the stopped run takes less time than the full one (about 2/5 of it, so
the bound holds through a load swing of 2x between the two runs); srivc with ``tol=1e-300`` (otherwise ~10 s for
10⁴ iterations) stops within ``BUDGET`` + ``OVERRUN``.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import symid as si
from symid.engine.scr import ScrProgress
from symid.fit.frf.ls import LinearFRF
from symid.fit.registry import prepare
from symid.fit.timeseries.srivc import SimplifiedRIVC

BUDGET = 0.25
NAP = 0.1
OVERRUN = 2.0  # see the module notes
TRUTH_2DOF = {"m1": 1.0, "m2": 2.0, "c1": 0.1, "c2": 0.3, "k1": 2.0, "k2": 1.0}


def two_dof_sensors():
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[[1], [0]], C=[[1, 0], [0, 1]])


def weighted_frf(lines):
    model = two_dof_sensors()
    w = np.linspace(0.1, 3.0, lines)
    H = np.asarray(si.simulate_frf(model, TRUTH_2DOF, w, noise=0.01, seed=1).H)
    return model, si.FrequencyData(w, H, variance=(0.01 * np.abs(H)) ** 2 + 1e-8)


def oscillator():
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])


def records(n, noise):
    u = np.random.default_rng(0).standard_normal(n)
    return oscillator(), si.simulate_io(oscillator(), [2.0, 0.8, 50.0], u, dt=0.05, noise=noise, seed=2)


def ls_problem():
    return weighted_frf(200)


def svf_problem():
    return records(2000, 0.05)


def srivc_problem():
    return records(400, 0.01)


# (method, problem, options that keep it iterating, lines verbose prints start with)
CASES = [
    ("ls", ls_problem, {}, "ls     iteration"),
    ("svf", svf_problem, {}, "svf    iteration"),
    ("srivc", srivc_problem, {"tol": 1e-300, "max_iter": 50}, "srivc  iteration"),
]
IDS = [c[0] for c in CASES]


@pytest.fixture(scope="module")
def problems():
    return {fn: fn() for fn in {c[1] for c in CASES}}


def start(model):
    return np.ones(model.n_parameters)


def fits(est, out):
    """The success rule on the kept estimate alone: a stopped start is a success exactly when its estimate fits."""
    return est.outcome(out.start, out.theta, finished=True, status="", message="", iterations=0,
                       wall_time=0.0).success


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_a_time_limit_stops_a_slow_start_and_says_so(case, problems):
    method, problem, opts, _ = case
    model, data = problems[problem]

    def slow(info):
        time.sleep(NAP)
        return False

    est = prepare(model, data, method, {"time_limit": BUDGET, "callback": slow, **opts})
    t0 = time.perf_counter()
    out = est.run(start(model))
    wall = time.perf_counter() - t0
    assert out.status == "time_limit" and f"time limit of {BUDGET:g} s reached" in out.message
    assert not out.finished and out.success == fits(est, out)  # stopped short of its own rule; success = the fit
    assert 1 <= out.iterations <= BUDGET / NAP + 2
    assert wall <= BUDGET + OVERRUN, wall
    assert est.options["time_limit"] == BUDGET


@pytest.mark.parametrize("method", ["ls", "svf"])
def test_a_tiny_time_limit_stops_ls_and_svf_after_two_iterations_at_most(method):
    model, data = weighted_frf(2000) if method == "ls" else records(2000, 0.05)
    full = prepare(model, data, method, {"time_limit": 60.0}).run(start(model))
    assert full.status == ("solved" if method == "ls" else "least squares") and full.finished
    assert full.iterations >= 5
    est = prepare(model, data, method, {"time_limit": 1e-3})
    t0 = time.perf_counter()
    out = est.run(start(model))
    wall = time.perf_counter() - t0
    assert out.status == "time_limit" and "time limit of 0.001 s reached" in out.message
    assert not out.finished and out.success == fits(est, out) and 1 <= out.iterations <= 2
    assert np.all(np.isfinite(out.theta)) and np.isfinite(out.cost)  # the last estimate is kept
    assert wall < full.wall_time, (wall, full.wall_time)  # see the module notes


def test_a_time_limit_stops_srivc_that_would_run_for_seconds():
    model, data = srivc_problem()
    est = SimplifiedRIVC(model, data, tol=1e-300, max_iter=10**4, time_limit=BUDGET)
    t0 = time.perf_counter()
    out = est.run(start(model))
    wall = time.perf_counter() - t0
    assert out.status == "time_limit" and f"time limit of {BUDGET:g} s reached" in out.message
    assert not out.finished and out.success == fits(est, out) and 1 <= out.iterations < 10**4
    assert wall <= BUDGET + OVERRUN, wall
    assert SimplifiedRIVC(model, data, time_limit=60.0).run(start(model)).status == "converged"


def test_ls_without_a_variance_is_one_solve_whatever_the_budget():
    model, data = weighted_frf(200)
    plain = si.FrequencyData(data.w, data.H)
    seen = []
    out = LinearFRF(model, plain, time_limit=1e-9, callback=lambda i: seen.append(i) or True).run()
    assert (out.status, out.finished, out.iterations, len(seen)) == ("solved", True, 1, 1)


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_the_callback_sees_every_iteration_with_a_finite_misfit(case, problems):
    method, problem, _, _ = case
    model, data = problems[problem]
    seen = []
    est = prepare(model, data, method, {"callback": seen.append})
    out = est.run(start(model))
    assert out.finished and out.iterations >= 2
    assert seen and all(isinstance(i, ScrProgress) for i in seen)
    assert [i.iteration for i in seen] == list(range(1, out.iterations + 1))
    assert np.all(np.diff([i.elapsed for i in seen]) >= 0)
    assert all(np.isfinite(i.misfit) and np.isfinite(i.residual) and 0 <= i.residual for i in seen)
    assert seen[-1].misfit == pytest.approx(est.misfit(out.theta), rel=1e-9, abs=1e-14)
    assert seen[-1].misfit == pytest.approx(out.cost, rel=1e-9, abs=1e-14)
    np.testing.assert_allclose(seen[-1].theta, out.theta, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_a_callback_returning_true_stops_after_the_first_iteration(case, problems):
    method, problem, opts, _ = case
    model, data = problems[problem]
    seen = []
    est = prepare(model, data, method, {"callback": lambda i: seen.append(i) or True, **opts})
    out = est.run(start(model))
    assert (out.status, out.iterations, out.finished, out.success) == ("stopped", 1, False, fits(est, out))
    assert len(seen) == 1 and "stopped by the callback" in out.message


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_verbose_prints_one_line_per_iteration(case, problems, capsys):
    method, problem, _, head = case
    model, data = problems[problem]
    out = prepare(model, data, method, {"verbose": True}).run(start(model))
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith(head)]
    assert len(lines) == out.iterations >= 2
    assert "residual" in lines[-1] and "misfit" in lines[-1] and lines[-1].endswith(" s")


@pytest.mark.parametrize("case", CASES, ids=IDS)
@pytest.mark.parametrize(("options", "match"), [
    ({"time_limit": 0}, "time_limit must be a finite number > 0"),
    ({"time_limit": -1}, "time_limit must be a finite number > 0"),
    ({"time_limit": float("inf")}, "time_limit must be a finite number > 0"),
    ({"time_limit": "5"}, "time_limit must be a number"),
    ({"callback": 3}, "callback must be a function of one ScrProgress"),
    ({"verbose": "yes"}, "verbose must be True or False"),
])
def test_bad_progress_options_are_named_errors(case, options, match, problems):
    method, problem, _, _ = case
    model, data = problems[problem]
    with pytest.raises(si.OptionError, match=match):
        prepare(model, data, method, options)


def test_the_options_are_recorded(problems):
    model, data = problems[ls_problem]
    est = prepare(model, data, "ls", {"time_limit": 5.0, "callback": print, "verbose": False})
    assert (est.options["time_limit"], est.options["callback"], est.options["verbose"]) == (5.0, "given", False)
    assert prepare(model, data, "ls", {}).options["time_limit"] is None


def test_scr_that_runs_ls_on_a_frequency_response_passes_the_progress_options_on(problems):
    """"scr" on a second-order model with C known and square runs ls (4-10): time_limit, callback and verbose go
    with it, as the variance does (other SCR options are still refused)."""
    model, data = problems[ls_problem]
    seen = []
    est = prepare(model, data, "scr", {"time_limit": 30.0, "callback": seen.append})
    out = est.run(start(model))
    assert est.method == "ls" and out.status == "solved" and len(seen) == out.iterations == 5
    with pytest.raises(si.OptionError, match="max_iter are SCR options"):
        prepare(model, data, "scr", {"time_limit": 30.0, "max_iter": 5})
    res = si.identify(model, data, method="ls", time_limit=BUDGET, identifiability_check=False,
                      callback=lambda i: time.sleep(NAP))
    assert res.best_start.status == "time_limit" and not res.best_start.finished
    assert res.success == fits(prepare(model, data, "ls", {}), res.best_start) and res.options["time_limit"] == BUDGET
