"""How clearly the case analysis separates θ*'s case from the others, on chains driven next to the free end.

For each chain ``chain_at-n-(n−1).n`` of ``benchmarks/identifiability_models.py`` (n = 3…8,
the force on the mass next to the free end, the position of the end mass) and several
random points θ* (the report's own draws, :func:`symid.structural.global_.star_and_summary`
with ``seed`` and ``draw``), :func:`symid.structural.ladder_adjacent.case_margins` gives
how far θ*'s case is from θ* and the smallest residual of a failed check among all other
cases, in 80 digits (160 where a check was undecided in 80, as in the report). A check
passes below 1e-30 and fails above 1e-10 (``symid/structural/ladder_adjacent.py``): the
margins say how far both are from those thresholds. The time column is one point's case
analysis (a report computes it at θ* and at θ**).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/adjacent_margins.py [--draws 5]

Prints a table and writes ``benchmarks/results/adjacent_margins.json``.
"""

from __future__ import annotations

import argparse
import time

import identifiability_models
from _study import RESULTS, git_commit

from symid.runlog import write_json_atomic
from symid.structural.global_ import star_and_summary
from symid.structural.ladder_adjacent import FAIL, PASS, adjacent_of, case_margins


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=5, help="random points θ* per model")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rows = []
    print(f"{'model':16s} {'cases':>6s} {'theta* case (max)':>18s} {'nearest other (min)':>20s} {'s/point':>8s} "
          "digits")
    for n in range(3, 9):
        name = f"chain_at-{n}-{n - 1}.{n}"
        model = identifiability_models.build(name)
        lad = adjacent_of(model)
        for draw in range(args.draws):
            star = star_and_summary(model, seed=args.seed, draw=draw)[1]
            t0 = time.perf_counter()
            got = case_margins(lad, model, None, star)
            rows.append({"model": name, "draw": draw, "seconds": round(time.perf_counter() - t0, 3),
                         **(got or {"cases": None, "solutions": None, "theta_star": None, "nearest": None,
                                    "undecided": None, "digits": None})})
        mine = [r for r in rows if r["model"] == name]
        ok = all(r["theta_star"] is not None and r["nearest"] is not None for r in mine)
        worst = max(r["theta_star"] for r in mine) if ok else float("nan")
        near = min(r["nearest"] for r in mine) if ok else float("nan")
        print(f"{name:16s} {max(r['cases'] or 0 for r in mine):6d} {worst:18.1e} {near:20.1e} "
              f"{sum(r['seconds'] for r in mine) / len(mine):8.3f} {'/'.join(str(r['digits']) for r in mine)}",
              flush=True)
    clean = [r for r in rows if r["solutions"] == 1 and not r["undecided"] and r["nearest"] is not None]
    print(f"thresholds: pass < {PASS:g}, fail > {FAIL:g}; one solution, nothing undecided: {len(clean)} of "
          f"{len(rows)} points; largest theta* difference {max(r['theta_star'] for r in clean):.1e}, "
          f"smallest other {min(r['nearest'] for r in clean):.1e}")
    write_json_atomic(RESULTS / "adjacent_margins.json",
                      {"benchmark": "adjacent_margins", "commit": git_commit(), "seed": args.seed,
                       "draws": args.draws, "pass_below": PASS, "fail_above": FAIL, "rows": rows})
    print(f"wrote {RESULTS / 'adjacent_margins.json'}")


if __name__ == "__main__":
    main()
