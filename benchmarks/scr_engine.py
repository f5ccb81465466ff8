"""Time per SCR iteration of the two back ends on problems of growing size.

Problem family (a synthetic stand-in for the frequency-response formulation (3-15)):
s blocks, one per frequency ω_i, each the complex bilinear term
A(θ) Γ_i = jω_i Γ_i − b(θ) with θ ∈ R^4 shared and Γ_i ∈ C^{b×1} private; A(θ), b(θ)
have random dense coefficients, so presolve cannot remove anything and every block
stays in the nuclear norm (real representation (2-8): M is 4b × 2(b+1) per block).
The "belt drive" row is the thesis's (3-17) with 10 frequencies and the whole 3×3
block kept bilinear (``presolve=False``), the size quoted in the issue.

Run (pin BLAS to one thread, scr-lessons 12)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/scr_engine.py

Prints a table and writes ``benchmarks/results/scr_engine.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from symid import scr


def synthetic(s: int, b: int, seed: int = 0) -> tuple[scr.BilinearProblem, dict]:
    rng = np.random.default_rng(seed)
    nth = 4
    theta = scr.Variable("theta", (nth,))
    gs = [scr.Variable(f"G{i}", (b, 1), complex=True) for i in range(s)]
    A0 = rng.standard_normal((b, b)) / np.sqrt(b)
    Ak = rng.standard_normal((b, b, nth)) / np.sqrt(b)
    Bk = rng.standard_normal((b, 1, nth))
    w = np.logspace(-1, 1, s)
    eye = np.eye(b).reshape(b, 1, b, 1)
    terms = [scr.Bilinear(A=scr.Affine(A0, {theta: Ak}), P=np.eye(b), B=scr.Affine(np.zeros((b, 1)), {g: eye}),
                          C=scr.Affine(np.zeros((b, 1)), {g: 1j * wi * eye, theta: -Bk}))
             for g, wi in zip(gs, w, strict=True)]
    prob = scr.BilinearProblem(variables=[theta, *gs], bilinear=terms)
    x0 = {"theta": rng.standard_normal(nth)}
    for g in gs:
        x0[g.name] = rng.standard_normal((b, 1)) + 1j * rng.standard_normal((b, 1))
    return prob, x0


def belt_drive(s: int = 10) -> tuple[scr.BilinearProblem, dict]:
    th = np.array([-1, -0.5, -0.2, -0.15])  # thesis (3-18)
    A0 = np.array([[0, -1, 0.15], [0.2, 0, 0], [0, 0, 0]])
    Ak = np.zeros((3, 3, 4))
    Ak[2, 0, 0] = Ak[2, 1, 1] = Ak[2, 2, 2] = 1
    Bk = np.zeros((3, 1, 4))
    Bk[2, 0, 3] = 1
    Cm = np.array([[0, 1, 0.0]])
    w = 2 * np.pi * np.logspace(np.log10(0.4), np.log10(0.6), s)
    H = [Cm @ np.linalg.solve(1j * wi * np.eye(3) - (A0 + Ak @ th), Bk @ th) for wi in w]
    theta = scr.Variable("theta", (4,))
    gs = [scr.Variable(f"G{i}", (3, 1), complex=True) for i in range(s)]
    eye = np.eye(3).reshape(3, 1, 3, 1)
    terms = [scr.Bilinear(A=scr.Affine(A0, {theta: Ak}), P=np.eye(3), B=scr.Affine(np.zeros((3, 1)), {g: eye}),
                          C=scr.Affine(np.zeros((3, 1)), {g: 1j * wi * eye, theta: -Bk}))
             for g, wi in zip(gs, w, strict=True)]
    eqs = [scr.Affine(-Hi, {g: Cm.reshape(1, 1, 3, 1)}) for g, Hi in zip(gs, H, strict=True)]
    prob = scr.BilinearProblem(variables=[theta, *gs], bilinear=terms, equalities=eqs)
    rng = np.random.default_rng(1)
    return prob, {"theta": th + 0.1 * rng.standard_normal(4)}


def measure(prob: scr.BilinearProblem, x0: dict, backend: str, iters: int, presolve: bool = True) -> dict:
    t0 = time.perf_counter()
    sol = scr.solve(prob, x0=x0, backend=backend, max_iter=iters, tol=1e-12, presolve=presolve)
    total = time.perf_counter() - t0
    times = np.array([h.time for h in sol.history])
    steady = times[1:] if times.size > 1 else times
    out = {
        "backend": backend, "iterations": sol.iterations, "status": sol.status, "total_s": total,
        "setup_s": sol.info.get("setup_time", 0.0) + sol.info.get("presolve_time", 0.0),
        "first_iter_ms": 1e3 * float(times[0]) if times.size else None,
        "per_iter_ms": 1e3 * float(np.median(steady)) if times.size else None,
        "final_residual": sol.history[-1].residual if sol.history else None,
    }
    keys = ("build", "factor", "solve", "svd", "projection", "bookkeeping")
    parts = {k: 1e3 * float(np.median([h.timing.get(k, 0.0) for h in sol.history[1:] or sol.history])) for k in keys}
    out["breakdown_ms"] = {k: v for k, v in parts.items() if v > 0}
    if backend == "admm":
        inner = sol.info["inner_iterations"]
        out["inner_iterations"] = inner
        out["per_inner_us"] = 1e6 * float(np.sum(times[1:]) / max(1, np.sum(inner[1:]))) if len(inner) > 1 else None
    else:
        out["compile_s"] = sol.info.get("compile_time")
        out["compilations"] = sol.info.get("compilations")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small grid only")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "scr_engine.json"))
    args = ap.parse_args()
    grid_s = [10, 100] if args.quick else [10, 30, 100, 300, 1000]
    grid_b = [2, 3] if args.quick else [2, 3, 5, 10, 20]
    rows = []
    print(f"threads: OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}")
    hdr = (f"{'problem':<18}{'s':>6}{'b':>4}{'backend':>8}{'iters':>6}{'setup s':>9}{'ms/iter':>10}"
           f"{'inner':>7}{'µs/inner':>9}  breakdown ms")
    print(hdr)
    print("-" * len(hdr))

    def run(name, s, b, prob, x0, backend, iters, presolve=True):
        r = measure(prob, x0, backend, iters, presolve)
        r.update({"problem": name, "s": s, "b": b, "presolve": presolve})
        rows.append(r)
        inner = r.get("inner_iterations")
        print(f"{name:<18}{s:>6}{b:>4}{backend:>8}{r['iterations']:>6}{r['setup_s']:>9.3f}{r['per_iter_ms']:>10.2f}"
              f"{(int(np.median(inner[1:])) if inner and len(inner) > 1 else 0):>7}"
              f"{(r.get('per_inner_us') or 0):>9.1f}  "
              + " ".join(f"{k}={v:.2f}" for k, v in r["breakdown_ms"].items()), flush=True)

    prob, x0 = belt_drive()
    for backend, iters in (("cvxpy", 6), ("admm", 30)):
        run("belt drive (3-15)", 10, 3, prob, x0, backend, iters, presolve=False)
    for b in grid_b:
        for s in grid_s:
            prob, x0 = synthetic(s, b)
            run("synthetic", s, b, prob, x0, "admm", 20)
            if s <= 100 and s * (2 * b + 1) ** 2 <= 20000:  # keep the interior-point runs to minutes
                run("synthetic", s, b, prob, x0, "cvxpy", 4)
    bd = {r["backend"]: r for r in rows if r["problem"].startswith("belt")}
    speedup = bd["cvxpy"]["per_iter_ms"] / bd["admm"]["per_iter_ms"]
    print(f"\nbelt drive: ADMM {bd['admm']['per_iter_ms']:.2f} ms/iter vs cvxpy "
          f"{bd['cvxpy']['per_iter_ms']:.1f} ms/iter → {speedup:.1f}× faster per SCR iteration")
    growth = {}
    for b in grid_b:
        pts = sorted((r["s"], r["per_iter_ms"] / max(1, np.median(r["inner_iterations"][1:])))
                     for r in rows if r["problem"] == "synthetic" and r["b"] == b and r["backend"] == "admm")
        if len(pts) >= 2:
            ss, tt = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
            growth[b] = float(np.polyfit(ss, tt, 1)[0])
    print("ADMM time per inner iteration ~ s^k, fitted k per block size: "
          + ", ".join(f"b={b}: {k:.2f}" for b, k in growth.items()))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"machine": platform.platform(), "python": platform.python_version(),
                               "omp_threads": os.environ.get("OMP_NUM_THREADS"), "rows": rows,
                               "belt_drive_speedup": speedup, "admm_growth_exponent": growth}, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
