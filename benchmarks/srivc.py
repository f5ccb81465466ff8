"""SRIVC against filtered least squares and output error under output noise, over a few systems.

For each system, R records (seeds 0 … R − 1) of N samples are simulated with symid's
exact zero-order-hold simulator from a held random-step input (steps of ``hold_steps``
samples) and white Gaussian output noise of 10 % of the output's rms
(``si.simulate_io(noise=0.1)``). Methods per record:

* ``ls``: least squares on derivatives filtered by (s + λ)ⁿ, λ = 0.1/Δt (SRIVC's default
  start, :meth:`SimplifiedRIVC.least_squares`; the same as ``svf`` without IV steps for a
  model whose states are measured);
* ``srivc``: the SRIVC iteration from there (defaults);
* ``oe``: output error on the samples from the truth (IPOPT), on the first ``oe_records``
  records only (it is the slow one): the efficiency reference.

Reported per system and method, over the parameters: the largest |mean relative error|
(bias) and the largest standard deviation of the relative error across records
(spread), SRIVC's iteration counts, how many records it converged on and how many its
estimate passed the fit test (``success``; 10 % noise sits at that test's 1 % misfit bar when
no noise floor is given, so output error's own estimate fails it as often), SRIVC's misfit
over output error's on the same record (largest and median of cost ratio − 1), and the
median wall time per record.

Run::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/srivc.py [--quick]

Prints a table and writes ``benchmarks/results/srivc.json`` (``--quick``: 5 records, no oe,
``srivc_quick.json``).
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import symid as si
from symid.fit.timeseries.oe import OutputError
from symid.fit.timeseries.srivc import SimplifiedRIVC
from symid.runlog import write_json_atomic

NOISE = 0.1


def _systems() -> list[dict[str, Any]]:
    m, c, k = si.parameters("m c k", positive=True)
    msd = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    a, b = si.parameters("a b", positive=True)
    first = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]])
    a0, a1, a2, b0, b1 = si.parameters("a0 a1 a2 b0 b1")
    third = si.StateSpaceModel(A=[[-a2, 1, 0], [-a1, 0, 1], [-a0, 0, 0]], B=[[0], [b1], [b0]], C=[[1, 0, 0]])
    p0, p1, g = si.parameters("p0 p1 g", positive=True)
    simo = si.StateSpaceModel(A=[[0, 1], [-p0, -p1]], B=[[0], [g]], C=[[1, 0], [0, 1]])
    return [
        {"name": "mass-spring-damper ζ = 0.1", "model": msd, "theta": [2.0, 0.5, 3.0], "dt": 0.05, "hold_steps": 20},
        {"name": "mass-spring-damper ζ = 0.02", "model": msd, "theta": [1.0, 0.2, 25.0], "dt": 0.02,
         "hold_steps": 10},
        {"name": "first order", "model": first, "theta": [0.5, 2.0], "dt": 0.1, "hold_steps": 10},
        {"name": "third order, one zero", "model": third, "theta": [1.0, 3.0, 3.0, 1.0, 0.5], "dt": 0.05,
         "hold_steps": 20},
        {"name": "two outputs (q, q')", "model": simo, "theta": [4.0, 0.8, 2.0], "dt": 0.05, "hold_steps": 20},
    ]


def _stats(thetas: list[np.ndarray], truth: np.ndarray) -> dict[str, float]:
    rel = np.array(thetas) / truth - 1
    return {"bias": float(np.max(np.abs(rel.mean(axis=0)))),
            "spread": float(np.max(rel.std(axis=0, ddof=1))) if len(thetas) > 1 else float("nan")}


def _run_system(spec: dict[str, Any], records: int, samples: int, oe_records: int) -> dict[str, Any]:
    model, truth = spec["model"], np.array(spec["theta"])
    rng_u = np.random.default_rng(1000)
    ls, iv, oe, its, conv, ok, t_iv, t_oe, oe_ok, gap = [], [], [], [], 0, 0, [], [], 0, []
    both = 0
    for seed in range(records):
        steps = rng_u.standard_normal((samples // spec["hold_steps"] + 1, model.n_inputs))
        u = np.repeat(steps, spec["hold_steps"], axis=0)[:samples]
        io = si.simulate_io(model, truth, u, dt=spec["dt"], noise=NOISE, seed=seed)
        est = SimplifiedRIVC(model, io)
        ls.append(est.least_squares()[0])
        t0 = time.perf_counter()
        out = est.run(np.ones(model.n_parameters))
        t_iv.append(time.perf_counter() - t0)
        iv.append(out.theta)
        its.append(out.iterations)
        conv += out.status == "converged"
        ok += bool(out.success)
        if seed < oe_records:
            t0 = time.perf_counter()
            ref = OutputError(model, io).run(truth)
            t_oe.append(time.perf_counter() - t0)
            oe.append(ref.theta)
            oe_ok += bool(ref.success)
            both += bool(ref.success) == bool(out.success)
            gap.append(out.cost / ref.cost - 1)
    row = {"system": spec["name"], "records": records, "samples": samples, "ls": _stats(ls, truth),
           "srivc": _stats(iv, truth), "srivc_iterations": [int(min(its)), int(np.median(its)), int(max(its))],
           "srivc_converged": conv, "srivc_success": ok, "srivc_s_per_record": float(np.median(t_iv))}
    if oe:
        row["oe"] = {**_stats(oe, truth), "records": len(oe), "s_per_record": float(np.median(t_oe)),
                     "success": oe_ok, "same_verdict_as_srivc": both,
                     "srivc_cost_over_oe_cost_minus_1_max": float(np.max(gap)),
                     "srivc_cost_over_oe_cost_minus_1_median": float(np.median(gap))}
        row["srivc_first_oe_records"] = _stats(iv[:len(oe)], truth)
    return row


def _pct(x: float) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:.2f} %"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5 records per system, no output error")
    parser.add_argument("--records", type=int, default=30)
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--oe-records", type=int, default=10)
    args = parser.parse_args(argv)
    records = 5 if args.quick else args.records
    oe_records = 0 if args.quick else min(args.oe_records, records)
    rows = []
    print(f"| system | ls bias | srivc bias | srivc spread | oe spread ({oe_records} rec.) | srivc spread "
          "(same rec.) | srivc/oe cost − 1 max, median | iterations min/med/max | converged | success srivc, oe | "
          "s/record srivc | s/record oe |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for spec in _systems():
        row = _run_system(spec, records, args.samples, oe_records)
        rows.append(row)
        oe = row.get("oe", {})
        same = row.get("srivc_first_oe_records", {})
        print(f"| {row['system']} | {_pct(row['ls']['bias'])} | {_pct(row['srivc']['bias'])} | "
              f"{_pct(row['srivc']['spread'])} | {_pct(oe.get('spread', float('nan')))} | "
              f"{_pct(same.get('spread', float('nan')))} | "
              f"{oe.get('srivc_cost_over_oe_cost_minus_1_max', float('nan')):.1e}, "
              f"{oe.get('srivc_cost_over_oe_cost_minus_1_median', float('nan')):.1e} | "
              f"{'/'.join(map(str, row['srivc_iterations']))} | "
              f"{row['srivc_converged']}/{records} | {row['srivc_success']}/{records} | "
              f"{oe.get('success', '—')}/{oe.get('records', 0)}, {oe.get('same_verdict_as_srivc', '—')} | "
              f"{row['srivc_s_per_record']:.3f} | {oe.get('s_per_record', float('nan')):.2f} |", flush=True)
    out = Path(__file__).resolve().parent / "results" / ("srivc_quick.json" if args.quick else "srivc.json")
    write_json_atomic(out, {"complete": True, "noise": NOISE, "rows": rows, "python": sys.version.split()[0],
                            "machine": platform.machine(), "numpy": np.__version__})
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
