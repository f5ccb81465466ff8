"""compare's parameter error: the worst parameter by default, whatever the units (a new-user trial found the
2-norm error passing a mass 100 % off beside springs of 1e4 N/m)."""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid.errors import OptionError
from symid.fit.compare import largest_relative_error, relative_parameter_error


def test_largest_relative_error_sees_every_parameter():
    truth = np.array([2.0, 5.0, 4e4])  # kg, N·s/m, N/m
    est = np.array([4.0, 5.0, 4e4])  # the mass 100 % off
    assert relative_parameter_error(est, truth) < 1e-3  # the 2-norm does not see it
    assert largest_relative_error(est, truth) == pytest.approx(1.0, rel=1e-15)
    assert largest_relative_error([0.1, 1.0], [0.0, 1.0]) == pytest.approx(0.1, rel=1e-15)  # θ* = 0: absolute


def test_compare_counts_by_the_chosen_error():
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    truth = {"m": 2.0, "c": 5.0, "k": 4e4}
    frf = si.simulate_frf(model, truth, np.logspace(1.5, 2.5, 30))
    # a "method" that stops at once: IPOPT with one iteration from a start whose mass is 100 % off
    start = [4.0, 5.0, 4e4]
    opts = {"ipopt": {"max_iter": 1}}
    largest = si.compare(model, frf, methods=("ipopt",), starts=[start], truth=truth, options=opts, progress=False)
    l2 = si.compare(model, frf, methods=("ipopt",), starts=[start], truth=truth, options=opts, progress=False,
                    param_error="l2")
    err = largest["ipopt"].best_error
    assert err > 1e-3 and largest["ipopt"].n_success == 0  # one iteration does not bring the mass back
    assert l2["ipopt"].best_error == pytest.approx(relative_parameter_error(
        largest["ipopt"].result.theta_vector, model.theta_vector(truth)), rel=1e-12)
    assert "largest relative parameter error" in largest.criterion and "‖θ − θ*‖₂" in l2.criterion
    with pytest.raises(OptionError, match="param_error"):
        si.compare(model, frf, methods=("ipopt",), starts=1, truth=truth, param_error="rms")


def test_options_not_keyed_by_method_are_explained():
    # a new-user trial passed options={"time_limit": 10}: the error says how options are keyed
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    frf = si.simulate_frf(model, {"m": 2.0, "c": 5.0, "k": 4e4}, np.logspace(1.5, 2.5, 30))
    with pytest.raises(si.ModelError, match=r"options are keyed by method, e\.g\. options=\{'ipopt'.*\(ipopt, "
                                            r"scr\+polish\): time_limit"):
        si.compare(model, frf, methods=("ipopt", "scr+polish"), starts=1, options={"time_limit": 10},
                   progress=False)


def test_a_comparison_on_noisy_data_says_why_nothing_is_near_the_truth():
    # found by a new-user sweep: every method 0/3 against the truth at 1 % noise, all at the same noisy optimum,
    # and nothing said that the tolerance, not the methods, was the cause
    import numpy as np

    import symid as si

    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    frf = si.simulate_frf(model, [1.0, 0.2, 4.0], np.linspace(1.0, 3.0, 30), noise=0.01, seed=0)
    cmp = si.compare(model, frf, methods=["auto", "ipopt"], starts=2, truth=[1.0, 0.2, 4.0])
    assert all(s.n_success == 0 for s in cmp.stats)
    assert "NOTE: no start is within the tolerance of the truth, but 4 fit the data" in cmp.table()
    loose = si.compare(model, frf, methods=["auto"], starts=2, truth=[1.0, 0.2, 4.0], param_tol=0.05)
    assert loose["auto"].n_success == 2 and "NOTE" not in loose.table()


def test_a_method_that_cannot_take_the_data_is_refused_before_any_runs(monkeypatch):
    """A new user's trial: si.compare(..., methods=("oe", "srivc", "svf")) ran oe's starts, then srivc refused the
    model and the finished row was lost. Every method is now built first: the refusal comes before any start."""
    from symid.errors import ModelError
    from symid.fit.timeseries.oe import OutputError

    k, g, c = si.parameters("k g c", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[c]])  # the gain g·c is not affine in θ: srivc refuses
    io = si.simulate_io(model, {"k": 0.5, "g": 2.0, "c": 1.5}, np.random.default_rng(0).standard_normal(200), 0.1)
    runs = []
    monkeypatch.setattr(OutputError, "run", lambda self, x0: runs.append(x0))
    # which method, that nothing ran, and the call without it (a new user's ("lm", "ls") got ls's message alone)
    with pytest.raises(ModelError, match=r"compare\(\): method 'srivc' cannot run here, so nothing ran: .*"
                                         r"Leave it out \(methods=\('oe',\)\)"):
        si.compare(model, io, methods=("oe", "srivc"), starts=2)
    assert runs == []


def test_compare_takes_typical_values_for_every_method_that_takes_them():
    """A new user's si.compare(..., scale=...) was a bare TypeError (si.identify takes scale=); the typical values
    now go to every compared method that takes scale= (ls takes none), a method's own options winning, and serve
    the random starts."""
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    truth = {"m": 2.0, "c": 0.5, "k": 300.0}
    frf = si.simulate_frf(model, truth, np.linspace(5.0, 20.0, 20))
    typical = {"m": 1.0, "c": 1.0, "k": 100.0}
    cmp = si.compare(model, frf, methods=("auto", "ls", "ipopt"), starts=2, seed=0, truth=truth, scale=typical,
                     options={"ipopt": {"scale": {"m": 3.0, "c": 1.0, "k": 100.0}}})
    got = {s.method: s.result.options.get("scale") for s in cmp.stats}
    assert got == {"auto": [1.0, 1.0, 100.0], "ls": None, "ipopt": [3.0, 1.0, 100.0]}
    assert cmp["auto"].n_success == 2
