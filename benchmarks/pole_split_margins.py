"""How clearly the pole-split test separates θ*'s split from the others, on chains driven at an interior mass.

For each chain ``chain_mid-n-mm`` of ``benchmarks/identifiability_models.py`` (n = 3…8,
driven and measured at the middle mass) and several random points θ* (the report's own
draws, :func:`symid.structural.global_.star_and_summary` with ``seed`` and ``draw``),
:func:`symid.structural.ladder_interior.split_margins` gives θ*'s residual (40 digits) and
the smallest residual of every other split. The test passes a split below 1e-25 and fails
it above 1e-12 (``symid/structural/pole_split.py``): the margins say how far both are from
those thresholds.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/pole_split_margins.py [--draws 5]

Prints a table and writes ``benchmarks/results/pole_split_margins.json``.
"""

from __future__ import annotations

import argparse
import time

import identifiability_models
from _study import RESULTS, git_commit

from symid.runlog import write_json_atomic
from symid.structural.global_ import star_and_summary
from symid.structural.ladder import ladder_of
from symid.structural.ladder_interior import split_margins
from symid.structural.pole_split import FAIL, PASS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=5, help="random points θ* per model")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rows = []
    print(f"{'model':16s} {'splits':>6s} {'theta* split (max)':>19s} {'nearest other (min)':>20s} {'s/point':>8s}")
    for n in range(3, 9):
        name = f"chain_mid-{n}-mm"
        model = identifiability_models.build(name)
        lad = ladder_of(model, driven_anywhere=True)
        for draw in range(args.draws):
            star = star_and_summary(model, seed=args.seed, draw=draw)[1]
            t0 = time.perf_counter()
            got = split_margins(lad, model, None, star)
            rows.append({"model": name, "draw": draw, "seconds": round(time.perf_counter() - t0, 3),
                         **(got or {"splits": None, "true": None, "nearest": None})})
        mine = [r for r in rows if r["model"] == name]
        ok = all(r["true"] is not None for r in mine)
        worst = max(r["true"] for r in mine) if ok else float("nan")
        near = min(r["nearest"] for r in mine) if ok else float("nan")
        print(f"{name:16s} {mine[0]['splits'] or 0:6d} {worst:19.1e} {near:20.1e} "
              f"{sum(r['seconds'] for r in mine) / len(mine):8.3f}", flush=True)
    decided = [r for r in rows if r["true"] is not None]
    print(f"thresholds: pass < {PASS:g}, fail > {FAIL:g}; every point decided: {len(decided) == len(rows)}; "
          f"largest theta* residual {max(r['true'] for r in decided):.1e}, "
          f"smallest other {min(r['nearest'] for r in decided):.1e}")
    write_json_atomic(RESULTS / "pole_split_margins.json",
                      {"benchmark": "pole_split_margins", "commit": git_commit(), "seed": args.seed,
                       "draws": args.draws, "pass_below": PASS, "fail_above": FAIL, "rows": rows})
    print(f"wrote {RESULTS / 'pole_split_margins.json'}")


if __name__ == "__main__":
    main()
