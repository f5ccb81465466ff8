"""The success rule of today's code on every estimate the population benchmark logged.

:mod:`symid.fit.success` decides whether an estimate fits the data. This study takes every
start logged in ``benchmarks/results/population.jsonl`` (its estimate θ̂, as the method
returned it) and judges θ̂ with two rules, on the same data (the problem rebuilt from its
logged draw, the same noise seed):

* **before**: the rule up to this study — the solver finished *and* the estimate fits
  (exact fit, noise floor or whiteness), and nothing the model declares rules it out;
* **now**: today's :meth:`symid.fit.base.Estimator.outcome` — the estimate fits, whether
  or not the solver finished, and a fit that is not exact is refused when a black box of
  the model's order fits ten times better.

The benchmark's own verdict — the parameters are right (noise-free: largest relative
error ≤ 1e-3, or an exact fit of a problem not proven globally identifiable; 1 % noise:
within twice the error of IPOPT started at the truth) — says which verdicts are correct.
Tabulated per noise level and method: estimates the benchmark counts right or wrong,
against both rules; and every estimate whose verdict changed, with today's reason. A
wrong estimate flagged a success is a plausible wrong answer; a right one flagged a
failure sends a user to restart.

Run (seconds; nothing is estimated again)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/success_rule.py

Prints the tables and writes ``benchmarks/results/success_rule.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/_study.py (script folder on the path)
from population import start_success
from population_models import make_problem

from symid.fit.frf.ipopt import IpoptFRF
from symid.fit.success import fit_test, physical_check
from symid.runlog import write_json_atomic


def _latest(path: Path) -> dict[str, dict[str, Any]]:
    """The last record of every key in a population log."""
    latest: dict[str, dict[str, Any]] = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.strip():
                rec = json.loads(line)
                latest[rec["key"]] = rec
    return latest


def _before(est: Any, theta: np.ndarray) -> bool:
    """The fit part of the rule before this study: exact, noise floor or whiteness, no black box; physical."""
    cost = est.misfit(theta) if np.all(np.isfinite(theta)) else float("inf")
    res = est.residuals(theta) if np.isfinite(cost) else None
    fits = fit_test(cost, n_data=est.n_data(), n_parameters=int(theta.size), residuals=res,
                    noise_floor=est.noise_floor).fits
    return fits and physical_check(est.model, theta) is None


def rejudge(log_path: Path) -> dict[str, Any]:
    """Every logged start judged again; the tally and the changed verdicts."""
    latest = _latest(log_path)
    problems = {k.split("/")[0]: r for k, r in latest.items() if k.endswith("/problem")}
    references = {tuple(k.split("/")[:2]): r for k, r in latest.items() if k.endswith("/reference")}
    groups: dict[tuple[str, str], list[tuple[str, dict[str, Any]]]] = defaultdict(list)
    for key, rec in latest.items():
        parts = key.split("/")
        if len(parts) == 5 and parts[4].startswith("start") and rec.get("theta") is not None:
            groups[(parts[0], parts[1])].append((key, rec))
    tally: Counter = Counter()
    changed = []
    floors = {}
    for (name, noise_key), recs in sorted(groups.items()):
        pr = problems[name]
        p = make_problem(pr["cls"], pr["n"], pr["index"], check=False, draw=pr["info"]["draw"])
        noise = float(noise_key.removeprefix("noise"))
        est = IpoptFRF(p.model, p.data(noise=noise, seed=0))  # the rule depends on the data, not the method
        bb = est.black_box()
        floors[f"{name}/{noise_key}"] = None if bb is None else bb[0]
        globally = bool(pr["info"].get("global", True))
        ref = None if noise == 0 else references.get((name, noise_key))
        positive = np.asarray(p.model.positive, dtype=bool)
        for key, rec in recs:
            theta = np.asarray(rec["theta"], dtype=float)
            right = start_success(theta, rec["cost"], np.asarray(p.truth), positive, globally, ref)
            out = est.outcome(np.asarray(rec["start"], dtype=float), theta, finished=rec["finished"],
                              status=rec["status"], message="", iterations=0, wall_time=0.0)
            before = bool(rec["finished"]) and _before(est, theta)
            method = key.split("/")[3]
            tally[(noise_key, method, right, before, out.success)] += 1
            if out.success != before:
                changed.append({"key": key, "right": right, "before": before, "now": out.success,
                                "finished": bool(rec["finished"]), "cost": rec["cost"], "fit": out.fit})
    rows = [{"noise": float(nk.removeprefix("noise")), "method": m, "right": r, "success_before": old,
             "success_now": new, "estimates": n} for (nk, m, r, old, new), n in sorted(tally.items(), key=str)]
    return {"rows": rows, "changed": changed, "black_box_floors": floors}


def summary_table(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per noise level and method: wrong estimates flagged a success, right ones flagged a failure (before, now)."""
    cells: dict[tuple[float, str], Counter] = defaultdict(Counter)
    for r in rows:
        c = cells[(r["noise"], r["method"])]
        c["estimates"] += r["estimates"]
        c["right"] += r["estimates"] if r["right"] else 0
        for when, flag in (("before", r["success_before"]), ("now", r["success_now"])):
            if flag and not r["right"]:
                c[f"wrong_success_{when}"] += r["estimates"]
            if r["right"] and not flag:
                c[f"right_failure_{when}"] += r["estimates"]
    return [{"noise": nz, "method": m, **{k: int(c[k]) for k in ("estimates", "right", "wrong_success_before",
                                                                  "wrong_success_now", "right_failure_before",
                                                                  "right_failure_now")}}
            for (nz, m), c in sorted(cells.items())]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--log", default=str(RESULTS / "population.jsonl"), help="population log (default %(default)s)")
    ap.add_argument("--out", default=str(RESULTS / "success_rule.json"), help="summary JSON (default %(default)s)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    result = rejudge(Path(args.log))
    table = summary_table(result["rows"])
    print("noise | method | estimates | right | wrong flagged success: before -> now | right flagged failure: "
          "before -> now")
    for r in table:
        print(f"{r['noise']:g} | {r['method']} | {r['estimates']} | {r['right']} | {r['wrong_success_before']} -> "
              f"{r['wrong_success_now']} | {r['right_failure_before']} -> {r['right_failure_now']}")
    for noise in sorted({r["noise"] for r in table}):
        rows = [r for r in table if r["noise"] == noise]
        print(f"noise {noise:g}, every method: {sum(r['right'] for r in rows)} of {sum(r['estimates'] for r in rows)} "
              f"right; wrong flagged success {sum(r['wrong_success_before'] for r in rows)} -> "
              f"{sum(r['wrong_success_now'] for r in rows)}; right flagged failure "
              f"{sum(r['right_failure_before'] for r in rows)} -> {sum(r['right_failure_now'] for r in rows)}")
    print(f"\n{len(result['changed'])} verdicts changed:")
    for c in result["changed"]:
        print(f"  {c['key']}: {'right' if c['right'] else 'wrong'} estimate, success {c['before']} -> {c['now']}"
              f"{'' if c['finished'] else ' (solver stopped short)'}: {c['fit'][:160]}")
    doc = {"benchmark": "success_rule", "command": " ".join(["benchmarks/success_rule.py", *(argv or sys.argv[1:])]),
           "git_commit": git_commit(), "log": str(Path(args.log).name), "table": table, **result,
           "machine": {"platform": platform.platform(), "python": platform.python_version(),
                       "numpy": np.__version__},
           "wall_time": time.perf_counter() - t0}
    write_json_atomic(Path(args.out), doc)
    print(f"\nwritten {args.out} ({doc['wall_time']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
