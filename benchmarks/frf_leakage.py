"""How a Welch (Hann) estimate's resolution biases a fitted resonance, and what symid.fit.frf.leakage says of it.

An oscillator at 10 Hz with ζ = 0.5, 1, 2 and 5 %, driven by white noise held at 200 Hz (2¹⁷
samples, exact zero-order-hold simulation, estimated with ``hold="zoh"``), its response
estimated by Welch segments of 256 … 16384 samples (L lines across the half-power bandwidth
2ζωₙ); ``lm`` from the truth, (a) noise-free output, equal weights: the smoothing alone;
(b) noise-free output, the estimate's own variance (the default): the coherence drop at the
peak weighs the smoothed lines down; (c) 2 % output noise, default weights, 8 records of
12 000 samples each: the damper's error in its standard errors, how often its interval
holds the truth, and how often the leakage note (``res.options["leakage"]``) is given.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/frf_leakage.py        # about 3 minutes

Prints a table and writes ``benchmarks/results/frf_leakage.json``.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np

import symid as si

RESULTS = Path(__file__).resolve().parent / "results"
FS = 200.0
WN = 2 * np.pi * 10.0


def _model():
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])


def smoothing_rows() -> list[dict]:
    """(a) and (b): the damper's relative error against L, noise-free output."""
    model, dt = _model(), 1 / FS
    u = np.random.default_rng(0).standard_normal(2**17)
    rows = []
    for zeta in (0.005, 0.01, 0.02, 0.05):
        truth = np.array([1.0, 2 * zeta * WN, WN**2])
        io = si.simulate_io(model, truth, u, dt)
        for nper in (256, 512, 1024, 2048, 4096, 8192, 16384):
            frf = si.estimate_frf(io, nperseg=nper, hold="zoh", band=(2 * np.pi * 2, 2 * np.pi * 30))
            row = {"zeta": zeta, "nperseg": nper, "lines": 2 * zeta * WN / (2 * np.pi / (nper * dt))}
            for label, variance in (("equal", None), ("data", "data")):
                r = si.identify(model, frf, method="lm", x0=truth, identifiability_check=False, variance=variance)
                err = r.theta_vector / truth - 1
                row[label] = {"c": float(err[1]), "k": float(err[2]), "m": float(err[0]), "success": bool(r.success)}
            rows.append(row)
    return rows


def noisy_rows(records: int = 8) -> list[dict]:
    """(c): 2 % output noise, default weights; the damper in standard errors, coverage, the note."""
    model, dt = _model(), 1 / FS
    rows = []
    for zeta in (0.01, 0.03):
        truth = np.array([1.0, 2 * zeta * WN, WN**2])
        for nper in (256, 512, 1024, 2048, 4096):
            z, covered, noted, fits = [], 0, 0, 0
            for seed in range(records):
                u = np.random.default_rng(seed).standard_normal(12000)
                io = si.simulate_io(model, truth, u, dt, noise=0.02, seed=seed + 100)
                frf = si.estimate_frf(io, nperseg=nper, hold="zoh", band=(2 * np.pi * 2, 2 * np.pi * 30))
                r = si.identify(model, frf, method="lm", x0=truth, identifiability_check=False)
                se = float(r.uncertainty.standard_errors[1])
                z.append(float((r.theta_vector[1] - truth[1]) / se))
                covered += abs(z[-1]) <= 1.96
                noted += "leakage" in r.options
                fits += bool(r.success)
            rows.append({"zeta": zeta, "nperseg": nper, "lines": 2 * zeta * WN / (2 * np.pi / (nper * dt)),
                         "records": records, "c_error_in_se_median": float(np.median(z)), "covered": covered,
                         "noted": noted, "success": fits})
    return rows


def main() -> int:
    warnings.simplefilter("ignore")
    smooth = smoothing_rows()
    print("zeta   nperseg  lines  | c error: equal weights  data weights")
    for r in smooth:
        print(f"{r['zeta']:<6} {r['nperseg']:>7} {r['lines']:6.2f} | {100 * r['equal']['c']:+9.2f} % "
              f"{100 * r['data']['c']:+12.2f} %")
    noisy = noisy_rows()
    print("\n2 % noise, default weights: zeta nperseg lines | c error/se (median) covered noted success")
    for r in noisy:
        print(f"{r['zeta']:<6} {r['nperseg']:>7} {r['lines']:6.2f} | {r['c_error_in_se_median']:+8.2f} "
              f"{r['covered']}/{r['records']} {r['noted']}/{r['records']} {r['success']}/{r['records']}")
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "frf_leakage.json"
    out.write_text(json.dumps({"benchmark": "frf_leakage", "smoothing": smooth, "noisy": noisy}, indent=1))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
