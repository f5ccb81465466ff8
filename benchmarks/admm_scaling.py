"""ADMM back end: one penalty per LMI block (``ADMMOptions.lmi_rho``) and Ruiz equilibration
(``ADMMOptions.equilibrate``), against Clarabel.

Issue 14, item 5: "ADMM preconditioning (per-block and per-variable scaling) so that ADMM
converges on ``msd3_psd``". Variants: ``admm-fixed-lmi`` (one ρ for every block, the back end
before ``lmi_rho``), ``admm`` (the default: the LMI blocks' penalties adapted),
``admm-equilibrated`` (the default with Ruiz equilibration), ``clarabel``. Sections
(``--only`` runs some of them; the others keep their earlier results):

``subproblems``
    Single SCR sub-problems of ``msd3_psd`` (thesis §5-6: 170 frequencies, 18 parameters,
    M, V, K ⪰ 0; P of the 170 terms spans 10 decades), centred at θ* (1 + ε N(0, 1))
    (ε = 0.01, 0.1, 0.3, seed 1): Clarabel's exact solution against ADMM after a fixed
    budget of inner iterations (``--budgets``; tolerances 0, adaptive ρ as by default),
    with one ρ for all blocks, with the LMIs' penalties adapted, and with equilibration
    too. Reported: the relative gap of the relaxation
    (ADMM's value − Clarabel's)/Clarabel's, and the largest parameter difference.
``msd3_psd``
    SCR on ``msd3_psd`` (Algorithm 5.1, random Yᵢ as in §5-6) from ``--starts`` starts
    (``si.compare``, seed ``--seed``), time limit ``--time-limit`` s per start: the three
    ADMM variants and Clarabel, on the same starts. Success: the
    largest relative parameter error ≤ 1e-3 (``si.compare``'s default).
``frf``
    Frequency-response SCR (ADMM, its default back end), the three ADMM variants:
    the belt drive (thesis §3-6) and the 2-DOF mass-damper (thesis §4-6-2), ``--frf-starts``
    starts each; a 3-mass chain of ``benchmarks/population_models.py`` (``chain``, n = 3,
    problem 0: physical values, force on one mass, one position), 5 uninformed starts
    (two decades around the typical values, ``scale=`` them), ``--chain-time-limit`` s
    per start. Success as above; the median and best parameter error are kept too.

Run (one BLAS thread per process; one process at a time on a shared machine)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/admm_scaling.py [--only subproblems]

Prints a table per section and writes ``benchmarks/results/admm_scaling.json`` when every
section is done; runs are logged to ``benchmarks/results/admm_scaling.jsonl`` as they end
(resumable after Ctrl-C; ``--fresh`` starts over). The default run takes about half an
hour, most of it Clarabel's starts on ``msd3_psd`` and the chain's starts.
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
from population_models import make_problem

import symid as si
from symid import scr
from symid.fit.compare import largest_relative_error
from symid.fit.spectra.scr import ScrPSD
from symid.runlog import RunLog

SECTIONS = ("subproblems", "msd3_psd", "frf")
EPSILONS = (0.01, 0.1, 0.3)


def _variants() -> dict[str, dict[str, Any]]:
    return {"admm-fixed-lmi": {"backend": "admm", "admm": scr.ADMMOptions(equilibrate=False, lmi_rho=False)},
            "admm": {"backend": "admm", "admm": scr.ADMMOptions(equilibrate=False)},
            "admm-equilibrated": {"backend": "admm", "admm": scr.ADMMOptions(equilibrate=True)},
            "clarabel": {"backend": "cvxpy"}}


def subproblems(args: argparse.Namespace, log: RunLog) -> dict:
    entry = si.load_model("msd3_psd")
    truth = entry.model.theta_vector(entry.truth)
    est = ScrPSD(entry.model, entry.data(), backend="cvxpy")
    rng = np.random.default_rng(1)
    rows = []
    for eps in EPSILONS:
        x0 = truth * (1 + eps * rng.standard_normal(truth.size))

        def reference(x0: np.ndarray = x0) -> dict:
            t = time.perf_counter()
            ref = scr.solve(est.compiled, {"theta": x0}, backend="cvxpy", max_iter=1)
            return {"relaxation": ref.history[0].relaxation, "theta": ref.x_vector.tolist(),
                    "time": time.perf_counter() - t}

        ref = logged(log, f"eps={eps}/clarabel", reference)
        z_ref = np.asarray(ref["theta"])
        for eq, lmi in ((False, False), (False, True), (True, True)):
            for budget in args.budgets:
                def admm(x0: np.ndarray = x0, eq: bool = eq, lmi: bool = lmi, budget: int = budget) -> dict:
                    opts = scr.ADMMOptions(inner_first=budget, inner_max=budget, eps_abs=0.0, eps_rel=0.0,
                                           tighten=None, equilibrate=eq, lmi_rho=lmi)
                    t = time.perf_counter()
                    sol = scr.solve(est.compiled, {"theta": x0}, backend="admm", max_iter=1, admm=opts)
                    h = sol.history[0]
                    return {"relaxation": h.relaxation, "theta": sol.x_vector.tolist(), "time": time.perf_counter() - t,
                            "rho_final": sol.info["rho_final"], "primal": h.timing["primal_residual"],
                            "dual": h.timing["dual_residual"]}

                r = logged(log, f"eps={eps}/equilibrate={eq}/lmi_rho={lmi}/budget={budget}", admm)
                rows.append({"epsilon": eps, "equilibrate": eq, "lmi_rho": lmi, "budget": budget,
                             "relative_gap": (r["relaxation"] - ref["relaxation"]) / abs(ref["relaxation"]),
                             "max_parameter_difference": float(np.max(np.abs(np.asarray(r["theta"]) - z_ref))),
                             "start_distance": float(np.max(np.abs(x0 - z_ref))), "time": r["time"],
                             "rho_final": r["rho_final"], "clarabel_time": ref["time"]})
    head = (f"{'ε':>5} {'equilibrate':>11} {'lmi_rho':>7} {'inner it.':>9} {'rel. gap':>9} {'max |θ−θ_ref|':>14} "
            f"{'|θ₀−θ_ref|':>11} {'s':>6}")
    print(head)
    print("-" * len(head))
    for r in rows:
        print(f"{r['epsilon']:>5g} {r['equilibrate']!s:>11} {r['lmi_rho']!s:>7} {r['budget']:>9} "
              f"{r['relative_gap']:>9.1e} {r['max_parameter_difference']:>14.2e} {r['start_distance']:>11.2e} "
              f"{r['time']:>6.1f}")
    return {"rows": rows}


def _compare_rows(name: str, model: Any, data: Any, truth: Any, starts: Any, variants: dict[str, dict], seed: int,
                  log: RunLog) -> list[dict]:
    rows = []
    truth_vec = model.theta_vector(truth)
    for label, opts in variants.items():
        cmp = si.compare(model, data, methods=("scr",), options={"scr": opts}, starts=starts, seed=seed,
                         truth=truth, progress=False, log=log.scoped(f"{name}/{label}/"))
        s = cmp["scr"]
        errs = [largest_relative_error(o.theta, truth_vec) for o in s.result.starts]
        rows.append({"problem": name, "variant": label, "starts": s.n_starts, "successes": s.n_success,
                     "median_time_per_start": s.median_time, "time_to_solution": s.time_to_solution,
                     "median_error": float(np.median(errs)), "best_error": float(np.min(errs)),
                     "errors": errs, "statuses": [o.status for o in s.result.starts],
                     "times": [o.wall_time for o in s.result.starts]})
        print(f"{name:>18} {label:>18} {s.n_success:>4}/{s.n_starts:<3} {s.median_time:>10.2f} "
              f"{np.median(errs):>12.2e} {np.min(errs):>12.2e}", flush=True)
    return rows


def _table_head() -> None:
    head = f"{'problem':>18} {'variant':>18} {'succ.':>8} {'median s':>10} {'median err.':>12} {'best err.':>12}"
    print(head)
    print("-" * len(head))


def msd3_psd(args: argparse.Namespace, log: RunLog) -> dict:
    entry = si.load_model("msd3_psd")
    variants = {k: {**v, "time_limit": args.time_limit} for k, v in _variants().items()}
    _table_head()
    rows = _compare_rows("msd3_psd", entry.model, entry.data(), entry.truth, args.starts, variants, args.seed, log)
    by = {r["variant"]: r for r in rows}
    ratios = {k: by["clarabel"]["median_time_per_start"] / by[k]["median_time_per_start"]
              for k in by if k != "clarabel"}
    for k, v in ratios.items():
        print(f"Clarabel / {k} median time per start: {v:.1f}× ({by[k]['successes']}/{by[k]['starts']} successes; "
              f"target ≥ 5× with ≥ 4/5)")
    return {"rows": rows, "time_limit": args.time_limit, "starts": args.starts, "seed": args.seed,
            "clarabel_over_admm_time": ratios}


def frf(args: argparse.Namespace, log: RunLog) -> dict:
    admm = {k: v for k, v in _variants().items() if k != "clarabel"}
    rows = []
    _table_head()
    for name in ("belt_drive", "mass_damper_2dof"):
        entry = si.load_model(name)
        rows += _compare_rows(name, entry.model, entry.data(), entry.truth, args.frf_starts, admm, args.seed, log)
    p = make_problem("chain", 3, 0)
    starts = [p.model.theta_dict(s) for s in p.starts("uninformed", 5)]
    variants = {k: {**v, "scale": p.typical, "time_limit": args.chain_time_limit} for k, v in admm.items()}
    rows += _compare_rows(p.name, p.model, p.data(), p.model.theta_dict(p.truth), starts, variants, args.seed, log)
    return {"rows": rows, "chain_time_limit": args.chain_time_limit}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default=",".join(SECTIONS), help="comma-separated subset of %(default)s")
    parser.add_argument("--budgets", default="2000,10000", help="ADMM inner iterations per sub-problem")
    parser.add_argument("--starts", type=int, default=5, help="msd3_psd starts per variant")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--time-limit", type=float, default=150.0, help="seconds per msd3_psd start")
    parser.add_argument("--frf-starts", type=int, default=10)
    parser.add_argument("--chain-time-limit", type=float, default=60.0)
    parser.add_argument("--out", default=str(RESULTS / "admm_scaling.json"))
    add_log_arguments(parser, "admm_scaling")
    args = parser.parse_args(argv)
    args.budgets = tuple(int(v) for v in args.budgets.split(","))
    only = tuple(s.strip() for s in args.only.split(",") if s.strip())
    if not only or set(only) - set(SECTIONS):
        parser.error(f"--only must name some of {', '.join(SECTIONS)}")
    fns = {"subproblems": subproblems, "msd3_psd": msd3_psd, "frf": frf}
    out = Path(args.out)
    previous = {}
    if out.exists():
        old = json.loads(out.read_text())
        previous = {k: v for k, v in old.items() if k in SECTIONS and k not in only}
    header = {"benchmark": "admm_scaling", "command": " ".join(["benchmarks/admm_scaling.py", *(argv or sys.argv[1:])]),
              "options": {k: v for k, v in vars(args).items() if k not in ("log", "out")},
              "machine": {"platform": platform.platform(), "python": platform.python_version(),
                          "numpy": np.__version__, "cpus": os.cpu_count(), "load_average_start": os.getloadavg()}}
    return run_study({name: (lambda log, fn=fns[name]: fn(args, log)) for name in only}, out=out,
                     log_path=Path(args.log), fresh=args.fresh, header=header, previous=previous)


if __name__ == "__main__":
    raise SystemExit(main())
