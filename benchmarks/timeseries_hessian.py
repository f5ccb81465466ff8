"""Time series at n = 5: output error's ``hessian="auto"`` (the default) against ``hessian="exact"``.

On the records of ``timeseries_population.py`` (its problems at n = 5: a 5-mass chain, a
chain with gains, 5 compartments, a 5-state network; noise-free and 1 %), one uninformed
start each, ``si.identify`` with its default method (``auto``) and a 60 s budget, once with
each Hessian choice. What it measures: whether the start's budget holds (CasADi's build of
the exact Hessian cannot be interrupted: 45-57 s predicted for the chain and the chain with
gains, whose graphs are 8.2 and 10.3 million nodes × unknowns) and whether the estimate
fits. Each fit runs in a fresh process (CasADi keeps what it built).

Run (about 20 minutes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/timeseries_hessian.py

Prints a table and writes ``benchmarks/results/timeseries_hessian.json``.
"""

from __future__ import annotations

import argparse
import platform
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from typing import Any

from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from population import parameter_error as error
from population_models import make_problem
from timeseries_population import records

import symid as si
from symid.runlog import write_json_atomic

CLASSES = ("chain", "gains", "compartment", "state_space")
NOISES = (0.0, 0.01)
HESSIANS = ("auto", "exact")
VARIANTS = {"auto": {}, "exact": {"hessian": "exact"}, "trf": {"solver": "trf"}}
"""What ``--variants`` may compare: the default, IPOPT with the exact Hessian, trust-region least squares on the
numpy sensitivities (``solver="trf"``, no CasADi graph)."""
TIME_LIMIT = 60.0


def fit(cls: str, n: int, noise: float, hessian: str) -> dict[str, Any]:
    """One ``si.identify`` from the problem's first uninformed start, as a JSON-able record."""
    p = make_problem(cls, n, 0, check=False)
    io = records(p, noise)
    x0 = p.starts("uninformed", 1, seed=0)[0]
    opts = VARIANTS[hessian]
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = si.identify(p.model, io, x0=x0.tolist(), identifiability_check=False, time_limit=TIME_LIMIT, **opts)
    return {"problem": p.name, "noise": noise, "hessian": hessian, "seconds": time.perf_counter() - t0,
            "cost": float(res.cost), "success": bool(res.success), "error": float(error(res.theta_vector, p.truth)),
            "samples": len(io.y), "message": res.message}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=5)
    ap.add_argument("--workers", type=int, default=1, help="default 1: the times are what is measured")
    ap.add_argument("--variants", default=",".join(HESSIANS), help=f"default %(default)s; from {list(VARIANTS)}")
    ap.add_argument("--out", default="timeseries_hessian.json", help="file name in benchmarks/results/")
    args = ap.parse_args(argv)
    variants = [v for v in args.variants.split(",") if v]
    if any(v not in VARIANTS for v in variants):
        ap.error(f"--variants: choose from {list(VARIANTS)}")
    t_all = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn"), max_tasks_per_child=1) as pool:
        jobs = [pool.submit(fit, c, args.size, nz, h) for c in CLASSES for nz in NOISES for h in variants]
        rows = [j.result() for j in jobs]
    print(f"{'problem':18s} {'noise':>5s} {'hessian':7s} {'seconds':>7s} {'success':7s} {'misfit':>9s} {'error':>9s}")
    for r in rows:
        print(f"{r['problem']:18s} {r['noise']:5g} {r['hessian']:7s} {r['seconds']:7.1f} {r['success']!s:7s} "
              f"{r['cost']:9.3e} {r['error']:9.3g}")
    summary = {h: {"success": sum(r["success"] for r in rows if r["hessian"] == h),
                   "runs": sum(r["hessian"] == h for r in rows),
                   "max_seconds": max(r["seconds"] for r in rows if r["hessian"] == h)} for h in variants}
    for h, s in summary.items():
        print(f"{h}: {s['success']}/{s['runs']} fit, longest start {s['max_seconds']:.1f} s (budget {TIME_LIMIT:g} s)")
    out = RESULTS / args.out
    write_json_atomic(out, {"benchmark": "timeseries_hessian", "command": "benchmarks/timeseries_hessian.py",
                            "git_commit": git_commit(), "size": args.size, "time_limit": TIME_LIMIT,
                            "rows": rows, "summary": summary, "wall_time": time.perf_counter() - t_all,
                            "machine": platform.machine()})
    print(f"wrote {out} ({time.perf_counter() - t_all:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
