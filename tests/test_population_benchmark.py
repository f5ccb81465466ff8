"""benchmarks/population.py and its generator (issue 14, item 1): identifiable problems only, the starts and
the success rule as documented, a run that resumes from its log and summarises it."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import symid as si

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module("population_models"), importlib.import_module("population")
    finally:
        sys.path.remove(str(BENCH))


@pytest.mark.parametrize("cls", ["chain", "chain_sensors", "gains", "state_space", "compartment"])
def test_generated_problems_are_checked_and_physical(bench, cls):
    pm, _ = bench
    p = pm.make_problem(cls, 2, 0, timeout=20)
    assert "none" not in p.info["verdicts"].values()
    assert np.all(p.truth > 0) and all(p.model.positive)
    # the grid covers every mode: from 0.3x the slowest to 3x the fastest |λ| of the true model
    lam = np.abs(np.linalg.eigvals(p.model.state_space(p.truth).A))
    assert p.w[0] <= lam[lam > 0].min() and p.w[-1] >= lam.max()
    # rebuilt from its draw without checking again: the same problem
    q = pm.make_problem(cls, 2, 0, check=False, draw=p.info["draw"])
    np.testing.assert_array_equal(q.truth, p.truth)


def test_a_draw_the_identifiability_check_rejects_is_drawn_again(bench, monkeypatch):
    pm, _ = bench
    real = pm._draw
    calls = []

    def fake(cls, n, rng):
        calls.append(1)
        if len(calls) == 1:  # m1 and m2 only ever appear as their sum: neither is identifiable
            m1, m2, k = si.parameters("m1 m2 k", positive=True)
            model = si.SecondOrderModel(M=[[m1 + m2]], V=[[1]], K=[[k]], B=[[1]], C=[[1]])
            return model, np.array([1.0, 2.0, 3.0]), np.ones(3), {}
        return real(cls, n, rng)

    monkeypatch.setattr(pm, "_draw", fake)
    p = pm.make_problem("chain", 2, 0, timeout=20)
    assert p.info["draw"] == 1 and p.info["refused"] == ["none"]


def test_starts_are_where_the_docstring_says(bench):
    pm, _ = bench
    p = pm.make_problem("gains", 3, 0, check=False)
    inf, uninf = p.starts("informed", 50), p.starts("uninformed", 50)
    assert np.all(np.abs(np.log(inf / p.truth)) <= np.log(3) + 1e-12)
    assert np.all(np.abs(np.log10(uninf / p.typical)) <= 1 + 1e-12)
    with pytest.raises(ValueError, match="informed"):
        p.starts("clever", 1)


def test_success_rule(bench):
    _, pop = bench
    truth, pos = np.array([1.0, 2.0]), np.array([True, True])
    assert pop.start_success([1.0, 2.0005], 1e-20, truth, pos, True, None)  # 2e-4 relative error
    assert not pop.start_success([1.5, 0.5], 1e-20, truth, pos, True, None)  # another solution, but global
    assert pop.start_success([1.5, 0.5], 1e-20, truth, pos, False, None)  # an admissible other solution
    assert not pop.start_success([1.5, -0.5], 1e-20, truth, pos, False, None)  # not admissible
    assert not pop.start_success(None, None, truth, pos, False, None)
    ref = {"theta": [1.01, 2.0], "cost": 1e-4}  # 1 % off in the first parameter
    assert pop.start_success([1.0, 2.03], 2e-4, truth, pos, True, ref)  # 1.5 % < 2 x 1 %
    assert not pop.start_success([1.0, 2.1], 2e-4, truth, pos, True, ref)  # 5 %
    # per parameter, whatever the units: a spring of 1e4 exact does not hide a mass 50 % off
    assert not pop.start_success([1.5, 1e4], 1e-20, np.array([1.0, 1e4]), pos, True, None)
    assert pop.start_success([1.3, 1.0], 1.0005e-4, truth, pos, False, ref)  # fits as well as the reference


def test_a_tiny_run_logs_resumes_and_summarises(bench, tmp_path):
    _, pop = bench
    log, out = tmp_path / "pop.jsonl", tmp_path / "pop.json"
    argv = ["--classes", "compartment", "--sizes", "2", "--problems", "1", "--starts", "1", "--methods", "lm,ipopt",
            "--noise", "0,0.01", "--kinds", "uninformed", "--time-limit", "30", "--log", str(log), "--out", str(out)]
    assert pop.main(argv) == 0
    first = log.read_text(encoding="utf-8").splitlines()
    # the run's code, the problem, the noisy reference, and per noise level each method's setup and start
    assert len(first) == 1 + 1 + 1 + 2 * 2 * 2
    assert pop.main(argv) == 0  # resumed: nothing run again
    assert log.read_text(encoding="utf-8").splitlines() == first
    doc = json.loads(out.read_text(encoding="utf-8"))
    cells = {(r["method"], r["noise"]) for r in doc["rows"]}
    assert cells == {("lm", 0.0), ("ipopt", 0.0), ("lm", 0.01), ("ipopt", 0.01)}
    assert all(r["starts"] == 1 and r["problems"] == 1 for r in doc["rows"])
    assert [(r["methods"], r["sizes"]) for r in doc["runs"]] == [(["lm", "ipopt"], [2])]  # the resume added none


def test_rerun_runs_a_method_again_once_per_commit(bench, tmp_path):
    _, pop = bench
    log, out = tmp_path / "pop.jsonl", tmp_path / "pop.json"
    argv = ["--classes", "compartment", "--sizes", "2", "--problems", "1", "--starts", "1", "--methods", "lm",
            "--noise", "0", "--kinds", "uninformed", "--time-limit", "30", "--log", str(log), "--out", str(out)]
    assert pop.main(argv) == 0
    first = log.read_text(encoding="utf-8").splitlines()
    assert pop.main([*argv, "--rerun", "lm"]) == 0
    again = log.read_text(encoding="utf-8").splitlines()
    # a run header naming the rerun, lm's setup and start again, and the marker of the finished rerun
    added = [json.loads(line)["key"].split("/")[-1] for line in again[len(first):]]
    assert added[0].startswith("20") and sorted(added[1:]) == ["rerun", "setup", "start0"]
    assert pop.main([*argv, "--rerun", "lm"]) == 0  # this commit's rerun is done: nothing run again
    assert log.read_text(encoding="utf-8").splitlines() == again
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert [r["starts"] for r in doc["rows"]] == [1]  # the new start replaces the old one; the marker is no start
    assert doc["runs"][-1]["rerun"] == ["lm"]


def test_resolution_is_the_first_order_misfit_of_the_worst_1e_3_error(bench):
    """population_models.resolution against a direct computation: the misfit of θ* (1 + δ) at the δ it
    implies (box-constrained, some |δₖ| = 1e-3) agrees to first order, and no single-parameter 1e-3 error
    fits better than it claims."""
    pm, _ = bench
    p = pm.make_problem("chain", 2, 0, check=False)
    floor = p.info["resolution"]
    H0 = si.simulate_frf(p.model, p.truth, p.w).H

    def misfit(theta):
        return float(np.sum(np.abs(si.simulate_frf(p.model, theta, p.w).H - H0) ** 2) / np.sum(np.abs(H0) ** 2))

    singles = [misfit(p.truth * np.where(np.arange(p.truth.size) == k, 1.001, 1.0)) for k in range(p.truth.size)]
    # a single parameter off is one admissible δ: the minimum over all of them can only be lower
    # (second-order terms: relative size ~1e-3, so a 1 % allowance is ample)
    assert floor <= min(singles) * 1.01
    assert floor > pm.RESOLUTION_FLOOR  # measured 1.2e-12 for this draw (n = 2 resolves, module docstring)


def test_unresolved_problems_are_skipped_and_listed(bench, tmp_path, monkeypatch):
    """A problem whose grid cannot resolve the tolerance is not run; the next index is, and the summary lists
    the skipped one apart."""
    _, pop = bench
    real = pop.make_problem

    def first_unresolved(cls, n, index, **kw):
        p = real(cls, n, index, **kw)
        if index == 0:
            p.info["resolution"] = 1e-30
        return p

    monkeypatch.setattr(pop, "make_problem", first_unresolved)
    monkeypatch.setattr(pop, "_logged_resolution", lambda rec: float(rec["info"]["resolution"]))
    log, out = tmp_path / "pop.jsonl", tmp_path / "pop.json"
    argv = ["--classes", "compartment", "--sizes", "2", "--problems", "1", "--starts", "1", "--methods", "lm",
            "--noise", "0", "--kinds", "uninformed", "--time-limit", "30", "--log", str(log), "--out", str(out)]
    assert pop.main(argv) == 0
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["unresolved"] == {"compartment-n2-0": 1e-30}
    assert doc["problems"] == 1 and doc["rows"][0]["starts"] == 1
    keys = [json.loads(line)["key"] for line in log.read_text(encoding="utf-8").splitlines()]
    assert not any(k.startswith("compartment-n2-0/noise") for k in keys)  # never run
    assert any(k.startswith("compartment-n2-1/noise0/uninformed/lm/start") for k in keys)
