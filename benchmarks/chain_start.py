"""How good is the continued-fraction start of ``auto`` on chains driven and measured at one mass?

:func:`symid.fit.frf.chain.chain_start` reads a chain's masses, dampers and springs off its
driving-point response node by node. This measures it on chains drawn by the generator of
``population_models.py`` (this folder; SI ranges, 100 lines from 0.3× the slowest to 3× the
fastest mode), forced to be driven at the grounded end mass, the free end mass or an
interior mass, with a sensor on it (``chain``), a second sensor elsewhere
(``chain_sensors``), or known masses, an unknown actuator gain and a second sensor with an
unknown gain (``gains``; the second gain is not read), with seeds the population
benchmark does not use:

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
        [--sizes 3,5,8] [--draws 6] [--compare 2] [--time-limit 30]

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

from population import parameter_error  # noqa: E402
from population_models import RESOLUTION_FLOOR, _chain, _grid, relative_noise, resolution  # noqa: E402

import symid as si  # noqa: E402
from symid.fit.frf.chain import chain_start  # noqa: E402

SEED = 20261127  # not a seed of population_models.make_problem


WHERE = ("grounded", "free", "interior")
CLASSES = ("chain", "chain_sensors", "gains")


def draw(cls: str, n: int, end: str, index: int) -> tuple[Any, np.ndarray, np.ndarray, dict]:
    """A chain of ``cls`` driven at its grounded end (mass 1), free end (mass n) or an interior mass,
    with the first sensor on the driven mass."""
    rng = np.random.default_rng([SEED, n, index, WHERE.index(end), CLASSES.index(cls)])
    want = {"grounded": (1,), "free": (n,), "interior": tuple(range(2, n))}[end]
    for _ in range(10_000):
        model, truth, typical, info = _chain(rng, n, sensors=1 if cls == "chain" else 2, gains=cls == "gains")
        if info["drive"] in want and info["sensors"][0] == info["drive"]:
            return model, truth, typical, info
    raise RuntimeError("no such draw")  # pragma: no cover


def one(cls: str, n: int, end: str, index: int, args: argparse.Namespace, compare: bool) -> dict[str, Any]:
    model, truth, typical, info = draw(cls, n, end, index)
    w = _grid(model, truth)
    res = resolution(model, truth, w)
    exact = si.simulate_frf(model, truth, w)
    row: dict[str, Any] = {"class": cls, "n": n, "end": end, "index": index, "output": info["output"],
                           "sensors": info["sensors"], "resolution": res, "resolved": bool(res >= RESOLUTION_FLOOR)}
    for level in args.noise:
        data = relative_noise(exact, level, index)
        t0 = time.perf_counter()
        st = chain_start(model, data)
        row[f"read_s_{level:g}"] = time.perf_counter() - t0
        if st is None:
            row[f"start_error_{level:g}"] = None
            continue
        # parameters the chain does not hold (a second sensor's gain) stay at the typical value
        theta = np.array([st.values.get(name, typ) for name, typ in zip(model.parameter_names, typical, strict=True)])
        held = np.array([name in st.values for name in model.parameter_names])
        row[f"start_error_{level:g}"] = (parameter_error(theta[held], truth[held])
                                         if np.all(np.isfinite(theta)) else None)
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
    """Per size and driven mass: counts over the draws whose grid resolves the tolerance (and over all draws)."""
    out = []
    for n in args.sizes:
        for end in WHERE:
            every = [r for r in rows if r["n"] == n and r["end"] == end]
            sel = [r for r in every if r["resolved"]]
            if not every:
                continue
            s: dict[str, Any] = {"n": n, "driven": end, "draws": len(every), "resolved": len(sel)}
            for level in args.noise:
                ok = [r[f"start_error_{level:g}"] for r in sel if r[f"start_error_{level:g}"] is not None]
                s[f"read_{level:g}"] = len(ok)
                s[f"within_1e-3_{level:g}"] = sum(e <= 1e-3 for e in ok)
                s[f"within_10pct_{level:g}"] = sum(e <= 0.1 for e in ok)
                s[f"median_error_{level:g}"] = float(np.median(ok)) if ok else None
                s[f"read_s_median_{level:g}"] = float(np.median([r[f"read_s_{level:g}"] for r in every]))
            passes = [r for r in sel if "pass_error" in r]
            s["pass_truth"] = sum(r["pass_error"] <= 1e-3 for r in passes)
            s["pass_s_median"] = float(np.median([r["pass_s"] for r in passes])) if passes else None
            cmp_rows = [r for r in sel if "auto_on_error" in r]
            s["compared"] = len(cmp_rows)
            for arm in ("on", "off"):
                s[f"auto_{arm}_truth"] = sum(r[f"auto_{arm}_error"] <= 1e-3 for r in cmp_rows)
                s[f"auto_{arm}_s_total"] = float(sum(r[f"auto_{arm}_s"] for r in cmp_rows))
            out.append(s)
    return out


def table(summ: list[dict[str, Any]], args: argparse.Namespace) -> str:
    """The summary as a Markdown table (counts over the draws whose grid resolves the tolerance)."""
    noisy = next((lv for lv in args.noise if lv > 0), None)
    noisy_head = f"within 10 % at {noisy:g} noise" if noisy is not None else "noisy data not run"
    lines = ["| n | driven mass | draws (resolved) | values within 1e-3 | median error | read s | lm pass from them "
             f"reaches the truth | {noisy_head} | auto with / without: truth, s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for s in summ:
        r = s["resolved"]
        noisy_text = f"{s[f'within_10pct_{noisy:g}']}/{r}" if noisy is not None else "–"
        cmp_text = "–"
        if s["compared"]:
            cmp_text = (f"{s['auto_on_truth']}/{s['compared']}, {s['auto_on_s_total']:.1f} / "
                        f"{s['auto_off_truth']}/{s['compared']}, {s['auto_off_s_total']:.1f}")
        med = s["median_error_0"]
        lines.append(f"| {s['n']} | {s['driven']} | {s['draws']} ({r}) | {s['within_1e-3_0']}/{r} | "
                     f"{'–' if med is None else f'{med:.0e}'} | {s['read_s_median_0']:.2f} | {s['pass_truth']}/{r} | "
                     f"{noisy_text} | {cmp_text} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="3,5,8")
    ap.add_argument("--draws", type=int, default=6, help="draws per class, size and driven mass (default 6)")
    ap.add_argument("--noise", default="0,0.01")
    ap.add_argument("--compare", type=int, default=2,
                    help="draws per class, size and driven mass also run by auto with and without chain_start "
                         "(default 2)")
    ap.add_argument("--time-limit", type=float, default=30.0)
    ap.add_argument("--out", default=str(HERE / "results" / "chain_start.json"))
    args = ap.parse_args(argv)
    args.sizes = [int(v) for v in args.sizes.split(",")]
    args.noise = [float(v) for v in args.noise.split(",")]
    warnings.simplefilter("ignore")
    t_all = time.perf_counter()
    rows = []
    for n in args.sizes:
        for cls in CLASSES:
            for end in WHERE if n > 2 else WHERE[:2]:
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
    print(table(summ, args))
    from _study import git_commit

    result = {"benchmark": "chain_start", "commit": git_commit(), "noise": args.noise,
              "command": "benchmarks/chain_start.py " + " ".join(argv or sys.argv[1:]),
              "python": platform.python_version(), "seconds": time.perf_counter() - t_all,
              "time_limit": args.time_limit, "summary": summ, "rows": rows}
    Path(args.out).write_text(json.dumps(result, indent=1, default=float))
    print(f"\nwrote {args.out} ({result['seconds']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
