"""SCR against CasADi/IPOPT on frequency responses: success rate and time to solution.

Problems (zoo data recipes, noise-free):

- ``belt_drive``: thesis (3-17), 10 log-spaced points in 0.4–0.6 rad/s;
- ``mass_damper_2dof``: thesis (4-19)–(4-21), 30 log-spaced points in 0.5–2 rad/s,
  position of m1 measured; B = [[1], [0]] and C = [[1, 0]] are not square, so SCR runs
  formulation (4-8) with M, V, K ⪰ 0 (the benchmark checks it did not switch to LS).

Methods, from the same seeded starts (:func:`symid.compare`; state-space models get the
zero start first, as thesis ch. 3):

- ``scr``: default options (ADMM back end, presolve, tol 1e-6, unit weights);
- ``scr+polish``: SCR handing over to IPOPT (:meth:`symid.fit.frf.scr.ScrFRF.run_polished`):
  after SCR iterations 1, 2, 4, … a trial IPOPT run from the current SCR estimate, and the
  start ends as soon as one fits the data (relative misfit ≤ 1e-8); else the final SCR
  estimate is polished. Built and run on its own (nothing shared with the ``scr`` row);
  time per start = SCR + every polish, trials included;
- ``ipopt``: CasADi ``nlpsol`` with exact Hessian, objective normalised by Σ‖Hᵢ‖², bounds
  θ ≥ 0 on parameters declared positive, tolerance 1e-12 (the normalised objective keeps
  IPOPT from stopping early on a small raw objective). Other
  IPOPT configurations (L-BFGS, no bounds, parameter scaling, looser tolerance) run from
  the same starts too, to show the default is IPOPT at its best here.

Success: ‖θ̂ − θ*‖₂/‖θ*‖₂ ≤ 1e-3. Time to solution: (setup + all starts) / successes.
Also measured: SCR's wall time from the all-zero start to ‖θ̂ − θ*‖₂ ≤ 1e-6 on the belt
drive, with the import and model setup excluded but the problem construction included.

Run (one BLAS thread per process: threaded BLAS slows the many small solves on 2 cores)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/frf.py [--starts 20] [--seed 0]

Prints a table per problem and the targets of issue 4, and writes
``benchmarks/results/frf.json`` when everything is done. Every start is logged as it ends
to ``benchmarks/results/frf.jsonl`` (``--log``); after Ctrl-C (exit status 130, no summary
written) the same command resumes; ``--fresh`` starts over; the log is removed once the
summary is written. ``--problems`` and ``--no-variants`` run a part. Absolute times
depend on the machine and on what else runs on it (the JSON records the load average);
ratios are measured in one run.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
from _study import add_log_arguments, finish_log, logged  # benchmarks/_study.py (the script's folder is on the path)

import symid as si
from symid.runlog import RunLog, write_json_atomic

PROBLEMS = ("belt_drive", "mass_damper_2dof")
METHODS = ("scr", "scr+polish", "ipopt")


def _fmt(ratio: float | None) -> str:
    return "n/a (IPOPT never succeeded)" if ratio is None else f"{ratio:.3g}"


def _finite(obj: object) -> object:
    """JSON-safe copy: non-finite floats (an infinite time to solution) become None."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    return obj


def belt_drive_from_zeros() -> dict:
    """Wall time of SCR from θ = 0 on the belt drive, construction included."""
    entry = si.load_model("belt_drive")
    model, data = entry.model, entry.data()
    truth = model.theta_vector(entry.truth)  # thesis (3-18)
    t0 = time.perf_counter()
    res = si.identify(model, data, method="scr", identifiability_check=False)
    wall = time.perf_counter() - t0
    return {"error": float(np.linalg.norm(res.theta_vector - truth)), "wall_time": wall, "message": res.message}


IPOPT_VARIANTS = {  # the default first; the others show it is IPOPT's best configuration here
    "default (exact Hessian, bounds, scale 1)": {},
    "L-BFGS Hessian": {"hessian": "limited-memory"},
    "no bounds": {"positivity": False},
    "scale 0.5": {"scale": 0.5},
    "scale 2": {"scale": 2.0},
    "tol 1e-8": {"tol": 1e-8},
}


def ipopt_variants(name: str, starts: int, seed: int, log: RunLog) -> dict:
    """Success rate and time to solution of IPOPT configurations from the same starts."""
    entry = si.load_model(name)
    data = entry.data()
    rows = {}
    for label, opts in IPOPT_VARIANTS.items():
        st = si.compare(entry.model, data, methods=("ipopt",), starts=starts, seed=seed, truth=entry.truth,
                        param_error="l2", progress=False, options={"ipopt": opts}, log=log.scoped(f"{label}/"))["ipopt"]
        rows[label] = {"options": opts, "n_success": st.n_success, "success_rate": st.success_rate,
                       "median_time": st.median_time, "time_to_solution": st.time_to_solution}
    print(f"\n{name}: IPOPT configurations, {starts} starts (seed {seed})")
    for label, r in rows.items():
        print(f"  {label:42s} {r['n_success']:>2d}/{starts}   time to solution {r['time_to_solution']:.3f} s")
    return rows


def run_problem(name: str, starts: int, seed: int, log: RunLog) -> dict:
    entry = si.load_model(name)
    cmp = si.compare(entry.model, entry.data(), methods=METHODS, starts=starts, seed=seed, truth=entry.truth,
                     param_error="l2", progress=True, log=log)  # the thesis's measure, as the README states
    print(f"\n{name}: {entry.title}\n{cmp.table()}")
    if name == "mass_damper_2dof":
        assert cmp["scr"].ran_as == "scr", "the 2-DOF must run SCR (4-8), not the LS special case"
    out = cmp.to_dict()
    for m in out["methods"]:  # keep the JSON small: per start only what the figures are made of
        m["starts"] = [{"start": s["start"], "theta": s["theta"], "cost": s["cost"], "iterations": s["iterations"],
                        "wall_time": s["wall_time"], "message": s["message"]} for s in m["starts"]]
    tts = {m: cmp[m].time_to_solution for m in METHODS}
    out["ratio_time_to_solution"] = {
        "scr/ipopt": tts["scr"] / tts["ipopt"] if np.isfinite(tts["ipopt"]) else None,
        "scr+polish/ipopt": tts["scr+polish"] / tts["ipopt"] if np.isfinite(tts["ipopt"]) else None,
    }
    out["title"] = entry.title
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--problems", default=",".join(PROBLEMS), help="comma-separated subset of %(default)s")
    parser.add_argument("--no-variants", action="store_true", help="skip the IPOPT configurations")
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "frf.json"))
    add_log_arguments(parser, "frf")
    args = parser.parse_args(argv)
    problems = tuple(p.strip() for p in args.problems.split(",") if p.strip())
    if not problems or set(problems) - set(PROBLEMS):
        parser.error(f"--problems must name some of {', '.join(PROBLEMS)}")
    log = RunLog(args.log, fresh=args.fresh)
    if len(log):
        print(f"resuming from {args.log}: {len(log)} finished runs are read back, not run again", flush=True)
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    try:
        zeros = logged(log, "belt_drive_from_zeros", belt_drive_from_zeros)
        print(f"belt drive, SCR from θ = 0: ‖θ̂ − θ*‖₂ = {zeros['error']:.2e} in {zeros['wall_time']:.3f} s")
        results = {name: run_problem(name, args.starts, args.seed, log.scoped(f"{name}/")) for name in problems}
        variants = {} if args.no_variants else {
            name: ipopt_variants(name, args.starts, args.seed, log.scoped(f"variants/{name}/")) for name in problems}
    except KeyboardInterrupt:
        print(f"\ninterrupted: {len(RunLog(args.log))} finished runs are kept in {args.log}; run the same command "
              "again to resume (no summary written)", file=sys.stderr)
        return 130
    return _summarise(args, problems, zeros, results, variants, load0, t0)


def _summarise(args: argparse.Namespace, problems: tuple[str, ...], zeros: dict, results: dict, variants: dict,
               load0: tuple, t0: float) -> int:

    def rate(p: str, m: str) -> float:
        return next(s["success_rate"] for s in results[p]["methods"] if s["method"] == m)

    def tts(p: str, m: str) -> float:
        return next(s["time_to_solution"] for s in results[p]["methods"] if s["method"] == m)

    print("\nratio of time to solution, SCR / IPOPT (< 1: SCR faster)")
    for p in problems:
        r = results[p]["ratio_time_to_solution"]
        print(f"  {p:18s} scr {_fmt(r['scr/ipopt'])}   scr+polish {_fmt(r['scr+polish/ipopt'])}")
    harder = min(problems, key=lambda p: rate(p, "ipopt"))
    best_scr = min(tts(harder, "scr"), tts(harder, "scr+polish"))
    targets = {
        "belt drive from zeros to 1e-6 in < 1 s": zeros["error"] <= 1e-6 and zeros["wall_time"] < 1.0,
        **{f"SCR success >= 90% on {p}": rate(p, "scr") >= 0.9 for p in problems},
        f"SCR(+polish) time to solution <= IPOPT's on {harder} (IPOPT's lower success rate)":
            bool(best_scr <= tts(harder, "ipopt")),
    }
    print("\ntargets (issue 4)")
    for k, v in targets.items():
        print(f"  {'met    ' if v else 'NOT MET'}  {k}")
    doc = {"benchmark": "frf", "complete": True, "starts": args.starts, "seed": args.seed,
           "belt_drive_from_zeros": zeros,
           "problems": results, "ipopt_variants": variants, "targets": targets, "total_time": time.perf_counter() - t0,
           "machine": {"platform": platform.platform(), "python": platform.python_version(),
                       "cpus": os.cpu_count(), "load_average_start": load0, "load_average_end": os.getloadavg(),
                       "threads": {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")}}}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out, _finite(doc))
    finish_log(Path(args.log))
    print(f"\nwrote {out} (total {doc['total_time']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
