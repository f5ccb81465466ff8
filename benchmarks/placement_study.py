"""``auto`` on chains whose sensor is not at the driven mass (non-collocated), noise-free, uninformed starts.

The population benchmark (``population.py``) draws one or two problems per class and
size, and its chains at n = 5 and 8 all came out collocated (sensor at the driven mass),
where ``auto`` starts from the chain's own values read off the response by continued
fractions (:func:`symid.fit.frf.chain.chain_start`). That start needs the driving-point
response; with the sensor on another mass ``auto`` has only its restarts. This study draws
chains with one sensor from the same generator (:mod:`population_models`, class
``chain``, indices from ``--first`` on) and keeps the non-collocated ones whose grid
resolves the success tolerance, until ``--problems`` per size; each is run from
``--starts`` uninformed starts (log-uniform within a factor 10 of the typical values,
given as ``scale=``) with ``--time-limit`` seconds per start, as in ``population.py``.
Success is that benchmark's rule (largest relative error ≤ 1e-3, or, for a problem not
proven globally identifiable, another exact fit with positive parameters).

Run (one BLAS thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/placement_study.py \\
        [--sizes 3,4,5] [--problems 3] [--starts 2] [--time-limit 45] [--workers 2]

Writes ``benchmarks/results/placement_study.json`` (``--out``) and prints a table.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _study import git_commit  # noqa: E402
from population import parameter_error, start_success  # noqa: E402
from population_models import RESOLUTION_FLOOR, make_problem  # noqa: E402

from symid.runlog import json_safe  # noqa: E402


def _problems(n: int, count: int, first: int, timeout: float) -> list[Any]:
    out, index = [], first
    while len(out) < count and index < first + 40:
        p = make_problem("chain", n, index, timeout=timeout)
        index += 1
        if p.info["collocated"] or float(p.info["resolution"]) <= RESOLUTION_FLOOR:
            continue
        out.append(p)
    return out


def _run(cls: str, n: int, index: int, draw: int, k: int, starts: int, time_limit: float) -> dict[str, Any]:
    from symid.fit.frf.lm import AutoFRF

    p = make_problem(cls, n, index, check=False, draw=draw)
    x0 = p.starts("uninformed", starts, seed=0)[k]
    t0 = time.perf_counter()
    out = AutoFRF(p.model, p.data(0.0), scale=p.typical, time_limit=time_limit).run(x0)
    return {"theta": out.theta.tolist(), "cost": float(out.cost), "seconds": time.perf_counter() - t0,
            "status": out.status, "message": out.message}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="3,4,5")
    ap.add_argument("--problems", type=int, default=3)
    ap.add_argument("--first", type=int, default=0, help="first problem index drawn")
    ap.add_argument("--starts", type=int, default=2)
    ap.add_argument("--time-limit", type=float, default=45.0)
    ap.add_argument("--check-timeout", type=float, default=20.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=str(HERE / "results" / "placement_study.json"))
    args = ap.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",")]
    rows, jobs = [], []
    with ProcessPoolExecutor(args.workers, max_tasks_per_child=1) as pool:
        for n in sizes:
            for p in _problems(n, args.problems, args.first, args.check_timeout):
                globally = p.info.get("identifiability") == "global"
                positive = np.asarray(p.model.positive, dtype=bool)
                for k in range(args.starts):
                    fut = pool.submit(_run, p.cls, n, int(p.name.rsplit("-", 1)[1]), p.info["draw"], k, args.starts,
                                      args.time_limit)
                    jobs.append((p, globally, positive, k, fut))
        for p, globally, positive, k, fut in jobs:
            r = fut.result()
            ok = start_success(r["theta"], r["cost"], p.truth, positive, globally, None)
            rows.append({"problem": p.name, "n": p.truth.size // 3, "drive": p.info["drive"],
                         "sensor": p.info["sensors"][0], "output": p.info["output"],
                         "identifiability": p.info.get("identifiability"), "start": k, "success": ok,
                         "error": parameter_error(r["theta"], p.truth), **r})
            print(f"{p.name:12s} drive {p.info['drive']} sensor {p.info['sensors'][0]} {p.info['output']:12s} "
                  f"start {k}: {'ok  ' if ok else 'miss'} error {rows[-1]['error']:.1e} misfit {r['cost']:.1e} "
                  f"{r['seconds']:.1f} s", flush=True)
    print("\n| n | problems | successes / starts | median s / start |\n|---|---|---|---|")
    for n in sizes:
        sel = [r for r in rows if r["n"] == n]
        if sel:
            print(f"| {n} | {len({r['problem'] for r in sel})} | {sum(r['success'] for r in sel)}/{len(sel)} | "
                  f"{np.median([r['seconds'] for r in sel]):.1f} |")
    doc = {"command": " ".join(["benchmarks/placement_study.py", *(argv if argv is not None else sys.argv[1:])]),
           "commit": git_commit(), "python": platform.python_version(), "machine": platform.machine(),
           "options": vars(args), "rows": rows}
    Path(args.out).write_text(json.dumps(json_safe(doc), indent=1) + "\n")
    return doc


if __name__ == "__main__":
    main()
