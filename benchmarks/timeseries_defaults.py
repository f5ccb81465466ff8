"""A user's first call on time series: ``si.identify(model, data)`` with no start and no scale.

The problems and records of ``timeseries_population.py`` (mass-spring-damper chains,
chains with gains, compartment models with a volume, first-order state-space networks,
n = 2 and 3; physical values; white-noise input; noise-free and 1 % output noise). For
each, ``si.identify(model, record, seed=s)`` with the default method (``auto``) and no
``x0`` or ``scale`` — what a new user types — under two ways of drawing the start:

- ``normal``: N(0, 1), positive parameters in absolute value (the default before);
- ``scale``: log-uniform within a factor 3 of typical values read off the record's
  frequency response (:func:`symid.fit.timeseries.scale.typical_scale`; the default now).

Success as in ``population.py`` (noise-free: largest relative parameter error ≤ 1e-3, or
for a problem not proven globally identifiable an exact fit with positive parameters;
1 %: error at most twice that of the least-squares estimate from the truth, as
``timeseries_population.py`` finds it, or not proven global, a misfit at most 1.001 times
its misfit). 60 s per start (``--time-limit``).

Run::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/timeseries_defaults.py \\
        [--seeds 0,1] [--draws normal,scale] [--workers 2]

Prints a table and writes ``benchmarks/results/timeseries_defaults.json``. With ``--draws``
naming one way only, the other's rows are taken from that file (each row keeps the commit
that ran it), so a change to one way is measured again without the other.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from typing import Any

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from population import parameter_error as error
from population import start_success
from timeseries_population import CLASSES, NOISES, REFERENCES, fit, problem_list, reference

from symid.runlog import write_json_atomic

DRAWS = ("normal", "scale")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2,3")
    ap.add_argument("--seeds", default="0,1", help="seeds of the drawn start (default %(default)s)")
    ap.add_argument("--draws", default=",".join(DRAWS), help="ways of drawing the start to run (default %(default)s)")
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    sizes = [int(v) for v in args.sizes.split(",") if v]
    seeds = [int(v) for v in args.seeds.split(",") if v]
    run_draws = [d for d in args.draws.split(",") if d]
    if any(d not in DRAWS for d in run_draws):
        ap.error(f"--draws: choose from {', '.join(DRAWS)}")
    commit = git_commit()
    out = RESULTS / "timeseries_defaults.json"
    kept = []  # rows of the ways not run now, from the last results
    if set(run_draws) != set(DRAWS) and out.exists():
        last = json.loads(out.read_text())
        kept = [{"commit": last["git_commit"], **r} for r in last["rows"] if r["draws"] not in run_draws]
    t_all = time.perf_counter()
    problems = problem_list(sizes)
    jobs: dict[tuple, Any] = {}
    # a fresh process per fit: CasADi keeps what an output-error solver built (timeseries_population.py)
    with ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn"), max_tasks_per_child=1) as pool:
        for p in problems:
            for noise in NOISES:
                if noise:
                    for ref_method in REFERENCES:
                        jobs[(p.name, noise, "reference", ref_method)] = pool.submit(
                            fit, p.cls, p.n_size, p.info["draw"], noise, ref_method, p.truth.tolist(),
                            time_limit=args.time_limit)
                for d in run_draws:
                    for s in seeds:
                        jobs[(p.name, noise, d, s)] = pool.submit(
                            fit, p.cls, p.n_size, p.info["draw"], noise, None, None, time_limit=args.time_limit,
                            seed=s, draws=d)
        results = {}
        for k, f in jobs.items():
            results[k] = f.result()
            if k[2] != "reference":
                r = results[k]
                cost = "-" if r["cost"] is None else format(r["cost"], ".3g")
                print(f"{k[0]:18s} noise {k[1]:<4g} {k[2]:6s} seed {k[3]}: {r['status']:12s} cost {cost} "
                      f"{r['seconds']:.1f} s", flush=True)
    by = {p.name: p for p in problems}
    rows, cells = [], {}
    for (name, noise, d, s), rec in results.items():
        if d == "reference":
            continue
        p = by[name]
        ref = reference({r: results[(name, noise, "reference", r)] for r in REFERENCES}) if noise else None
        ok = start_success(rec["theta"], rec["cost"], p.truth, np.ones(p.truth.size, bool), bool(p.info.get("global")),
                           ref)
        rows.append({"problem": name, "noise": noise, "draws": d, "seed": s, "success": ok, "commit": commit,
                     "error": None if rec["theta"] is None else error(rec["theta"], p.truth), **rec})
    rows += [r for r in kept if r["problem"] in by and r["seed"] in seeds]
    for r in rows:
        for key in ((by[r["problem"]].cls, r["draws"], r["noise"]), ("all", r["draws"], r["noise"])):
            c = cells.setdefault(key, {"starts": 0, "success": 0, "times": []})
            c["starts"] += 1
            c["success"] += r["success"]
            c["times"].append(r["seconds"])
    table = []
    print(f"\n{'class':12s} {'draws':6s} {'exact':>7s} {'1 %':>7s} {'median s':>8s}")
    for cls in (*CLASSES, "all"):
        for d in DRAWS:
            cs = [cells.get((cls, d, nz)) for nz in NOISES]
            if any(c is None for c in cs):
                continue
            row = {"class": cls, "draws": d, "exact": f"{cs[0]['success']}/{cs[0]['starts']}",
                   "1 %": f"{cs[1]['success']}/{cs[1]['starts']}",
                   "median_s": float(np.median([t for c in cs for t in c["times"]]))}
            table.append(row)
            print(f"{cls:12s} {d:6s} {row['exact']:>7s} {row['1 %']:>7s} {row['median_s']:8.1f}")
    write_json_atomic(out, {"benchmark": "timeseries_defaults", "command": "benchmarks/timeseries_defaults.py",
                            "git_commit": commit, "commits": sorted({r["commit"] for r in rows}), "sizes": sizes,
                            "seeds": seeds,
                            "time_limit": args.time_limit, "table": table, "rows": rows,
                            "wall_time": time.perf_counter() - t_all,
                            "machine": {"platform": platform.platform(), "python": platform.python_version()}})
    print(f"wrote {out} ({time.perf_counter() - t_all:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
