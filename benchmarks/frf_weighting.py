"""Noise-weighted FRF fitting for ``ls`` and SCR: Monte Carlo of weighted against equal weights.

Problems (truths chosen here or from the thesis):

``one-mass``
    m ẍ + c ẋ + k x = u, m = 2, c = 0.4, k = 50 (resonance 5 rad/s), position measured,
    40 lines on 2–8 rad/s: ``ls`` (sensors case, thesis (4-10)).
``chain-actuators``
    Two masses as the thesis's 2-DOF (truth (4-20)), forces on both (B = I), velocity of
    mass 1 measured, 30 lines on 0.5–2 rad/s: ``ls`` (actuators case, (4-11)).
``2dof``
    The 2-DOF mass-damper of thesis §4-6-2 (C = [1, 0], truth (4-20), its 30 lines):
    ``scr`` alone and ``scr+polish``, from the start θ* × (0.5, 2, 2.5, 0.4, 0.6, 1.8)
    (within a factor 2.5, as the default starts).

Noise profiles (complex circular Gaussian, the true variance given as ``FrequencyData.variance``):
``step``: standard deviation 0.1 % of |H| on the lower half of the band, 3 % on the upper half;
``ramp``: from 0.1 % to 3 % of |H| geometrically over the band; ``abs``: a constant standard
deviation, 1 % of the mean |H| (relative noise then varies with |H| across the resonance).

For every record the estimate with ``variance="data"`` and with ``variance=None``; the table gives
the mean over records of Σₖ (θ̂ₖ/θₖ − 1)² for both, their ratio (weighted / equal), how many
estimates are successes, and for ``ls`` the propagated standard errors of the last record over
the Monte Carlo rms error (1 when the uncertainty is right).

Run (one BLAS thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/frf_weighting.py [--records 50]
        [--scr-records 20] [--only ls]

Prints the table and writes ``benchmarks/results/frf_weighting.json``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from _study import git_commit  # benchmarks/_study.py (the script's folder is on the path)

import symid as si
from symid.fit.frf.ls import LinearFRF
from symid.fit.frf.scr import ScrFRF

RESULTS = Path(__file__).resolve().parent / "results"
THESIS_2DOF = np.array([1.0, 1.0, 0.1, 0.3, 2.0, 1.0])  # thesis (4-20)


def one_mass():
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    return model, np.array([2.0, 0.4, 50.0]), np.linspace(2.0, 8.0, 40)


def chain_actuators():
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                K=[[k1 + k2, -k2], [-k2, k2]], B=[[1, 0], [0, 1]], C=[[1, 0]], output="velocity")
    return model, THESIS_2DOF, np.linspace(0.5, 2.0, 30)


def two_dof():
    entry = si.load_model("mass_damper_2dof")
    return entry.model, entry.model.theta_vector(entry.truth), np.asarray(entry.data().w)


PROBLEMS = {"one-mass": one_mass, "chain-actuators": chain_actuators, "2dof": two_dof}


def noise_sd(profile: str, H0: np.ndarray) -> np.ndarray:
    s = H0.shape[0]
    if profile == "step":
        return np.where(np.arange(s) < s // 2, 1e-3, 3e-2)[:, None, None] * np.abs(H0)
    if profile == "ramp":
        return np.geomspace(1e-3, 3e-2, s)[:, None, None] * np.abs(H0)
    return np.full(H0.shape, 1e-2 * float(np.mean(np.abs(H0))))


def run_case(problem: str, method: str, profile: str, records: int, seed: int) -> dict:
    model, truth, w = PROBLEMS[problem]()
    H0 = np.asarray(si.simulate_frf(model, truth, w).H)
    sd = noise_sd(profile, H0)
    x0 = truth * np.array([0.5, 2.0, 2.5, 0.4, 0.6, 1.8]) if problem == "2dof" else None
    rng = np.random.default_rng(seed)
    err: dict[str, list] = {"weighted": [], "equal": []}
    ok = {"weighted": 0, "equal": 0}
    times: list[float] = []
    se_ratio = None
    for _ in range(records):
        e = sd * (rng.standard_normal(H0.shape) + 1j * rng.standard_normal(H0.shape)) / np.sqrt(2)
        frf = si.FrequencyData(w, H0 + e, variance=sd**2)
        for key, var in (("weighted", "data"), ("equal", None)):
            t0 = time.perf_counter()
            if method == "ls":
                est = LinearFRF(model, frf, variance=var)
                out = est.run()
            else:
                est = ScrFRF(model, frf, variance=var)
                out = est.run_polished(x0, est.polisher()) if method == "scr+polish" else est.run(x0)
            times.append(time.perf_counter() - t0)
            ok[key] += bool(out.success)
            err[key].append(out.theta / truth - 1)
            if method == "ls" and key == "weighted":
                last = (est, out.theta)
    mse = {k: float(np.mean(np.sum(np.square(v), axis=1))) for k, v in err.items()}
    if method == "ls":
        est, theta = last
        se = est.uncertainty(theta, model.parameter_names).standard_errors / np.abs(truth)
        se_ratio = (se / np.sqrt(np.mean(np.square(err["weighted"]), axis=0))).tolist()
    return {"problem": problem, "method": method, "profile": profile, "records": records, "seed": seed,
            "mse_weighted": mse["weighted"], "mse_equal": mse["equal"], "ratio": mse["weighted"] / mse["equal"],
            "successes_weighted": ok["weighted"], "successes_equal": ok["equal"],
            "median_seconds": float(np.median(times)), "se_over_rms": se_ratio}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=50, help="records per ls and scr+polish case")
    parser.add_argument("--scr-records", type=int, default=20, help="records per SCR-alone case (~3 s a run)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only", choices=["ls", "scr"], default=None)
    parser.add_argument("--out", default=str(RESULTS / "frf_weighting.json"))
    args = parser.parse_args(argv)
    cases = []
    if args.only in (None, "ls"):
        cases += [("one-mass", "ls", p, args.records) for p in ("step", "ramp", "abs")]
        cases += [("chain-actuators", "ls", p, args.records) for p in ("step", "ramp", "abs")]
    if args.only in (None, "scr"):
        cases += [("2dof", "scr+polish", p, args.records) for p in ("step", "ramp", "abs")]
        cases += [("2dof", "scr", p, args.scr_records) for p in ("step", "ramp", "abs")]
    header = (f"{'problem':16} {'method':11} {'profile':7} {'records':>7} {'MSE weighted':>12} {'MSE equal':>10} "
              f"{'ratio':>7} {'ok w/eq':>8} {'s/run':>6}  se/rms (ls)")
    print(header)
    rows = []
    for problem, method, profile, n in cases:
        r = run_case(problem, method, profile, n, args.seed)
        rows.append(r)
        se = "" if r["se_over_rms"] is None else " ".join(f"{v:.2f}" for v in r["se_over_rms"])
        print(f"{problem:16} {method:11} {profile:7} {n:7d} {r['mse_weighted']:12.3e} {r['mse_equal']:10.3e} "
              f"{r['ratio']:7.3f} {r['successes_weighted']:3d}/{r['successes_equal']:<4d} "
              f"{r['median_seconds']:6.3f}  {se}", flush=True)
    code = git_commit()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"code": code, "records": args.records, "scr_records": args.scr_records,
                               "seed": args.seed, "rows": rows}, indent=1) + "\n")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
