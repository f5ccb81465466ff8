"""The success rule above 10 % rms on measured samples: the right model against a wrong one, no noise level given.

A lightly damped second-order system (a = 4, b = 0.8, g = 2; x'' + b x' + a x = g u, x measured) under a white
input, 1500 samples at dt = 0.1, output noise 12, 20, 30 and 45 % of the output's rms, 10 records each. Each
record is fitted by output error (``method="oe"``) with the right model and with a first-order model (a wrong
structure: one real pole for a resonance), neither told the noise level. Above a relative misfit of 0.01 a fit
counts when its residual is white, independent of every input and no step from a minimum
(``symid.fit.success``, rule 3, up to ``NOISY_CEILING``); the table gives how often each model's fit counts.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/timeseries_loud_noise.py        # about a minute

Prints a table and writes ``benchmarks/results/timeseries_loud_noise.json``.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np

import symid as si

RESULTS = Path(__file__).resolve().parent / "results"
LEVELS = (0.12, 0.20, 0.30, 0.45)
RECORDS = 10


def main() -> int:
    a, b, g = si.parameters("a b g", positive=True)
    right = si.StateSpaceModel(A=[[0, 1], [-a, -b]], B=[[0], [g]], C=[[1, 0]])
    wrong = si.StateSpaceModel(A=[[-a]], B=[[g]], C=[[1]])
    truth = {"a": 4.0, "b": 0.8, "g": 2.0}
    rows = []
    for level in LEVELS:
        counts = {"right": 0, "wrong": 0}
        for seed in range(RECORDS):
            u = np.random.default_rng(100 + seed).standard_normal(1500)
            clean = si.simulate_io(right, truth, u, dt=0.1)
            sigma = level * float(np.sqrt(np.mean(clean.y**2)))
            noise = sigma * np.random.default_rng(200 + seed).standard_normal(clean.y.shape)
            record = si.IOData(clean.u, clean.y + noise, dt=0.1)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                fits = {"right": si.identify(right, record, method="oe", x0={"a": 3.0, "b": 1.0, "g": 1.5},
                                             identifiability_check=False, progress=False),
                        "wrong": si.identify(wrong, record, method="oe", x0={"a": 1.0, "g": 1.0},
                                             identifiability_check=False, progress=False)}
            for name, res in fits.items():
                counts[name] += bool(res.success)
        rows.append({"noise": level, "right_success": counts["right"], "wrong_success": counts["wrong"],
                     "records": RECORDS})
        print(f"noise {100 * level:4.0f} % of the output's rms: right model {counts['right']}/{RECORDS}, "
              f"first-order model {counts['wrong']}/{RECORDS}", flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "timeseries_loud_noise.json").write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
