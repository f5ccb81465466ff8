"""IPOPT's set-up on a population of generated FRF problems: does it stay on a good fit, and does it still find one?

IPOPT's log barrier on the bounds θ ≥ 0 starts at μ₀ = 0.1. Against a relative misfit
of 1e-2 (a good fit of noisy or real data), it dominates: on the F-16 ground vibration
test (24 parameters, lightly damped modes) IPOPT started at a converged fit walked from
misfit 0.0102 to 0.034. :class:`symid.engine.ipopt.ScaledIpopt` scales θ by the start's
own magnitudes and the objective by its start's decade. This study compares set-ups of
the same nonlinear least squares (the relative FRF misfit of
:func:`symid.fit.frf.ipopt.frf_objective`) from the same starts:

- ``legacy``: IPOPT on θ and on the misfit as it is (symid before the change);
- ``objective``: the objective divided by its start's decade only;
- ``scaled``: θ / |θ₀| and the objective by its decade;
- ``scaled-mu1e-4``: as ``scaled`` with IPOPT's ``mu_init`` = 1e-4;
- ``scaled-adaptive``, ``scaled-gradmu``, ``x-gradmu``, ``obj-gradmu``: IPOPT's adaptive
  barrier; μ₀ from the start's gradient (``barrier_from_start``), with both scalings or one;
- ``scaled-gradmu-best``: ``scaled-gradmu``, and when IPOPT ends above the best objective
  its iterates reached, IPOPT again from that iterate with μ₀ = 1e-9 (``from_best``;
  ``IpoptFRF``'s default). Every other variant has ``from_best=False``.

Problems: ``benchmarks/population_models.py`` (chains, chains with two sensors, gains in B
and C, state-space networks, compartment models; values in physical units), generated
without the identifiability check (``check=False``; every set-up gets the same problems,
so a problem no data could settle counts against all alike), noise-free and with 1 %
relative noise. Starts per problem: ``--starts`` informed (within a factor 3 of the
truth), uninformed (log-uniform over two decades around the typical values) and
``normal`` (symid's default N(0, 1) draws, positive parameters in absolute value).

Reference: the lowest misfit reached from the truth by any set-up (or unbounded).
Success: the estimate is within max(2 × the reference's parameter error, 1e-3) of the
truth (largest relative error over the parameters), or its misfit is within 0.1 % of the
reference's (another solution of the same fit). Stay: started at the reference estimate,
the estimate moves by at most 1e-4 (relative, per parameter) — the property the change
is for. ``--f16`` adds the F-16 case (the committed subset ``examples/data/f16_subset.npz``)
when it is there.

Run::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/ipopt_barrier.py [--problems 3] [--starts 3]

Prints a table per class and overall, writes ``benchmarks/results/ipopt_barrier.json``;
runs are logged to ``benchmarks/results/ipopt_barrier.jsonl`` as they end (resumable,
Ctrl-C keeps them).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
from _study import RESULTS, add_log_arguments, logged, run_study  # benchmarks/_study.py (the script's folder)

import symid as si
from symid.engine.ipopt import IPOPT_SUCCESS, ScaledIpopt, positivity_bounds
from symid.fit.frf.ipopt import frf_objective
from symid.fit.frf.misfit import relative_misfit
from symid.fit.starts import make_starts

_OFF = {"from_best": False}  # the set-ups as they were measured: IPOPT's own end point, whatever its iterates saw
VARIANTS: dict[str, dict[str, Any]] = {
    "legacy": {"start_scaling": False, "objective_scaling": False, "barrier_from_start": False, **_OFF},
    "objective": {"start_scaling": False, "objective_scaling": True, "barrier_from_start": False, **_OFF},
    "scaled": {"start_scaling": True, "objective_scaling": True, "barrier_from_start": False, **_OFF},
    "scaled-mu1e-4": {"start_scaling": True, "objective_scaling": True, "barrier_from_start": False,
                      "ipopt_options": {"mu_init": 1e-4}, **_OFF},
    "scaled-adaptive": {"start_scaling": True, "objective_scaling": True, "barrier_from_start": False,
                        "ipopt_options": {"mu_strategy": "adaptive"}, **_OFF},
    "scaled-gradmu": {"start_scaling": True, "objective_scaling": True, "barrier_from_start": True, **_OFF},
    "x-gradmu": {"start_scaling": True, "objective_scaling": False, "barrier_from_start": True, **_OFF},
    "obj-gradmu": {"start_scaling": False, "objective_scaling": True, "barrier_from_start": True, **_OFF},
    # symid's default: scaled-gradmu, and again from the best iterate when IPOPT ends above it
    "scaled-gradmu-best": {"start_scaling": True, "objective_scaling": True, "barrier_from_start": True},
}
SIZES = {"chain": (2, 3, 4), "chain_sensors": (2, 3), "gains": (2, 3), "state_space": (2, 3),
         "compartment": (2, 3)}
NOISES = (0.0, 0.01)
KINDS = ("informed", "uninformed", "normal")
MAX_ITER = 3000
TIME_LIMIT = 10.0


def _error(theta: np.ndarray, truth: np.ndarray) -> float:
    return float(np.max(np.abs(np.asarray(theta) - truth) / np.abs(truth)))


def _solvers(model: Any, data: Any, variants: list[str], bounded: bool = True) -> dict[str, ScaledIpopt]:
    l = model.n_parameters
    theta = ca.MX.sym("theta", l)
    f = frf_objective(model, data, theta)
    lower, upper = positivity_bounds(model.positive, bounded, np.ones(l))
    return {v: ScaledIpopt("bench_" + "".join(ch if ch.isalnum() else "x" for ch in v), theta, f, lower=lower,
                           upper=upper, max_iter=MAX_ITER, tol=1e-12, hessian="exact", time_limit=TIME_LIMIT,
                           **VARIANTS[v]) for v in variants}


def _cost(rec: dict[str, Any]) -> float:
    """A logged misfit (a non-finite one is logged as null)."""
    c = rec.get("cost")
    return float("inf") if c is None or not np.isfinite(c) else float(c)


def _record(model: Any, data: Any, run: Any, truth: np.ndarray) -> dict[str, Any]:
    theta = np.asarray(run.z, dtype=float)
    return {"theta": theta.tolist(), "cost": relative_misfit(model, data, theta), "status": run.status,
            "iterations": run.iterations, "seconds": run.seconds, "error": _error(theta, truth)}


def _case(log: Any, key: str, model: Any, data: Any, truth: np.ndarray, starts: dict[str, np.ndarray],
          variants: list[str]) -> dict[str, Any]:
    """Every set-up from the truth, the reference, every start, and the stay test."""
    solvers: dict[str, ScaledIpopt] = {}

    def get(v: str) -> ScaledIpopt:
        if not solvers:
            solvers.update(_solvers(model, data, variants))
        return solvers[v]

    def unbounded() -> dict[str, Any]:
        s = _solvers(model, data, ["legacy"], bounded=False)["legacy"]
        return _record(model, data, s.solve(truth), truth)

    from_truth = {v: logged(log, f"{key}/truth/{v}", lambda v=v: _record(model, data, get(v).solve(truth), truth))
                  for v in variants}
    free = logged(log, f"{key}/truth/unbounded", unbounded)
    candidates = dict(from_truth)
    if np.all(np.asarray(free["theta"])[np.asarray(model.positive, bool)] >= 0):
        candidates["unbounded"] = free  # admissible: the bounds are not active at the unbounded optimum
    best = min(candidates, key=lambda v: _cost(candidates[v]))
    ref = candidates[best]
    ref_theta = np.asarray(ref["theta"])
    out: dict[str, Any] = {"reference": {"cost": ref["cost"], "error": ref["error"], "status": ref["status"],
                                         "from": best}, "variants": {}}
    for v in variants:
        stay = logged(log, f"{key}/stay/{v}", lambda v=v: _record(model, data, get(v).solve(ref_theta), truth))
        moved = float(np.max(np.abs(np.asarray(stay["theta"]) - ref_theta) / np.fmax(np.abs(ref_theta), 1e-300)))
        runs = {}
        for kind, xs in starts.items():
            for i, x in enumerate(xs):
                r = logged(log, f"{key}/{kind}{i}/{v}", lambda v=v, x=x: _record(model, data, get(v).solve(x), truth))
                err = np.inf if r["error"] is None else r["error"]
                r["success"] = bool(err <= max(2 * ref["error"], 1e-3) or _cost(r) <= _cost(ref) * (1 + 1e-3) + 1e-14)
                runs[f"{kind}{i}"] = {k: r[k] for k in ("cost", "error", "status", "iterations", "seconds", "success")}
        out["variants"][v] = {"stay": {"moved": moved, "cost": stay["cost"], "iterations": stay["iterations"],
                                       "status": stay["status"], "seconds": stay["seconds"],
                                       "kept": bool(_cost(stay) <= _cost(ref) * (1 + 1e-6) + 1e-14)},
                              "runs": runs}
    return out


def _section(cls: str, problems: int, n_starts: int, variants: list[str]) -> Any:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import population_models as pm

    def run(log: Any) -> dict[str, Any]:
        cases = {}
        for n in SIZES[cls]:
            for idx in range(problems):
                prob = pm.make_problem(cls, n, idx, check=False)
                for noise in NOISES:
                    data = prob.data(noise=noise, seed=idx)
                    starts = {"informed": prob.starts("informed", n_starts),
                              "uninformed": prob.starts("uninformed", n_starts),
                              "normal": np.array(make_starts(prob.model, n_starts, seed=idx))}
                    key = f"{prob.name}/noise{noise:g}"
                    t0 = time.perf_counter()
                    cases[key] = _case(log, key, prob.model, data, prob.truth, starts, variants)
                    print(f"  {key}: {time.perf_counter() - t0:.1f} s", flush=True)
        return {"cases": cases}

    return run


def _f16_section(variants: list[str]) -> Any:
    def run(log: Any) -> dict[str, Any]:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
        import f16_gvt as f16

        frf = f16.read_subset()["frf"]
        model = f16.modal_model()
        # the converged fit: IPOPT without bounds from a start by peak picking and residue least squares
        rec = logged(log, "optimum", lambda: _f16_optimum(model, frf))
        opt = np.asarray(rec["theta"])
        out = {"optimum_cost": rec["cost"], "variants": {}}
        for v in variants:
            r = logged(log, f"stay/{v}", lambda v=v: _record(model, frf, _solvers(model, frf, [v])[v].solve(opt),
                                                              opt))
            out["variants"][v] = {"cost": r["cost"], "moved": r["error"], "iterations": r["iterations"],
                                  "seconds": r["seconds"], "status": r["status"]}
        return out

    return run


def _f16_optimum(model: Any, frf: Any) -> dict[str, Any]:
    from scipy.signal import find_peaks

    w, H = np.asarray(frf.w), np.asarray(frf.H)[:, 0, 0]
    pk, _ = find_peaks(np.abs(H), distance=5)
    pk = pk[np.argsort(np.abs(H)[pk])[::-1][:6]]
    wn = np.concatenate([[0.5 * w[0]], np.sort(w[pk]), [1.5 * w[-1]]])
    k = wn**2
    v = 2 * 0.02 * wn
    v[[0, -1]] = wn[[0, -1]]
    A = np.column_stack([-(w**2) / (k[r] - w**2 + 1j * w * v[r]) for r in range(wn.size)])
    b = np.linalg.lstsq(np.vstack([A.real, A.imag]), np.concatenate([H.real, H.imag]), rcond=None)[0]
    x0 = np.concatenate([b, v, k])
    run = _solvers(model, frf, ["legacy"], bounded=False)["legacy"].solve(x0)
    return _record(model, frf, run, np.where(x0 != 0, x0, 1.0))


def _table(doc: dict[str, Any], variants: list[str]) -> str:
    """Per class, noise level and set-up: the fit kept from a converged reference (of the cases whose reference
    converged), successes per kind of start, median seconds and iterations per start."""
    head = (f"{'class':14s} {'noise':>5s} {'set-up':14s} {'kept':>6s} " + " ".join(f"{k:>10s}" for k in KINDS)
            + f" {'all':>10s} {'median s':>8s} {'median it':>9s}")
    lines = [head]
    totals: dict[str, dict[str, list[int]]] = {v: {k: [0, 0] for k in ("kept", *KINDS, "all")} for v in variants}
    per_noise: dict[tuple[str, float], list[int]] = {}
    for cls in SIZES:
        if cls not in doc:
            continue
        for noise in NOISES:
            cases = [c for k, c in doc[cls]["cases"].items() if k.endswith(f"noise{noise:g}")]
            for v in variants:
                conv = [c for c in cases if c["reference"].get("status") in IPOPT_SUCCESS]
                kept = [c["variants"][v]["stay"]["kept"] for c in conv]
                runs = [(name, r) for c in cases for name, r in c["variants"][v]["runs"].items()]
                cols = []
                for kind in (*KINDS, "all"):
                    ok = [r["success"] for name, r in runs if kind == "all" or name.startswith(kind)]
                    cols.append(f"{sum(ok):>4d}/{len(ok):<5d}")
                    totals[v][kind][0] += sum(ok)
                    totals[v][kind][1] += len(ok)
                    if kind == "all":
                        acc = per_noise.setdefault((v, noise), [0, 0])
                        acc[0] += sum(ok)
                        acc[1] += len(ok)
                totals[v]["kept"][0] += sum(kept)
                totals[v]["kept"][1] += len(kept)
                secs = [r["seconds"] for _, r in runs]
                its = [r["iterations"] for _, r in runs]
                lines.append(f"{cls:14s} {noise:5.2f} {v:14s} {sum(kept):>2d}/{len(kept):<3d} " + " ".join(cols)
                             + f" {np.median(secs) if secs else float('nan'):8.2f}"
                             + f" {np.median(its) if its else float('nan'):9.0f}")
    lines.append("")
    for v in variants:
        t = totals[v]
        parts = ", ".join(f"{k} {t[k][0]}/{t[k][1]}" for k in KINDS)
        noisy = ", ".join(f"noise {n:g}: {per_noise[(v, n)][0]}/{per_noise[(v, n)][1]}" for n in NOISES
                          if (v, n) in per_noise)
        lines.append(f"{v:14s}: kept a converged fit {t['kept'][0]}/{t['kept'][1]}; successes {t['all'][0]}/"
                     f"{t['all'][1]} ({100 * t['all'][0] / max(t['all'][1], 1):.1f} %: {parts}; {noisy})")
    if "f16" in doc:
        lines.append("")
        lines.append(f"F-16 (24 parameters), started at the converged fit (misfit {doc['f16']['optimum_cost']:.4f}):")
        for v, r in doc["f16"]["variants"].items():
            lines.append(f"  {v:14s} misfit {r['cost']:.4f}, moved {r['moved']:.2e}, {r['iterations']} iterations, "
                         f"{r['seconds']:.1f} s, {r['status']}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problems", type=int, default=3, help="problems per class and size (default 3)")
    parser.add_argument("--starts", type=int, default=3, help="starts of each kind per problem (default 3)")
    parser.add_argument("--classes", nargs="*", default=list(SIZES), choices=list(SIZES))
    parser.add_argument("--variants", nargs="*", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--f16", action="store_true", help="add the F-16 stay test (examples/data/f16_subset.npz)")
    parser.add_argument("--out", default=str(RESULTS / "ipopt_barrier.json"))
    add_log_arguments(parser, "ipopt_barrier")
    args = parser.parse_args(argv)
    sections = {cls: _section(cls, args.problems, args.starts, args.variants) for cls in args.classes}
    if args.f16:
        sections["f16"] = _f16_section(args.variants)
    header = {"variants": {v: VARIANTS[v] for v in args.variants}, "problems": args.problems,
              "starts": args.starts, "load_average": list(os.getloadavg()), "casadi": ca.__version__,
              "symid": si.__version__ if hasattr(si, "__version__") else "dev"}
    status = run_study(sections, out=Path(args.out), log_path=Path(args.log), fresh=args.fresh, header=header)
    if status == 0:
        import json

        doc = json.loads(Path(args.out).read_text())
        print(_table(doc, args.variants))
    return status


if __name__ == "__main__":
    raise SystemExit(main())
