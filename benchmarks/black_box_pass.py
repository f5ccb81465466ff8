"""Would a pass of ``auto`` from the black-box start rescue the starts it misses at n = 5 and 8?

Issue 14 asked whether :class:`symid.fit.frf.lm.AutoFRF` should try the black-box start of
:func:`symid.fit.frf.modal.black_box_start` (the model's poles placed on those of a vector
fit of the data) as a restart when the pass from the user's start does not fit. This
measures, on generated problems of :mod:`population_models` (this folder) that
``population.py`` does not use (indices 3, 4, 5 by default; the grid must resolve a 1e-3
error), for each noise level:

- the seconds to build the black-box start with the typical values as ``typical``;
- how far it is from the truth (largest relative error; share of parameters within a
  factor 10);
- one pass of ``auto`` from it (``restarts=0``: eight frequency bands, then the full
  criteria; ``time_limit`` seconds): does it reach the truth (largest relative error ≤ 1e-3
  noise-free, ≤ 2 × that of IPOPT started at the truth at 1 % noise) and in how long.

Run (one BLAS thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/black_box_pass.py \\
        [--classes chain,chain_sensors,gains] [--sizes 5,8] [--indices 3,4,5] [--noise 0,0.01]

Writes ``benchmarks/results/black_box_pass.json`` (``--out``) and prints one line per
problem and a summary per size and noise level.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
import warnings
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _study import git_commit  # noqa: E402
from population import parameter_error  # noqa: E402
from population_models import RESOLUTION_FLOOR, make_problem  # noqa: E402

import symid as si  # noqa: E402
from symid.fit.frf.lm import AutoFRF  # noqa: E402
from symid.fit.frf.modal import black_box_start  # noqa: E402
from symid.runlog import json_safe  # noqa: E402


def run(classes: list[str], sizes: list[int], indices: list[int], noises: list[float], time_limit: float
        ) -> list[dict[str, Any]]:
    rows = []
    for n in sizes:
        for cls in classes:
            for idx in indices:
                p = make_problem(cls, n, idx, check=False)
                if p.info["resolution"] <= RESOLUTION_FLOOR:
                    print(f"{p.name}: skipped (resolution {p.info['resolution']:.1e})", flush=True)
                    continue
                for noise in noises:
                    data = p.data(noise, seed=0)
                    tol = 1e-3
                    if noise > 0:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            ref = si.identify(p.model, data, method="ipopt", x0=p.truth, scale=p.typical,
                                              identifiability_check=False)
                        tol = 2 * parameter_error(ref.theta_vector, p.truth)
                    t0 = time.perf_counter()
                    bb = black_box_start(p.model, data, p.typical, seed=0)
                    build = time.perf_counter() - t0
                    row: dict[str, Any] = {"problem": p.name, "n": n, "noise": noise, "build_s": build,
                                           "found": bb is not None, "tolerance": tol}
                    if bb is not None:
                        row["start_error"] = parameter_error(bb.theta, p.truth)
                        row["within_10x"] = float(np.mean(np.abs(np.log10(bb.theta / p.truth)) < 1))
                        t0 = time.perf_counter()
                        out = AutoFRF(p.model, data, scale=p.typical, restarts=0, time_limit=time_limit).run(bb.theta)
                        row.update(pass_s=time.perf_counter() - t0, pass_error=parameter_error(out.theta, p.truth),
                                   pass_cost=out.cost, truth=bool(parameter_error(out.theta, p.truth) <= tol))
                    rows.append(row)
                    print(json.dumps(json_safe(row)), flush=True)
    return rows


def summarise(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    groups: dict[tuple, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        groups[(r["n"], r["noise"])].append(r)
    out = []
    for (n, noise), rs in sorted(groups.items()):
        found = [r for r in rs if r["found"]]
        out.append({"n": n, "noise": noise, "problems": len(rs), "found": len(found),
                    "truth": sum(r["truth"] for r in found),
                    "build_s_median": float(np.median([r["build_s"] for r in rs])),
                    "build_s_max": float(np.max([r["build_s"] for r in rs])),
                    "within_10x_median": float(np.median([r["within_10x"] for r in found])) if found else None,
                    "pass_s_median": float(np.median([r["pass_s"] for r in found])) if found else None})
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--classes", default="chain,chain_sensors,gains")
    ap.add_argument("--sizes", default="5,8")
    ap.add_argument("--indices", default="3,4,5")
    ap.add_argument("--noise", default="0,0.01")
    ap.add_argument("--time-limit", type=float, default=45.0)
    ap.add_argument("--out", default=str(HERE / "results" / "black_box_pass.json"))
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows = run(args.classes.split(","), [int(v) for v in args.sizes.split(",")],
               [int(v) for v in args.indices.split(",")], [float(v) for v in args.noise.split(",")], args.time_limit)
    summary = summarise(rows)
    commit = git_commit()
    doc = {"command": " ".join(["benchmarks/black_box_pass.py", *(argv if argv is not None else sys.argv[1:])]),
           "commit": commit, "python": platform.python_version(), "wall_seconds": time.perf_counter() - t0,
           "summary": summary, "rows": rows}
    Path(args.out).write_text(json.dumps(json_safe(doc), indent=1) + "\n", encoding="utf-8")
    for s in summary:
        print(f"n = {s['n']}, noise {s['noise']:g}: black-box start found {s['found']}/{s['problems']}, one auto pass "
              f"from it reaches the truth {s['truth']}/{s['found']}; build {s['build_s_median']:.2f} s median "
              f"({s['build_s_max']:.2f} max), pass {s['pass_s_median']} s median")
    print(f"written {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
