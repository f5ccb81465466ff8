"""Where ``auto`` restarts: around the start only, or every other pass around the typical values (and the doubt).

Issue 14 asks ``method="auto"`` to reach the truth from uninformed starts (log-uniform
within a factor 10 of the typical values, which it is given as ``scale=``). This runs
:class:`symid.fit.frf.lm.AutoFRF` from the same uninformed starts of generated problems
(:mod:`population_models`, this folder; indices 3, 4 by default, which ``population.py``
does not use; the grid must resolve a 1e-3 error) in three variants:

- ``start``: no ``scale``, and a fit that is not exact stops the restarts (the doubt of
  :mod:`symid.fit.frf.lm` switched off): every restart within a factor 10 of the start —
  for models whose parameters are all declared positive, ``auto`` as it was before the
  restarts around the typical values;
- ``typical``: ``scale=`` the typical values (every other restart around them), doubt off;
- ``typical+doubt``: ``auto`` as it is (the default).

Per variant: starts that reach the truth (largest relative error ≤ 1e-3, noise-free) and
the median seconds per start (``--time-limit`` each).

Run (one BLAS thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/auto_restarts.py \\
        [--classes chain,chain_sensors] [--sizes 5] [--indices 3,4] [--starts 2] [--time-limit 45]

Writes ``benchmarks/results/auto_restarts.json`` (``--out``).
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _study import git_commit  # noqa: E402
from population import parameter_error  # noqa: E402
from population_models import RESOLUTION_FLOOR, make_problem  # noqa: E402

import symid.fit.frf.lm as lm  # noqa: E402
from symid.runlog import json_safe  # noqa: E402

VARIANTS = ("start", "typical", "typical+doubt")


def run_variant(variant: str, p: Any, data: Any, x0: np.ndarray, time_limit: float) -> Any:
    doubt = lm._DOUBT
    try:
        if variant != "typical+doubt":
            lm._DOUBT = math.inf  # no black box beats a fit by an infinite factor: the doubt is off
        scale = None if variant == "start" else p.typical
        return lm.AutoFRF(p.model, data, scale=scale, time_limit=time_limit).run(x0)
    finally:
        lm._DOUBT = doubt


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--classes", default="chain,chain_sensors")
    ap.add_argument("--sizes", default="5")
    ap.add_argument("--indices", default="3,4")
    ap.add_argument("--starts", type=int, default=2)
    ap.add_argument("--time-limit", type=float, default=45.0)
    ap.add_argument("--out", default=str(HERE / "results" / "auto_restarts.json"))
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows = []
    for n in (int(v) for v in args.sizes.split(",")):
        for cls in args.classes.split(","):
            for idx in (int(v) for v in args.indices.split(",")):
                p = make_problem(cls, n, idx, check=False)
                if p.info["resolution"] <= RESOLUTION_FLOOR:
                    print(f"{p.name}: skipped (resolution {p.info['resolution']:.1e})", flush=True)
                    continue
                data = p.data(0.0)
                for k, x0 in enumerate(p.starts("uninformed", args.starts, seed=0)):
                    for variant in VARIANTS:
                        t1 = time.perf_counter()
                        out = run_variant(variant, p, data, x0, args.time_limit)
                        err = parameter_error(out.theta, p.truth)
                        rows.append({"problem": p.name, "start": k, "variant": variant, "error": err,
                                     "truth": bool(err <= 1e-3), "cost": out.cost, "success": bool(out.success),
                                     "seconds": time.perf_counter() - t1, "message": out.message})
                        print(json.dumps(json_safe(rows[-1])), flush=True)
    groups: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        groups[r["variant"]].append(r)
    summary = [{"variant": v, "starts": len(groups[v]), "truth": sum(r["truth"] for r in groups[v]),
                "median_seconds": float(np.median([r["seconds"] for r in groups[v]]))} for v in VARIANTS if groups[v]]
    commit = git_commit()
    doc = {"command": " ".join(["benchmarks/auto_restarts.py", *(argv if argv is not None else sys.argv[1:])]),
           "commit": commit, "python": platform.python_version(), "wall_seconds": time.perf_counter() - t0,
           "summary": summary, "rows": rows}
    Path(args.out).write_text(json.dumps(json_safe(doc), indent=1) + "\n", encoding="utf-8")
    for s in summary:
        print(f"{s['variant']}: truth from {s['truth']}/{s['starts']} uninformed starts, "
              f"median {s['median_seconds']:.1f} s")
    print(f"written {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
