"""Intervals of a fit weighted by a variance the data estimated: coverage with and without the inflation ν/(ν − 4).

``si.estimate_frf`` on P periods of a periodic multisine gives the FRF and its sample variance
with ν = 2(P − 1) degrees of freedom; ``si.identify`` then weighs the fit by 1/σ̂². Taking σ̂² as
exact, the 95 % intervals are too narrow; the covariance the library reports multiplies that
by ν/(ν − 4) (:func:`symid.fit.frf.misfit.estimated_variance_inflation`). Both are computed from
the same fit (the two covariances differ by that factor only), so their coverages are side by side.

Problems (truths chosen here):

``chain3-acc``
    Three masses grounded at mass 1, force on mass 1, acceleration of mass 3, masses known
    (2, 5, 8 kg), c = (30, 15, 10) N s/m and k = (8e4, 3e4, 1.5e4) N/m free: 6 parameters,
    lines 1–60 Hz (a new user's trial).
``two-mass``
    Two masses grounded at mass 1, force on and position of mass 2, all six parameters free
    (m = 1.5, 0.6 kg, c = 4, 1.5 N s/m, k = 2e3, 8e2 N/m), lines 0.5–20 Hz.

Each record: 1 % additive output noise (of the output's rms), ``estimate_frf(..., period=)``,
``si.identify`` from a start within 40 % of the truth. The table gives, per problem and number of
periods, the successes, the spread of the estimates over the median reported standard error
(1 when the standard errors are right) and the coverage of the 95 % intervals per parameter.

Run (one BLAS thread, about 2 minutes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/frf_estimated_variance.py [--records 100]

Prints the table and writes ``benchmarks/results/frf_estimated_variance.json``.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np
from _study import git_commit  # benchmarks/_study.py (the script's folder is on the path)

import symid as si
from symid.fit.frf.misfit import estimated_variance_inflation

RESULTS = Path(__file__).resolve().parent / "results"


def _chain(n: int, drive: int, out: int, output: str, masses_known: dict | None = None):
    m = si.parameters(" ".join(f"m{i + 1}" for i in range(n)), positive=True)
    c = si.parameters(" ".join(f"c{i + 1}" for i in range(n)), positive=True)
    k = si.parameters(" ".join(f"k{i + 1}" for i in range(n)), positive=True)
    m, c, k = (list(v) if isinstance(v, tuple) else [v] for v in (m, c, k))

    def ground(e):
        mat = [[0] * n for _ in range(n)]
        for i in range(n):
            mat[i][i] += e[i]
            if i + 1 < n:
                mat[i][i] += e[i + 1]
                mat[i][i + 1] -= e[i + 1]
                mat[i + 1][i] -= e[i + 1]
        return mat

    B = [[1 if j == drive else 0] for j in range(n)]
    C = [[1 if j == out else 0 for j in range(n)]]
    model = si.SecondOrderModel(M=[[m[i] if i == j else 0 for j in range(n)] for i in range(n)], V=ground(c),
                                K=ground(k), B=B, C=C, output=output)
    return model if not masses_known else model.with_known(masses_known)


def problem(name: str):
    """(model, full truth, free truth, dt, period, lines)."""
    if name == "chain3-acc":
        truth = {"m1": 2.0, "m2": 5.0, "m3": 8.0, "c1": 30.0, "c2": 15.0, "c3": 10.0, "k1": 8e4, "k2": 3e4,
                 "k3": 1.5e4}
        model = _chain(3, 0, 2, "acceleration", {"m1": 2.0, "m2": 5.0, "m3": 8.0})
        return model, truth, 0.002, 2000, np.arange(4, 241)  # 0.25 Hz lines, 1–60 Hz
    truth = {"m1": 1.5, "m2": 0.6, "c1": 4.0, "c2": 1.5, "k1": 2e3, "k2": 8e2}
    return _chain(2, 1, 1, "position"), truth, 0.005, 2000, np.arange(5, 201)  # 0.1 Hz lines, 0.5–20 Hz


def run(name: str, periods: int, records: int) -> dict:
    model, truth, dt, period, lines = problem(name)
    names = model.parameter_names
    tv = np.array([truth[n] for n in names])
    rng = np.random.default_rng(100)
    U = np.zeros(period // 2 + 1, complex)
    U[lines] = np.exp(2j * np.pi * rng.random(lines.size)) * period
    wk = 2 * np.pi * np.arange(period // 2 + 1) / (period * dt)
    H = si.simulate_frf(model, [truth[n] for n in names], wk[lines]).H[:, 0, 0]
    Y = np.zeros_like(U)
    Y[lines] = H * U[lines]
    u1, y1 = np.fft.irfft(U, period), np.fft.irfft(Y, period)
    start = tv * np.where(np.arange(tv.size) % 2 == 0, 1.4, 0.7)
    band = (float(wk[lines[0]]), float(wk[lines[-1]]))
    th, se, ok, seconds, dof = [], [], [], [], None
    for seed in range(records):
        noise = 0.01 * np.std(y1) * np.random.default_rng(seed).standard_normal(periods * period)
        io = si.IOData(np.tile(u1, periods)[:, None], (np.tile(y1, periods) + noise)[:, None], dt)
        frf = si.estimate_frf(io, period=period, band=band)
        dof = frf.variance_dof
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = si.identify(model, frf, x0=start)
        seconds.append(time.perf_counter() - t0)
        th.append(res.theta_vector)
        se.append(np.asarray(res.uncertainty.standard_errors, dtype=float))
        ok.append(bool(res.success))
    th, se = np.array(th), np.array(se)
    kappa = estimated_variance_inflation(dof)
    exact = se / np.sqrt(kappa)  # the standard errors that take σ̂² as the exact variance
    return {"problem": name, "periods": periods, "dof": dof, "records": records, "successes": int(sum(ok)),
            "inflation": kappa, "parameters": list(names),
            "spread_over_se": (th.std(0, ddof=1) / np.median(se, 0)).tolist(),
            "coverage_as_exact": (np.abs(th - tv) <= 1.96 * exact).mean(0).tolist(),
            "coverage_inflated": (np.abs(th - tv) <= 1.96 * se).mean(0).tolist(),
            "median_seconds": float(np.median(seconds))}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=100)
    parser.add_argument("--periods", type=int, nargs="+", default=[4, 8, 16])
    parser.add_argument("--out", default=str(RESULTS / "frf_estimated_variance.json"))
    args = parser.parse_args(argv)
    print(f"{'problem':11} {'P':>3} {'ν':>4} {'ok':>7} {'spread/SE':>10} {'coverage σ̂² exact':>20} "
          f"{'coverage ×ν/(ν−4)':>20}")
    rows = []
    for name in ("chain3-acc", "two-mass"):
        for periods in args.periods:
            r = run(name, periods, args.records)
            rows.append(r)

            def span(v):
                return f"{100 * min(v):.0f}–{100 * max(v):.0f} %"

            print(f"{name:11} {periods:3d} {r['dof']:4g} {r['successes']:3d}/{r['records']:<3d} "
                  f"{min(r['spread_over_se']):.2f}–{max(r['spread_over_se']):.2f} "
                  f"{span(r['coverage_as_exact']):>20} {span(r['coverage_inflated']):>20}", flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"code": git_commit(), "records": args.records, "rows": rows}, indent=1) + "\n")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
