"""How often symid's 95 % intervals hold the truth on a model with two solutions close together.

A half car (body mass m and pitch inertia J, front and rear suspension kf, cf, kr, cr; lever
arms 1.2 and 1.5 m known; force and acceleration at the front axle; a new user's model, 80
lines from 0.2 to 8 Hz) is locally but not globally identifiable: two parameter values give
the same response, m = 700 kg and about 620 kg at the truth below, and the data cannot
separate them. Each record (1 % relative noise) is fitted with ``lm`` started at the
truth and its Fisher-information intervals (:mod:`symid.fit.uncertainty`) are checked
against the truth; the other solution at the estimate
(:func:`symid.structural.analyse.solutions_at`) is measured in standard errors (of the
parameter where it is farthest, and as the Mahalanobis distance); the same with m known
(globally identifiable) for comparison.

Run (about 20 s)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/interval_coverage.py

Prints the coverage and the rms of (estimate − truth) / standard error per parameter (1 for
intervals that hold), and writes ``benchmarks/results/interval_coverage.json``.
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np

import symid as si
from symid.structural.analyse import solutions_at

A, B = 1.2, 1.5  # lever arms (m), known
TRUTH = {"m": 700.0, "J": 1100.0, "kf": 35000.0, "kr": 38000.0, "cf": 2500.0, "cr": 2800.0}
W = 2 * np.pi * np.logspace(np.log10(0.2), np.log10(8.0), 80)


def half_car(mass_known: bool) -> si.SecondOrderModel:
    """The half car; with ``mass_known`` the body mass is 700 kg."""
    m, J, kf, kr, cf, cr = si.parameters("m J kf kr cf cr", positive=True)
    mass = TRUTH["m"] if mass_known else m
    return si.SecondOrderModel(
        M=[[mass, 0], [0, J]],
        V=[[cf + cr, A * cf - B * cr], [A * cf - B * cr, A**2 * cf + B**2 * cr]],
        K=[[kf + kr, A * kf - B * kr], [A * kf - B * kr, A**2 * kf + B**2 * kr]],
        B=[[1], [A]], C=[[1, A]], output="acceleration")


def coverage(mass_known: bool, records: int) -> dict:
    """Coverage of the 95 % intervals and rms z per parameter over ``records`` noisy records."""
    model = half_car(mass_known)
    names = model.parameter_names
    truth = {k: TRUTH[k] for k in names}
    tr = np.array([truth[k] for k in names])
    held, z, withheld, apart, mahalanobis = np.zeros(len(names)), [], 0, [], []
    for seed in range(records):
        frf = si.simulate_frf(model, truth, W, noise=0.01, seed=100 + seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = si.identify(model, frf, method="lm", x0=truth, identifiability_check=False)
        unc = res.uncertainty
        if np.any(np.isnan(unc.intervals)):
            withheld += 1
            continue
        held += (unc.intervals[:, 0] <= tr) & (tr <= unc.intervals[:, 1])
        z.append((res.theta_vector - tr) / unc.standard_errors)
        for other in solutions_at(model, res.theta_vector, timeout=None) or []:
            d = np.array([other[n] for n in names]) - res.theta_vector
            apart.append(float(np.max(np.abs(d) / unc.standard_errors)))
            mahalanobis.append(float(np.sqrt(d @ np.linalg.solve(unc.covariance, d))))
    n = records - withheld
    z = np.array(z)
    return {"parameters": list(names), "records": records, "withheld": withheld,
            "coverage": dict(zip(names, (held / max(n, 1)).round(3).tolist(), strict=True)),
            "rms_z": dict(zip(names, np.sqrt(np.mean(z**2, axis=0)).round(2).tolist(), strict=True)),
            "other_solution_se": [round(min(apart), 2), round(max(apart), 2)] if apart else None,
            "other_solution_mahalanobis": [round(min(mahalanobis), 2), round(max(mahalanobis), 2)]
            if mahalanobis else None}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=40)
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "interval_coverage.json"))
    args = parser.parse_args()
    rows = {"m free (2 solutions)": coverage(False, args.records), "m known (1 solution)": coverage(True, args.records)}
    print(f"{'case':<22} {'parameter':>9} {'coverage':>9} {'rms z':>7}")
    for case, row in rows.items():
        for name in row["parameters"]:
            print(f"{case:<22} {name:>9} {row['coverage'][name]:>9.3f} {row['rms_z'][name]:>7.2f}")
        print(f"{case:<22} {'records':>9} {row['records']:>9d} (intervals withheld on {row['withheld']})")
        if row["other_solution_se"]:
            print(f"{case:<22} the other solution at the estimate: {row['other_solution_se'][0]:g} to "
                  f"{row['other_solution_se'][1]:g} standard errors away (farthest parameter), Mahalanobis "
                  f"{row['other_solution_mahalanobis'][0]:g} to {row['other_solution_mahalanobis'][1]:g}")
    Path(args.out).write_text(json.dumps({"benchmark": "interval_coverage", "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
