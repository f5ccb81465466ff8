"""Every frequency-response method on a generated population of models nobody tuned for.

Problems come from :mod:`population_models` (this folder): mass-spring-damper chains of
n masses (position, velocity or acceleration output; collocated or not), chains with a
second sensor, chains with an actuator gain in B and a sensor gain in C, first-order
state-space networks with parameters in A, B and C, and catenary or mammillary
compartment models with a volume in C; true values drawn log-uniformly over physical
ranges (SI units), frequency grids that cover the modes. Every problem is checked with
:func:`symid.identifiability` before it is used: one with a parameter that is not
locally identifiable is drawn again, never counted against a method. A problem whose
grid cannot resolve the success tolerance — some parameter 10⁻³ off changes the
relative misfit by less than 10⁻²⁰ (:func:`population_models.resolution`) — is skipped
and the next problem index taken (at most ``--problems`` + 10 per class and size); the
summary lists the skipped ones (``unresolved``), which are never counted against a method.

Per problem, noise level (noise-free, 1 % relative) and kind of start:

- informed starts: within a factor 3 of the truth (log-uniform);
- uninformed starts: log-uniform over two decades around the typical value of each
  parameter, which every method that takes one is given as ``scale=`` (what a user
  knows before measuring: the order of magnitude of a mass, a stiffness, a rate).

Every method runs from the same starts through :func:`symid.compare`, each start with a
wall-time budget (``--time-limit``, the methods' ``time_limit=`` option). A start
succeeds when

- noise-free: maxₖ |θ̂ₖ − θ*ₖ|/|θ*ₖ| ≤ 1e-3, or, for a problem not proven globally
  identifiable, θ̂ fits the data exactly (relative misfit ≤ 1e-10) with every parameter
  declared positive: another admissible solution;
- 1 % noise: maxₖ |θ̂ₖ − θ*ₖ|/|θ*ₖ| ≤ 2 × that of the reference estimate (IPOPT and
  ``lm`` started at the truth, whichever ends at the lower misfit: ``REFERENCES``), or θ̂
  fits at least as well as the reference with positive parameters (misfit ≤ its misfit;
  ≤ 1.001 × it for a problem not proven globally identifiable). The reference is taken
  for the least-squares estimate; a fit below its misfit is a better one, even where the
  landscape is so flat that it lies more than twice the reference's error away (measured:
  a 3-mass chain with gains at misfit 1.6079e-5 and error 10.1 against the reference's
  1.6080e-5 and 1.0).

The error is the largest relative error of any parameter, not ‖θ̂ − θ*‖/‖θ*‖: in SI units
the springs (1e3–1e5 N/m) would dominate that norm and a mass 100 % off would pass.

Tabulated per class × method × noise × start kind: success rate, median seconds per
start, time to solution (all starts' time / successes).

Run (one BLAS thread per process)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/population.py \\
        [--classes chain,gains] [--sizes 2,3,5,8] [--problems 2] [--starts 3] [--methods auto,ipopt,scr] \\
        [--noise 0,0.01] [--kinds informed,uninformed] [--time-limit 60] [--workers 2 | --dask ADDRESS]

Every finished start is appended to ``benchmarks/results/population.jsonl`` (``--log``) as
it ends; running the command again resumes (finished starts are read back), ``--fresh``
starts over. A finished start is never run again unless its method is named in
``--rerun`` (after a change to the method): its logged starts on the problems of this run
are then run again once by the current commit, the new records superseding the old ones (a
``rerun`` marker per problem, noise level and kind of start records the finished rerun, so a
resumed rerun does not repeat it). ``--summary-only`` rebuilds the summary from the log. The summary
(``benchmarks/results/population.json``, the README table's source) is rewritten from the
whole log after every problem, so it always describes exactly what the log holds.
``--recheck`` checks every logged problem's identifiability again with the current code
(a problem the checker could not decide when it was drawn may be proven globally
identifiable now, and then its starts are judged by their parameter error alone).
``--workers N`` runs the starts in a local process pool; ``--dask ADDRESS`` on a Dask
cluster (``distributed.Client(ADDRESS).get_executor()``, the optional extra
``symid[dask]``).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
import warnings
from collections import defaultdict
from concurrent.futures import Executor, ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np
from _study import git_commit  # benchmarks/ (the script's folder) is on the path
from population_models import (  # benchmarks/ (the script's folder) is on the path
    CLASSES,
    RESOLUTION_FLOOR,
    Problem,
    identifiability_info,
    make_problem,
    resolution,
)

import symid as si
from symid.fit.frf.ls import ls_applicable
from symid.fit.success import EXACT_FIT
from symid.interrupt import Interrupted
from symid.runlog import RunLog, write_json_atomic

RESULTS = Path(__file__).resolve().parent / "results"
METHODS = ("auto", "lm", "ipopt", "scr", "scr+polish", "ls")
SCALED = ("auto", "lm", "ipopt", "scr")  # methods that take the user's typical values as scale=
TIMED = ("auto", "lm", "ipopt", "scr")  # methods that take time_limit=
MAX_SIZE = {"compartment": 6, "state_space": 8}  # larger sizes of these classes are skipped
EXTRA_INDICES = 10  # problem indices tried beyond --problems when some are skipped as unresolved


def _problem(log: RunLog, cls: str, n: int, index: int, timeout: float) -> Problem:
    """The problem, checked once and rebuilt from its draw afterwards (the check is logged)."""
    key = f"{cls}-n{n}-{index}/problem"
    rec = log.get(key)
    if rec is not None:
        p = make_problem(cls, n, index, check=False, draw=rec["info"]["draw"])
        p.info.update(rec["info"])  # a problem logged before resolutions were: the one just computed stays
        return p
    t0 = time.perf_counter()
    p = make_problem(cls, n, index, timeout=timeout)
    log.append(key, {"cls": cls, "n": n, "index": index, "n_parameters": p.model.n_parameters,
                     "parameter_names": list(p.model.parameter_names), "truth": p.truth, "typical": p.typical,
                     "w": [float(p.w[0]), float(p.w[-1]), int(p.w.size)], "info": p.info,
                     "check_time": time.perf_counter() - t0})
    return p


REFERENCES = ("ipopt", "lm")
"""The 1 % reference is the lower misfit of IPOPT (the issue's definition) and ``lm`` started at the truth: the
least-squares estimate nearest the truth. IPOPT alone can stop short of it (``benchmarks/noisy_reference.py``: on 6
of 27 problems ``lm`` from the truth ended lower, the reference up to 2.14 times higher, e.g. an 8-mass chain at
6.08e-5 and error 14.6 where ``lm`` reaches 5.96e-5 at error 2.2); the time-series benchmark takes the same rule."""


def _reference_run(p: Problem, data: Any, method: str) -> dict[str, Any]:
    """One reference run: ``method`` started at the truth, with the typical values as ``scale=``."""
    t0 = time.perf_counter()
    res = si.identify(p.model, data, method=method, x0=p.truth, identifiability_check=False, scale=p.typical)
    return {"theta": res.theta_vector, "cost": res.cost, "error": parameter_error(res.theta_vector, p.truth),
            "status": res.status, "seconds": time.perf_counter() - t0}


def _reference(log: RunLog, p: Problem, noise: float, data: Any) -> dict[str, Any]:
    """The estimate a method is measured against on noisy data: the lower misfit of :data:`REFERENCES` started at
    the truth (every run is logged under ``runs``)."""
    key = f"{p.name}/noise{noise:g}/reference"
    rec = log.get(key)
    if rec is None:
        runs = {m: _reference_run(p, data, m) for m in REFERENCES}
        finite = [m for m in REFERENCES if runs[m]["cost"] is not None and np.isfinite(runs[m]["cost"])]
        best = min(finite, key=lambda m: runs[m]["cost"]) if finite else REFERENCES[0]
        log.append(key, {**{k: runs[best][k] for k in ("theta", "cost", "error", "status")}, "method": best,
                         "runs": runs})
        rec = log.get(key)
    return rec


def parameter_error(theta: Any, truth: Any) -> float:
    """maxₖ |θₖ − θ*ₖ| / |θ*ₖ|: the largest relative error of any parameter, whatever their units."""
    theta, truth = np.asarray(theta, dtype=float), np.asarray(truth, dtype=float)
    return float(np.max(np.abs(theta - truth) / np.abs(truth)))


def start_success(theta: Any, cost: Any, truth: np.ndarray, positive: np.ndarray, globally: bool,
                  reference: dict[str, Any] | None) -> bool:
    """The benchmark's success rule for one start (module docstring)."""
    if theta is None or cost is None:
        return False
    theta = np.asarray(theta, dtype=float)
    if not np.all(np.isfinite(theta)):
        return False
    err = parameter_error(theta, truth)
    admissible = bool(np.all(theta[positive] > 0))
    if reference is None:  # noise-free
        return err <= 1e-3 or (not globally and admissible and float(cost) <= EXACT_FIT)
    ref_err, ref_cost = parameter_error(reference["theta"], truth), float(reference["cost"])
    # a fit at least as good as the least-squares estimate found from the truth is one too, wherever it lies: in a
    # sloppy landscape two fits of nearly equal misfit can differ by a factor 10 in some parameter
    return err <= 2 * ref_err or (admissible and float(cost) <= (1.0 if globally else 1.001) * ref_cost)


def run_problem(log: RunLog, p: Problem, args: argparse.Namespace, executor: Executor | None) -> None:
    methods = [m for m in args.methods if m != "ls" or ls_applicable(p.model) is not None]
    for noise in args.noise:
        data = p.data(noise=noise, seed=0)
        if noise > 0:
            _reference(log, p, noise, data)
        for kind in args.kinds:
            starts = list(p.starts(kind, args.starts, seed=0))
            options = {m: {**({"scale": p.typical} if m in SCALED else {}),
                           **({"time_limit": args.time_limit} if m in TIMED else {}),
                           **({"force_scr": True} if m == "scr" else {})}  # SCR itself, even where ls applies
                       for m in {x.removesuffix("+polish") for x in methods}}
            scope = log.scoped(f"{p.name}/noise{noise:g}/{kind}/")
            rerun = [m for m in args.rerun if m in methods and (scope.get(f"{m}/rerun") or {}).get("commit")
                     != args.commit]
            for m in rerun:  # run again by this code (until a finished rerun is marked with its commit)
                for key in [f"{m}/setup", *(f"{m}/start{i}" for i in range(len(starts)))]:
                    scope.forget(key)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # identifiability was checked above
                si.compare(p.model, data, methods=methods, starts=starts, options=options, log=scope,
                           executor=executor, progress=args.progress, noise_floor=None)
            for m in rerun:
                scope.append(f"{m}/rerun", {"commit": args.commit})


def resolved(p: Problem) -> bool:
    """The grid resolves the success tolerance (module docstring)."""
    return float(p.info["resolution"]) > RESOLUTION_FLOOR


def _logged_resolution(rec: dict[str, Any]) -> float:
    """The resolution of a logged problem (computed again for logs written before it was recorded)."""
    info = rec["info"]
    if "resolution" in info:
        return float(info["resolution"])
    p = make_problem(rec["cls"], int(rec["n"]), int(rec["index"]), check=False, draw=info["draw"])
    return resolution(p.model, p.truth, p.w)


def summarise(log: RunLog) -> dict[str, Any]:
    """Success rate, median time per start and time to solution per class × method × noise × start kind,
    from every record in the log (problems the grid does not resolve are listed apart, not counted)."""
    problems: dict[str, dict[str, Any]] = {}
    unresolved: dict[str, float] = {}
    refs: dict[tuple[str, str], dict[str, Any]] = {}
    runs: list[dict[str, Any]] = []
    for rec in log.records():
        parts = rec["key"].split("/")
        if parts[0] == "run" and len(parts) == 2:
            runs.append({k: rec.get(k) for k in ("started", "commit", "methods", "sizes", "rerun") if k in rec})
        elif parts[-1] == "problem":
            res = _logged_resolution(rec)
            if res > RESOLUTION_FLOOR:
                problems[parts[0]] = rec
            else:
                unresolved[parts[0]] = res
        elif parts[-1] == "reference":
            refs[(parts[0], parts[1])] = rec
    cells: dict[tuple, dict[str, Any]] = defaultdict(lambda: {"starts": 0, "success": 0, "times": [], "setup": 0.0,
                                                              "problems": set()})
    for rec in log.records():
        parts = rec["key"].split("/")
        if len(parts) != 5 or parts[0] not in problems:
            continue
        name, noise_key, kind, method, what = parts
        prob = problems[name]
        cell = cells[(prob["cls"], method, noise_key, kind)]
        by_size = cells[(f"n={prob['n']}", method, noise_key, kind)]
        if what == "rerun":  # the marker of a finished rerun (--rerun), not a start
            continue
        if what == "setup":
            cell["setup"] += float(rec.get("setup_time", 0.0))
            by_size["setup"] += float(rec.get("setup_time", 0.0))
            continue
        globally = bool(prob["info"].get("global", False))
        model_positive = np.asarray([True] * prob["n_parameters"])  # every generated parameter is declared positive
        ref = None if noise_key == "noise0" else refs.get((name, noise_key))
        ok = start_success(rec.get("theta"), rec.get("cost"), np.asarray(prob["truth"]), model_positive, globally,
                           ref)
        for c in (cell, by_size):
            c["starts"] += 1
            c["success"] += int(ok)
            c["times"].append(float(rec["wall_time"]))
            c["problems"].add(name)
    rows, size_rows = [], []
    for (cls, method, noise_key, kind), c in sorted(cells.items()):
        if not c["starts"]:  # a method set up whose starts have not finished yet
            continue
        total = c["setup"] + sum(c["times"])
        row = {"class": cls, "method": method, "noise": float(noise_key.removeprefix("noise")), "starts_kind": kind,
               "problems": len(c["problems"]), "starts": c["starts"], "successes": c["success"],
               "success_rate": c["success"] / c["starts"], "median_time": float(np.median(c["times"])),
               "time_to_solution": total / c["success"] if c["success"] else None}
        (size_rows if cls.startswith("n=") else rows).append(row)
    sizes = defaultdict(set)
    for prob in problems.values():
        sizes[prob["cls"]].add(int(prob["n"]))
    return {"rows": rows, "size_rows": size_rows, "problems": len(problems),
            "sizes": {k: sorted(v) for k, v in sizes.items()}, "runs": runs,
            "unresolved": {k: unresolved[k] for k in sorted(unresolved)}}


def print_table(summary: dict[str, Any]) -> None:
    head = ("class", "method", "noise", "starts", "problems", "success", "median s/start", "time to solution s")
    print(" | ".join(head))
    for r in [*summary["rows"], *summary["size_rows"]]:
        rate = "—" if r["success_rate"] is None else f"{r['successes']}/{r['starts']} ({100 * r['success_rate']:.0f} %)"
        med = "—" if r["median_time"] is None else f"{r['median_time']:.3g}"
        tts = "inf" if r["time_to_solution"] is None else f"{r['time_to_solution']:.3g}"
        print(" | ".join([r["class"], r["method"], f"{r['noise']:g}", r["starts_kind"], str(r["problems"]), rate, med,
                          tts]))


def redo_references(log: RunLog, timeout: float) -> None:
    """Every logged reference computed again by this code (the new records supersede the old ones)."""
    keys = [r["key"] for r in log.records() if r["key"].endswith("/reference")]
    for i, key in enumerate(keys):
        name, noise_key, _ = key.split("/")
        prob = log.get(f"{name}/problem")
        if prob is None:
            continue
        p = _problem(log, prob["cls"], int(prob["n"]), int(prob["index"]), timeout)
        noise = float(noise_key.removeprefix("noise"))
        old = log.get(key)
        log.forget(key)
        t0 = time.perf_counter()
        new = _reference(log, p, noise, p.data(noise=noise, seed=0))
        before = parameter_error(old["theta"], p.truth)  # recomputed: old records may hold another definition
        print(f"[{i + 1}/{len(keys)}] {key}: error {before:.3g} -> {new['error']:.3g}, misfit "
              f"{old['cost']:.4g} -> {new['cost']:.4g} ({new['method']}: {new['status']}, "
              f"{time.perf_counter() - t0:.1f} s)",
              flush=True)


def recheck(log: RunLog, timeout: float) -> None:
    """Every logged problem the grid resolves checked again by this code's :func:`symid.identifiability` (the new
    problem records supersede the old ones): a verdict the checker could not decide when the problem was drawn may
    be decided now, and whether a problem is proven globally identifiable selects its success rule."""
    todo = [r for r in log.records() if r["key"].endswith("/problem") and _logged_resolution(r) > RESOLUTION_FLOOR]
    for i, rec in enumerate(todo):
        p = make_problem(rec["cls"], int(rec["n"]), int(rec["index"]), check=False, draw=rec["info"]["draw"])
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rep = si.identifiability(p.model, timeout=timeout)
        info = {**rec["info"], **identifiability_info(rep), "rechecked": git_commit()}
        seconds = time.perf_counter() - t0
        log.append(rec["key"], {**{k: v for k, v in rec.items() if k != "key"}, "info": info, "check_time": seconds})
        print(f"[{i + 1}/{len(todo)}] {rec['key'].removesuffix('/problem')}: {rec['info'].get('identifiability')} "
              f"-> {rep.verdict} (global: {rec['info'].get('global')} -> {info['global']}; {seconds:.1f} s)",
              flush=True)


def _floats(text: str) -> list[float]:
    return [float(v) for v in text.split(",") if v]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--classes", default=",".join(CLASSES))
    ap.add_argument("--sizes", default="2,3,5,8", help="masses / states / compartments (default %(default)s)")
    ap.add_argument("--problems", type=int, default=2, help="problems per class and size (default %(default)s)")
    ap.add_argument("--starts", type=int, default=3, help="starts of each kind (default %(default)s)")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--noise", default="0,0.01", help="relative noise levels (default %(default)s)")
    ap.add_argument("--kinds", default="informed,uninformed")
    ap.add_argument("--time-limit", type=float, default=60.0, help="seconds per start (default %(default)s)")
    ap.add_argument("--check-timeout", type=float, default=30.0, help="identifiability check budget (s)")
    ap.add_argument("--workers", type=int, default=1, help="local worker processes (default: serial)")
    ap.add_argument("--dask", default=None, help="address of a Dask scheduler to run the starts on")
    ap.add_argument("--log", default=str(RESULTS / "population.jsonl"))
    ap.add_argument("--out", default=str(RESULTS / "population.json"))
    ap.add_argument("--fresh", action="store_true", help="start over: discard the log")
    ap.add_argument("--summary-only", action="store_true", help="rebuild the summary from the log; run nothing")
    ap.add_argument("--redo-references", action="store_true",
                    help="compute every logged noisy reference (IPOPT and lm started at the truth, the lower "
                         "misfit) again with this code, then rebuild the summary: the noisy successes are "
                         "judged against the new references")
    ap.add_argument("--recheck", action="store_true",
                    help="check every logged problem's identifiability again with this code (budget --check-timeout), "
                         "then rebuild the summary: a problem now proven globally identifiable is judged by its "
                         "parameter error alone")
    ap.add_argument("--progress", action="store_true", help="progress bars per method")
    ap.add_argument("--rerun", default="", help="methods whose logged starts are run again by this commit "
                    "(e.g. after a change to the method; the new records supersede the old ones)")
    args = ap.parse_args(argv)
    args.classes = [c for c in args.classes.split(",") if c]
    bad = sorted(set(args.classes) - set(CLASSES))
    if bad:
        ap.error(f"unknown classes {bad}; choose among {', '.join(CLASSES)}")
    args.methods = [m for m in args.methods.split(",") if m]
    args.rerun = [m for m in args.rerun.split(",") if m]
    args.noise = _floats(args.noise)
    args.kinds = [k for k in args.kinds.split(",") if k]
    sizes = [int(v) for v in args.sizes.split(",") if v]
    log = RunLog(args.log, fresh=args.fresh)
    args.commit = git_commit()
    header = {"commit": args.commit, "machine": platform.machine(), "cpus": os.cpu_count(),
              "python": platform.python_version()}

    def write_summary() -> dict[str, Any]:
        summary = {**header, **summarise(log), "criteria": {
            "noise-free": "largest relative error of any parameter <= 1e-3, or (not proven globally identifiable) "
                          "an exact fit (misfit <= 1e-10) with positive parameters",
            "problems": f"structurally locally identifiable, and a 1e-3 error of any parameter changes the misfit by "
                        f"more than {RESOLUTION_FLOOR:g} (to first order); the others are listed in 'unresolved'",
            "noisy": "largest relative error of any parameter <= 2 x that of the reference (the lower misfit of "
                     "IPOPT and lm started at the truth), or misfit <= the reference's (<= 1.001 x it where not proven "
                     "globally identifiable) with positive parameters"}}
        write_json_atomic(args.out, summary)
        return summary

    if args.summary_only:
        print_table(write_summary())
        return 0
    if args.recheck:
        recheck(log, args.check_timeout)
        print_table(write_summary())
        return 0
    if args.redo_references:
        redo_references(log, args.check_timeout)
        print_table(write_summary())
        return 0
    executor: Executor | None = None
    client = None
    if args.dask:
        import distributed

        client = distributed.Client(args.dask)
        executor = client.get_executor()
    elif args.workers > 1:
        executor = ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn"))
    # which code ran which rows of a log that several runs fill (a resumed run of the same code adds nothing)
    run = {"commit": header["commit"], "methods": args.methods, "sizes": sizes,
           **({"rerun": args.rerun} if args.rerun else {})}
    last = [r for r in log.records() if r["key"].startswith("run/")][-1:]
    if not last or any(last[0].get(k) != v for k, v in run.items()):
        started = time.strftime("%Y-%m-%dT%H:%M:%S")
        log.append(f"run/{started}", {"started": started, **run})
    t0 = time.perf_counter()
    try:
        for n in sizes:  # every class at a size before the next size: a partial run covers every class
            for cls in args.classes:
                if n > MAX_SIZE.get(cls, 8):
                    continue
                accepted = 0
                for index in range(args.problems + EXTRA_INDICES):
                    if accepted == args.problems:
                        break
                    p = _problem(log, cls, n, index, args.check_timeout)
                    if not resolved(p):
                        print(f"{p.name}: skipped, the grid does not resolve a 1e-3 error (resolution "
                              f"{p.info['resolution']:.1e} <= {RESOLUTION_FLOOR:g})", flush=True)
                        continue
                    accepted += 1
                    print(f"{p.name}: {p.model.n_parameters} parameters, {p.info.get('identifiability')}, "
                          f"{time.perf_counter() - t0:.0f} s", flush=True)
                    run_problem(log, p, args, executor)
                    write_summary()
                if accepted < args.problems:
                    print(f"{cls}, n = {n}: only {accepted} of {args.problems} problems resolved in "
                          f"{args.problems + EXTRA_INDICES} indices", flush=True)
    except (KeyboardInterrupt, Interrupted):
        print(f"\ninterrupted: {len(log)} finished runs are kept in {args.log}; run the same command again to "
              f"resume", file=sys.stderr)
        write_summary()
        return 130
    finally:
        if isinstance(executor, ProcessPoolExecutor):
            executor.shutdown(cancel_futures=True)
        if client is not None:
            client.close()
    print_table(write_summary())
    print(f"wrote {args.out} (log: {args.log})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
