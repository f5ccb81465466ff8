"""FRF ``auto`` on the population benchmark's 1 % noisy problems with ``confirm=0`` against ``confirm=4``.

``confirm`` (``symid/fit/frf/lm.py``, choice 7): after a fit only the noise rule accepts, the
restarts go on until a second pass ends at the best misfit or ``confirm`` passes are spent.
This runs, side by side in one process, every noisy problem the population benchmark counts
(``benchmarks/results/population.jsonl``: the problems it logged, their 1 % references), two
informed and two uninformed starts each (``Problem.starts``, seed 0), 45 s per start, with each
value of ``confirm``, and judges every start by the population benchmark's rule
(:func:`population.start_success`).

Run (about 15 minutes per process; ``--problems`` splits the list across processes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/auto_confirm.py [--problems A,B,...]

Appends one JSON line per start to ``benchmarks/results/auto_confirm.jsonl`` and prints the
summary of everything in that file.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from collections import defaultdict
from pathlib import Path

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from population import _logged_resolution, start_success
from population_models import RESOLUTION_FLOOR, make_problem

import symid as si
from symid.runlog import RunLog

LOG = RESULTS / "population.jsonl"
OUT = RESULTS / "auto_confirm.jsonl"
NOISE = 0.01
TIME_LIMIT = 45.0


def counted_problems(latest: dict[str, dict]) -> list[str]:
    """The problems the population benchmark counts that have a 1 % reference, in log order."""
    names = []
    for key in latest:
        if key.endswith(f"/noise{NOISE:g}/reference"):
            name = key.split("/")[0]
            prob = latest.get(f"{name}/problem")
            if prob is not None and _logged_resolution(prob) > RESOLUTION_FLOOR:
                names.append(name)
    return names


def summary(path: Path) -> None:
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    cells: dict[tuple, list] = defaultdict(list)
    for r in rows:
        if "confirm" in r:
            cells[(r["confirm"], r["kind"])].append(r)
    print(f"{'confirm':>7s} {'kind':11s} {'success':>8s} {'median s':>8s} {'mean s':>7s}")
    for (c, kind), rs in sorted(cells.items()):
        walls = [r["wall"] for r in rs]
        print(f"{c:7d} {kind:11s} {sum(r['ok'] for r in rs):>3d}/{len(rs):<4d} {np.median(walls):8.2f} "
              f"{np.mean(walls):7.2f}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--problems", default="", help="comma-separated names (default: every counted noisy problem)")
    ap.add_argument("--confirm", default="0,4")
    ap.add_argument("--kinds", default="uninformed,informed")
    args = ap.parse_args(argv)
    latest = {r["key"]: r for r in RunLog(LOG).records()}
    names = [n for n in args.problems.split(",") if n] or counted_problems(latest)
    confirms = [int(c) for c in args.confirm.split(",")]
    commit = git_commit()
    with OUT.open("a") as out:
        out.write(json.dumps({"run": time.strftime("%Y-%m-%d %H:%M:%S"), "commit": commit, "problems": names}) + "\n")
        for name in names:
            prob = latest[f"{name}/problem"]
            p = make_problem(prob["cls"], int(prob["n"]), int(prob["index"]), check=False, draw=prob["info"]["draw"])
            data = p.data(noise=NOISE, seed=0)
            ref = latest[f"{name}/noise{NOISE:g}/reference"]
            for kind in args.kinds.split(","):
                for i, x0 in enumerate(p.starts(kind, 2, seed=0)):
                    for c in confirms:
                        t0 = time.perf_counter()
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            res = si.identify(p.model, data, method="auto", x0=x0, scale=p.typical,
                                              time_limit=TIME_LIMIT, confirm=c, identifiability_check=False)
                        ok = start_success(res.theta_vector, res.cost, np.asarray(prob["truth"]),
                                           np.ones(prob["n_parameters"], bool), bool(prob["info"].get("global")), ref)
                        rec = {"name": name, "kind": kind, "start": i, "confirm": c, "ok": bool(ok),
                               "cost": float(res.cost), "ref": float(ref["cost"]), "wall": time.perf_counter() - t0,
                               "msg": res.message, "commit": commit}
                        print(json.dumps(rec), flush=True)
                        out.write(json.dumps(rec) + "\n")
                        out.flush()
    summary(OUT)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
