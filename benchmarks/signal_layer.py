"""Accuracy and speed of the signal layer: ``si.d2c`` with and without balancing, N4SID at N = 50 000.

Two studies in one run (the machine is shared; ratios are measured side by side):

1. **d2c on badly scaled states.** 100 random stable systems, n = 20 states, m = 2
   inputs, dt = 0.05 s; a well-scaled A₀ (standard normal, shifted so that the largest
   real part of an eigenvalue is −0.5) and B₀ are put in a basis with state scales
   T = diag(10^U(−3, 3)): A = T A₀ T⁻¹, B = T B₀. The error of a d2c route is
   ``max |T⁻¹ Â T − A₀| / max |A₀|`` (basis-free: measured in the well-scaled basis).
   Routes: ``si.d2c`` (balances the augmented matrix before ``logm``) and the same
   logarithm without balancing (what ``si.d2c`` did before).
2. **N4SID at N = 50 000.** A random stable 4-state, 2-input, 2-output system with
   feedthrough, white-noise input, dt = 0.05 s, a random initial state, noise-free
   output. Routes: ``si.n4sid`` (vectorised B, D, x0 step), ``si.n4sid`` with the former
   per-sample loop for that step (kept below as the reference), python-control's
   Markov-parameter least squares + eigensystem realisation (``control.markov`` with
   200 Markov parameters, then ``control.eigensys_realization`` on a 99 × 99 block Hankel
   matrix; the slowest mode decays by e^{-3} over 200 samples, so the truncated impulse
   response limits its accuracy), and ``nfoursid``
   (``NFourSID.subspace_identification`` then ``system_identification``; on the first
   10 000 samples only, beside symid on the same, see ``NFOURSID_MAX_N``). The error of
   each is the largest relative error of its discrete-time frequency response against
   the exact zero-order-hold model on 50 frequencies up to 0.8 × Nyquist. Median of 3
   runs for the time.

Run::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/signal_layer.py [--quick]

Prints a table and writes ``benchmarks/results/signal_layer.json`` (``--quick``: 20 systems
and N = 5 000, written to ``signal_layer_quick.json``). The file is not called ``signal.py``:
run as a script, that name would shadow the standard library's ``signal`` module for every
import. python-control and nfoursid are optional
(``pip install control nfoursid``); a route whose package is missing is reported as
``not installed``.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
import warnings
from pathlib import Path
from typing import Any
from unittest import mock

import numpy as np
import scipy.linalg

import symid as si
from symid.runlog import write_json_atomic
from symid.signal import subspace
from symid.signal.simulate import zoh_discretize

MARKOV_COUNT = 200
#: nfoursid builds N × N intermediates (measured: 1.8 GB and 6.9 s at N = 10 000; killed for lack of memory at
#: N = 50 000 on a 23 GB machine), so it runs on the first NFOURSID_MAX_N samples only, beside symid on the same.
NFOURSID_MAX_N = 10000
RESULTS = Path(__file__).resolve().parent / "results"


# -- study 1: d2c ----------------------------------------------------------------------------

def _logm_unbalanced(Ad: np.ndarray, Bd: np.ndarray, dt: float) -> np.ndarray:
    """The former d2c step: ``logm`` of the augmented matrix as it is."""
    n, m = Bd.shape
    big = np.zeros((n + m, n + m))
    big[:n, :n], big[:n, n:], big[n:, n:] = Ad, Bd, np.eye(m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        L = scipy.linalg.logm(big)
    return np.real(L)[:n, :n] / dt


def d2c_study(count: int, seed: int = 0) -> dict[str, Any]:
    rng = np.random.default_rng(seed)
    n, m, dt = 20, 2, 0.05
    err = {"balanced": [], "unbalanced": []}
    secs = {"balanced": 0.0, "unbalanced": 0.0}
    for _ in range(count):
        A0 = rng.standard_normal((n, n))
        A0 -= (np.linalg.eigvals(A0).real.max() + 0.5) * np.eye(n)
        B0 = rng.standard_normal((n, m))
        T = 10.0 ** rng.uniform(-3, 3, n)
        A, B = (T[:, None] * A0) / T[None, :], T[:, None] * B0
        Ad, Bd = zoh_discretize(A, B, dt)
        t = time.perf_counter()
        Ah = si.d2c(Ad, Bd, np.ones((1, n)), None, dt).A
        secs["balanced"] += time.perf_counter() - t
        err["balanced"].append(np.abs((Ah / T[:, None]) * T[None, :] - A0).max() / np.abs(A0).max())
        t = time.perf_counter()
        Ah = _logm_unbalanced(Ad, Bd, dt)
        secs["unbalanced"] += time.perf_counter() - t
        err["unbalanced"].append(np.abs((Ah / T[:, None]) * T[None, :] - A0).max() / np.abs(A0).max())
    out = {}
    for k, e in err.items():
        e = np.asarray(e)
        out[k] = {"max_error": float(e.max()), "median_error": float(np.median(e)),
                  "cases_above_1e-10": int(np.sum(e > 1e-10)), "seconds": secs[k]}
    return {"systems": count, "n": n, "m": m, "dt": dt, "routes": out}


# -- study 2: N4SID ---------------------------------------------------------------------------

def _b_d_x0_loop(io: si.IOData, A: np.ndarray, C: np.ndarray, feedthrough: bool) -> tuple[np.ndarray, ...]:
    """The former per-sample loop of the B, D, x0 least squares (the reference for the vectorised one)."""
    u, y = io.u, io.y
    N, m = u.shape
    p, n = C.shape
    X = np.zeros((m, n, n))
    P = np.eye(n)
    rows_B = np.empty((N, p, m, n))
    rows_x0 = np.empty((N, p, n))
    for k in range(N):
        rows_B[k] = np.einsum("pn,cnr->pcr", C, X)
        rows_x0[k] = C @ P
        X = A @ X + u[k][:, None, None] * np.eye(n)
        P = A @ P
    blocks = [np.transpose(rows_B, (0, 1, 3, 2)).reshape(N * p, n * m)]
    if feedthrough:
        blocks.append(np.einsum("pq,kc->kpqc", np.eye(p), u).reshape(N * p, p * m))
    blocks.append(rows_x0.reshape(N * p, n))
    sol, *_ = np.linalg.lstsq(np.hstack(blocks), y.reshape(-1), rcond=None)
    B = sol[: n * m].reshape(n, m)
    D = sol[n * m: n * m + p * m].reshape(p, m) if feedthrough else np.zeros((p, m))
    return B, D, sol[n * m + (p * m if feedthrough else 0):]


def _dfrf(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, z: np.ndarray) -> np.ndarray:
    n = A.shape[0]
    return np.stack([C @ np.linalg.solve(zi * np.eye(n) - A, B) + D for zi in z])


def _route_symid(io: si.IOData, n: int) -> tuple:
    d = si.n4sid(io, n)
    return d.A, d.B, d.C, d.D


def _route_symid_loop(io: si.IOData, n: int) -> tuple:
    with mock.patch.object(subspace, "_b_d_x0", _b_d_x0_loop):
        d = si.n4sid(io, n)
    return d.A, d.B, d.C, d.D


def _route_control(io: si.IOData, n: int) -> tuple:
    import control

    # MARKOV_COUNT Markov parameters by least squares (the first equations dropped, truncate=True, so that
    # the unknown initial state matters less); ERA's Hankel matrix takes (MARKOV_COUNT − 2) / 2 block rows
    # and columns of them. Longer sequences cost a least squares with MARKOV_COUNT · m unknowns.
    H = control.markov(io.y.T, io.u.T, m=MARKOV_COUNT, transpose=False, truncate=True)
    half = (MARKOV_COUNT - 2) // 2
    sys_, _ = control.eigensys_realization(H, n, m=half, n=half, dt=True)
    return (np.asarray(sys_.A), np.asarray(sys_.B), np.asarray(sys_.C), np.asarray(sys_.D))


def _route_nfoursid(io: si.IOData, n: int) -> tuple:
    import pandas as pd
    from nfoursid.nfoursid import NFourSID

    cols_u = [f"u{j}" for j in range(io.n_inputs)]
    cols_y = [f"y{i}" for i in range(io.n_outputs)]
    frame = pd.DataFrame(np.hstack([io.u, io.y]), columns=cols_u + cols_y)
    model = NFourSID(frame, output_columns=cols_y, input_columns=cols_u, num_block_rows=10)
    model.subspace_identification()
    ss, _ = model.system_identification(rank=n)
    return ss.a, ss.b, ss.c, ss.d


ROUTES = {"symid n4sid (vectorised)": (_route_symid, None, None),
          "symid n4sid (per-sample loop)": (_route_symid_loop, None, None),
          "python-control markov + ERA": (_route_control, "control", None),
          "nfoursid": (_route_nfoursid, "nfoursid", NFOURSID_MAX_N),
          "symid n4sid (vectorised), nfoursid's N": (_route_symid, None, NFOURSID_MAX_N)}


def n4sid_study(N: int, repeats: int, seed: int = 1) -> dict[str, Any]:
    import importlib.util

    rng = np.random.default_rng(seed)
    n, m, p, dt = 4, 2, 2, 0.05
    A0 = rng.standard_normal((n, n))
    A0 -= (np.linalg.eigvals(A0).real.max() + 0.3) * np.eye(n)
    bb = si.BlackBox(A0, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m)))
    io = si.simulate_io(bb, None, rng.standard_normal((N, m)), dt, x0=rng.standard_normal(n))
    Ad, Bd = zoh_discretize(bb.A, bb.B, dt)
    z = np.exp(1j * np.linspace(0.01, 0.8 * np.pi, 50))
    H0 = _dfrf(Ad, Bd, bb.C, bb.D, z)
    out: dict[str, Any] = {}
    for name, (fn, package, max_n) in ROUTES.items():
        if package is not None and importlib.util.find_spec(package) is None:
            out[name] = {"status": "not installed"}
            continue
        if max_n is not None and name.startswith("symid") and "nfoursid" not in out:
            continue
        rec = io if max_n is None or N <= max_n else si.IOData(io.u[:max_n], io.y[:max_n], io.dt)
        times, err = [], float("nan")
        try:
            for _ in range(repeats):
                t = time.perf_counter()
                A, B, C, D = fn(rec, n)
                times.append(time.perf_counter() - t)
            H = _dfrf(np.asarray(A), np.asarray(B), np.asarray(C), np.asarray(D), z)
            err = float(np.abs(H - H0).max() / np.abs(H0).max())
            out[name] = {"status": "ok", "N": rec.n_samples, "seconds": statistics.median(times), "frf_error": err}
        except Exception as exc:  # a foreign package failing is a result, not a crash of the benchmark
            out[name] = {"status": f"failed: {type(exc).__name__}: {exc}"}
        print(f"  {name:32s} {out[name]}", flush=True)
    return {"N": N, "n": n, "m": m, "p": p, "dt": dt, "repeats": repeats, "routes": out}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="20 systems, N = 5 000")
    args = ap.parse_args(argv)
    count, N = (20, 5000) if args.quick else (100, 50000)
    print(f"d2c: {count} random systems, n = 20, states scaled 1e±3 ...", flush=True)
    d2c = d2c_study(count)
    print(f"N4SID: N = {N} ...", flush=True)
    sid = n4sid_study(N, repeats=3)
    print()
    print(f"{'d2c route':28s} {'max error':>10s} {'median':>10s} {'> 1e-10':>8s} {'time [s]':>9s}")
    for name, r in d2c["routes"].items():
        print(f"{name:28s} {r['max_error']:10.2e} {r['median_error']:10.2e} {r['cases_above_1e-10']:8d} "
              f"{r['seconds']:9.3f}")
    print()
    print(f"{'N4SID route':40s} {'N':>6s} {'time [s]':>9s} {'FRF error':>10s}")
    for name, r in sid["routes"].items():
        if r["status"] == "ok":
            print(f"{name:40s} {r['N']:6d} {r['seconds']:9.3f} {r['frf_error']:10.2e}")
        else:
            print(f"{name:40s} {r['status']}")
    loop, vec = sid["routes"]["symid n4sid (per-sample loop)"], sid["routes"]["symid n4sid (vectorised)"]
    speedup = loop["seconds"] / vec["seconds"]
    print(f"\nvectorised N4SID speed-up over the per-sample loop: {speedup:.2f}x")
    summary = {"d2c": d2c, "n4sid": sid, "n4sid_speedup": speedup, "complete": True,
               "machine": {"python": sys.version.split()[0], "platform": platform.platform(),
                           "numpy": np.__version__, "scipy": scipy.__version__, "load": os.getloadavg()}}
    path = RESULTS / ("signal_layer_quick.json" if args.quick else "signal_layer.json")
    write_json_atomic(path, summary)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
