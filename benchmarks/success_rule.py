"""The success rule of today's code on every estimate the population benchmark logged.

:mod:`symid.fit.success` decides whether an estimate fits the data. This study takes every
start logged in ``benchmarks/results/population.jsonl`` (its estimate θ̂, as the method
returned it) and judges θ̂ with two rules, on the same data (the problem rebuilt from its
logged draw, the same noise seed):

* **before**: the rule up to 2026-11-27 — exact fit, noise floor, or a white residual when
  each line's residual is divided by that line's own level (the lag-one autocorrelation
  scaled by √(s − 1)); refused when a black box of the model's order fits ten times better;
* **now**: today's :meth:`symid.fit.base.Estimator.outcome` — the whiteness test in the
  misfit's own weighting (self-normalised statistic), the black box's margin
  2·(N − l)/(N − b).

Both require nothing the model declares to rule the estimate out. Two references say
which verdicts are correct:

* the benchmark's own — the parameters are right (noise-free: largest relative error
  ≤ 1e-3, or an exact fit of a problem not proven globally identifiable; 1 % noise: within
  twice the error of IPOPT started at the truth);
* at 1 % noise, **fits**: the misfit is within a likelihood-ratio bound of the
  least-squares estimate's (IPOPT started at the truth), cost ≤ ref·(1 + χ²₀.₉₉₉(l)/N) —
  what ``success`` promises: the estimate fits the data as well as the data allow. The
  least-squares estimates themselves are judged too.

Tabulated per noise level and method: estimates the benchmark counts right or wrong, against
both rules; and every estimate whose verdict changed, with today's reason. A wrong estimate
flagged a success is a plausible wrong answer; a right one flagged a failure sends a user to
restart.

Run (a minute; nothing is estimated again)::

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
from symid.fit.frf.misfit import relative_residuals
from symid.fit.success import CEILING, EXACT_FIT, WHITENESS_LIMIT, physical_check
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


def _old_whiteness(residuals: np.ndarray) -> float:
    """The statistic before: lag-one autocorrelation of the residuals, scaled by √((s − 1)·c) (·√2 if complex)."""
    r = np.nan_to_num(np.asarray(residuals, dtype=complex))
    s = r.shape[0]
    if s < 3:
        return 0.0
    r = r.reshape(s, -1)
    den = float(np.sum(np.abs(r) ** 2))
    if den == 0.0:
        return 0.0
    num = float(np.real(np.sum(np.conj(r[:-1]) * r[1:])))
    return float(num / den * np.sqrt((s - 1) * r.shape[1] * (2 if np.iscomplexobj(residuals) else 1)))


def _before(est: Any, theta: np.ndarray) -> bool:
    """The rule before: relative residuals (each line by its level), the old statistic, a black box ten times better."""
    cost = est.misfit(theta) if np.all(np.isfinite(theta)) else float("inf")
    if not np.isfinite(cost) or physical_check(est.model, theta) is not None:
        return False
    if cost <= EXACT_FIT:
        return True
    res = relative_residuals(est.model, est.data, theta)
    if res is None or cost > CEILING or _old_whiteness(res) > WHITENESS_LIMIT:
        return False
    bb = est.black_box()
    return bb is None or bb[1] > est.n_data() / 2 or cost <= 10.0 * bb[0]


def _fits(cost: float, ref_cost: float | None, n_data: int, n_parameters: int) -> bool | None:
    """Within the likelihood-ratio bound of the least-squares estimate's misfit (None without a reference)."""
    if ref_cost is None:
        return None
    from scipy.stats import chi2

    return bool(cost <= ref_cost * (1 + chi2.ppf(0.999, n_parameters) / n_data))


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
        ref_cost = None if ref is None else est.misfit(np.asarray(ref["theta"], dtype=float))
        n_data, n_par = est.n_data(), p.model.n_parameters
        if ref is not None:  # the least-squares estimate itself (IPOPT from the truth), judged by both rules
            theta = np.asarray(ref["theta"], dtype=float)
            out = est.outcome(theta, theta, finished=True, status="", message="", iterations=0, wall_time=0.0)
            tally[(noise_key, "reference", True, True, _before(est, theta), out.success)] += 1
        for key, rec in recs:
            theta = np.asarray(rec["theta"], dtype=float)
            right = start_success(theta, rec["cost"], np.asarray(p.truth), positive, globally, ref)
            out = est.outcome(np.asarray(rec["start"], dtype=float), theta, finished=rec["finished"],
                              status=rec["status"], message="", iterations=0, wall_time=0.0)
            before = _before(est, theta)
            fits = _fits(out.cost, ref_cost, n_data, n_par)
            method = key.split("/")[3]
            tally[(noise_key, method, right, fits, before, out.success)] += 1
            if out.success != before:
                changed.append({"key": key, "right": right, "fits": fits, "before": before, "now": out.success,
                                "finished": bool(rec["finished"]), "cost": rec["cost"], "fit": out.fit})
    rows = [{"noise": float(nk.removeprefix("noise")), "method": m, "right": r, "fits": f, "success_before": old,
             "success_now": new, "estimates": n} for (nk, m, r, f, old, new), n in sorted(tally.items(), key=str)]
    return {"rows": rows, "changed": changed, "black_box_floors": floors}


_COUNTS = ("estimates", "right", "wrong_success_before", "wrong_success_now", "right_failure_before",
           "right_failure_now", "fit", "fit_refused_before", "fit_refused_now", "unfit_accepted_before",
           "unfit_accepted_now")


def summary_table(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per noise level and method: wrong estimates flagged a success, right ones flagged a failure; at 1 % noise
    also against ``fits`` (the likelihood-ratio bound): fits refused, misfits accepted (before, now)."""
    cells: dict[tuple[float, str], Counter] = defaultdict(Counter)
    for r in rows:
        c = cells[(r["noise"], r["method"])]
        c["estimates"] += r["estimates"]
        c["right"] += r["estimates"] if r["right"] else 0
        c["fit"] += r["estimates"] if r["fits"] else 0
        for when, flag in (("before", r["success_before"]), ("now", r["success_now"])):
            if flag and not r["right"]:
                c[f"wrong_success_{when}"] += r["estimates"]
            if r["right"] and not flag:
                c[f"right_failure_{when}"] += r["estimates"]
            if r["fits"] is True and not flag:
                c[f"fit_refused_{when}"] += r["estimates"]
            if r["fits"] is False and flag:
                c[f"unfit_accepted_{when}"] += r["estimates"]
    return [{"noise": nz, "method": m, **{k: int(c[k]) for k in _COUNTS}} for (nz, m), c in sorted(cells.items())]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--log", default=str(RESULTS / "population.jsonl"), help="population log (default %(default)s)")
    ap.add_argument("--out", default=str(RESULTS / "success_rule.json"), help="summary JSON (default %(default)s)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    result = rejudge(Path(args.log))
    table = summary_table(result["rows"])
    print("noise | method | estimates | right | wrong flagged success: before -> now | right flagged failure: "
          "before -> now | fit (LR bound) | fit refused: before -> now | no fit accepted: before -> now")
    for r in table:
        print(f"{r['noise']:g} | {r['method']} | {r['estimates']} | {r['right']} | {r['wrong_success_before']} -> "
              f"{r['wrong_success_now']} | {r['right_failure_before']} -> {r['right_failure_now']} | {r['fit']} | "
              f"{r['fit_refused_before']} -> {r['fit_refused_now']} | {r['unfit_accepted_before']} -> "
              f"{r['unfit_accepted_now']}")
    for noise in sorted({r["noise"] for r in table}):
        rows = [r for r in table if r["noise"] == noise and r["method"] != "reference"]
        tot = {k: sum(r[k] for r in rows) for k in _COUNTS}
        print(f"noise {noise:g}, every method: {tot['right']} of {tot['estimates']} right; wrong flagged success "
              f"{tot['wrong_success_before']} -> {tot['wrong_success_now']}; right flagged failure "
              f"{tot['right_failure_before']} -> {tot['right_failure_now']}"
              + ("" if noise == 0 else f"; {tot['fit']} fit (LR bound): refused {tot['fit_refused_before']} -> "
                 f"{tot['fit_refused_now']}; {tot['estimates'] - tot['fit']} do not: accepted "
                 f"{tot['unfit_accepted_before']} -> {tot['unfit_accepted_now']}"))
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
