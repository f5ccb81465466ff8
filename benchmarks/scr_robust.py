"""SCR on frequency responses beyond the thesis's examples: Γ start, noise, problems nobody tuned for.

Sections (``--only`` runs some of them; the others keep their earlier results):

``thesis_aux_init``
    The 2-DOF mass-damper of thesis §4-6-2 (noise-free), ``--seeds`` × ``--starts`` seeded
    N(0, 1) starts (:func:`symid.fit.starts.make_starts`), SCR (ADMM, defaults) with Γᵢ
    started from the model at the start (``aux_init="model"``) or from seeded N(0, 1)
    draws (``"random"``). Success: ‖θ̂ − θ*‖₂/‖θ*‖₂ ≤ 1e-3.
``population_aux_init``
    Generated problems of ``benchmarks/population_models.py`` (chains, chains with two
    sensors, gains, state-space networks, compartment models; sizes ``--sizes``;
    ``--problems`` problems each; physical values), noise-free, from the truth and from
    ``--pop-starts`` informed (within a factor 3 of the truth) and uninformed (two
    decades around the typical values) starts; SCR with ``scale=`` the typical values,
    ``time_limit`` ``--time-limit`` s per start, Γ from the model or random. Success:
    max_k |θ̂_k − θ*_k| / |θ*_k| ≤ 1e-3.
``noise``
    Belt drive (thesis §3-6) with relative noise 1e-4 (seed 1) and with the exact response
    rounded to 6 decimals: SCR's estimate against the term-weighted least-squares
    estimate of its equations computed here with numpy; 2-DOF with 1 % noise, 5 records
    × 5 starts: SCR alone (distance to IPOPT's estimate in IPOPT's standard errors) and
    ``scr+polish`` (relative difference to IPOPT's estimate, trial polishes, time).
``progress``
    CPU time of the same 2-DOF starts with and without a per-iteration ``callback`` (which
    evaluates the data misfit every iteration): the overhead of progress reports.
``time_limit``
    Generated chains of 3 and 5 masses, uninformed starts, both back ends, with a budget
    (``--budget`` s) far below what SCR needs: the longest wall time of a start.

Run (one BLAS thread per process)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/scr_robust.py [--only noise]

Prints a table per section and writes ``benchmarks/results/scr_robust.json`` when every
section is done; runs are logged to ``benchmarks/results/scr_robust.jsonl`` as they end
(resumable after Ctrl-C; ``--fresh`` starts over).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from _study import RESULTS, add_log_arguments, logged, run_study  # benchmarks/_study.py (script folder on the path)

import symid as si
from symid.fit.frf.ipopt import IpoptFRF
from symid.fit.frf.scr import ScrFRF
from symid.fit.starts import make_starts
from symid.runlog import RunLog

SECTIONS = ("thesis_aux_init", "population_aux_init", "noise", "progress", "time_limit")
CLASSES = ("chain", "chain_sensors", "gains", "state_space", "compartment")


def _rel_l2(theta: np.ndarray, truth: np.ndarray) -> float:
    return float(np.linalg.norm(theta - truth) / np.linalg.norm(truth))


def _rel_max(theta: np.ndarray, truth: np.ndarray) -> float:
    return float(np.max(np.abs(theta - truth) / np.abs(truth)))


def _scr_record(est: ScrFRF, x0: np.ndarray, truth: np.ndarray) -> dict[str, Any]:
    t = time.perf_counter()
    out = est.run(x0)
    return {"error_l2": _rel_l2(out.theta, truth), "error_max": _rel_max(out.theta, truth),
            "iterations": out.iterations, "time": time.perf_counter() - t, "status": out.status,
            "success": out.success, "cost": out.cost}


def _rate(rows: list[dict], key: str, tol: float) -> tuple[int, int]:
    return sum(r[key] <= tol for r in rows), len(rows)


# -- sections ----------------------------------------------------------------------------------------

def thesis_aux_init(args: argparse.Namespace, log: RunLog) -> dict:
    entry = si.load_model("mass_damper_2dof")
    model, data = entry.model, entry.data()
    truth = model.theta_vector(entry.truth)  # thesis (4-20)
    out: dict[str, Any] = {}
    for aux in ("model", "random"):
        est = ScrFRF(model, data, aux_init=aux)
        rows = []
        for seed in range(args.seeds):
            for k, x0 in enumerate(make_starts(model, args.starts, seed)):
                rows.append(logged(log, f"{aux}/{seed}/{k}", lambda x0=x0, est=est: _scr_record(est, x0, truth)))
        ok, n = _rate(rows, "error_l2", 1e-3)
        out[aux] = {"success": ok, "starts": n, "median_iterations": float(np.median([r["iterations"] for r in rows])),
                    "median_time": float(np.median([r["time"] for r in rows])), "runs": rows}
        print(f"  Γ {aux:6s}: {ok}/{n} within 1e-3, median {out[aux]['median_iterations']:.0f} SCR iterations, "
              f"{out[aux]['median_time']:.2f} s per start", flush=True)
    return out


def _population():
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from population_models import make_problem  # benchmarks/population_models.py

    return make_problem


def population_aux_init(args: argparse.Namespace, log: RunLog) -> dict:
    make_problem = _population()
    table: dict[str, Any] = {}
    for cls in CLASSES:
        for n in args.sizes:
            for idx in range(args.problems):
                p = make_problem(cls, n, idx, check=False)
                data = p.data()
                starts = {"truth": [p.truth], "informed": list(p.starts("informed", args.pop_starts)),
                          "uninformed": list(p.starts("uninformed", args.pop_starts))}
                for aux in ("model", "random"):
                    est = None
                    for kind, xs in starts.items():
                        for k, x0 in enumerate(xs):
                            key = f"{p.name}/{aux}/{kind}/{k}"
                            if key not in log and est is None:
                                est = ScrFRF(p.model, data, scale=p.typical, aux_init=aux, time_limit=args.time_limit)
                            rec = logged(log, key, lambda x0=x0, est=est, p=p: _scr_record(est, x0, p.truth))
                            cell = table.setdefault(f"{cls}/{aux}/{kind}", [])
                            cell.append({"problem": p.name, **rec})
    summary = {}
    print(f"  {'class':14s} {'Γ start':8s} {'from truth':>11s} {'informed':>10s} {'uninformed':>11s}   median s")
    for cls in CLASSES:
        for aux in ("model", "random"):
            cells = {kind: table[f"{cls}/{aux}/{kind}"] for kind in ("truth", "informed", "uninformed")}
            rates = {kind: _rate(rows, "error_max", 1e-3) for kind, rows in cells.items()}
            med = float(np.median([r["time"] for kind in ("informed", "uninformed") for r in cells[kind]]))
            summary[f"{cls}/{aux}"] = {kind: {"success": a, "starts": b} for kind, (a, b) in rates.items()} | {
                "median_time": med}
            print(f"  {cls:14s} {aux:8s} " + " ".join(f"{a:>5d}/{b:<5d}" for a, b in rates.values())
                  + f"   {med:7.2f}", flush=True)
    totals = {aux: {kind: [sum(summary[f"{c}/{aux}"][kind][x] for c in CLASSES) for x in ("success", "starts")]
                    for kind in ("truth", "informed", "uninformed")} for aux in ("model", "random")}
    for aux, t in totals.items():
        print(f"  {'all':14s} {aux:8s} " + " ".join(f"{a:>5d}/{b:<5d}" for a, b in t.values()))
    return {"summary": summary, "totals": totals, "runs": table}


def _belt_reference(model: Any, data: Any) -> np.ndarray:
    """The estimate the presolve must return on the belt drive, computed here without the engine.

    With C = [0, 1, 0] and the first two rows of A known, (3-10) and Hᵢ = CΓᵢ give
    Γ₂ = Hᵢ, Γ₁ = jωᵢHᵢ/0.2, Γ₃ = (jωᵢΓ₁ + Γ₂)/0.15 exactly; the third row,
    θ₁Γ₁ + θ₂Γ₂ + θ₃Γ₃ + θ₄ = jωᵢΓ₃, is linear in θ: two real equations per frequency,
    each weighted by the size of its terms at the estimate (reweighted to a fixed point).
    """
    w, H = np.asarray(data.w), np.asarray(data.H)[:, 0, 0]
    g2 = H
    g1 = 1j * w * H / 0.2
    g3 = (1j * w * g1 + g2) / 0.15
    rows = np.stack([g1, g2, g3, np.ones_like(g1)], axis=1)
    D = np.vstack([rows.real, rows.imag])
    d = np.concatenate([(1j * w * g3).real, (1j * w * g3).imag])
    x = np.linalg.lstsq(D, d, rcond=None)[0]
    for _ in range(50):
        T = np.sqrt(np.sum((D * x) ** 2, axis=1) + d**2)
        x = np.linalg.lstsq(D / T[:, None], d / T, rcond=None)[0]
    return x


def noise(args: argparse.Namespace, log: RunLog) -> dict:
    out: dict[str, Any] = {}
    belt = si.load_model("belt_drive")
    model, w = belt.model, belt.data().w
    truth = model.theta_vector(belt.truth)  # thesis (3-18)
    records = {"noise 1e-4 (seed 1)": si.simulate_frf(model, truth, w, noise=1e-4, seed=1),
               "rounded to 6 decimals": si.FrequencyData(w, np.round(np.asarray(belt.data().H), 6))}
    for label, data in records.items():
        ref = _belt_reference(model, data)
        res = ScrFRF(model, data).run(np.zeros(4))
        out[f"belt/{label}"] = {"success": res.success, "status": res.status,
                                "relative_difference_to_reference": _rel_max(res.theta, ref),
                                "error_to_truth": _rel_max(res.theta, truth), "time": res.wall_time}
        print(f"  belt drive, {label}: {res.status}, success {res.success}; |θ̂ − θ_ref|/|θ_ref| ≤ "
              f"{_rel_max(res.theta, ref):.1e}, error to θ* {_rel_max(res.theta, truth):.1e}, {res.wall_time:.3f} s")
    two = si.load_model("mass_damper_2dof")
    model, w = two.model, two.data().w
    truth = model.theta_vector(two.truth)  # thesis (4-20)
    rows = []
    for rec in range(args.records):
        data = si.simulate_frf(model, truth, w, noise=1e-2, seed=rec)

        def run(data: Any = data, rec: int = rec) -> dict:
            ip = IpoptFRF(model, data)
            ref = ip.run(truth)
            est = ScrFRF(model, data)
            unc = ip.uncertainty(ref.theta, model.parameter_names)
            cov_inv = np.linalg.inv(unc.covariance)
            res = []
            for x0 in make_starts(model, args.noise_starts, 100 + rec):
                t = time.perf_counter()
                alone = est.run(x0)
                t_alone = time.perf_counter() - t
                t = time.perf_counter()
                pol = est.run_polished(x0, ip)
                t_pol = time.perf_counter() - t
                d = alone.theta - ref.theta
                res.append({"scr_success": alone.success, "scr_status": alone.status,
                            "scr_iterations": alone.iterations, "scr_time": t_alone,
                            "scr_se_distance": float(np.sqrt(d @ cov_inv @ d)),
                            "polish_success": pol.success, "polish_relative_difference": _rel_max(pol.theta, ref.theta),
                            "polish_time": t_pol, "polish_message": pol.message})
            return {"record": rec, "ipopt_cost": ref.cost, "starts": res}

        rows.append(logged(log, f"2dof/{rec}", run))
    starts = [s for r in rows for s in r["starts"]]
    n = len(starts)
    se = np.array([s["scr_se_distance"] for s in starts])
    ok = [s for s in starts if s["scr_success"]]
    out["2dof"] = {
        "records": rows, "scr_success": len(ok), "starts": n,
        "scr_se_distance_max_of_successes": float(max((s["scr_se_distance"] for s in ok), default=np.nan)),
        "scr_se_distance_median": float(np.median(se)),
        "scr_median_time": float(np.median([s["scr_time"] for s in starts])),
        "polish_success": sum(s["polish_success"] for s in starts),
        "polish_relative_difference_max": float(max(s["polish_relative_difference"] for s in starts
                                                    if s["polish_success"])),
        "polish_median_time": float(np.median([s["polish_time"] for s in starts]))}
    o = out["2dof"]
    print(f"  2-DOF, 1 % noise, {args.records} records × {args.noise_starts} starts: "
          f"SCR success {o['scr_success']}/{n}, "
          f"distance to IPOPT's estimate ≤ {o['scr_se_distance_max_of_successes']:.2f} standard errors (median "
          f"{o['scr_se_distance_median']:.2f}), median {o['scr_median_time']:.2f} s; scr+polish success "
          f"{o['polish_success']}/{n}, |θ̂ − θ_ipopt|/|θ_ipopt| ≤ {o['polish_relative_difference_max']:.1e}, "
          f"median {o['polish_median_time']:.2f} s")
    return out


def progress(args: argparse.Namespace, log: RunLog) -> dict:
    """Cost of the per-iteration report: the same starts with and without a callback (interleaved)."""
    entry = si.load_model("mass_damper_2dof")
    model, data = entry.model, entry.data()
    plain = ScrFRF(model, data)
    seen: list[Any] = []
    reported = ScrFRF(model, data, callback=seen.append)
    rows = []
    for k, x0 in enumerate(make_starts(model, args.starts, 0)):
        def run(x0: np.ndarray = x0) -> dict:
            out = {}
            for label, est in (("plain", plain), ("callback", reported)):
                c = time.process_time()
                res = est.run(x0)
                out[label] = {"cpu": time.process_time() - c, "iterations": res.iterations}
            return out
        rows.append(logged(log, f"2dof/{k}", run))
    same = all(r["plain"]["iterations"] == r["callback"]["iterations"] for r in rows)
    cpu = {label: sum(r[label]["cpu"] for r in rows) for label in ("plain", "callback")}
    ratio = cpu["callback"] / cpu["plain"]
    print(f"  2-DOF, {len(rows)} starts: CPU {cpu['plain']:.2f} s without, {cpu['callback']:.2f} s with a callback "
          f"(misfit every iteration): overhead {100 * (ratio - 1):+.1f} %; same iterations: {same}")
    return {"cpu": cpu, "overhead": ratio - 1, "same_iterations": same, "runs": rows}


def time_limit(args: argparse.Namespace, log: RunLog) -> dict:
    """Wall time per start against a budget far below what SCR needs: generated chains, uninformed starts."""
    make_problem = _population()
    rows = []
    for n in (3, 5):
        p = make_problem("chain", n, 0, check=False)
        data = p.data()
        for backend in ("admm", "cvxpy"):
            est = None
            for k, x0 in enumerate(p.starts("uninformed", 2)):
                key = f"{p.name}/{backend}/{k}"
                if key not in log and est is None:
                    est = ScrFRF(p.model, data, scale=p.typical, backend=backend, time_limit=args.budget)

                def run(x0: np.ndarray = x0, est: Any = est) -> dict:
                    t = time.perf_counter()
                    out = est.run(x0)
                    return {"wall": time.perf_counter() - t, "status": out.status, "iterations": out.iterations}
                rec = logged(log, key, run)
                rows.append({"problem": p.name, "backend": backend, **rec})
                print(f"  {p.name:14s} {backend:6s} start {k}: {rec['status']:10s} {rec['iterations']:4d} iterations "
                      f"{rec['wall']:6.2f} s (budget {args.budget:g} s)", flush=True)
    worst = max(r["wall"] for r in rows)
    print(f"  longest start {worst:.2f} s for a budget of {args.budget:g} s")
    return {"budget": args.budget, "longest": worst, "runs": rows}


# -- driver ------------------------------------------------------------------------------------------

def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default=",".join(SECTIONS), help="comma-separated subset of %(default)s")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--starts", type=int, default=20)
    parser.add_argument("--sizes", default="2,3", help="population sizes (masses, states, compartments)")
    parser.add_argument("--problems", type=int, default=2, help="problems per class and size")
    parser.add_argument("--pop-starts", type=int, default=2, help="informed and uninformed starts per problem")
    parser.add_argument("--time-limit", type=float, default=20.0, help="seconds per SCR start (population)")
    parser.add_argument("--records", type=int, default=5)
    parser.add_argument("--noise-starts", type=int, default=5)
    parser.add_argument("--budget", type=float, default=2.0, help="time_limit of the time_limit section (s)")
    parser.add_argument("--out", default=str(RESULTS / "scr_robust.json"))
    add_log_arguments(parser, "scr_robust")
    args = parser.parse_args(argv)
    args.sizes = tuple(int(v) for v in args.sizes.split(","))
    only = tuple(s.strip() for s in args.only.split(",") if s.strip())
    if not only or set(only) - set(SECTIONS):
        parser.error(f"--only must name some of {', '.join(SECTIONS)}")
    fns = {"thesis_aux_init": thesis_aux_init, "population_aux_init": population_aux_init, "noise": noise,
           "progress": progress, "time_limit": time_limit}
    out = Path(args.out)
    previous = {}
    if out.exists():
        old = json.loads(out.read_text())
        previous = {k: v for k, v in old.items() if k in SECTIONS and k not in only}
    header = {"benchmark": "scr_robust", "options": {k: v for k, v in vars(args).items() if k not in ("log", "out")},
              "machine": {"platform": platform.platform(), "python": platform.python_version(),
                          "cpus": os.cpu_count(), "load_average_start": os.getloadavg()}}
    return run_study({name: (lambda log, fn=fns[name]: fn(args, log)) for name in only}, out=out,
                     log_path=Path(args.log), fresh=args.fresh, header=header, previous=previous)


if __name__ == "__main__":
    raise SystemExit(main())
