"""oe talks during long runs and keeps to a time budget (issue 14 item 6): callback=, verbose=, time_limit=.

These are IPOPT's (``solver="ipopt"``), whose iterations and solver build the callback and the budget see;
tests/test_oe_trf.py has the same for ``solver="trf"``, the default.

Reference: the one-mass oscillator m q̈ + c q̇ + k q = u (m = 2, c = 0.8, k = 50), 200 samples at 0.05 s of a white
force, 1 % output noise, started 30-50 % off (IPOPT takes 10 iterations; tests/test_units_invariance.py).
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import symid as si
from symid.errors import OptionError
from symid.fit.timeseries.oe import OutputError

TRUTH = np.array([2.0, 0.8, 50.0])
START = TRUTH * np.array([1.5, 0.6, 1.3])


def oscillator():
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])


@pytest.fixture(scope="module")
def io():
    u = np.random.default_rng(0).standard_normal(200)
    return si.simulate_io(oscillator(), TRUTH, u, 0.05, noise=0.01, seed=2)


def test_callback_sees_every_iteration_with_the_misfit_and_theta(io):
    seen = []
    est = OutputError(oscillator(), io, callback=seen.append, solver="ipopt")
    out = est.run(START)
    assert [i.iteration for i in seen] == list(range(out.iterations + 1))
    np.testing.assert_allclose(seen[0].theta, START, rtol=1e-12)
    assert seen[0].objective == pytest.approx(est.misfit(START), rel=1e-9)
    assert seen[-1].objective == pytest.approx(out.cost, rel=1e-9)
    np.testing.assert_allclose(seen[-1].theta, out.theta, rtol=1e-12)
    assert np.all(np.diff([i.elapsed for i in seen]) >= 0)


def test_callback_stops_the_start(io):
    out = OutputError(oscillator(), io, callback=lambda info: info.iteration >= 2, solver="ipopt").run(START)
    assert (out.status, out.iterations, out.success) == ("User_Requested_Stop", 2, False)


def test_verbose_prints_one_line_per_iteration(io, capsys):
    out = OutputError(oscillator(), io, verbose=True, solver="ipopt").run(START)
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == out.iterations + 1 and all(line.startswith("ipopt  iteration") for line in lines)


def test_time_limit_stops_the_start_after_the_iteration_that_exceeds_it(io):
    def crawl(info):
        time.sleep(0.2)
        return False

    est = OutputError(oscillator(), io, time_limit=0.5, callback=crawl, solver="ipopt")
    out = est.run(START)
    assert out.status == "Maximum_WallTime_Exceeded" and not out.success
    assert 1 <= out.iterations <= 3  # 0.2 s per iteration against 0.5 s: stopped after the third (iteration 2)
    assert est.run(START).status == "Maximum_WallTime_Exceeded"  # every start has its own budget
    assert OutputError(oscillator(), io, time_limit=60.0, solver="ipopt").run(START).status == "Solve_Succeeded"


def test_building_the_solver_counts_in_the_time_limit(io):
    # a build of 1 s (slept, standing in for CasADi's, which takes 2-10 s on 4000 samples of a 3-mass chain) and a
    # budget of 1.2 s: the start stops after the first iteration that ends past 1.2 s, 1.3 s in (0.3 s per
    # iteration), not 1.2 s after the build (2.2 s and more)
    def crawl(info):
        time.sleep(0.3)
        return False

    est = OutputError(oscillator(), io, time_limit=1.2, callback=crawl, solver="ipopt")
    build = est._solver

    def slow_build(s_max):
        time.sleep(1.0)
        return build(s_max)

    est._solver = slow_build
    out = est.run(START)
    assert out.status == "Maximum_WallTime_Exceeded"
    assert 1.2 <= out.wall_time < 2.0, out.wall_time


def test_bad_progress_options_are_named(io):
    with pytest.raises(OptionError, match="callback"):
        OutputError(oscillator(), io, callback=3)
    with pytest.raises(OptionError, match="time_limit"):
        OutputError(oscillator(), io, time_limit=0)
    with pytest.raises(OptionError, match="verbose"):
        OutputError(oscillator(), io, verbose="yes")
