"""The success rule of today's code on every estimate the population benchmark logged.

:mod:`symid.fit.success` decides whether an estimate fits the data. This study takes every
start logged in ``benchmarks/results/population.jsonl`` (its estimate θ̂, as the method
returned it) and judges θ̂ again with the current rule, on the same data (the problem
rebuilt from its logged draw, the same noise seed). The benchmark's own verdict — the
parameters are right (noise-free: largest relative error ≤ 1e-3, or an exact fit of a
problem not proven globally identifiable; 1 % noise: within twice the error of IPOPT
started at the truth) — says which of the rule's verdicts are correct.

Tabulated per noise level and method: estimates the benchmark counts right or wrong,
against the success flag the method logged and the flag today's rule gives; and every
estimate whose flag changed, with the rule's reason. A wrong estimate flagged a success
is a plausible wrong answer; a right one flagged a failure sends a user to restart.

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
            method = key.split("/")[3]
            tally[(noise_key, method, right, bool(rec["success"]), out.success)] += 1
            if out.success != bool(rec["success"]):
                changed.append({"key": key, "right": right, "logged": bool(rec["success"]), "now": out.success,
                                "cost": rec["cost"], "fit": out.fit})
    rows = [{"noise": float(nk.removeprefix("noise")), "method": m, "right": r, "logged_success": old,
             "success_now": new, "estimates": n} for (nk, m, r, old, new), n in sorted(tally.items(), key=str)]
    return {"rows": rows, "changed": changed, "black_box_floors": floors}


def summary_table(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per noise level and method: wrong estimates flagged a success, right ones flagged a failure (logged, now)."""
    cells: dict[tuple[float, str], Counter] = defaultdict(Counter)
    for r in rows:
        c = cells[(r["noise"], r["method"])]
        c["estimates"] += r["estimates"]
        c["right"] += r["estimates"] if r["right"] else 0
        for when, flag in (("logged", r["logged_success"]), ("now", r["success_now"])):
            if flag and not r["right"]:
                c[f"wrong_success_{when}"] += r["estimates"]
            if r["right"] and not flag:
                c[f"right_failure_{when}"] += r["estimates"]
    return [{"noise": nz, "method": m, **{k: int(c[k]) for k in ("estimates", "right", "wrong_success_logged",
                                                                  "wrong_success_now", "right_failure_logged",
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
    print("noise | method | estimates | right | wrong flagged success: logged -> now | right flagged failure: "
          "logged -> now")
    for r in table:
        print(f"{r['noise']:g} | {r['method']} | {r['estimates']} | {r['right']} | {r['wrong_success_logged']} -> "
              f"{r['wrong_success_now']} | {r['right_failure_logged']} -> {r['right_failure_now']}")
    print(f"\n{len(result['changed'])} verdicts changed:")
    for c in result["changed"]:
        print(f"  {c['key']}: {'right' if c['right'] else 'wrong'} estimate, success {c['logged']} -> {c['now']}: "
              f"{c['fit'][:160]}")
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
