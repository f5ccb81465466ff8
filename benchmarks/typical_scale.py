"""How far the typical values read off a frequency response lie from the truth, per parameter role.

:func:`symid.fit.frf.scale.typical_scale` gives every parameter an order of magnitude from
the data alone (dimensional analysis); the default starts are drawn within a factor 3 of
it, and time series get it through their estimated frequency response. This study draws
problems of the population benchmark's classes (:mod:`population_models`, draws
``0 … --draws − 1`` per class and size, noise-free responses on their own grids) and
prints, per problem, the largest |log₁₀(typical / true)| of each role (M, V, K, A, B, C):
how many decades the analysis misses by.

Run (seconds)::

    .venv/bin/python benchmarks/typical_scale.py [--classes gains] [--sizes 2,3,5,8] [--draws 3]

Writes ``benchmarks/results/typical_scale.json`` and prints a table.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _study import RESULTS, git_commit  # noqa: E402
from population_models import CLASSES, make_problem  # noqa: E402

from symid.fit.frf.scale import parameter_roles, typical_scale  # noqa: E402
from symid.runlog import write_json_atomic  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--classes", default="gains", help=f"comma-separated, of {', '.join(CLASSES)}")
    ap.add_argument("--sizes", default="2,3,5,8")
    ap.add_argument("--draws", type=int, default=3, help="problems per class and size (default %(default)s)")
    args = ap.parse_args(argv)
    classes = [c for c in args.classes.split(",") if c]
    if any(c not in CLASSES for c in classes):
        ap.error(f"--classes: choose from {', '.join(CLASSES)}")
    sizes = [int(v) for v in args.sizes.split(",") if v]
    t0 = time.perf_counter()
    rows = []
    print(f"{'problem':18s} {'role':4s} {'largest |log10(typical/true)|':>30s}")
    for cls in classes:
        for n in sizes:
            for draw in range(args.draws):
                try:
                    p = make_problem(cls, n, draw, check=False)
                except RuntimeError as exc:  # a class without problems of this size
                    print(f"{cls}-n{n}-{draw}: not drawn ({type(exc).__name__}: {exc})")
                    continue
                off = np.log10(typical_scale(p.model, p.data(noise=0.0, seed=0)) / p.truth)
                roles = parameter_roles(p.model)
                per_role = {r: float(np.max(np.abs(off[[x == r for x in roles]]))) for r in sorted(set(roles))}
                rows.append({"problem": p.name, "class": cls, "n": n, "offsets": off.tolist(), "roles": list(roles),
                             "largest_by_role": per_role})
                print(f"{p.name:18s} " + "  ".join(f"{r}: {v:.1f}" for r, v in per_role.items()), flush=True)
    worst = max((v for r in rows for v in r["largest_by_role"].values()), default=float("nan"))
    print(f"\nlargest over {len(rows)} problems: {worst:.1f} decades")
    out = RESULTS / "typical_scale.json"
    write_json_atomic(out, {"benchmark": "typical_scale", "command": "benchmarks/typical_scale.py "
                            + " ".join(argv if argv is not None else sys.argv[1:]), "git_commit": git_commit(),
                            "largest_decades": worst, "rows": rows, "wall_time": time.perf_counter() - t0,
                            "machine": {"platform": platform.platform(), "python": platform.python_version()}})
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
