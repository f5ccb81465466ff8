"""The continued-fraction inversion of end-driven chains against the Gröbner step, on random chain structures.

Each trial draws a chain of 1–4 masses driven and measured at an end mass
(``symid/structural/ladder.py``): every damper, spring and ground element present, absent
or a known number at random (a mass is never absent), the ground element at the driven
end, the far end or nowhere, a position, velocity or acceleration sensor, and the masses
numbered in a random order. The report is made twice, with the inversion and with it
turned off (the Gröbner step decides), and the two are compared: verdicts per parameter
and the complex solution count must be the same. The inversion may decline (the Gröbner
step then decides both times); it must never disagree.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/ladder_check.py [--seed 0] [--trials 40] [--interior | --adjacent]

Prints one line per trial and writes ``benchmarks/results/ladder_check.json``.

``--adjacent``: chains of 3–4 masses driven at the mass next to an end and measured at
that end, or the reverse (``symid/structural/ladder_adjacent.py``), the ground element
at the far end (mostly), at the sensor's end or nowhere, elements mostly present, and
``benchmarks/results/ladder_check_adjacent.json``.

``--interior``: chains of 3–4 masses driven and measured at a random interior mass
(``symid/structural/ladder_interior.py``), the ground element at either end or nowhere,
and ``benchmarks/results/ladder_check_interior.json``. A chain free at both ends with
the same structure on either side has two solutions (the sides swapped): the inversion
must decline it.
"""

from __future__ import annotations

import argparse
import random
import time

import sympy as sp
from _study import RESULTS, git_commit

import symid as si
import symid.structural.global_ as global_module
from symid.runlog import write_json_atomic
from symid.structural.ladder import ladder_of
from symid.structural.ladder_adjacent import adjacent_of


def _chain(rng: random.Random, interior: bool = False, adjacent: bool = False):
    n = rng.randint(3, 4) if interior or adjacent else rng.randint(1, 4)
    at = rng.randint(1, n - 2) if interior else n - 2 if adjacent else 0
    params = []

    def slot(name: str, p_absent: float, p_known: float):
        r = rng.random()
        if r < p_absent:
            return 0
        if r < p_absent + p_known:
            return sp.Rational(rng.randint(1, 9), rng.randint(1, 5))
        sym = si.parameters(name, positive=True)
        params.append(sym)
        return sym

    absent = 0.05 if adjacent else 1  # the adjacent placement's inversion needs every element: mostly present
    m = [slot(f"m{i}", 0, 0.15) for i in range(n)]
    ce = [slot(f"ce{i}", 0.3 * absent, 0.1) for i in range(n - 1)]
    ke = [slot(f"ke{i}", 0.15 * absent, 0.1) for i in range(n - 1)]
    for i in range(n - 1):
        if ce[i] == 0 and ke[i] == 0:
            ke[i] = slot(f"ke{i}", 0, 0)
    if adjacent:
        where = rng.choice(["far end"] * 4 + ["sensor end", "none"])
    else:
        where = rng.choice(["first end", "last end", "none"] if interior else ["driven end", "far end", "none"])
    cg, kg = [0] * n, [0] * n
    if where != "none":
        j = 0 if where in ("driven end", "first end", "far end" if adjacent else "") else n - 1
        cg[j], kg[j] = slot(f"cg{j}", 0.3 * absent, 0.1), slot(f"kg{j}", 0.2 * absent, 0.1)

    def laplacian(e, g):
        X = sp.zeros(n, n)
        for i in range(n - 1):
            X[i, i] += e[i]
            X[i + 1, i + 1] += e[i]
            X[i, i + 1] -= e[i]
            X[i + 1, i] -= e[i]
        for i in range(n):
            X[i, i] += g[i]
        return X

    perm = list(range(n))
    rng.shuffle(perm)
    P = sp.zeros(n, n)
    for i, p in enumerate(perm):
        P[p, i] = 1
    output = rng.choice(["position", "velocity", "acceleration"])
    if not params:
        return None, n, where, output
    sensor = at + 1 if adjacent else at
    if adjacent and rng.random() < 0.5:
        at, sensor = sensor, at  # the force at the end, the sensor beside it: the same response
    model = si.SecondOrderModel(M=P * sp.diag(*m) * P.T, V=P * laplacian(ce, cg) * P.T,
                                K=P * laplacian(ke, kg) * P.T, B=P[:, at], C=P[:, sensor].T, output=output)
    return model, n, where, output


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--timeout", type=float, default=60.0, help="budget of each report (s)")
    ap.add_argument("--interior", action="store_true", help="chains driven at an interior mass")
    ap.add_argument("--adjacent", action="store_true",
                    help="chains driven next to the free end and measured there (or the reverse)")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    rows = []
    for trial in range(args.trials):
        model, n, where, output = _chain(rng, args.interior, args.adjacent)
        if model is None:  # every element known: nothing to identify
            continue
        recognised = (adjacent_of(model) if args.adjacent else ladder_of(model, driven_anywhere=args.interior)) \
            is not None
        t0 = time.perf_counter()
        rep = si.identifiability(model, timeout=args.timeout)
        t1 = time.perf_counter()
        inversion = global_module.proves_global
        global_module.proves_global = lambda *a, **k: ""
        try:
            ref = si.identifiability(model, timeout=args.timeout)
        finally:
            global_module.proves_global = inversion
        t2 = time.perf_counter()
        same = rep.verdicts == ref.verdicts and rep.n_solutions_complex == ref.n_solutions_complex
        row = {"trial": trial, "masses": n, "ground": where, "output": output, "parameters": len(model.parameters),
               "recognised": recognised, "engine": rep.engine, "reference_engine": ref.engine,
               "verdict": rep.verdict, "reference_verdict": ref.verdict, "same": same,
               "seconds": round(t1 - t0, 3), "reference_seconds": round(t2 - t1, 3)}
        rows.append(row)
        print(f"{trial:3d} n={n} ground={where:10s} {output:12s} engine={rep.engine or '-':7s} "
              f"reference={ref.engine or '-':7s} {rep.verdict} / {ref.verdict}  same={same}", flush=True)
    decided = sum(r["engine"] == "ladder" for r in rows)
    agree = sum(r["same"] for r in rows)
    print(f"same verdicts and counts: {agree} of {len(rows)}; decided by the inversion: {decided}")
    out = RESULTS / ("ladder_check_adjacent.json" if args.adjacent else
                     "ladder_check_interior.json" if args.interior else "ladder_check.json")
    write_json_atomic(out,
                      {"benchmark": "ladder_check", "interior": args.interior, "adjacent": args.adjacent,
                       "commit": git_commit(),
                       "seed": args.seed, "trials": len(rows), "same": agree, "decided_by_inversion": decided,
                       "rows": rows})
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
