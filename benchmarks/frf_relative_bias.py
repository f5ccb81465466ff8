"""Bias and interval coverage of variance="relative" fits: weights from the measured |Hᵢ| against the model's |H(θ̂)|.

The 2-mass chain of ``tests/test_lm_auto.py`` (SI units, force and sensor on the free mass),
60 lines from 0.3× its slowest to 3× its fastest mode, relative noise H₀(1 + ε n), n complex
normal, ε = 5 % and 10 %, 100 records each; ``lm`` from the truth with
(a) ``variance=(ε|Hᵢ|)²``: weights from the measured values (what ``variance="relative"`` was);
(b) ``variance="relative"``: weights from the model at the estimate, iterated
(``symid.fit.frf.misfit.NoiseWeighted.reweigh_relative``);
(c) ``variance=(ε|H₀|)²``: the true noise weights (an oracle no user has).
Per parameter: mean relative error over its spread (bias in standard deviations) and how often
the 95 % interval holds the truth.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/frf_relative_bias.py      # about 3 minutes

Prints a table and writes ``benchmarks/results/frf_relative_bias.json``.
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np

import symid as si

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from test_lm_auto import TRUTH, chain2, grid  # noqa: E402  (the tests' own model, not a copy)

RESULTS = HERE / "results"
RECORDS = 100


def run(eps: float) -> dict:
    model, w = chain2(), grid(TRUTH)
    H0 = si.simulate_frf(model, TRUTH, w).H
    out = {}
    for label in ("measured", "relative", "oracle"):
        est, se = [], []
        for seed in range(RECORDS):
            rng = np.random.default_rng(seed)
            H = H0 * (1 + eps * (rng.standard_normal(H0.shape) + 1j * rng.standard_normal(H0.shape)) / np.sqrt(2))
            variance = {"measured": (eps * np.abs(H)) ** 2, "relative": "relative",
                        "oracle": (eps * np.abs(H0)) ** 2}[label]
            r = si.identify(model, si.FrequencyData(w, H), method="lm", x0=TRUTH, variance=variance,
                            identifiability_check=False, progress=False)
            est.append(r.theta_vector)
            se.append(r.uncertainty.standard_errors)
        est, se = np.array(est), np.array(se)
        rel = est / TRUTH - 1
        out[label] = {"bias_in_sd": (rel.mean(0) / rel.std(0)).tolist(),
                      "coverage": np.mean(np.abs(est - TRUTH) <= 1.96 * se, axis=0).tolist()}
    return out


def main() -> int:
    warnings.simplefilter("ignore")
    names = list(chain2().parameter_names)
    rows = {}
    for eps in (0.05, 0.10):
        rows[str(eps)] = run(eps)
        print(f"relative noise {100 * eps:g} %, {RECORDS} records   " + "  ".join(f"{n:>6}" for n in names))
        for label, r in rows[str(eps)].items():
            print(f"  {label:9s} bias/sd  " + "  ".join(f"{v:+6.2f}" for v in r["bias_in_sd"]))
            print(f"  {label:9s} coverage " + "  ".join(f"{v:6.2f}" for v in r["coverage"]))
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / "frf_relative_bias.json"
    path.write_text(json.dumps({"benchmark": "frf_relative_bias", "records": RECORDS, "parameters": names,
                                "rows": rows}, indent=1))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
