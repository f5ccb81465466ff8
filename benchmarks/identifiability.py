"""Wall time of the full identifiability report on every zoo model except the truss, cold process.

Each model runs in a fresh interpreter (``python -c "import symid; ..."``), so the time
includes importing sympy and symid and loading the zoo entry: what a user waits for at
the command line. Columns: ``wall`` (whole process), ``cpu`` (user + system CPU time of
the process: close to what the wall time is on an idle machine, and much less sensitive
to other jobs than the wall time), ``import`` (``import symid``), ``load``
(``symid.load_model``), ``report`` (``symid.identifiability``); the last three are wall.

Run ``python benchmarks/identifiability.py`` (options: ``--timeout S``, the budget of
:func:`symid.identifiability`, default 30 s as there; ``--models a b``). Prints a table
and writes ``benchmarks/results/identifiability.json``. Target: each under 2 s.

``--families [chain chain_mid shear rlc catenary mammillary cycle]`` runs the model families of
``benchmarks/identifiability_models.py`` instead (issue 17: the structures users write,
up to 24 parameters; ``--max-parameters``), each cold with ``--timeout`` (default there
10 s), and writes ``benchmarks/results/identifiability_families.json``: per model the
wall time and whether the report is complete (no "local, global undetermined").
``--families chain_at`` runs every placement of force and position sensor on chains of 3 to 8
masses instead (116 models, about 15 minutes) and writes
``benchmarks/results/identifiability_placements.json``.

Column ``verdict``: the model verdict, with ``(proven by witnesses)`` when certified
witnesses settled it before the Gröbner basis finished and ``(global undetermined)``
when nothing settled it. Column ``k``: admissible solutions of summary(θ) = summary(θ*)
(``inf``: positive-dimensional); ``>=j`` when j − 1 other solutions were certified by
the Krawczyk test (a proven lower bound; ``~>=j`` if only verified numerically). A model
settled by witnesses is run a second time with ``exact_count=True`` (the Gröbner step
gets the whole budget) to show what the exact count would cost. The load average is
recorded: the machine is shared, and timings taken under load are inflated; so is the
number of cores the run was allowed (``cpus_usable``: ``taskset -c 1`` makes it 1, and then
the exact step and the witness search share that core). Column ``engine`` of the JSON: which
exact engine ran (``msolve`` when installed, for full-rank models).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

from symid.runlog import write_json_atomic

MODELS = ("belt_drive", "belt_drive_dorf", "enose", "enose_overparameterized", "compartment_catenary",
          "mass_damper_2dof", "msd3_psd", "msd3_similarity", "random5")
TARGET_S = 2.0

_SNIPPET = """
import json, sys, time
t0 = time.perf_counter()
import symid
t1 = time.perf_counter()
if {family!r}:
    sys.path.insert(0, {here!r})
    import identifiability_models
    model = identifiability_models.build({name!r})
else:
    model = symid.load_model({name!r}).model
t2 = time.perf_counter()
rep = symid.identifiability(model, timeout={timeout!r}, exact_count={exact!r})
t3 = time.perf_counter()
print(json.dumps({{"import_s": t1 - t0, "load_s": t2 - t1, "report_s": t3 - t2, "verdict": rep.verdict,
                  "global_determined": rep.global_determined, "n_solutions": rep.n_solutions,
                  "n_solutions_complex": rep.n_solutions_complex, "n_witnesses": len(rep.witnesses),
                  "verdicts": rep.verdicts, "solution_count": rep.solution_count,
                  "n_certified": sum(rep.witnesses_certified), "verdicts_proven": rep.verdicts_proven,
                  "n_solutions_at_least": rep.n_solutions_at_least,
                  "n_parameters": len(rep.parameters),
                  "combinations": [c["expression"] for c in rep.combinations],
                  "engine": rep.engine, "timing": rep.timing}}))
"""


def run_one(name: str, timeout: float, exact_count: bool = False, family: bool = False) -> dict:
    """Time one cold report in a subprocess: wall time, and CPU time (user + system) of the child."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    code = _SNIPPET.format(name=name, timeout=timeout, exact=exact_count, family=family,
                           here=str(Path(__file__).resolve().parent))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode != 0:
        return {"model": name, "wall_s": wall, "cpu_s": cpu, "error": proc.stderr.strip().splitlines()[-1:]}
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out.update(model=name, wall_s=wall, cpu_s=cpu, exact_count=exact_count)
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark, print the table, write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=30.0, help="global-step deadline (s), default 30")
    parser.add_argument("--models", nargs="*", default=list(MODELS))
    parser.add_argument("--families", nargs="*", default=None, help="run the model families instead (all if empty)")
    parser.add_argument("--max-parameters", type=int, default=24)
    args = parser.parse_args(argv)
    if args.families is not None:
        return _families(args, parser)
    load_before = os.getloadavg()[0]
    rows = [run_one(name, args.timeout) for name in args.models]
    # a model whose exact global step did not finish: what insisting on the exact count costs
    rows += [run_one(r["model"], args.timeout, exact_count=True) for r in list(rows)
             if not r.get("global_determined", True)]
    load_after = os.getloadavg()[0]
    print(f"{'model':26s} {'wall s':>7s} {'cpu s':>6s} {'import':>7s} {'load':>6s} {'report':>7s}  {'verdict':34s} "
          f"{'k':>6s}  within {TARGET_S:g} s")
    for r in rows:
        if "error" in r:
            print(f"{r['model']:26s} {r['wall_s']:7.2f}  ERROR {r['error']}")
            continue
        if r["global_determined"]:
            verdict = r["verdict"]
            k = "inf" if r["n_solutions"] is None else str(r["n_solutions"])
        elif r["verdicts_proven"]:
            verdict = f"{r['verdict']} (proven by witnesses)"
            k = f">={r['n_solutions_at_least']}"
        else:
            verdict = r["verdict"] if "undetermined" in r["verdict"] else f"{r['verdict']} (global undetermined)"
            k = f"~>={1 + r['n_witnesses']}" if r["n_witnesses"] else "?"
        ok = "yes" if r["wall_s"] < TARGET_S else "NO"
        label = f"{r['model']} (exact_count)" if r["exact_count"] else r["model"]
        print(f"{label:26s} {r['wall_s']:7.2f} {r['cpu_s']:6.2f} {r['import_s']:7.2f} {r['load_s']:6.2f} "
              f"{r['report_s']:7.2f}  "
              f"{verdict:34s} {k:>6s}  {ok}")
    print(f"load average (1 min) before/after: {load_before:.2f}/{load_after:.2f} on {os.cpu_count()} cores, "
          f"niceness {os.nice(0)}")
    out = {"benchmark": "identifiability", "target_s": TARGET_S, "timeout_s": args.timeout,
           "python": sys.version.split()[0], "machine": platform.machine(), "cores": os.cpu_count(),
           "cpus_usable": _cpus_usable(),
           "load_average_before": load_before, "load_average_after": load_after, "niceness": os.nice(0),
           "rows": rows}
    path = Path(__file__).resolve().parent / "results" / "identifiability.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(path, out, indent=2)
    print(f"wrote {path}")
    return 0


def _cpus_usable() -> int | None:
    """How many cores this process may run on (``taskset``), where the OS says."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None


def _complete(row: dict) -> bool:
    return "error" not in row and "local, global undetermined" not in (row["verdict"], *row["verdicts"].values())


def _families(args, parser) -> int:
    """The model families of identifiability_models.py, one cold process each."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import identifiability_models

    timeout = args.timeout if "--timeout" in sys.argv else 10.0
    names = identifiability_models.names(args.families or None, args.max_parameters)
    load_before = os.getloadavg()[0]
    rows = []
    print(f"{'model':22s} {'par':>3s} {'wall s':>7s} {'cpu s':>6s}  {'verdict':28s} {'k (complex)':>11s}  complete")
    for name in names:
        r = run_one(name, timeout, family=True)
        rows.append(r)
        if "error" in r:
            print(f"{name:22s} ERROR {r['error']}", flush=True)
            continue
        k = "inf" if r["verdict"] == "none" else (str(r["n_solutions_complex"]) if r["n_solutions_complex"]
                                                  else (f">={r['n_solutions_at_least']}"
                                                        if r["n_solutions_at_least"] else "?"))
        print(f"{name:22s} {r['n_parameters']:3d} {r['wall_s']:7.2f} {r['cpu_s']:6.2f}  {r['verdict']:28s} {k:>11s}  "
              f"{'yes' if _complete(r) else 'NO'}", flush=True)
    load_after = os.getloadavg()[0]
    ok = [r for r in rows if _complete(r) and r["wall_s"] <= TARGET_S]
    print(f"complete within {TARGET_S:g} s: {len(ok)} of {len(rows)}; load average (1 min) before/after: "
          f"{load_before:.2f}/{load_after:.2f} on {os.cpu_count()} cores")
    out = {"benchmark": "identifiability_families", "target_s": TARGET_S, "timeout_s": timeout,
           "python": sys.version.split()[0], "machine": platform.machine(), "cores": os.cpu_count(),
           "cpus_usable": _cpus_usable(),
           "load_average_before": load_before, "load_average_after": load_after, "niceness": os.nice(0),
           "complete": True, "rows": rows}
    stem = "identifiability_placements" if args.families == ["chain_at"] else "identifiability_families"
    path = Path(__file__).resolve().parent / "results" / f"{stem}.json"
    write_json_atomic(path, out, indent=2)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
