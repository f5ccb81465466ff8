"""The comparison studies of thesis §6-7: SCR against ALS, GB and IPOPT on the similarity transformation.

``random`` — §6-7-1, Figure 6-3 (no prior knowledge). The random stable 5th-order SISO
system (6-29), black box = its balanced realisation (the zoo's ``random5`` data; the
printed (6-30) is not a realisation of (6-29), see models/random5.py). For k = 1 … 10
unknown entries, ``--experiments`` experiments (thesis: 100; here 20 by default): each
draws which k entries of (A*, B*, C*) are unknown (``random_parameterisation(k, r)``)
and one random start, T₀ = α·N(0, 1), S₀ = N(0, 1)/α seeded by r, θ₀ by least squares
(C-8), identical for the four methods. Success: NEE = ‖θ* − θ‖/‖θ*‖ ≤ 1e-3 (6-32),
rate (6-33). Thesis: ALS and GB better up to 7 unknowns, SCR better from 8 on, at
least twice as good at 10.

``prior`` — §6-7-2, Figure 6-4 (prior knowledge). The driver belt (6-37), truth all −10
(6-38), black box the zoo's (a seeded similarity transform; the system is unstable).
Starts θ₀ = θ* + ε, ε ~ N(0, σ² I), σ² ∈ {0.01, 0.1, 1, 10, 100} (6-34)–(6-36), 10 runs
per σ², T₀ from θ₀ by least squares (C-7) (``aux_init="model"``). Recorded: ‖θ₀ − θ*‖ and
‖θ − θ*‖ per run and method.

Method settings: SCR with symid's defaults (λ = 1, nuclear norm, ADMM, 1000 iterations;
the thesis used λ = 10 and 500 + 500 nuclear / truncated-nuclear iterations), ALS with
the relative-step stop 1e-6 (6-31) and at most 10 000 sweeps, GB = BFGS with the
analytic gradients (C-12)–(C-18), IPOPT on (6-9).

Every run is appended to ``benchmarks/results/similarity_study_<study>.jsonl`` as soon as
it finishes: an interrupted study keeps what it finished, and running again resumes
(``--fresh`` starts over). At the end the runs are summarised in
``benchmarks/results/similarity_study.json`` and plotted in
``benchmarks/results/similarity_study_<study>.png``.

Run (pin BLAS to one thread)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/similarity_study.py --study random
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/similarity_study.py --study prior
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

import symid as si
from symid.fit.registry import prepare
from symid.progress import progress_bar
from symid.runlog import write_json_atomic

RESULTS = Path(__file__).resolve().parent / "results"
METHODS = ("scr", "als", "gb", "ipopt")
SUCCESS = 1e-3  # thesis (6-32)/(6-33)
SIGMA2 = (0.01, 0.1, 1.0, 10.0, 100.0)  # thesis (6-36)


def _runs_file(study: str) -> Path:
    return RESULTS / f"similarity_study_{study}.jsonl"


def _done(path: Path) -> dict[tuple, dict]:
    """Runs already on file, by key (a run cut off mid-line is ignored and redone)."""
    out = {}
    if path.exists():
        for line in path.read_text().splitlines():
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue
            out[tuple(rec["key"])] = rec
    return out


def _append(path: Path, rec: dict) -> None:
    with path.open("a") as fh:
        fh.write(json.dumps(rec, default=float) + "\n")


def _nee(theta: np.ndarray, truth: np.ndarray) -> float:
    return float(np.linalg.norm(truth - theta) / np.linalg.norm(truth))


def _one(model: Any, data: Any, method: str, options: dict, x0: np.ndarray, truth: np.ndarray) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        solver = prepare(model, data, method, dict(options))
        t0 = time.perf_counter()
        out = solver.run(x0)
    return {"nee": _nee(out.theta, truth), "misfit": out.cost, "time": time.perf_counter() - t0,
            "iterations": out.iterations, "message": out.message}


def random_study(experiments: int, counts: range, fresh: bool) -> list[dict]:
    """§6-7-1: success rate against the number of unknown entries."""
    path = _runs_file("random")
    if fresh and path.exists():
        path.unlink()
    done = _done(path)
    entry = si.load_model("random5")
    data = entry.data()
    todo = [(k, r, m) for k in counts for r in range(experiments) for m in METHODS if (k, r, m) not in done]
    for k, r, method in progress_bar(todo, desc="random5 runs", enabled=True):
        model, truth = entry.extra["random_parameterisation"](k, r)
        tv = model.theta_vector(truth)
        rec = {"key": [k, r, method], "unknowns": k, "experiment": r, "method": method,
               **_one(model, data, method, {"seed": r}, np.zeros(k), tv)}
        _append(path, rec)
        done[(k, r, method)] = rec
    return [done[key] for key in sorted(done)]


def prior_study(runs: int, fresh: bool) -> list[dict]:
    """§6-7-2: final against initial parameter error on the driver belt."""
    path = _runs_file("prior")
    if fresh and path.exists():
        path.unlink()
    done = _done(path)
    entry = si.load_model("belt_drive_dorf")
    model, data = entry.model, entry.data()
    tv = model.theta_vector(entry.truth)
    todo = [(i, r, m) for i in range(len(SIGMA2)) for r in range(runs) for m in METHODS if (i, r, m) not in done]
    for i, r, method in progress_bar(todo, desc="belt drive runs", enabled=True):
        x0 = tv + np.sqrt(SIGMA2[i]) * np.random.default_rng([638, i, r]).standard_normal(tv.size)
        rec = {"key": [i, r, method], "sigma2": SIGMA2[i], "run": r, "method": method,
               "initial_error": float(np.linalg.norm(x0 - tv)),
               **_one(model, data, method, {"aux_init": "model", "allow_unstable": True}, x0, tv)}
        rec["final_error"] = rec["nee"] * float(np.linalg.norm(tv))
        _append(path, rec)
        done[(i, r, method)] = rec
    return [done[key] for key in sorted(done)]


def summarise_random(recs: list[dict]) -> dict:
    out: dict[str, Any] = {"success_threshold": SUCCESS, "rate": {}, "n": {}, "median_time": {}}
    for m in METHODS:
        mine = [x for x in recs if x["method"] == m]
        ks = sorted({x["unknowns"] for x in mine})
        out["rate"][m] = {k: float(np.mean([x["nee"] <= SUCCESS for x in mine if x["unknowns"] == k])) for k in ks}
        out["n"][m] = {k: sum(x["unknowns"] == k for x in mine) for k in ks}
        out["median_time"][m] = {k: float(np.median([x["time"] for x in mine if x["unknowns"] == k])) for k in ks}
    return out


def summarise_prior(recs: list[dict]) -> dict:
    out: dict[str, Any] = {"success_threshold": SUCCESS, "successes": {}, "n": {}}
    for m in METHODS:
        mine = [x for x in recs if x["method"] == m]
        out["successes"][m] = {s: int(sum(x["nee"] <= SUCCESS for x in mine if x["sigma2"] == s)) for s in SIGMA2}
        out["n"][m] = {s: sum(x["sigma2"] == s for x in mine) for s in SIGMA2}
    return out


def plot_random(summary: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for m in METHODS:
        ks = sorted(int(k) for k in summary["rate"][m])
        ax.plot(ks, [100 * summary["rate"][m][k] for k in ks], marker="o", label=m.upper())
    ax.set_xlabel("number of unknown entries")
    ax.set_ylabel(f"success rate (NEE ≤ {SUCCESS:g}) [%]")
    n = max(max(v.values()) for v in summary["n"].values())
    ax.set_title(f"random5 (6-29), {n} experiments per count (thesis Figure 6-3)")
    ax.set_ylim(-5, 105)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_prior(recs: list[dict], path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.5))
    for m, marker in zip(METHODS, "os^D", strict=True):
        mine = [x for x in recs if x["method"] == m]
        ax.scatter([x["initial_error"] for x in mine], [max(x["final_error"], 1e-16) for x in mine],
                   marker=marker, label=m.upper(), alpha=0.7)
    lim = [min(x["initial_error"] for x in recs) / 2, max(x["initial_error"] for x in recs) * 2]
    ax.plot(lim, lim, "k:", label="final = initial")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("‖θ₀ − θ*‖")
    ax.set_ylabel("‖θ − θ*‖")
    ax.set_title("driver belt (6-37), prior knowledge (thesis Figure 6-4)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _table_random(summary: dict) -> str:
    ks = sorted({int(k) for m in METHODS for k in summary["rate"][m]})
    lines = ["unknowns " + " ".join(f"{m:>7s}" for m in METHODS)]
    for k in ks:
        lines.append(f"{k:>8d} " + " ".join(f"{100 * summary['rate'][m].get(k, float('nan')):6.0f}%" for m in METHODS))
    return "\n".join(lines)


def _table_prior(summary: dict) -> str:
    lines = ["sigma^2  " + " ".join(f"{m:>7s}" for m in METHODS)]
    for s in SIGMA2:
        lines.append(f"{s:>7g}  " + " ".join(f"{summary['successes'][m][s]:>3d}/{summary['n'][m][s]:<3d}"
                                            for m in METHODS))
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", choices=("random", "prior", "both"), default="both")
    parser.add_argument("--experiments", type=int, default=20, help="random5 experiments per count (thesis: 100)")
    parser.add_argument("--max-unknowns", type=int, default=10)
    parser.add_argument("--runs", type=int, default=10, help="belt-drive runs per variance (thesis: 10)")
    parser.add_argument("--fresh", action="store_true", help="discard runs on file and start over")
    args = parser.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    summary_path = RESULTS / "similarity_study.json"
    try:
        summary = json.loads(summary_path.read_text()) if summary_path.exists() else {}
    except ValueError:  # a damaged summary is rebuilt from the run logs
        summary = {}
    if args.study in ("random", "both"):
        recs = random_study(args.experiments, range(1, args.max_unknowns + 1), args.fresh)
        summary["random"] = summarise_random(recs) | {"experiments_per_count": args.experiments}
        plot_random(summary["random"], RESULTS / "similarity_study_random.png")
        print(_table_random(summary["random"]))
    if args.study in ("prior", "both"):
        recs = prior_study(args.runs, args.fresh)
        summary["prior"] = summarise_prior(recs) | {"runs_per_variance": args.runs}
        plot_prior(recs, RESULTS / "similarity_study_prior.png")
        print(_table_prior(summary["prior"]))
    write_json_atomic(summary_path, summary)
    print(f"wrote {summary_path}")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        print("\ninterrupted: finished runs are kept in benchmarks/results/similarity_study_*.jsonl; run the same "
              "command again to resume (summary not written)", file=sys.stderr)
        raise SystemExit(130) from None
