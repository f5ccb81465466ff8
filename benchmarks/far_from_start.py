"""False alarms of the far-from-start note on the population benchmark's logged estimates, by threshold.

``si.identify`` notes a successful fit whose parameters lie, in the median, more than
``FAR_FROM_START`` times from the user's start (``symid/fit/identify.py``): a time or
frequency unit read wrongly moves every rate together. This reads every start that
``benchmarks/population.py`` logged (``benchmarks/results/population.jsonl``: informed
starts within a factor 3 of the truth, uninformed ones within a factor 10 of typical values,
every method), keeps the right fits (largest relative parameter error ≤ 0.1, the fit
reported a success), and counts how many a threshold would flag: each flag there is a false
alarm. Beside it, the rule taken per role (the median within the masses, the dampers, the
springs, … — what a frequency in Hz read as rad/s moves while the masses of an acceleration
response stay), whose false alarms are far more frequent.

Run (a minute)::

    .venv/bin/python benchmarks/far_from_start.py

Prints a table; writes ``benchmarks/results/far_from_start.json``.
"""

from __future__ import annotations

import json
import math

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from population_models import make_problem

from symid.fit.frf.scale import parameter_roles
from symid.runlog import write_json_atomic

THRESHOLDS = (10, 20, 30, 100)


def main() -> int:
    problems, rows = {}, []
    for line in open(RESULTS / "population.jsonl", encoding="utf-8"):
        r = json.loads(line)
        if r["key"].endswith("/problem"):
            problems[r["key"].split("/")[0]] = r
        elif r.get("theta") is not None and "start" in r:
            rows.append(r)
    roles = {}
    for name, p in problems.items():
        roles[name] = parameter_roles(make_problem(p["cls"], p["n"], p["index"], check=False,
                                                   draw=p["info"]["draw"]).model)
    overall = dict.fromkeys(THRESHOLDS, 0)
    by_role = dict.fromkeys(THRESHOLDS, 0)
    n = 0
    for r in rows:
        name = r["key"].split("/")[0]
        theta, start = np.abs(np.array(r["theta"])), np.abs(np.array(r["start"]))
        truth = np.abs(np.array(problems[name]["truth"]))
        if not r.get("success") or theta.size != truth.size or np.any(theta <= 0) or np.any(start <= 0):
            continue
        if np.max(np.abs(theta / truth - 1)) > 0.1:
            continue
        n += 1
        logs = np.abs(np.log10(theta / start))
        groups: dict[str, list[float]] = {}
        for role, v in zip(roles[name], logs, strict=True):
            groups.setdefault(role, []).append(float(v))
        worst_group = max(float(np.median(v)) for v in groups.values())
        for t in THRESHOLDS:
            overall[t] += float(np.median(logs)) > math.log10(t)
            by_role[t] += worst_group > math.log10(t)
    print(f"{n} right fits (reported success, every parameter within 10 % of the truth) logged by population.py")
    print(f"{'threshold':>10s} {'median over all':>16s} {'median per role':>16s}")
    for t in THRESHOLDS:
        print(f"{t:>10d} {overall[t]:>16d} {by_role[t]:>16d}")
    write_json_atomic(RESULTS / "far_from_start.json",
                      {"benchmark": "far_from_start", "git_commit": git_commit(), "right_fits": n,
                       "false_alarms_median_over_all": {str(t): overall[t] for t in THRESHOLDS},
                       "false_alarms_median_per_role": {str(t): by_role[t] for t in THRESHOLDS}})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
