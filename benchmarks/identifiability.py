"""Wall time of the full identifiability report on every zoo model except the truss, cold process.

Each model runs in a fresh interpreter (``python -c "import symid; ..."``), so the time
includes importing sympy and symid: what a user waits for at the command line.

Run ``python benchmarks/identifiability.py`` (options: ``--timeout S`` for the global
step, default 30 s as in :func:`symid.structural`; ``--models a b``). Prints a table
and writes ``benchmarks/results/identifiability.json``. Target: each under 2 s.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

MODELS = ("belt_drive", "belt_drive_dorf", "enose", "enose_overparameterized", "compartment_catenary",
          "mass_damper_2dof", "msd3_psd", "msd3_similarity", "random5")
TARGET_S = 2.0

_SNIPPET = """
import json, time
t0 = time.perf_counter()
import symid
t1 = time.perf_counter()
rep = symid.structural(symid.load_model({name!r}).model, timeout={timeout!r})
t2 = time.perf_counter()
print(json.dumps({{"import_s": t1 - t0, "report_s": t2 - t1, "verdict": rep.verdict,
                  "global_determined": rep.global_determined, "n_solutions": rep.n_solutions,
                  "n_solutions_complex": rep.n_solutions_complex, "n_parameters": len(rep.parameters),
                  "combinations": [c["expression"] for c in rep.combinations],
                  "timing": rep.timing}}))
"""


def run_one(name: str, timeout: float) -> dict:
    """Time one cold report in a subprocess."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", _SNIPPET.format(name=name, timeout=timeout)],
                          capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        return {"model": name, "wall_s": wall, "error": proc.stderr.strip().splitlines()[-1:]}
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out.update(model=name, wall_s=wall)
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark, print the table, write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=30.0, help="global-step deadline (s), default 30")
    parser.add_argument("--models", nargs="*", default=list(MODELS))
    args = parser.parse_args(argv)
    rows = [run_one(name, args.timeout) for name in args.models]
    print(f"{'model':26s} {'wall s':>7s} {'import':>7s} {'report':>7s}  verdict  k      within {TARGET_S:g} s")
    for r in rows:
        if "error" in r:
            print(f"{r['model']:26s} {r['wall_s']:7.2f}  ERROR {r['error']}")
            continue
        verdict = r["verdict"] if r["global_determined"] else f"{r['verdict']} (global undetermined)"
        k = "inf" if r["n_solutions"] is None and r["global_determined"] else str(r["n_solutions"])
        ok = "yes" if r["wall_s"] < TARGET_S else "NO"
        print(f"{r['model']:26s} {r['wall_s']:7.2f} {r['import_s']:7.2f} {r['report_s']:7.2f}  "
              f"{verdict:8s} {k:6s} {ok}")
    out = {"benchmark": "identifiability", "target_s": TARGET_S, "timeout_s": args.timeout,
           "python": sys.version.split()[0], "machine": platform.machine(), "rows": rows}
    path = Path(__file__).resolve().parent / "results" / "identifiability.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
