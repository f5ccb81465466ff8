"""How good is the continued-fraction start of ``auto`` on chains driven and measured at one end?

:func:`symid.fit.frf.chain.chain_start` reads a chain's masses, dampers and springs off its
driving-point response node by node. This measures it on chains drawn by the generator of
``population_models.py`` (this folder; SI ranges, 100 lines from 0.3× the slowest to 3× the
fastest mode), forced to be driven at an end mass (the grounded one or the free one) with a
sensor on it (``chain``) and, for ``chain_sensors``, a second sensor elsewhere, with seeds
the population benchmark does not use:

- seconds to read the values, and their largest relative error against the truth,
  noise-free and at 1 % relative noise;
- one pass of ``lm`` started from them (no restarts, ``time_limit`` s): does it reach the
  truth (largest relative error ≤ 1e-3 noise-free);
- side by side (``--compare``, noise-free, one uninformed start per draw drawn as the
  population benchmark draws them): ``auto`` with and without ``chain_start``, the truth
  reached or not and the seconds, on the same start and the same budget.

Draws whose grid does not resolve a 1e-3 error (``population_models.resolution`` below
1e-20) are counted apart: there the data cannot fix the deepest elements to the tolerance.

Run (one BLAS thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/chain_start.py \\
        [--sizes 3,5,8] [--draws 12] [--compare 8] [--time-limit 30]

Writes ``benchmarks/results/chain_start.json`` (``--out``) and prints one line per draw and
a summary table.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from population_models import RESOLUTION_FLOOR, _chain, _grid, resolution  # noqa: E402

import symid as si  # noqa: E402
from symid.fit.frf.chain import chain_start  # noqa: E402

SEED = 20261127  # not a seed of population_models.make_problem


def parameter_error(theta: Any, truth: Any) -> float:
    theta, truth = np.asarray(theta, dtype=float), np.asarray(truth, dtype=float)
    return float(np.max(np.abs(theta - truth) / np.abs(truth)))


def draw(cls: str, n: int, end: str, index: int) -> tuple[Any, np.ndarray, np.ndarray, dict]:
    """A chain of ``cls`` driven at its grounded end (mass 1) or free end (mass n), sensor on the driven mass."""
    which = [("grounded", "free").index(end), ("chain", "chain_sensors").index(cls)]
    rng = np.random.default_rng([SEED, n, index, *which])
    want = 1 if end == "grounded" else n
    for _ in range(10_000):
        model, truth, typical, info = _chain(rng, n, sensors=1 if cls == "chain" else 2, gains=False)
        if info["drive"] == want and info["sensors"][0] == want:
            return model, truth, typical, info
    raise RuntimeError("no such draw")  # pragma: no cover


def noisy(frf: Any, level: float, seed: int) -> Any:
    if level == 0:
        return frf
    rng = np.random.default_rng([seed, 7919])
    H = np.asarray(frf.H)
    e = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    return si.FrequencyData(frf.w, H * (1 + level * e))


def one(cls: str, n: int, end: str, index: int, args: argparse.Namespace, compare: bool) -> dict[str, Any]:
    model, truth, typical, info = draw(cls, n, end, index)
    w = _grid(model, truth)
    res = resolution(model, truth, w)
    exact = si.simulate_frf(model, truth, w)
    row: dict[str, Any] = {"class": cls, "n": n, "end": end, "index": index, "output": info["output"],
                           "sensors": info["sensors"], "resolution": res, "resolved": bool(res >= RESOLUTION_FLOOR)}
    for level in args.noise:
        data = noisy(exact, level, index)
        t0 = time.perf_counter()
        st = chain_start(model, data)
        row[f"read_s_{level:g}"] = time.perf_counter() - t0
        if st is None:
            row[f"start_error_{level:g}"] = None
            continue
        theta = np.array([st.values[name] for name in model.parameter_names])
        row[f"start_error_{level:g}"] = parameter_error(theta, truth) if np.all(np.isfinite(theta)) else None
        if level == 0:
            x0 = np.where(theta > 0, theta, typical)
            t0 = time.perf_counter()
            r = si.identify(model, data, method="lm", x0=x0, scale=typical, identifiability_check=False,
                            time_limit=args.time_limit)
            row["pass_s"] = time.perf_counter() - t0
            row["pass_error"] = parameter_error(r.theta_vector, truth)
    if compare:
        rng = np.random.default_rng([SEED, n, index, 104729])
        x0 = typical * 10.0 ** rng.uniform(-1.0, 1.0, truth.size)  # as population_models.Problem.starts
        for flag in (True, False):
            t0 = time.perf_counter()
            r = si.identify(model, exact, method="auto", x0=x0, scale=typical, identifiability_check=False,
                            time_limit=args.time_limit, chain_start=flag)
            row[f"auto_{'on' if flag else 'off'}_s"] = time.perf_counter() - t0
            row[f"auto_{'on' if flag else 'off'}_error"] = parameter_error(r.theta_vector, truth)
    return row


def summary(rows: list[dict[str, Any]], args: argparse.Namespace) -> list[dict[str, Any]]:
    out = []
    for n in args.sizes:
        for resolved in (True, False):
            sel = [r for r in rows if r["n"] == n and r["resolved"] == resolved]
            if not sel:
                continue
            s: dict[str, Any] = {"n": n, "resolved": resolved, "draws": len(sel)}
            for level in args.noise:
                errs = [r[f"start_error_{level:g}"] for r in sel]
                ok = [e for e in errs if e is not None]
                s[f"read_{level:g}"] = len(ok)
                s[f"within_1e-3_{level:g}"] = sum(e <= 1e-3 for e in ok)
                s[f"within_10pct_{level:g}"] = sum(e <= 0.1 for e in ok)
                s[f"median_error_{level:g}"] = float(np.median(ok)) if ok else None
                s[f"read_s_median_{level:g}"] = float(np.median([r[f"read_s_{level:g}"] for r in sel]))
            passes = [r for r in sel if "pass_error" in r]
            s["pass_truth"] = sum(r["pass_error"] <= 1e-3 for r in passes)
            s["pass_s_median"] = float(np.median([r["pass_s"] for r in passes])) if passes else None
            cmp_rows = [r for r in sel if "auto_on_error" in r]
            if cmp_rows:
                s["compared"] = len(cmp_rows)
                for arm in ("on", "off"):
                    s[f"auto_{arm}_truth"] = sum(r[f"auto_{arm}_error"] <= 1e-3 for r in cmp_rows)
                    s[f"auto_{arm}_s_total"] = float(sum(r[f"auto_{arm}_s"] for r in cmp_rows))
            out.append(s)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="3,5,8")
    ap.add_argument("--draws", type=int, default=12, help="draws per class, size and end (default 12)")
    ap.add_argument("--noise", default="0,0.01")
    ap.add_argument("--compare", type=int, default=4,
                    help="draws per class, size and end also run by auto with and without chain_start (default 4)")
    ap.add_argument("--time-limit", type=float, default=30.0)
    ap.add_argument("--out", default=str(HERE / "results" / "chain_start.json"))
    args = ap.parse_args(argv)
    args.sizes = [int(v) for v in args.sizes.split(",")]
    args.noise = [float(v) for v in args.noise.split(",")]
    warnings.simplefilter("ignore")
    t_all = time.perf_counter()
    rows = []
    for n in args.sizes:
        for cls in ("chain", "chain_sensors"):
            for end in ("grounded", "free"):
                for index in range(args.draws):
                    row = one(cls, n, end, index, args, compare=index < args.compare)
                    rows.append(row)
                    errs = " ".join(f"{lv:g}: {row.get(f'start_error_{lv:g}') or float('nan'):.1e}"
                                    for lv in args.noise)
                    extra = ""
                    if "auto_on_error" in row:
                        extra = (f" | auto on {row['auto_on_error']:.0e} in {row['auto_on_s']:.1f} s, "
                                 f"off {row['auto_off_error']:.0e} in {row['auto_off_s']:.1f} s")
                    print(f"{cls}-n{n} {end:8s} #{index:2d} res {row['resolution']:.0e}: start error {errs}; "
                          f"lm pass {row.get('pass_error', float('nan')):.0e}{extra}", flush=True)
    summ = summary(rows, args)
    print()
    print("| n | grid resolves 1e-3 | draws | read (exact) | start within 1e-3 | within 10 % | median error | "
          "lm pass reaches truth | within 10 % at 1 % noise | auto with / without (truth, s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for s in summ:
        cmp_text = "–"
        if "compared" in s:
            cmp_text = (f"{s['auto_on_truth']}/{s['compared']} in {s['auto_on_s_total']:.0f} s / "
                        f"{s['auto_off_truth']}/{s['compared']} in {s['auto_off_s_total']:.0f} s")
        noisy_text = f"{s.get('within_10pct_0.01', '–')}/{s['draws']}" if 0.01 in args.noise else "–"
        print(f"| {s['n']} | {'yes' if s['resolved'] else 'no'} | {s['draws']} | {s['read_0']} | "
              f"{s['within_1e-3_0']} | {s['within_10pct_0']} | {s['median_error_0']:.1e} | {s['pass_truth']} | "
              f"{noisy_text} | {cmp_text} |")
    result = {"benchmark": "chain_start", "command": "benchmarks/chain_start.py " + " ".join(argv or sys.argv[1:]),
              "python": platform.python_version(), "seconds": time.perf_counter() - t_all,
              "time_limit": args.time_limit, "summary": summ, "rows": rows}
    Path(args.out).write_text(json.dumps(result, indent=1, default=float))
    print(f"\nwrote {args.out} ({result['seconds']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
