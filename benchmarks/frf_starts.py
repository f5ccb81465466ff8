"""Default starts for frequency responses on the generated population: before and after the black-box start.

What :func:`symid.identify` does on a frequency response when the user gives no start,
measured on problems nobody tuned for (:mod:`population_models`, this folder: chains,
chains with two sensors, chains with known masses and gains, state-space networks,
compartment models; sizes 2 and 3 by default), noise-free and with 1 % relative noise.
Three starts per problem, each given to ``si.identify(model, frf, x0=start, seed=k)``
(default method ``"auto"``, one start, ``time_limit`` seconds):

- ``typical-d9af9db``: the default before this work — one draw within a factor 3 of the
  typical values of :func:`symid.fit.frf.scale.typical_scale` as committed in d9af9db
  (read from git: the dimensional analysis without the level of models with known
  masses and gains);
- ``typical``: the same draw around today's ``typical_scale``;
- ``black-box``: today's default first start, :func:`symid.fit.frf.modal.black_box_start`
  (the model's poles on a vector fit's), or the ``typical`` draw when there is none.

Per class × size × noise: the fraction of parameters whose start is within a factor 10
of the truth, the start's misfit (mean squared log H error, median), how often
``identify`` reports ``success`` (the estimate fits the data) and reaches the truth
(‖θ̂ − θ*‖ / ‖θ*‖ ≤ 1e-3 noise-free, 5e-2 at 1 %), and the median seconds (the start's
construction included). Problems are drawn with ``check=False`` (no identifiability
check): a problem with several solutions counts as a success when the fit is, and the
truth column tells the difference.

Run (one BLAS thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/frf_starts.py \\
        [--classes chain,gains] [--sizes 2,3] [--problems 5] [--noise 0,0.01] [--time-limit 30]

Writes ``benchmarks/results/frf_starts.json`` (``--out``) and prints the table.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import subprocess
import sys
import time
import types
import warnings
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from population_models import CLASSES, make_problem  # noqa: E402

import symid as si  # noqa: E402
from symid.fit.frf.modal import black_box_start, log_misfit  # noqa: E402
from symid.fit.frf.scale import typical_scale  # noqa: E402
from symid.fit.starts import make_starts  # noqa: E402

BEFORE = "d9af9db"  # the commit whose typical_scale was the default before the black-box start
STARTS = ("typical-" + BEFORE, "typical", "black-box")


def previous_typical_scale() -> Any:
    """``typical_scale`` as committed in :data:`BEFORE` (the repository's own history, read with git)."""
    src = subprocess.run(["git", "show", f"{BEFORE}:symid/fit/frf/scale.py"], cwd=HERE.parent, check=True,
                         capture_output=True, text=True).stdout
    module = types.ModuleType("scale_" + BEFORE)
    exec(compile(src, f"{BEFORE}:symid/fit/frf/scale.py", "exec"), module.__dict__)  # our own committed source
    return module.typical_scale


def starts_for(model: Any, frf: Any, seed: int, old_scale: Any) -> dict[str, tuple[np.ndarray, float]]:
    """Each kind of start with the seconds it took to build."""
    out = {}
    t0 = time.perf_counter()
    out[STARTS[0]] = (make_starts(model, 1, seed, typical=old_scale(model, frf))[0], time.perf_counter() - t0)
    t0 = time.perf_counter()
    typ = typical_scale(model, frf)
    draw = make_starts(model, 1, seed, typical=typ)[0]
    out[STARTS[1]] = (draw, time.perf_counter() - t0)
    found = black_box_start(model, frf, typ, seed=seed)
    out[STARTS[2]] = (draw if found is None else found.theta, time.perf_counter() - t0)
    return out


def run(classes: list[str], sizes: list[int], problems: int, noises: list[float], time_limit: float
        ) -> list[dict[str, Any]]:
    old_scale = previous_typical_scale()
    rows = []
    for n in sizes:
        for cls in classes:
            for idx in range(problems):
                prob = make_problem(cls, n, idx, check=False)
                for noise in noises:
                    frf = prob.data(noise, seed=idx)
                    for kind, (x0, build) in starts_for(prob.model, frf, idx, old_scale).items():
                        t0 = time.perf_counter()
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            res = si.identify(prob.model, frf, x0=x0, seed=idx, time_limit=time_limit,
                                              identifiability_check=False)
                        err = float(np.linalg.norm(res.theta_vector - prob.truth) / np.linalg.norm(prob.truth))
                        rows.append({"problem": prob.name, "class": cls, "n": n, "noise": noise, "start": kind,
                                     "within_10x": float(np.mean(np.abs(np.log10(np.abs(x0) / prob.truth)) < 1)),
                                     "start_misfit": log_misfit(prob.model, frf, x0), "success": bool(res.success),
                                     "truth": err <= (1e-3 if noise == 0 else 5e-2), "error": err,
                                     "seconds": build + time.perf_counter() - t0})
                        print(f"{prob.name:>18} noise {noise:<4g} {kind:>17}: start within 10x "
                              f"{rows[-1]['within_10x']:.2f}, misfit {rows[-1]['start_misfit']:.2e}, "
                              f"success {res.success}, error {err:.1e}, {rows[-1]['seconds']:.1f} s", flush=True)
    return rows


def summarise(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    groups: dict[tuple, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        groups[(r["class"], r["n"], r["noise"], r["start"])].append(r)
        groups[("all", 0, r["noise"], r["start"])].append(r)
    out = []
    for (cls, n, noise, kind), rs in groups.items():
        out.append({"class": cls, "n": n, "noise": noise, "start": kind, "problems": len(rs),
                    "within_10x": float(np.mean([r["within_10x"] for r in rs])),
                    "start_misfit_median": float(np.median([r["start_misfit"] for r in rs])),
                    "success": sum(r["success"] for r in rs), "truth": sum(r["truth"] for r in rs),
                    "seconds_median": float(np.median([r["seconds"] for r in rs]))})
    order = {c: i for i, c in enumerate((*CLASSES, "all"))}
    out.sort(key=lambda s: (order[s["class"]], s["n"], s["noise"], STARTS.index(s["start"])))
    return out


def table(summary: list[dict[str, Any]]) -> str:
    lines = ["| class | n | noise | start | within 10x | start misfit | success | truth | median s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for s in summary:
        n = "all" if s["class"] == "all" else s["n"]
        lines.append(f"| {s['class']} | {n} | {s['noise']:g} | {s['start']} | {s['within_10x']:.2f} | "
                     f"{s['start_misfit_median']:.1e} | {s['success']}/{s['problems']} | "
                     f"{s['truth']}/{s['problems']} | {s['seconds_median']:.1f} |")
    return "\n".join(lines)


def _finite(value: Any) -> Any:
    """JSON has no infinity: a misfit that could not be evaluated is written as null."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--classes", default=",".join(CLASSES))
    ap.add_argument("--sizes", default="2,3")
    ap.add_argument("--problems", type=int, default=5)
    ap.add_argument("--noise", default="0,0.01")
    ap.add_argument("--time-limit", type=float, default=30.0)
    ap.add_argument("--out", default=str(HERE / "results" / "frf_starts.json"))
    args = ap.parse_args(argv)
    classes = args.classes.split(",")
    unknown = [c for c in classes if c not in CLASSES]
    if unknown:
        ap.error(f"unknown class(es) {', '.join(unknown)}; choose from {', '.join(CLASSES)}")
    t0 = time.perf_counter()
    rows = run(classes, [int(s) for s in args.sizes.split(",")], args.problems,
               [float(v) for v in args.noise.split(",")], args.time_limit)
    summary = summarise(rows)
    doc = {"command": " ".join(["benchmarks/frf_starts.py", *(argv if argv is not None else sys.argv[1:])]),
           "time_limit": args.time_limit, "python": platform.python_version(), "numpy": np.__version__,
           "symid": si.__version__, "wall_seconds": time.perf_counter() - t0, "summary": summary, "rows": rows}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(_finite(doc), indent=1) + "\n", encoding="utf-8")
    print(table(summary))
    print(f"written {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
