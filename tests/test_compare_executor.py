"""``si.compare(..., executor=...)`` and explicit start lists (issue 14, item 1).

Every start is independent of the others, so running the starts as tasks of an executor
(a process pool, or a Dask cluster's executor) must give the estimates of a serial run,
start by start, in start order.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import symid as si
from symid.runlog import RunLog

TRUTH = {"m": 2.0, "c": 0.5, "k": 3.0}


@pytest.fixture(scope="module")
def problem():
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    return model, si.simulate_frf(model, TRUTH, np.linspace(0.5, 2.0, 8))


def _same(a, b):
    for method in ("scr", "ipopt"):
        sa, sb = a[method].result.starts, b[method].result.starts
        assert len(sa) == len(sb)
        for x, y in zip(sa, sb, strict=True):
            np.testing.assert_array_equal(x.start, y.start)
            # the same code on the same input in another process: equal up to rounding of the solver's
            # floating-point work, which repeats exactly on one machine
            np.testing.assert_allclose(x.theta, y.theta, rtol=1e-9, atol=1e-12)
            assert x.success == y.success and x.status == y.status


def test_process_pool_gives_the_serial_results(problem):
    model, frf = problem
    kw = {"methods": ("scr", "ipopt"), "starts": 4, "seed": 3, "truth": TRUTH, "options": {"scr": {"force_scr": True}}}
    serial = si.compare(model, frf, **kw)
    with ProcessPoolExecutor(max_workers=2) as pool:
        parallel = si.compare(model, frf, executor=pool, **kw)
    _same(serial, parallel)
    # SCR's per-iteration history comes back from the worker with the outcome
    assert len(parallel["scr"].result.starts[0].history) == parallel["scr"].result.starts[0].iterations


def test_executor_runs_are_logged_and_resumed(problem, tmp_path):
    model, frf = problem
    log_path = tmp_path / "run.jsonl"
    kw = {"methods": ("ipopt",), "starts": 3, "seed": 1, "truth": TRUTH}
    with ThreadPoolExecutor(max_workers=2) as pool:  # any Executor is accepted; threads are enough here
        first = si.compare(model, frf, executor=pool, log=RunLog(log_path), **kw)
    assert len(RunLog(log_path).records()) == 1 + 3  # the setup record and every start
    again = si.compare(model, frf, log=RunLog(log_path), **kw)  # read back, nothing run
    for x, y in zip(first["ipopt"].result.starts, again["ipopt"].result.starts, strict=True):
        np.testing.assert_array_equal(x.theta, y.theta)
        assert x.wall_time == y.wall_time


def test_dask_local_cluster_executor(problem):
    distributed = pytest.importorskip("distributed", reason="Dask is the optional extra symid[dask]")
    model, frf = problem
    kw = {"methods": ("scr", "ipopt"), "starts": 3, "seed": 5, "truth": TRUTH, "options": {"scr": {"force_scr": True}}}
    serial = si.compare(model, frf, **kw)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
            distributed.Client(cl) as client:
        parallel = si.compare(model, frf, executor=client.get_executor(), **kw)
    _same(serial, parallel)


def test_explicit_starts_are_used_as_given(problem):
    model, frf = problem
    starts = [TRUTH, [1.0, 1.0, 1.0], np.array([4.0, 0.1, 9.0])]
    cmp = si.compare(model, frf, methods=("ipopt",), starts=starts, truth=TRUTH)
    got = [s.start for s in cmp["ipopt"].result.starts]
    np.testing.assert_array_equal(got, [[2.0, 0.5, 3.0], [1.0, 1.0, 1.0], [4.0, 0.1, 9.0]])
    assert cmp.n_starts == 3


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"starts": [[1.0, 2.0]]}, si.OptionError, "start 0: .*3"),
    ({"starts": []}, si.OptionError, "non-empty sequence of starts"),
    ({"starts": "abc"}, si.OptionError, "number of starts or a non-empty sequence"),
    ({"starts": [[1.0, 1.0, 1.0]], "x0": [1.0, 1.0, 1.0]}, si.OptionError, "either x0 or an explicit list"),
    ({"starts": 2, "executor": "pool"}, si.ModelError, "executor must be a concurrent.futures.Executor"),
])
def test_bad_starts_and_executors_are_named(problem, kwargs, error, match):
    model, frf = problem
    with pytest.raises(error, match=match):
        si.compare(model, frf, methods=("ipopt",), **kwargs)
