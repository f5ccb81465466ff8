"""Thesis chapters 6 and 7 reproduced: the e-nose, its over-parameterised form, the 3-D mass-spring-damper.

Sections (``--only`` picks one):

``enose``
    Model (6-19), truth (6-16), black box: the zoo's exact similarity transform of the
    truth closest to the printed N4SID + d2c estimate (6-18). SCR, ALS, GB and IPOPT
    from the same 10 seeded random starts (random T, S; :mod:`symid.fit.
    similarity.start`); success = ‖θ − θ*‖/‖θ*‖ ≤ 1e-3. Thesis §6-6-2: SCR "roughly 3
    out of every 10". Also SCR on the printed (6-18) itself, which is a noisy estimate
    (DC gain 0.1526 against 0.15), so no exact solution exists: its best parameter error.
``enose_over``
    Model (6-22) (7 parameters, not identifiable): SCR from 10 random starts; the best
    point's ‖TS − I‖, ‖ST − I‖, misfit against the black box and eigenvalues (thesis
    (6-24)/(6-25): TS = I, same frequency response).
``msd3``
    Model (7-17) with full symmetric M, V, K (18 parameters), I/O data of §7-6-1 (dt =
    1 ms, N = 5000, seeded white-noise input), N4SID + exact ZOH, then (7-10) by SCR from
    3 random starts; relative errors of M, V, K (thesis (7-21)/(7-22): about 1e-2), and
    after an IPOPT polish.

Run (pin BLAS to one thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/similarity_thesis.py

Prints tables and writes ``benchmarks/results/similarity_thesis.json`` when every section
is done (``--only`` updates one section and keeps the others' earlier results). Every
start is logged as it ends to ``benchmarks/results/similarity_thesis.jsonl`` (``--log``);
after Ctrl-C (exit status 130, no summary written) the same command resumes;
``--fresh`` starts over.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from _study import add_log_arguments, logged, run_study  # benchmarks/_study.py (the script's folder is on the path)

import symid as si
from symid.fit.compare import relative_parameter_error
from symid.fit.registry import prepare
from symid.fit.similarity.data import similarity_data
from symid.fit.similarity.scr import ScrSimilarity
from symid.fit.starts import make_starts
from symid.progress import progress_bar
from symid.runlog import RunLog

RESULTS = Path(__file__).resolve().parent / "results" / "similarity_thesis.json"
SUCCESS = 1e-3  # thesis (6-32)/(6-33)
SCR_OPTIONS = {"max_iter": 2000}


def enose(log: RunLog, starts: int = 10, seed: int = 0) -> dict:
    """SCR, ALS, GB and IPOPT on the e-nose (6-19) from identical random starts."""
    entry = si.load_model("enose")
    cmp = si.compare(entry.model, entry.data(), methods=("scr", "als", "gb", "ipopt"), starts=starts, seed=seed,
                     truth=entry.truth, param_tol=SUCCESS, param_error="l2", progress=True,
                     options={"scr": SCR_OPTIONS}, log=log.scoped("compare/"))
    print(cmp.table())
    truth = entry.model.theta_vector(entry.truth)
    out = {"starts": starts, "seed": seed, "success_threshold": SUCCESS, "thesis_scr": "about 3 of 10",
           "methods": {}}
    for s in cmp.stats:
        errs = [relative_parameter_error(o.theta, truth) for o in s.result.starts]
        out["methods"][s.method] = {"successes": s.n_success, "parameter_errors": errs,
                                    "times": [o.wall_time for o in s.result.starts],
                                    "median_time": s.median_time, "options": s.result.options}
    # thesis §6-6-2: "S, T initialized as zero matrices ... the method fails"
    def zero_start() -> dict:
        zero = prepare(entry.model, entry.data(), "scr", {"aux_init": "zero", **SCR_OPTIONS}).run(
            np.zeros(entry.model.n_parameters))
        return {"parameter_error": relative_parameter_error(zero.theta, truth), "iterations": zero.iterations,
                "time": zero.wall_time}

    out["zero_start"] = logged(log, "zero_start", zero_start)
    print(f"SCR from T = S = 0: parameter error {out['zero_start']['parameter_error']:.3e} after "
          f"{out['zero_start']['iterations']} iterations")
    # the printed (6-18): a noisy estimate, no exact solution
    bb = si.BlackBox(entry.extra["A_bb_printed"], entry.extra["B_bb_printed"], entry.extra["C_bb_printed"])
    res = si.identify(entry.model, bb, method="scr", starts=starts, seed=seed, progress=True,
                      identifiability_check=False, **SCR_OPTIONS)
    err = relative_parameter_error(res.theta_vector, truth)
    print(f"printed (6-18): best SCR estimate {np.round(res.theta_vector, 4)}, parameter error {err:.3e}, "
          f"misfit {res.cost:.3e}")
    out["printed_6_18"] = {"theta": res.theta, "parameter_error": err, "misfit": res.cost}
    return out


def enose_over(log: RunLog, starts: int = 10, seed: int = 0) -> dict:
    """SCR on the over-parameterised e-nose (6-22): a point of the solution manifold."""
    entry = si.load_model("enose_overparameterized")
    model = entry.model
    sd = similarity_data(model, entry.data())
    solver = ScrSimilarity(model, sd, **SCR_OPTIONS)
    runs = []

    def one(x: np.ndarray) -> dict:
        t0 = time.perf_counter()
        sol = solver.solve(x)
        T, S = solver.transform(sol, original=True)
        theta = np.asarray(sol.x["theta"], dtype=float)
        return {"theta": theta.tolist(), "misfit": sd.misfit(model, theta),
                "TS_minus_I": float(np.linalg.norm(T @ S - np.eye(3))),
                "ST_minus_I": float(np.linalg.norm(S @ T - np.eye(3))), "iterations": sol.iterations,
                "time": time.perf_counter() - t0}

    for i, x in enumerate(progress_bar(make_starts(model, starts, seed, zero_first=True), desc="scr", enabled=True)):
        runs.append(logged(log, f"start{i}", lambda x=x: one(x)))
    best = min(runs, key=lambda r: r["misfit"])
    theta = np.array(best["theta"])
    A_true = model.maps["A"](model.theta_vector(entry.truth))
    eig = np.sort_complex(np.linalg.eigvals(model.maps["A"](theta)))
    eig_err = float(np.max(np.abs(eig - np.sort_complex(np.linalg.eigvals(A_true)))))
    found = sum(r["misfit"] < 1e-10 and r["TS_minus_I"] < 1e-6 for r in runs)
    print(f"over-parameterised e-nose: {found}/{starts} starts reach the manifold (misfit < 1e-10, ‖TS − I‖ < 1e-6)")
    print(f"best: θ̂ = {np.round(theta, 4)}, misfit {best['misfit']:.2e}, ‖TS − I‖ {best['TS_minus_I']:.2e}, "
          f"‖ST − I‖ {best['ST_minus_I']:.2e}, eigenvalue error {eig_err:.2e}, "
          f"θ̂2 + θ̂4 + θ̂6 = {theta[1] + theta[3] + theta[5]:.4f} (0 at the physical point)")
    return {"starts": starts, "seed": seed, "found": found, "best": best, "eigenvalue_error": eig_err, "runs": runs}


def msd3(log: RunLog, starts: int = 3, seed: int = 0) -> dict:
    """Algorithm 7.1 on the 3-D mass-spring-damper (7-17) from simulated I/O data."""
    entry = si.load_model("msd3_similarity")
    model, io = entry.model, entry.data()
    truth = model.theta_vector(entry.truth)
    true_mats = model.matrices(truth)
    t0 = time.perf_counter()
    sd = similarity_data(model, io)
    t_bb = time.perf_counter() - t0
    w = sd.frf.w
    H0 = model.frequency_response(truth, w)
    bb_err = float(np.max(np.abs(sd.frf.H - H0)) / np.max(np.abs(H0)))
    print(f"N4SID + d2c: {t_bb:.2f} s, black-box frequency response off by {bb_err:.2e} (max, relative)")
    cmp = si.compare(model, io, methods=("scr", "scr+polish"), starts=starts, seed=seed, truth=entry.truth,
                     param_tol=1e-2, param_error="l2", progress=True, options={"scr": SCR_OPTIONS},
                     log=log.scoped("compare/"))
    print(cmp.table())
    out = {"n4sid_time": t_bb, "blackbox_frf_error": bb_err, "starts": starts, "seed": seed, "methods": {}}
    for s in cmp.stats:
        rows = []
        for o in s.result.starts:
            mats = model.matrices(o.theta) if np.all(np.isfinite(o.theta)) else None
            errs = {k: (float(np.linalg.norm(mats[k] - true_mats[k]) / np.linalg.norm(true_mats[k]))
                        if mats is not None else float("inf")) for k in "MVK"}
            rows.append({"relative_errors": errs, "misfit": o.cost, "time": o.wall_time, "iterations": o.iterations})
            print(f"  {s.method:>10s}: M {errs['M']:.2e}  V {errs['V']:.2e}  K {errs['K']:.2e}  "
                  f"({o.iterations} it, {o.wall_time:.1f} s)")
        out["methods"][s.method] = rows
    return out


SECTIONS = {"enose": enose, "enose_over": enose_over, "msd3": msd3}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=sorted(SECTIONS), help="run one section")
    parser.add_argument("--out", default=str(RESULTS), help="summary JSON (default: %(default)s)")
    add_log_arguments(parser, "similarity_thesis")
    args = parser.parse_args(argv)
    out = Path(args.out)
    previous = {}
    if args.only and out.is_file():  # keep the other sections' earlier results; a damaged file is not trusted
        try:
            previous = {k: v for k, v in json.loads(out.read_text()).items() if k in SECTIONS}
        except (ValueError, OSError):
            print(f"{out} is not valid JSON; it will be replaced", file=sys.stderr)
    sections = {k: v for k, v in SECTIONS.items() if not args.only or k == args.only}
    return run_study(sections, out=out, log_path=Path(args.log), fresh=args.fresh,
                     header={"benchmark": "similarity_thesis"}, previous=previous)


if __name__ == "__main__":
    raise SystemExit(main())
