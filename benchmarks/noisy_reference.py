"""How good is the population benchmark's 1 % noise reference, IPOPT started at the truth?

The benchmark (``benchmarks/population.py``) judges a start on noisy data by its parameter
error against that of IPOPT started at the truth (within twice it), taking that estimate
for the least-squares estimate the data allow. This study fits every logged noisy problem
again from the truth with two other solvers of the same misfit and prints, per problem:

* the logged reference's misfit and largest relative parameter error;
* ``lm`` (trust-region least squares, one pass) from the truth, the same equal weights:
  its misfit and error — a lower misfit means the reference is not the least-squares
  estimate;
* ``lm`` from the truth weighted by the noise the benchmark adds (relative, 1 % of |H| per
  line: variance (0.01 |H|)², the maximum-likelihood weighting for these data): its error;
* the misfit of the true parameters themselves (the same criterion): a least-squares
  estimate lies below it by what it fits of the noise, so an estimate between the two fits
  the data as well as the truth does.

Nothing here changes the benchmark; it measures whether its noisy criterion means what it
says. Run (about 3 minutes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/noisy_reference.py

Prints a table and a summary, and writes ``benchmarks/results/noisy_reference.json``.
"""

from __future__ import annotations

import argparse
import platform
import time
import warnings
from typing import Any

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from population import parameter_error, resolved
from population_models import make_problem

import symid as si
from symid.fit.frf.misfit import relative_misfit
from symid.runlog import RunLog, write_json_atomic

LOG = RESULTS / "population.jsonl"
NOISE = 0.01


def _fit(p: Any, data: Any, variance: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # identifiability was checked when the problem was generated
        return si.identify(p.model, data, method="lm", x0=p.truth, scale=p.typical, identifiability_check=False,
                           variance=variance, time_limit=60)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.parse_args(argv)
    log = RunLog(LOG)  # the last record of every key, as the benchmark reads it
    rows = []
    t0 = time.perf_counter()
    print(f"{'problem':22s} {'ref misfit':>11s} {'ref error':>10s} {'lm misfit':>11s} {'lm error':>10s} "
          f"{'ML error':>10s} {'truth misfit':>12s}")
    for prob in log.records():
        if not prob["key"].endswith("/problem"):
            continue
        name = prob["key"].split("/")[0]
        ref = log.get(f"{name}/noise{NOISE:g}/reference")
        if ref is None:
            continue
        p = make_problem(prob["cls"], int(prob["n"]), int(prob["index"]), check=False, draw=prob["info"]["draw"])
        data = p.data(noise=NOISE, seed=0)
        equal = _fit(p, data, None)
        ml = _fit(p, data, (NOISE * np.abs(np.asarray(data.H))) ** 2)
        row = {"problem": name, "class": prob["cls"], "n": int(prob["n"]), "counted": resolved(p),
               "reference_misfit": float(ref["cost"]), "reference_error": parameter_error(ref["theta"], p.truth),
               "lm_misfit": float(equal.cost), "lm_error": parameter_error(equal.theta_vector, p.truth),
               "ml_error": parameter_error(ml.theta_vector, p.truth),
               "truth_misfit": relative_misfit(p.model, data, p.truth)}
        rows.append(row)
        print(f"{name:22s} {row['reference_misfit']:11.4e} {row['reference_error']:10.3g} {row['lm_misfit']:11.4e} "
              f"{row['lm_error']:10.3g} {row['ml_error']:10.3g} {row['truth_misfit']:12.4e}"
              f"{'' if row['counted'] else '  (not counted)'}",
              flush=True)
    counted = [r for r in rows if r["counted"]]
    lower = [r for r in counted if r["lm_misfit"] < r["reference_misfit"] * (1 - 1e-6)]
    summary = {
        "problems": len(counted),
        "reference_not_least_squares": len(lower),
        "worst_reference_misfit_ratio": max((r["reference_misfit"] / r["lm_misfit"] for r in counted), default=None),
        "reference_below_truth_misfit": sum(r["reference_misfit"] < r["truth_misfit"] for r in counted),
        "reference_error_above_1": sum(r["reference_error"] > 1 for r in counted),
        "reference_error_above_1e3": sum(r["reference_error"] > 1e3 for r in counted),
        "median_error": {k: float(np.median([r[k] for r in counted])) for k in
                         ("reference_error", "lm_error", "ml_error")},
    }
    print(f"\n{summary['problems']} counted problems; lm from the truth ends below the reference's misfit on "
          f"{summary['reference_not_least_squares']} (reference up to {summary['worst_reference_misfit_ratio']:.2f} "
          f"times lm's); the reference fits better than the truth on {summary['reference_below_truth_misfit']}; "
          f"reference error > 100 % on {summary['reference_error_above_1']}, > 1e5 % on "
          f"{summary['reference_error_above_1e3']}; median errors: reference "
          f"{summary['median_error']['reference_error']:.3g}, lm {summary['median_error']['lm_error']:.3g}, "
          f"lm noise-weighted {summary['median_error']['ml_error']:.3g}")
    out = RESULTS / "noisy_reference.json"
    write_json_atomic(out, {"benchmark": "noisy_reference", "command": "benchmarks/noisy_reference.py",
                            "git_commit": git_commit(), "noise": NOISE, "summary": summary, "rows": rows,
                            "wall_time": time.perf_counter() - t0,
                            "machine": {"platform": platform.platform(), "python": platform.python_version(),
                                        "numpy": np.__version__}})
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
