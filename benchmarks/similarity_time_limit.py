"""How far past its ``time_limit`` a start of every similarity method runs (issue 14 item 6).

Two measurements, each start timed around ``Estimator.run`` (the black box and the
problem are built before, as :func:`symid.identify` does once per method):

1. every method on the problems of ``tests/test_similarity_progress.py`` (the e-nose black
   box; the 2-DOF mass-damper with one sensor, and with a full set of sensors from noisy
   records), with a callback that sleeps ``--nap`` seconds per iteration so that no start
   ends on its own rule within ``--budget`` (``ls`` ends after 5 reweighting rounds of
   milliseconds: its nap is budget / 3.5, so the budget falls in its fourth round);
2. the start that ran longest in ``benchmarks/two_stage_similarity.py`` (chain_sensors-n3-0:
   the second-order SCR of thesis (7-10) on the vector-fitted black box, 300 iterations,
   130 s there), once with ``time_limit`` = ``--long-budget`` and no callback.

Run ``OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/similarity_time_limit.py``
(about ``8 × budget + long budget`` seconds); prints a table and writes
``benchmarks/results/similarity_time_limit.json``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))

import population_models as pm  # noqa: E402  (benchmarks/ on the path)
import test_similarity_progress as cases  # noqa: E402  (the problems of the tests)
from two_stage_similarity import black_box  # noqa: E402

from symid.fit.registry import prepare  # noqa: E402
from symid.runlog import write_json_atomic  # noqa: E402


def timed(est, x0) -> tuple[object, float]:
    t0 = time.perf_counter()
    out = est.run(x0)
    return out, time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", type=float, default=1.0, help="time_limit of part 1, s (default %(default)s)")
    ap.add_argument("--nap", type=float, default=0.05, help="sleep per iteration in part 1, s (default %(default)s)")
    ap.add_argument("--long-budget", type=float, default=10.0, help="time_limit of part 2, s (default %(default)s)")
    ap.add_argument("--out", default=str(HERE / "results" / "similarity_time_limit.json"))
    args = ap.parse_args(argv)
    rows = []
    print("case | status | iterations | wall s | past the budget s")

    for label, problem, method, *_ in cases.CASES:
        nap = args.budget / 3.5 if method == "ls" else args.nap

        def slow(info, nap=nap):
            time.sleep(nap)
            return False

        model, data = problem()
        est = prepare(model, data, method, {"time_limit": args.budget, "callback": slow})
        out, wall = timed(est, cases.start(model))
        rows.append({"case": label, "budget": args.budget, "nap": nap, "status": out.status,
                     "iterations": out.iterations, "wall": wall, "overrun": wall - args.budget})
        print(f"{label} | {out.status} | {out.iterations} | {wall:.3f} | {wall - args.budget:+.3f}", flush=True)
    p = pm.make_problem("chain_sensors", 3, 0, check=False)
    bb, _ = black_box(p.model, p.data())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = prepare(p.model, bb, "scr", {"max_iter": 300, "time_limit": args.long_budget})
    out, wall = timed(est, p.starts("uninformed", 1)[0])
    rows.append({"case": f"{p.name} scr (7-10), two-stage benchmark", "budget": args.long_budget, "nap": 0.0,
                 "status": out.status, "iterations": out.iterations, "wall": wall, "overrun": wall - args.long_budget})
    print(f"{p.name} scr (7-10) | {out.status} | {out.iterations} | {wall:.3f} | {wall - args.long_budget:+.3f}")
    load = os.getloadavg()[0]
    write_json_atomic(args.out, {"benchmark": "similarity_time_limit", "rows": rows, "load_average_1min": load})
    print(f"load average (1 min) {load:.2f}; wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
