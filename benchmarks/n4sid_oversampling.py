"""N4SID on records sampled far above the band of interest: default horizon, longer horizon, decimation.

The system: two lightly damped modes, f = 1 Hz (ζ = 2 %) and 3 Hz (ζ = 1 %), one force
input, one displacement output (the sum of the modal coordinates). For each
oversampling ratio r (sample rate fs = r × 3 Hz, the highest mode) and each of three
seeds, a record of 60 periods of the slowest mode is simulated with a zero-order-hold
white-noise input and 1 % output noise (relative to the output's rms). Routes, all
N4SID of order 4 followed by the exact ``si.d2c``:

* ``default``: the raw record, the default horizon (10);
* ``horizon``: the raw record, horizon i with i·dt ≥ a quarter period of the slowest
  mode (at least 10, at most 120, where one run stays under a minute);
* ``decimated``: the record decimated by an integer q to a rate of about 10 × 3 Hz
  (``scipy.signal.decimate``, order-8 Chebyshev, zero phase, on input and output),
  default horizon; ``decimated + i=20``: the same with horizon 20.

Reported per route: the largest relative error of the two natural frequencies and of
the two damping ratios, worst over the seeds ("failed" when N4SID or d2c refuses, or
a mode is missing). The poles do not depend on how the input is held between
samples, so the decimated records (whose input is no longer held) give exact poles;
the zeros, and so the frequency response, carry the hold's phase error of about
ω·dt/2 (0.31 rad at 3 Hz and 30 Hz sampling), which a grey-box fit of the poles does
not see but a frequency-response comparison does.

Run::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/n4sid_oversampling.py [--quick]

Prints a table and writes ``benchmarks/results/n4sid_oversampling.json`` (``--quick``:
two ratios, one seed, ``n4sid_oversampling_quick.json``).
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import scipy.signal

import symid as si
from symid.runlog import write_json_atomic

F_MODES = (1.0, 3.0)
ZETA = (0.02, 0.01)
PERIODS = 60
NOISE = 0.01
TARGET_RATIO = 10
MAX_HORIZON = 120
RATIOS = (10, 30, 100, 300)


def _truth() -> si.BlackBox:
    blocks = []
    for f, z in zip(F_MODES, ZETA, strict=True):
        w = 2 * np.pi * f
        blocks.append(np.array([[0.0, 1.0], [-w * w, -2 * z * w]]))
    A = np.zeros((4, 4))
    A[:2, :2], A[2:, 2:] = blocks
    return si.BlackBox(A, [[0.0], [1.0], [0.0], [1.0]], [[1.0, 0.0, 1.0, 0.0]])


def _modal_errors(bb: si.BlackBox) -> tuple[float, float]:
    """Largest relative error of the natural frequencies and of the damping ratios (nan if a mode is missing)."""
    ev = np.linalg.eigvals(bb.A)
    ev = ev[ev.imag > 0]
    if ev.size != len(F_MODES):
        return float("nan"), float("nan")
    ev = ev[np.argsort(np.abs(ev))]
    f = np.abs(ev) / (2 * np.pi)
    z = -ev.real / np.abs(ev)
    return (float(np.max(np.abs(f - F_MODES) / F_MODES)), float(np.max(np.abs(z - ZETA) / ZETA)))


def _route(io: si.IOData, horizon: int | None) -> dict[str, Any]:
    t0 = time.perf_counter()
    try:
        f_err, z_err = _modal_errors(si.n4sid(io, 4, horizon=horizon, feedthrough=False).to_continuous())
        note = "" if np.isfinite(f_err) else "a mode is missing (a real pole pair instead)"
    except si.DataError as exc:
        f_err, z_err, note = float("nan"), float("nan"), str(exc)[:160]
    return {"f_error": f_err, "zeta_error": z_err, "seconds": time.perf_counter() - t0,
            "horizon": horizon or "default", "samples": io.n_samples, "dt": io.dt, "note": note}


def _record(r: int, seed: int) -> si.IOData:
    fs = r * max(F_MODES)
    dt = 1.0 / fs
    N = int(PERIODS * fs / min(F_MODES))
    rng = np.random.default_rng([seed, r])
    u = rng.standard_normal(N)
    clean = si.simulate_io(_truth(), None, u, dt).y[:, 0]
    return si.IOData(u, clean + NOISE * np.sqrt(np.mean(clean**2)) * rng.standard_normal(N), dt)


def _decimate(io: si.IOData, q: int) -> si.IOData:
    return si.IOData(scipy.signal.decimate(io.u[:, 0], q, ftype="iir", zero_phase=True),
                     scipy.signal.decimate(io.y[:, 0], q, ftype="iir", zero_phase=True), io.dt * q)


ROUTES = ("default", "horizon", "decimated", "decimated + i=20")


def run(ratios: tuple[int, ...], seeds: tuple[int, ...]) -> list[dict[str, Any]]:
    rows = []
    for r in ratios:
        q = max(1, round(r / TARGET_RATIO))
        runs: dict[str, list[dict[str, Any]]] = {k: [] for k in ROUTES}
        for seed in seeds:
            io = _record(r, seed)
            quarter = min(max(math.ceil(0.25 / min(F_MODES) / io.dt), 10), MAX_HORIZON)
            dec = _decimate(io, q) if q > 1 else io
            runs["default"].append(_route(io, None))
            runs["horizon"].append(_route(io, quarter))
            runs["decimated"].append(_route(dec, None))
            runs["decimated + i=20"].append(_route(dec, 20))
        row: dict[str, Any] = {"ratio": r, "fs": r * max(F_MODES), "N": runs["default"][0]["samples"], "q": q,
                               "horizon_i": runs["horizon"][0]["horizon"], "runs": runs}
        for k in ROUTES:
            f = [x["f_error"] for x in runs[k]]
            z = [x["zeta_error"] for x in runs[k]]
            row[k] = {"f_error_worst": float(np.max(f)) if np.all(np.isfinite(f)) else None,
                      "zeta_error_worst": float(np.max(z)) if np.all(np.isfinite(z)) else None,
                      "failed": int(np.sum(~np.isfinite(f)))}
        rows.append(row)
        print(_line(row), flush=True)
    return rows


def _fmt(cell: dict[str, Any]) -> str:
    if cell["f_error_worst"] is None:
        return f"failed {cell['failed']}×"
    return f"{cell['f_error_worst']:.0e} / {cell['zeta_error_worst']:.0e}"


HEADER = (f"{'r':>4} {'N':>6} | {'default':>15} | {'horizon i':>9} {'':>15} | {'q':>3} {'decimated':>15} | "
          f"{'decimated, i=20':>15}\n" + " " * 12 + "(worst relative error of f / of ζ over the seeds)")


def _line(row: dict[str, Any]) -> str:
    return (f"{row['ratio']:>4} {row['N']:>6} | {_fmt(row['default']):>15} | {row['horizon_i']!s:>9} "
            f"{_fmt(row['horizon']):>15} | {row['q']:>3} {_fmt(row['decimated']):>15} | "
            f"{_fmt(row['decimated + i=20']):>15}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two ratios, one seed")
    args = ap.parse_args(argv)
    ratios, seeds = (RATIOS[:2], (0,)) if args.quick else (RATIOS, (0, 1, 2))
    print(HEADER)
    rows = run(ratios, seeds)
    out = Path(__file__).resolve().parent / "results" / (
        "n4sid_oversampling_quick.json" if args.quick else "n4sid_oversampling.json")
    write_json_atomic(out, {"complete": True, "modes_hz": F_MODES, "zeta": ZETA, "periods": PERIODS,
                            "noise": NOISE, "seeds": list(seeds), "rows": rows, "python": sys.version.split()[0],
                            "machine": platform.machine(), "numpy": np.__version__,
                            "scipy": scipy.__version__})
    print(f"written {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
