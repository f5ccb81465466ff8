"""Equal weights or ``variance="relative"`` on frequency responses with 1 % noise: the population's problems.

A frequency response with noise of a few % of each value (relative noise) is fitted best
(maximum likelihood) with every line weighed by its own level, 1/|Hᵢ|²; the default equal
weights let the largest lines decide, which matters when |H| spans decades (a load angle,
a position far from the force). symid's default stays equal weights (what the success
rule and ``cost`` mean) and its summary names ``variance="relative"`` when the residual
looks like relative noise and |H| spans more than a decade
(:func:`symid.fit.frf.misfit.relative_noise_note`). This study measures what that advice
is worth, and that it stays silent on additive noise.

Problems: those of ``benchmarks/population.py`` (chains, chains with two sensors, gains,
first-order networks, compartment models; 2 and 3 masses, states or compartments, two
problems each, and one each of 5), the same grids, skipped where the grid does not resolve
the success tolerance. Noise: relative, H·(1 + 0.01 e), as the benchmark adds, or additive,
0.01 × the rms |H| of each entry, three seeds each. Per record:

* ``equal``: ``lm`` from the truth with equal weights (the least-squares estimate);
* ``relative``: ``lm`` with ``variance="relative"`` started from ``equal``'s estimate (what
  a user who follows the note does);
* ``ml``: ``lm`` from the truth weighted by the true noise variance (the best one can do);
* whether the note appears at ``equal``'s estimate.

Each parameter error is the largest relative error of any parameter. Run (about 10 minutes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/frf_relative_weights.py

Prints a summary and writes ``benchmarks/results/frf_relative_weights.json``.
"""

from __future__ import annotations

import argparse
import math
import platform
import statistics
import time
import warnings
from typing import Any

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from population import parameter_error
from population_models import RESOLUTION_FLOOR, make_problem

import symid as si
from symid.fit.frf.misfit import relative_noise_note
from symid.runlog import write_json_atomic

NOISE = 0.01
CLASSES = ("chain", "chain_sensors", "gains", "state_space", "compartment")
SIZES = ((2, 2), (3, 2), (5, 1))  # (size, problems per class)
SEEDS = (0, 1, 2)


def additive_noise(frf: Any, level: float, seed: int) -> Any:
    """``frf`` plus complex Gaussian noise of ``level`` × the rms |H| of each entry (seeded)."""
    rng = np.random.default_rng([seed, 31337])
    H = np.asarray(frf.H)
    std = level * np.sqrt(np.mean(np.abs(H) ** 2, axis=0, keepdims=True))
    e = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / math.sqrt(2)
    return si.FrequencyData(frf.w, H + std * e)


def _lm(p: Any, data: Any, x0: Any, variance: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # identifiability was checked when the problem was generated
        return si.identify(p.model, data, method="lm", x0=x0, scale=p.typical, identifiability_check=False,
                           variance=variance, time_limit=60)


def run_record(p: Any, kind: str, seed: int) -> dict[str, Any]:
    """The three fits of one noisy record."""
    exact = si.simulate_frf(p.model, p.truth, p.w)
    H = np.asarray(exact.H)
    if kind == "relative":
        data, var = p.data(NOISE, seed), (NOISE * np.abs(H)) ** 2
    else:
        data = additive_noise(exact, NOISE, seed)
        var = np.broadcast_to(NOISE**2 * np.mean(np.abs(H) ** 2, axis=0, keepdims=True), H.shape).copy()
    t0 = time.perf_counter()
    equal = _lm(p, data, p.truth, None)
    note = relative_noise_note(p.model, data, equal.theta_vector)
    relative = _lm(p, data, equal.theta_vector, "relative")
    ml = _lm(p, data, p.truth, var)
    return {"problem": p.name, "noise": kind, "seed": seed, "note": note is not None,
            "decades": None if note is None else note["decades"],
            "error_equal": parameter_error(equal.theta_vector, p.truth),
            "error_relative": parameter_error(relative.theta_vector, p.truth),
            "error_ml": parameter_error(ml.theta_vector, p.truth),
            "success_equal": bool(equal.success), "success_relative": bool(relative.success),
            "seconds": time.perf_counter() - t0}


def _median(key: str, rows: list[dict[str, Any]]) -> float | None:
    return statistics.median(r[key] for r in rows) if rows else None


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per noise kind: how often the note appears, and the errors with and without following it."""
    out = {}
    for kind in ("relative", "additive"):
        rs = [r for r in rows if r["noise"] == kind]
        if not rs:
            continue
        noted = [r for r in rs if r["note"]]
        out[kind] = {
            "records": len(rs), "noted": len(noted),
            "median_error_equal": _median("error_equal", noted),
            "median_error_relative": _median("error_relative", noted), "median_error_ml": _median("error_ml", noted),
            "relative_not_worse": sum(r["error_relative"] <= r["error_equal"] * (1 + 1e-9) for r in noted),
            "relative_over_twice": sum(r["error_relative"] > 2 * r["error_equal"] for r in noted),
            "relative_no_fit": sum(not r["success_relative"] for r in noted),
            "equal_no_fit": sum(not r["success_equal"] for r in noted)}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.parse_args(argv)
    rows: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for n, count in SIZES:
        for cls in CLASSES:
            for index in range(count):
                try:
                    p = make_problem(cls, n, index, timeout=20.0)
                except RuntimeError:
                    continue
                if p.info.get("resolution", 1.0) <= RESOLUTION_FLOOR:
                    continue  # the grid does not resolve the success tolerance (as the benchmark skips it)
                for kind in ("relative", "additive"):
                    for seed in SEEDS:
                        row = run_record(p, kind, seed)
                        rows.append(row)
                        print(f"{row['problem']:22s} {kind:9s} seed {seed}  note {row['note']!s:5s}  error: "
                              f"equal {row['error_equal']:9.3g}  relative {row['error_relative']:9.3g}  "
                              f"ml {row['error_ml']:9.3g}  ({row['seconds']:.1f} s)", flush=True)
    summary = summarise(rows)
    for kind, s in summary.items():
        print(f"{kind} noise: the note on {s['noted']} of {s['records']} records", end="")
        if s["noted"]:
            print(f"; there the largest parameter error has a median {s['median_error_equal']:.3g} with equal "
                  f"weights, {s['median_error_relative']:.3g} with variance='relative' from that estimate "
                  f"({s['median_error_ml']:.3g} weighted by the true noise from the truth); not worse on "
                  f"{s['relative_not_worse']}, more than twice worse on {s['relative_over_twice']}, no fit on "
                  f"{s['relative_no_fit']} (equal weights: {s['equal_no_fit']})")
        else:
            print()
    write_json_atomic(RESULTS / "frf_relative_weights.json",
                      {"benchmark": "frf_relative_weights", "commit": git_commit(), "noise": NOISE,
                       "python": platform.python_version(), "seconds": time.perf_counter() - t0,
                       "summary": summary, "rows": rows})
    print(f"wrote {RESULTS / 'frf_relative_weights.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
