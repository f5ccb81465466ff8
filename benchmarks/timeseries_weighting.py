"""Output error on noise that grows with the signal: unweighted against ``variance=`` weighting.

A new user's mammillary three-compartment pharmacokinetic model (central compartment with
elimination k10, a fast peripheral k12/k21 and a slow one k13/k31, concentration q·A1;
minutes, mg, mg/L), two infusions (10 mg/min for an hour, 20 mg/min for 20 minutes at 3 h),
481 samples a minute apart, and a combined error model: ``--rel`` (default 5 %) of the
concentration plus 0.005 mg/L. Each record is fitted by ``oe`` started at the truth, four
ways: unweighted (each output by its energy, the default); with the error model
``variance={"proportional": rel, "additive": 0.005}`` and its weights from the measured
concentrations (``"weights": "measured"``, what an array ``(rel·y)² + 0.005²`` gives); the
same error model with its weights from the prediction (the default: refitted until they
settle); and with the true variance. The 95 % intervals are checked against the truth.

Run (about 20 s for 30 records)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/timeseries_weighting.py
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/timeseries_weighting.py --rel 0.2 \
        --records 200 --out benchmarks/results/timeseries_weighting_20.json

Prints the coverage and the median relative error per parameter and writes
``benchmarks/results/timeseries_weighting.json`` (or ``--out``).
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np

import symid as si

TRUTH = {"k10": 0.119, "k12": 0.112, "k21": 0.055, "k13": 0.042, "k31": 0.0033, "q": 1 / 4.27}
ABS = 0.005  # the combined error model's additive part, mg/L (its proportional part: --rel)


def model() -> si.StateSpaceModel:
    k10, k12, k21, k13, k31, q = si.parameters("k10 k12 k21 k13 k31 q", positive=True)
    return si.StateSpaceModel(A=[[-k10 - k12 - k13, k21, k31], [k12, -k21, 0], [k13, 0, -k31]],
                              B=[[1], [0], [0]], C=[[q, 0, 0]])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=30)
    parser.add_argument("--rel", type=float, default=0.05, help="the proportional part of the noise (default 0.05)")
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "timeseries_weighting.json"))
    args = parser.parse_args()
    pk = model()
    names = pk.parameter_names
    truth = np.array([TRUTH[k] for k in names])
    u = np.zeros(481)
    u[0:60], u[180:200] = 10.0, 20.0
    clean = si.simulate_io(pk, TRUTH, u, 1.0)
    rel = args.rel
    ways = ("unweighted", "error model, weights from the measured y", "error model, weights from the prediction",
            "true variance")
    held = {w: np.zeros(len(names)) for w in ways}
    errors: dict[str, list] = {w: [] for w in ways}
    for seed in range(args.records):
        rng = np.random.default_rng(200 + seed)
        y = clean.y * (1 + rel * rng.standard_normal(clean.y.shape)) + ABS * rng.standard_normal(clean.y.shape)
        record = si.IOData(u, y, 1.0)
        options = {"unweighted": {},
                   ways[1]: {"variance": {"proportional": rel, "additive": ABS, "weights": "measured"}},
                   ways[2]: {"variance": {"proportional": rel, "additive": ABS}},
                   "true variance": {"variance": (rel * clean.y) ** 2 + ABS**2}}
        for way, opts in options.items():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = si.identify(pk, record, method="oe", x0=TRUTH, identifiability_check=False, **opts)
            iv = res.uncertainty.intervals
            held[way] += (iv[:, 0] <= truth) & (truth <= iv[:, 1])
            errors[way].append(np.abs(res.theta_vector / truth - 1))
    rows = {w: {"coverage": dict(zip(names, (held[w] / args.records).round(3).tolist(), strict=True)),
                "median_relative_error": dict(zip(names, np.median(errors[w], axis=0).round(4).tolist(),
                                                  strict=True))} for w in ways}
    print(f"{args.records} records; coverage of the 95 % intervals | median relative error")
    print(f"{'':42}" + "".join(f"{n:>8}" for n in names))
    for w in ways:
        print(f"{w:42}" + "".join(f"{rows[w]['coverage'][n]:>8.3f}" for n in names))
        print(f"{'':42}" + "".join(f"{rows[w]['median_relative_error'][n]:>8.3f}" for n in names))
    Path(args.out).write_text(json.dumps({"benchmark": "timeseries_weighting", "records": args.records,
                                          "proportional": rel, "additive": ABS, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
