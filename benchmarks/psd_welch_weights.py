"""Output spectra from Welch averages: equal weights against weights by each entry's scatter.

A 3-storey footbridge (a new user's: ground–k1,c1–m1–k2,c2–m2–k3,c3–m3, SI units, modes
at 1.96, 5.27 and 8.28 Hz with ζ 0.9–3.8 %), white forces of intensity 1e4 N²s on every
floor, three accelerometers; each record simulated here, independently of symid (exact
zero-order-hold discretisation at 1 kHz, anti-alias decimation to 100 Hz, 20 min, sensor
noise a fraction of each output's standard deviation), then
``si.estimate_spectra(y, dt=0.01, Phi_uu=1e4·I, band=1–12 Hz)`` (segments of 8192 samples,
about 28 averages, 902 lines). Per record:

- ``none``: IPOPT on (5-13) with equal weights started at the truth (where ``auto`` with
  ``weighting="none"`` ends when it finds the least-squares estimate);
- ``variance``: ``si.identify(model, spectra, x0=...)``, the default ``auto``, which weighs
  each entry by its scatter (``symid.fit.spectra.welch``) and fits a white sensor noise on
  each output beside the model, from a start within a factor 3 of the truth;
- ``no noise fit``: the same with ``sensor_noise=False`` (one pass: ``restarts=0, scr=False``).

Per parameter: mean and standard deviation of the relative error (%), and for ``auto`` how
often its 95 % interval holds the truth; the success count and median time. Two
sensor-noise levels: 3 % (the user's) and 30 % of each output's standard deviation (noise
well above the spectra's level far from the modes).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/psd_welch_weights.py        # about 10 minutes

Prints a table and writes ``benchmarks/results/psd_welch_weights.json``.
"""

from __future__ import annotations

import json
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.signal

import symid as si
from symid.fit.spectra.ipopt import IpoptPSD

RESULTS = Path(__file__).resolve().parent / "results"
RECORDS = 8
NAMES = ("m1", "m2", "m3", "c1", "c2", "c3", "k1", "k2", "k3")
TRUTH = {"m1": 4000.0, "m2": 3000.0, "m3": 5000.0, "c1": 8e3, "c2": 5e3, "c3": 3e3,
         "k1": 4.5e6, "k2": 3.0e6, "k3": 2.0e6}
PHI = 1.0e4  # two-sided force intensity of each floor's white force, N²s


def bridge() -> si.SecondOrderModel:
    m1, m2, m3, c1, c2, c3, k1, k2, k3 = si.parameters(" ".join(NAMES), positive=True)
    return si.SecondOrderModel(
        M=[[m1, 0, 0], [0, m2, 0], [0, 0, m3]],
        V=[[c1 + c2, -c2, 0], [-c2, c2 + c3, -c3], [0, -c3, c3]],
        K=[[k1 + k2, -k2, 0], [-k2, k2 + k3, -k3], [0, -k3, k3]],
        B=np.eye(3), C=np.eye(3), output="acceleration")


def _matrices(t: dict[str, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    c1, c2, c3, k1, k2, k3 = (t[n] for n in ("c1", "c2", "c3", "k1", "k2", "k3"))
    V = np.array([[c1 + c2, -c2, 0], [-c2, c2 + c3, -c3], [0, -c3, c3]])
    K = np.array([[k1 + k2, -k2, 0], [-k2, k2 + k3, -k3], [0, -k3, k3]])
    return np.diag([t["m1"], t["m2"], t["m3"]]), V, K


def simulate(seed: int, sensor_noise: float, duration: float = 1200.0, fs: float = 100.0, oversample: int = 10,
             burn: float = 30.0) -> np.ndarray:
    """Floor accelerations (N, 3) at ``fs``: exact ZOH at ``oversample``·fs, modal recursion, FIR decimation."""
    M, V, K = _matrices(TRUTH)
    n = 3
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ V]])
    Bf = np.vstack([np.zeros((n, n)), Minv])
    dtf = 1.0 / (fs * oversample)
    N = round((duration + burn) * fs * oversample)
    rng = np.random.default_rng(seed)
    F = rng.standard_normal((N, n)) * np.sqrt(PHI / dtf)
    big = np.zeros((3 * n, 3 * n))
    big[:2 * n, :2 * n], big[:2 * n, 2 * n:] = A, Bf
    E = scipy.linalg.expm(big * dtf)
    Ad, Bd = E[:2 * n, :2 * n], E[:2 * n, 2 * n:]
    lam, T = np.linalg.eig(Ad)
    G = F @ (np.linalg.inv(T) @ Bd).T
    Z = np.empty_like(G, dtype=complex)
    for j in range(2 * n):
        Z[:, j] = scipy.signal.lfilter([0.0, 1.0], [1.0, -lam[j]], G[:, j])
    X = (Z @ T.T).real
    acc = (F - X[:, :n] @ K.T - X[:, n:] @ V.T) @ Minv.T
    y = scipy.signal.decimate(acc, oversample, ftype="fir", axis=0, zero_phase=True)[int(burn * fs):]
    return y + sensor_noise * y.std(axis=0) * rng.standard_normal(y.shape)


def run(sensor_noise: float) -> dict:
    model = bridge()
    truth = np.array([TRUTH[n] for n in NAMES])
    rows: dict[str, dict[str, list]] = {k: {"err": [], "cover": [], "success": [], "seconds": []}
                                        for k in ("none", "variance", "no noise fit")}
    for seed in range(1, RECORDS + 1):
        y = simulate(seed, sensor_noise)
        spec = si.estimate_spectra(y, dt=0.01, Phi_uu=PHI * np.eye(3), band=(2 * np.pi * 1.0, 2 * np.pi * 12.0))
        t0 = time.perf_counter()
        out = IpoptPSD(model, spec, scale=truth).run(truth)
        rows["none"]["err"].append((out.theta / truth - 1).tolist())
        rows["none"]["success"].append(bool(out.success))
        rows["none"]["seconds"].append(time.perf_counter() - t0)
        x0 = truth * np.exp(np.random.default_rng(100 + seed).uniform(-np.log(3), np.log(3), truth.size))
        # without the noise fit one pass, no restarts or SCR: the estimate, not the rescue of a failure (300 s each)
        for label, options in (("variance", {}), ("no noise fit", {"sensor_noise": False, "restarts": 0,
                                                                    "scr": False})):
            t0 = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = si.identify(model, spec, x0=x0, identifiability_check=False, progress=False, **options)
            rows[label]["seconds"].append(time.perf_counter() - t0)
            rows[label]["err"].append((res.theta_vector / truth - 1).tolist())
            rows[label]["success"].append(bool(res.success))
            lo, hi = np.asarray(res.uncertainty.intervals).T if res.uncertainty is not None else (truth, truth)
            rows[label]["cover"].append(((lo <= truth) & (truth <= hi)).tolist())
            err = np.round(100 * np.array(rows[label]["err"][-1]), 1)
            print(f"  noise {sensor_noise:g} record {seed} {label}: {err} success {res.success}", flush=True)
        print(f"  noise {sensor_noise:g} record {seed} none: {np.round(100 * np.array(rows['none']['err'][-1]), 1)}",
              flush=True)
    summary = {}
    for label, r in rows.items():
        err = 100 * np.array(r["err"])
        summary[label] = {"mean_pct": err.mean(0).tolist(), "sd_pct": err.std(0, ddof=1).tolist(),
                          "success": int(sum(r["success"])), "records": RECORDS,
                          "median_s": float(np.median(r["seconds"]))}
        if r["cover"]:
            summary[label]["coverage"] = np.mean(np.array(r["cover"]), axis=0).tolist()
    return summary


def main() -> int:
    result = {}
    for noise in (0.03, 0.30):
        result[f"{noise:g}"] = run(noise)
    print(f"\n{'sensor noise':>12} {'weights':>9} {'':>6} " + " ".join(f"{n:>6}" for n in NAMES)
          + "  success  median s")
    for noise, per in result.items():
        for label, s in per.items():
            print(f"{noise:>12} {label:>9} {'mean':>6} " + " ".join(f"{v:6.1f}" for v in s["mean_pct"])
                  + f"  {s['success']}/{s['records']}  {s['median_s']:8.1f}")
            print(f"{'':>12} {'':>9} {'sd':>6} " + " ".join(f"{v:6.1f}" for v in s["sd_pct"]))
            if "coverage" in s:
                print(f"{'':>12} {'':>9} {'cover':>6} " + " ".join(f"{v:6.2f}" for v in s["coverage"]))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "psd_welch_weights.json").write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
