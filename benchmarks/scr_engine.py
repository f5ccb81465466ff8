"""Time per SCR iteration of the two back ends of ``symid.scr``, and where it goes.

Three studies, all in one run so that ratios are measured side by side (the machine is
shared; absolute times move with its load, which is recorded):

1. **Belt drive** (thesis (3-17), 10 frequencies, the thesis's Algorithm 3.1 with the
   whole 3×3 block of A(θ)Γᵢ = jωᵢΓᵢ − B(θ) kept bilinear, ``presolve=False``: 10 complex
   blocks, M of 12×8 each in the real representation (2-8)), from θ* + 0.1·N(0, 1).
   Both back ends with their default options, alternated three times; per-iteration time
   is the median over iterations 2… (iteration 1 holds cvxpy's compilation and ADMM's
   cold start). Also the iterations and time each needs to bring the bilinear residual
   below 1e-5 and 1e-7, and the mean time per iteration over those runs (ADMM sub-problems
   need more inner steps as the tolerance tightens with the residual). With presolve the
   product solves this problem exactly (the known rows fix every Γᵢ); this is the thesis's formulation.
2. **Scaling in s and block size b** (synthetic stand-in for (3-15)): s blocks, one per
   frequency, A(θ)Γᵢ = jωᵢΓᵢ − b(θ) with θ ∈ R⁴ shared, Γᵢ ∈ C^{b×1} private, random dense
   coefficients so nothing is presolved away. ADMM runs exactly 50 inner iterations per
   SCR iteration (tolerances 0, fixed ρ) so that the work per iteration is comparable
   across sizes; cvxpy where its compile time stays reasonable.
3. **Growth**: the exponent k of time per SCR iteration ∝ s^k, fitted per block size on
   process CPU time (wall time on a shared 2-core machine moves by 2–3× with other jobs).

Run (one BLAS thread: with threaded BLAS the many small solves of the ADMM back end run
slower on this 2-core machine)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/scr_engine.py

Prints tables and writes ``benchmarks/results/scr_engine.json``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from symid import scr
from symid.runlog import write_json_atomic

TARGET_SPEEDUP = 10.0  # issue 3: ADMM ≥ 10× faster per SCR iteration than cvxpy on the belt drive
FIXED = scr.ADMMOptions(inner=50, inner_first=50, inner_max=50, eps_abs=0.0, eps_rel=0.0, adaptive_rho=False)
PARTS = ("build", "factor", "solve", "svd", "projection", "bookkeeping")
MAX_G_ENTRIES = 2.5e7  # skip grid points whose batched (s, p·q, u) coefficient array exceeds ~200 MB


def synthetic(s: int, b: int, seed: int = 0) -> tuple[scr.BilinearProblem, dict]:
    """s complex blocks A(θ) Γᵢ = jωᵢ Γᵢ − b(θ), Γᵢ ∈ C^{b×1}, θ ∈ R⁴, random dense coefficients."""
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
    """Thesis (3-17) on 10 frequencies in 2π·(0.4…0.6) rad/s, Γ substitution (3-10), output equation (3-10b)."""
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


def measure(prob: scr.BilinearProblem, x0: dict, backend: str, iters: int, presolve: bool = True,
            admm: scr.ADMMOptions | None = None) -> dict:
    """Run ``iters`` SCR iterations; per-iteration statistics over iterations 2…

    Besides wall times, the process CPU time of each iteration (``timing["cpu"]``): on a
    shared machine it is far less disturbed by other jobs than wall time, so ratios are
    also given on it and growth exponents are fitted on it. Medians describe a typical
    iteration, means the whole run (ADMM iterations vary with their inner step count).
    """
    t0 = time.perf_counter()
    sol = scr.solve(prob, x0=x0, backend=backend, max_iter=iters, tol=1e-14, presolve=presolve, admm=admm)
    total = time.perf_counter() - t0
    hist = sol.history[1:] or sol.history
    cpu = [h.timing["cpu"] for h in hist]
    out = {
        "backend": backend, "iterations": sol.iterations, "status": sol.status, "total_s": total,
        "cpu_per_iter_ms": 1e3 * float(np.median(cpu)), "cpu_mean_iter_ms": 1e3 * float(np.mean(cpu)),
        "mean_iter_ms": 1e3 * float(np.mean([h.time for h in hist])),
        "setup_s": sol.info.get("setup_time", 0.0) + sol.info.get("presolve_time", 0.0),
        "first_iter_ms": 1e3 * sol.history[0].time,
        "per_iter_ms": 1e3 * float(np.median([h.time for h in hist])),
        "breakdown_ms": {k: 1e3 * float(np.median([h.timing.get(k, 0.0) for h in hist])) for k in PARTS},
        "final_residual": sol.residual,
    }
    if backend == "admm":
        inner = [int(h.timing["inner_iterations"]) for h in hist]
        out["inner_per_iter"] = float(np.median(inner))
        out["per_inner_us"] = 1e6 * float(sum(h.time for h in hist) / max(1, sum(inner)))
        out["rho_final"] = sol.info.get("rho_final")
    else:
        out["compile_s"] = sol.info.get("compile_time")
        out["compilations"] = sol.info.get("compilations")
    return out


def to_residual(prob: scr.BilinearProblem, x0: dict, backend: str, level: float, max_iter: int,
                presolve: bool) -> dict:
    """Iterations and wall time until the bilinear residual first drops to ``level``."""
    t0 = time.perf_counter()
    sol = scr.solve(prob, x0=x0, backend=backend, max_iter=max_iter, tol=level, step_tol=1e9, presolve=presolve)
    wall = time.perf_counter() - t0
    res = np.array([h.residual for h in sol.history])
    hit = np.flatnonzero(res <= level)
    k = int(hit[0]) + 1 if hit.size else None
    return {"backend": backend, "level": level, "iterations": k, "reached": k is not None,
            "time_s": wall if k is not None else None, "final_residual": float(res[-1]) if res.size else None,
            "mean_iter_ms": 1e3 * float(np.mean([h.time for h in sol.history[1:]])) if res.size > 1 else None,
            "compile_s": sol.info.get("compile_time"),
            "inner_total": int(sum(sol.info.get("inner_iterations", []))) if backend == "admm" else None}


def fmt_parts(parts: dict) -> str:
    return " ".join(f"{k}={v:.2f}" for k, v in parts.items() if v > 0.005)


def belt_study(reps: int) -> dict:
    prob, x0 = belt_drive()
    print("\n1. Belt drive (3-17), 10 frequencies, whole 3×3 block bilinear (presolve=False)")
    hdr = (f"{'rep':>4}{'backend':>8}{'iters':>6}{'1st ms':>9}{'ms/iter':>9}{'cpu ms':>9}{'inner':>7}{'µs/inner':>9}"
           f"  breakdown ms (wall)")
    print(hdr)
    print("-" * len(hdr))
    runs = []
    for rep in range(reps):
        for backend, iters in (("cvxpy", 8), ("admm", 30)):
            r = measure(prob, x0, backend, iters, presolve=False)
            r["rep"] = rep
            runs.append(r)
            print(f"{rep:>4}{backend:>8}{r['iterations']:>6}{r['first_iter_ms']:>9.1f}{r['per_iter_ms']:>9.2f}"
                  f"{r['cpu_per_iter_ms']:>9.2f}{r.get('inner_per_iter', 0):>7.0f}"
                  f"{r.get('per_inner_us', 0) or 0:>9.1f}  {fmt_parts(r['breakdown_ms'])}", flush=True)
    pairs = list(zip(runs[0::2], runs[1::2], strict=True))

    def ratio(key: str) -> float:
        return float(np.median([c[key] / a[key] for c, a in pairs]))

    med = {b: float(np.median([r["per_iter_ms"] for r in runs if r["backend"] == b])) for b in ("cvxpy", "admm")}
    speedup, cpu_speedup = ratio("per_iter_ms"), ratio("cpu_per_iter_ms")
    mean_speedup, cpu_mean_speedup = ratio("mean_iter_ms"), ratio("cpu_mean_iter_ms")
    ratios = [c["per_iter_ms"] / a["per_iter_ms"] for c, a in pairs]
    met = min(speedup, cpu_speedup) >= TARGET_SPEEDUP
    print(f"typical (median) SCR iteration: cvxpy {med['cvxpy']:.1f} ms, ADMM {med['admm']:.2f} ms → ADMM "
          f"{speedup:.1f}× faster in wall time (per rep {', '.join(f'{x:.1f}' for x in ratios)}), {cpu_speedup:.1f}× "
          f"in CPU time; target ≥ {TARGET_SPEEDUP:g}×: {'met' if met else 'MISSED'}")
    print(f"mean over iterations 2…: ADMM {mean_speedup:.1f}× faster in wall time, {cpu_mean_speedup:.1f}× in CPU time")
    reach = []
    for level in (1e-5, 1e-7):
        pair = [to_residual(prob, x0, "cvxpy", level, 150, False), to_residual(prob, x0, "admm", level, 300, False)]
        reach += pair
        for r in pair:
            if r["reached"]:
                steps = f", {r['inner_total']} ADMM steps" if r["inner_total"] else ""
                print(f"  {r['backend']:>6}: bilinear residual ≤ {level:g} after {r['iterations']} SCR iterations, "
                      f"{r['time_s']:.2f} s (mean {r['mean_iter_ms']:.1f} ms per iteration after the first{steps})")
            else:
                print(f"  {r['backend']:>6}: residual {level:g} not reached (final {r['final_residual']:.2e})")
        if all(r["reached"] for r in pair):
            print(f"  to {level:g}: ADMM {pair[0]['time_s'] / pair[1]['time_s']:.1f}× less wall time, mean time per "
                  f"iteration ratio {pair[0]['mean_iter_ms'] / pair[1]['mean_iter_ms']:.1f}×")
    return {"runs": runs, "speedup_per_iteration": speedup, "speedups": ratios, "cpu_speedup_per_iteration":
            cpu_speedup, "mean_speedup": mean_speedup, "cpu_mean_speedup": cpu_mean_speedup, "median_ms": med,
            "target_met": met, "to_residual": reach}


def grid_study(grid_s: list[int], grid_b: list[int], cvxpy_s_max: int, cvxpy_b_max: int) -> tuple[list, dict]:
    print("\n2. Synthetic blocks: ADMM with exactly 50 inner iterations per SCR iteration; cvxpy/Clarabel")
    hdr = (f"{'s':>6}{'b':>4}{'M block':>9}{'backend':>8}{'setup s':>9}{'ms/iter':>10}{'cpu ms':>10}{'µs/inner':>10}"
           f"{'vs cvxpy':>9}  breakdown ms (wall)")
    print(hdr)
    print("-" * len(hdr))
    rows = []
    for b in grid_b:
        for s in grid_s:
            p, q = 4 * b, 2 * (b + 1)  # real representation of the (2b)×(b+1) complex M of (2-6)
            if s * p * q * (4 + 2 * b) > MAX_G_ENTRIES:
                continue
            prob, x0 = synthetic(s, b)
            ra = measure(prob, x0, "admm", 4, admm=FIXED)
            ra.update({"s": s, "b": b, "block": [p, q]})
            rows.append(ra)
            rc = None
            if s <= cvxpy_s_max and b <= cvxpy_b_max:
                rc = measure(prob, x0, "cvxpy", 3)
                rc.update({"s": s, "b": b, "block": [p, q]})
                rows.append(rc)
                ra["speedup_vs_cvxpy"] = rc["cpu_per_iter_ms"] / ra["cpu_per_iter_ms"]
            for r in (ra, rc):
                if r is None:
                    continue
                sp = f"{r['speedup_vs_cvxpy']:.1f}×" if "speedup_vs_cvxpy" in r else ""
                setup = r["setup_s"] + (r.get("compile_s") or 0.0)
                print(f"{s:>6}{b:>4}{f'{p}×{q}':>9}{r['backend']:>8}{setup:>9.3f}{r['per_iter_ms']:>10.2f}"
                      f"{r['cpu_per_iter_ms']:>10.2f}"
                      f"{(r.get('per_inner_us') or 0):>10.1f}{sp:>9}  {fmt_parts(r['breakdown_ms'])}", flush=True)
    growth = {}
    for b in grid_b:
        pts = sorted((r["s"], r["cpu_per_iter_ms"]) for r in rows if r["b"] == b and r["backend"] == "admm")
        if len(pts) >= 3:
            ss, tt = np.log([x[0] for x in pts]), np.log([x[1] for x in pts])
            growth[b] = {"k_all": float(np.polyfit(ss, tt, 1)[0]),
                         "k_upper": float(np.polyfit(ss[-3:], tt[-3:], 1)[0]), "s": [x[0] for x in pts]}
    print("\n3. ADMM CPU time per SCR iteration ∝ s^k (k over all s; k over the three largest s):")
    for b, g in growth.items():
        print(f"   b = {b:>2}: k = {g['k_all']:.2f}, k(largest s) = {g['k_upper']:.2f}  (s = {g['s']})")
    return rows, growth


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small grid only, one belt-drive repetition")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "scr_engine.json"))
    args = ap.parse_args()
    grid_s = [10, 100] if args.quick else [10, 30, 100, 300, 1000]
    grid_b = [2, 3] if args.quick else [2, 3, 5, 10, 20]
    load0 = os.getloadavg()
    print(f"threads: OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}, "
          f"load average at start {load0[0]:.2f} on {os.cpu_count()} cores")
    t0 = time.perf_counter()
    belt = belt_study(1 if args.quick else 3)
    rows, growth = grid_study(grid_s, grid_b, cvxpy_s_max=100, cvxpy_b_max=5)
    load1 = os.getloadavg()
    print(f"\nload average at end {load1[0]:.2f}; total {time.perf_counter() - t0:.0f} s")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out, {
        "complete": True, "machine": platform.platform(), "python": platform.python_version(),
        "cores": os.cpu_count(), "omp_threads": os.environ.get("OMP_NUM_THREADS"),
        "load_average": [load0[0], load1[0]], "belt_drive": belt, "grid": rows, "admm_growth_exponent": growth,
        "admm_fixed_options": {"inner": FIXED.inner, "eps_abs": FIXED.eps_abs, "adaptive_rho": FIXED.adaptive_rho},
    })
    print(f"wrote {out}")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:  # timings: nothing to resume; the summary is written only at the end
        print("\ninterrupted: no summary written (the previous one, if any, is untouched)", file=sys.stderr)
        raise SystemExit(130) from None
