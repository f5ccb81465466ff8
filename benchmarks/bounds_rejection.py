"""How often a right model's noisy fit is refused because the data pull it beyond its bounds (false refusals).

``si.identify`` calls a fit on its bounds a failure when the least-squares estimate lies
beyond them by more than noise explains (:meth:`symid.fit.uncertainty.Uncertainty.bounds_rejected`:
the Gauss–Newton shift, in standard errors, above √χ²(l) at probability 1e-6). With the
model right and the truth inside the bounds that should almost never happen; this measures
it on the population's problems (:mod:`population_models`, the first draw of every class
at n = 2 and 3), 1 % noise relative to |H| (as ``population.py``) or of one level on every
line, three records each, ``auto`` from an informed start (within a factor 3 of the truth)
with the typical values as ``scale``, 30 s per fit.

Run (about 2 minutes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bounds_rejection.py

Prints one line per fit and a summary; writes ``benchmarks/results/bounds_rejection.json``.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from population_models import make_problem

import symid as si
from symid.runlog import write_json_atomic

CLASSES = ("chain", "chain_sensors", "gains", "state_space", "compartment")
NOISES = ("relative", "additive")


def noisy(p: object, kind: str, seed: int) -> si.FrequencyData:
    """The problem's response with 1 % noise: relative to |H| at each line, or one level (1 % of rms |H|) on all."""
    if kind == "relative":
        return p.data(noise=0.01, seed=seed)
    exact = si.simulate_frf(p.model, p.truth, p.w)
    H = np.asarray(exact.H)
    rng = np.random.default_rng(seed)
    e = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    return si.FrequencyData(exact.w, H + 0.01 * np.sqrt(np.mean(np.abs(H) ** 2)) * e)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2,3")
    ap.add_argument("--records", type=int, default=3)
    args = ap.parse_args(argv)
    t_all = time.perf_counter()
    rows = []
    for cls in CLASSES:
        for n in (int(v) for v in args.sizes.split(",")):
            p = make_problem(cls, n, 0)
            for seed in range(args.records):
                for kind in NOISES:
                    x0 = p.starts("informed", 1, seed=seed)[0]
                    t0 = time.perf_counter()
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        res = si.identify(p.model, noisy(p, kind, seed), x0=x0.tolist(), scale=p.typical.tolist(),
                                          identifiability_check=False, time_limit=30)
                    unc = res.uncertainty
                    row = {"problem": p.name, "seed": seed, "noise": kind, "success": bool(res.success),
                           "refused_by_bounds": res.fit.startswith("pulled beyond the bounds"), "fit": res.fit,
                           "status": res.status,
                           "shift": None if unc is None else unc.shift,
                           "beyond_bounds": None if unc is None else unc.beyond_bounds,
                           "largest_error": float(np.max(np.abs(res.theta_vector / p.truth - 1))),
                           "seconds": time.perf_counter() - t0}
                    rows.append(row)
                    print(f"{p.name:18s} seed {seed} {kind:8s} success {row['success']!s:5s} refused by bounds "
                          f"{row['refused_by_bounds']!s:5s} shift {row['shift'] or 0:.3g}", flush=True)
    refused = sum(r["refused_by_bounds"] for r in rows)
    summary = {"fits": len(rows), "successes": sum(r["success"] for r in rows), "refused_by_bounds": refused,
               "failed_otherwise": sum(not r["success"] and not r["refused_by_bounds"] for r in rows)}
    print(f"\n{summary['fits']} fits: {summary['successes']} successes, {refused} refused by bounds, "
          f"{summary['failed_otherwise']} failed otherwise")
    out = RESULTS / "bounds_rejection.json"
    write_json_atomic(out, {"benchmark": "bounds_rejection", "git_commit": git_commit(), "summary": summary,
                            "rows": rows, "wall_time": time.perf_counter() - t_all})
    print(f"wrote {out} ({time.perf_counter() - t_all:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
