"""The witness search on the chains with force and sensor at opposite ends, each in a fresh interpreter.

``OMP_NUM_THREADS=1 python benchmarks/witness_chains.py [--sizes 4 5 6 7 8] [--seeds 0 1 2]`` prints, per model and
seed, what the witness step of :func:`symid.identifiability` does in its child process: ``import`` (symid),
``summary`` (θ* and the exhaustive summary, :func:`~symid.structural.global_.star_and_summary`), ``search``
(:func:`~symid.structural.witness.find_witnesses`: the traced curves and random starts, and the certification),
``formulas`` (:func:`~symid.structural.rational_formulas.rational_formulas` on the parameters the certified witnesses
do not move), and which parameters are settled. Nothing is written.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

_CODE = r"""
import json, sys, time
t0 = time.perf_counter()
import sympy as sp
import symid
t1 = time.perf_counter()
sys.path.insert(0, {here!r})
import identifiability_models
from symid.structural.global_ import star_and_summary
from symid.structural.rational_formulas import rational_formulas
from symid.structural.witness import find_witnesses
model = identifiability_models.build({name!r})
t2 = time.perf_counter()
params, star, minimal, summ, rng = prepared = star_and_summary(model, None, seed={seed!r})
t3 = time.perf_counter()
res = find_witnesses(model, None, positive=[bool(p.is_positive) for p in params], seed={seed!r}, prepared=prepared)
t4 = time.perf_counter()
st = {{k: float(sp.Rational(v)) for k, v in res.theta_star.items()}}
moved = {{k for w, ok in zip(res.witnesses, res.certified) if ok
         for k in st if abs(w[k] - st[k]) > 1e-6 * max(1, abs(st[k]))}}
rest = [p.name for p in params if p.name not in moved]
formulas = rational_formulas(summ, rest, seed={seed!r}, at=star) if rest else {{}}
t5 = time.perf_counter()
print(json.dumps(dict(import_s=t1 - t0, summary_s=t3 - t2, search_s=t4 - t3, formulas_s=t5 - t4,
                      curves_and_starts=res.n_starts, witnesses=len(res.witnesses), certified=sum(res.certified),
                      n_parameters=len(params), moved=len(moved), global_by_formula=sorted(formulas),
                      unsettled=sorted(set(rest) - set(formulas)))))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", nargs="*", type=int, default=[4, 5, 6, 7, 8])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0])
    parser.add_argument("--variant", default="1n")
    args = parser.parse_args()
    here = str(Path(__file__).resolve().parent)
    print(f"{'model':12s} {'seed':>4s} {'import':>7s} {'summary':>8s} {'search':>7s} {'formulas':>8s} "
          f"{'certified':>9s} {'moved':>7s}  global by formula / unsettled")
    for n in args.sizes:
        for seed in args.seeds:
            name = f"chain-{n}-{args.variant}"
            proc = subprocess.run([sys.executable, "-c", _CODE.format(here=here, name=name, seed=seed)],
                                  capture_output=True, text=True, check=True)
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            print(f"{name:12s} {seed:4d} {r['import_s']:7.2f} {r['summary_s']:8.2f} {r['search_s']:7.2f} "
                  f"{r['formulas_s']:8.2f} {r['certified']:4d} of {r['witnesses']:<2d} "
                  f"{r['moved']:3d}/{r['n_parameters']:<3d}"
                  f"  {','.join(r['global_by_formula']) or '-'} / {','.join(r['unsettled']) or '-'}", flush=True)


if __name__ == "__main__":
    main()
