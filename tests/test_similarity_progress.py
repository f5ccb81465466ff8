"""The similarity methods talk and stop (issue 14, item 6): time_limit=, callback=, verbose=.

Data: the zoo's e-nose black box (thesis (6-19), a StateSpaceModel: ``scr``, ``als``, ``gb``,
``ipopt``) and the 2-DOF mass-damper of thesis (4-19) (a SecondOrderModel: ``scr`` with one
sensor, ``ipopt`` on the black box's response, ``ls`` with a full set of sensors from noisy
records, where the reweighting takes 5 rounds).

Time limits: a callback that sleeps ``NAP`` seconds makes every iteration slow, so the run
cannot end on its own rule within ``BUDGET`` (the fastest, IPOPT, needs 40+ iterations here,
ls 5 rounds: 0.5 s of naps) and the budget is what stops it, on any machine. Every method checks its clock
after each iteration (IPOPT: its own ``max_wall_time``; SCR: also inside the ADMM iteration),
so a start overruns its budget by at most one iteration (one nap plus milliseconds of work
here) and the outcome's misfit on the black box's 200 frequencies (milliseconds): the bound
BUDGET + 2 s leaves room for a loaded 2-core machine.
"""

from __future__ import annotations

import time
import warnings

import numpy as np
import pytest

import symid as si
from symid.engine.ipopt import IpoptIteration
from symid.engine.scr import ScrProgress
from symid.fit.base import project_positive
from symid.fit.registry import prepare

BUDGET = 0.25
NAP = 0.1
OVERRUN = 2.0  # see the module notes


def two_dof(B, C):
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]], K=[[k1 + k2, -k2], [-k2, k2]],
                               B=B, C=C)


TRUTH_2DOF = {"m1": 1.0, "m2": 2.0, "c1": 0.1, "c2": 0.3, "k1": 2.0, "k2": 1.0}


def enose():
    entry = si.load_model("enose")
    return entry.model, entry.data()


def one_sensor():
    model = two_dof([[1], [0]], [[0, 1]])
    return model, si.BlackBox(*model.state_space(TRUTH_2DOF))


def full_sensors():
    model = two_dof([[1], [0]], [[1, 0], [0, 1]])
    u = np.random.default_rng(1).standard_normal(500)
    return model, si.simulate_io(model, TRUTH_2DOF, u, dt=0.05, noise=0.01, seed=2)


# (label, problem, method, record the callback receives, status of a budget stop, status of a callback stop)
CASES = [
    ("scr", enose, "scr", ScrProgress, "time_limit", "stopped"),
    ("als", enose, "als", ScrProgress, "time_limit", "stopped"),
    ("gb", enose, "gb", ScrProgress, "time_limit", "stopped"),
    ("ipopt", enose, "ipopt", IpoptIteration, "Maximum_WallTime_Exceeded", "User_Requested_Stop"),
    ("scr 2nd order", one_sensor, "scr", ScrProgress, "time_limit", "stopped"),
    ("ipopt 2nd order", one_sensor, "ipopt", IpoptIteration, "Maximum_WallTime_Exceeded", "User_Requested_Stop"),
    ("ls 2nd order", full_sensors, "ls", ScrProgress, "time_limit", "stopped"),
]
IDS = [c[0] for c in CASES]


@pytest.fixture(scope="module")
def problems():
    return {fn: fn() for fn in {c[1] for c in CASES}}


def start(model):
    return np.full(model.n_parameters, 0.5)


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_a_time_limit_stops_a_start_early_and_says_so(case, problems):
    _, problem, method, _, budget_status, _ = case
    model, data = problems[problem]

    def slow(info):
        time.sleep(NAP)
        return False

    est = prepare(model, data, method, {"time_limit": BUDGET, "callback": slow})
    t0 = time.perf_counter()
    out = est.run(start(model))
    wall = time.perf_counter() - t0
    assert out.status == budget_status and f"time limit of {BUDGET:g} s reached" in out.message
    assert not out.finished and not out.success  # stopped short of its own rule: not a success, whatever the fit
    assert 1 <= out.iterations <= BUDGET / NAP + 2
    assert wall <= BUDGET + OVERRUN, wall
    assert est.options["time_limit"] == BUDGET


def test_scr_is_cut_inside_an_iteration_without_a_callback(problems):
    """No callback: the engine's own clock (ADMM checks it inside the iteration) stops SCR, which needs 700+
    iterations (3-7 s) from this start on the e-nose."""
    model, data = problems[enose]
    t0 = time.perf_counter()
    out = prepare(model, data, "scr", {"time_limit": BUDGET}).run(start(model))
    assert out.status == "time_limit" and f"time limit of {BUDGET:g} s" in out.message and not out.success
    assert time.perf_counter() - t0 <= BUDGET + OVERRUN


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_the_callback_sees_every_iteration_with_a_finite_misfit(case, problems):
    _, problem, method, record, _, _ = case
    model, data = problems[problem]
    seen = []
    opts = {"max_iter": 15} if method in ("scr", "als", "gb") else {}
    est = prepare(model, data, method, {"callback": seen.append, **opts})
    out = est.run(start(model))
    assert seen and all(isinstance(i, record) for i in seen)
    first = 0 if record is IpoptIteration else 1  # IPOPT reports its start as iteration 0
    assert [i.iteration for i in seen] == list(range(first, out.iterations + 1))
    assert np.all(np.diff([i.elapsed for i in seen]) >= 0)
    if record is ScrProgress:
        assert all(np.isfinite(i.misfit) and np.isfinite(i.residual) for i in seen)
        # the misfit to the black box of the estimate (I/O records: the N4SID one; their cost is on the samples)
        black_box = getattr(est, "inner", est)
        assert seen[-1].misfit == pytest.approx(black_box.misfit(out.theta), rel=1e-9, abs=1e-14)
        # the estimate is the last iterate's θ; SCR's with a declared-positive value below 0 (here -1.5e-13, the
        # engine's tolerance on θ ≥ 0) projected onto the bound (symid.fit.base.project_positive); ALS and GB have no
        # such constraint and report their iterate as it is
        last = project_positive(model, seen[-1].theta)[0] if method == "scr" else seen[-1].theta
        np.testing.assert_allclose(last, out.theta, rtol=1e-12, atol=1e-14)
    else:
        assert all(np.isfinite(i.objective) for i in seen)
        assert all(i.theta.shape == (model.n_parameters,) for i in seen)  # θ alone, not the transform T


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_the_callback_stops_the_start(case, problems):
    _, problem, method, _, _, stop_status = case
    model, data = problems[problem]
    stop_at = 1 if method == "ls" else 2
    out = prepare(model, data, method, {"callback": lambda i: i.iteration >= stop_at}).run(start(model))
    assert (out.status, out.iterations, out.success) == (stop_status, stop_at, False)


@pytest.mark.parametrize(("method", "label"), [("als", "als"), ("gb", "gb"), ("scr", "scr"), ("ipopt", "ipopt")])
def test_verbose_prints_one_line_per_iteration(method, label, problems, capsys):
    model, data = problems[enose]
    out = prepare(model, data, method, {"verbose": True, "max_iter": 5}).run(start(model))
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith(f"{label} ")]
    assert len(lines) == out.iterations + (method == "ipopt") and "iteration" in lines[0]
    assert ("objective" if method == "ipopt" else "misfit") in lines[-1]


@pytest.mark.parametrize("case", CASES, ids=IDS)
@pytest.mark.parametrize(("options", "match"), [
    ({"time_limit": 0}, "time_limit must be a finite number > 0"),
    ({"time_limit": -1.0}, "time_limit must be a finite number > 0"),
    ({"time_limit": "5"}, "time_limit must be a number"),
    ({"callback": 3}, "callback must be a function"),
    ({"verbose": "yes"}, "verbose must be True or False"),
])
def test_bad_progress_options_are_named_errors(case, options, match, problems):
    _, problem, method, _, _, _ = case
    model, data = problems[problem]
    with pytest.raises(si.OptionError, match=match):
        prepare(model, data, method, options)


# -- through identify, compare and the command line --------------------------------------------------------

def test_identify_and_compare_pass_the_options_through(problems):
    model, data = problems[enose]
    seen = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        res = si.identify(model, data, method="gb", x0=start(model), time_limit=BUDGET,
                          callback=lambda i: seen.append(i) or time.sleep(NAP), identifiability_check=False)
        assert res.best_start.status == "time_limit" and seen and res.options["time_limit"] == BUDGET
        cmp = si.compare(model, data, methods=("als", "ipopt"), starts=[start(model)], progress=False,
                         options={"als": {"time_limit": BUDGET, "callback": lambda i: time.sleep(NAP)},
                                  "ipopt": {"time_limit": 60.0}})
    assert cmp["als"].result.starts[0].status == "time_limit"
    assert cmp["ipopt"].result.options["time_limit"] == 60.0


def test_io_records_through_the_black_box_keep_the_budget():
    """IOData with a similarity method: N4SID first, then the method with its budget (judged on the samples)."""
    a, b, c = si.parameters("a b c")
    model = si.StateSpaceModel(A=[[0, 1], [a, b]], B=[[0], [c]], C=[[1, 0]])
    u = np.random.default_rng(0).standard_normal(400)
    data = si.simulate_io(model, [-2.0, -0.5, 1.5], u, dt=0.05, noise=0.01, seed=1)
    for method in ("scr", "als"):
        out = prepare(model, data, method, {"time_limit": BUDGET, "callback": lambda i: time.sleep(NAP)}).run(
            start(model))
        assert out.status == "time_limit" and f"time limit of {BUDGET:g} s" in out.message and not out.success


def test_scr_that_runs_the_linear_case_passes_the_progress_options_on(problems):
    """"scr" on a second-order model with a full set of sensors runs ls (§7-5-2): time_limit, callback and verbose
    go with it (other SCR options are still refused)."""
    model, data = problems[full_sensors]
    seen = []
    est = prepare(model, data, "scr", {"time_limit": 30.0, "callback": seen.append})
    out = est.run(start(model))
    assert est.method == "ls" and out.status == "solved" and len(seen) == out.iterations == 5
    with pytest.raises(si.OptionError, match="are SCR options"):
        prepare(model, data, "scr", {"time_limit": 30.0, "max_iter": 5})


def test_command_line_time_limit_reaches_a_similarity_method(tmp_path, capsys):
    import json

    from symid.cli import main

    code = main(["identify", "enose", "--method", "als", "--time-limit", str(BUDGET), "--x0", "k01=0.5",
                 "k21=0.5", "k12=0.5", "k32=0.5", "k23=0.5", "f=0.5", "--option", "max_iter=10000000",
                 "--option", "tol=1e-300", "--out", str(tmp_path)])
    capsys.readouterr()
    result = json.loads((tmp_path / "result.json").read_text())
    assert code == 4 and result["options"]["time_limit"] == BUDGET
    assert result["starts"][0]["status"] == "time_limit"
