"""The ``symid`` command line."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from symid.errors import SymidError

__all__ = ["main"]


def _cmd_models(args: argparse.Namespace) -> int:
    from symid.zoo import list_models, load_model

    for name in list_models():
        entry = load_model(name)
        print(f"{name:28s} {entry.title}  [{entry.source}]")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from symid.zoo import load_model

    print(load_model(args.model).summary())
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from symid.demo import run_demo

    return run_demo(out=args.out)


def _entry_and_data(model_arg: str, data_arg: str | None):
    from symid.data import load
    from symid.zoo import load_model

    entry = load_model(model_arg)
    if data_arg:
        data = load(data_arg)
        source = data_arg
    else:
        data = entry.data()
        source = f"the zoo recipe: {entry.recipe}"
    return entry, data, source


def _method_options(args: argparse.Namespace) -> dict:
    opts = {}
    if getattr(args, "backend", None):
        opts["backend"] = args.backend
    if getattr(args, "max_iter", None):
        opts["max_iter"] = args.max_iter
    return opts


def _cmd_identify(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from symid.identification import identify
    from symid.plots import bode_plot, start_convergence_plot

    entry, data, source = _entry_and_data(args.model, args.data)
    print(f"model: {entry.name}   data: {source}")
    opts = _method_options(args) if args.method == "scr" else {}
    res = identify(entry.model, data, method=args.method, starts=args.starts, seed=args.seed,
                   polish=args.polish, progress=True if args.starts > 1 else None, **opts)
    truth = entry.truth if args.data is None else None
    print(res.summary(truth=truth))
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "result.json").write_text(json.dumps(res.to_dict(), indent=2))
        (out / "summary.txt").write_text(res.summary(truth=truth) + "\n")
        written = [out / "result.json", out / "summary.txt"]
        if hasattr(data, "H"):
            curves = {f"{res.method} estimate": (entry.model, res.theta_vector)}
            if res.polished is not None:
                curves["after polish"] = (entry.model, res.polished.theta_vector)
            written.append(bode_plot(data, curves, out / "bode.png", title=f"{entry.name}: data and estimate"))
        best = res.best_start
        if best.history and "families" in best.history[0]:  # SCR: thesis Figure 3-2 for the reported start
            written.append(start_convergence_plot(
                best, out / "convergence.png", truth=None if truth is None else entry.model.theta_vector(truth),
                title=f"{entry.name}: SCR convergence of the reported start"))
        print("wrote " + ", ".join(str(p) for p in written))
    final = res.polished if res.polished is not None else res
    return 0 if final.success else 1


def _cmd_compare(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from symid.comparison import compare

    entry, data, source = _entry_and_data(args.model, args.data)
    methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    truth = entry.truth if args.data is None else None
    print(f"model: {entry.name}   data: {source}")
    scr_opts = _method_options(args)
    cmp = compare(entry.model, data, methods=methods, starts=args.starts, seed=args.seed, truth=truth,
                  progress=True,
                  options={"scr": scr_opts} if scr_opts and {"scr", "scr+polish"} & set(methods) else None)
    print(cmp.table())
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "comparison.json").write_text(json.dumps(cmp.to_dict(), indent=2, default=float))
        (out / "comparison.md").write_text(cmp.to_markdown() + "\n")
        print(f"wrote {out / 'comparison.json'}, {out / 'comparison.md'}")
    return 0


def _cmd_identifiability(args: argparse.Namespace) -> int:
    from symid.structural import identifiability
    from symid.zoo import load_model

    known = {}
    for item in args.known or []:
        name, sep, value = item.partition("=")
        if not sep:
            raise SystemExit(f"symid identifiability: --known expects name=value, got {item!r}")
        try:
            known[name.strip()] = float(value)
        except ValueError:
            raise SystemExit(f"symid identifiability: --known {item!r}: {value!r} is not a number") from None
    positive = {"declared": None, "all": True, "ignore": False}[args.positive]
    report = identifiability(load_model(args.model).model, known=known, positive=positive,
                             timeout=args.timeout, exact_count=args.exact_count, seed=args.seed)
    print(report.summary())
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``symid`` command."""
    parser = argparse.ArgumentParser(
        prog="symid",
        description="Continuous-time grey-box system identification: symbolic models, "
                    "identifiability, and estimation by sequential convex relaxation (SCR).")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser("models", help="list the model zoo", description="List the models of the zoo.")
    p.set_defaults(func=_cmd_models)

    p = sub.add_parser("show", help="show a model: parameters, matrices, truth, data recipe",
                       description="Show a zoo model (or a model file): parameters, matrices, truth, data recipe.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    p.set_defaults(func=_cmd_show)

    p = sub.add_parser("identify", help="estimate a model's parameters from data",
                       description="Estimate the parameters of a zoo model (or model file) from a data file "
                                   "(CSV or NPZ written by symid); without --data, from the zoo's own recipe.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    p.add_argument("--data", metavar="FILE", help="data file (CSV or NPZ); default: simulate the zoo recipe")
    p.add_argument("--method", choices=("scr", "ipopt", "ls", "als", "gb"), default="scr",
                   help="estimator (default: scr); als and gb (alternating least squares, gradient-based BFGS, "
                        "thesis appendix C) take black-box or I/O data")
    p.add_argument("--starts", type=int, default=1, metavar="N", help="number of starts (default: 1)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="seed of the random starts (default: 0)")
    p.add_argument("--backend", choices=("admm", "cvxpy"), help="SCR back end")
    p.add_argument("--max-iter", type=int, dest="max_iter", metavar="K", help="SCR iterations per start")
    p.add_argument("--polish", action="store_true", help="refine the SCR estimate with IPOPT (reported apart)")
    p.add_argument("--out", metavar="DIR",
                   help="write result.json, summary.txt, bode.png and (SCR) convergence.png here")
    p.set_defaults(func=_cmd_identify)

    p = sub.add_parser("compare", help="compare estimators on the same data and starts",
                       description="Run several estimators from identical starts and tabulate success rate, "
                                   "median time per start, time to solution and best cost.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    p.add_argument("--data", metavar="FILE", help="data file; default: simulate the zoo recipe (truth known)")
    p.add_argument("--methods", default="scr,ipopt",
                   help="comma-separated methods among scr, scr+polish (SCR then IPOPT from its estimate, "
                        "reported apart), ipopt, ls, and for black-box or I/O data als, gb (default: scr,ipopt)")
    p.add_argument("--starts", type=int, default=10, metavar="N", help="number of starts (default: 10)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="seed of the random starts (default: 0)")
    p.add_argument("--backend", choices=("admm", "cvxpy"), help="SCR back end")
    p.add_argument("--max-iter", type=int, dest="max_iter", metavar="K", help="SCR iterations per start")
    p.add_argument("--out", metavar="DIR", help="write comparison.json and comparison.md here")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser("demo", help="run the demonstration on the belt drive",
                       description="Identify the belt drive (thesis (3-17)) from its 10-point frequency response.")
    p.add_argument("--out", default="symid-demo", help="output folder (default: ./symid-demo)")
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser(
        "identifiability", help="structural identifiability report of a model",
        description="Which parameters of a model can be recovered from noise-free input-output data: per "
                    "parameter global / local / none (exact Jacobian rank and a Gröbner basis), the number of "
                    "solutions, identifiable combinations and a reparameterisation.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    p.add_argument("--timeout", type=float, default=30.0, metavar="S",
                   help="time budget of the analysis in seconds; if the global (Gröbner) step does not finish "
                        "in it and no certified solution θ ≠ θ* settles the verdicts, the local verdict is reported "
                        "and the global one marked undetermined (default: 30)")
    p.add_argument("--exact-count", action="store_true",
                   help="keep the Gröbner step running for the exact number of solutions even when certified "
                        "numerical solutions already prove the model locally but not globally identifiable")
    p.add_argument("--known", nargs="*", metavar="NAME=VALUE", help="parameters taken as known")
    p.add_argument("--positive", choices=("declared", "all", "ignore"), default="declared",
                   help="discard solutions with non-positive values of the parameters declared positive "
                        "(default), of all parameters, or ignore positivity")
    p.add_argument("--seed", type=int, default=0, help="seed of the random rational points (default: 0)")
    p.set_defaults(func=_cmd_identifiability)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``symid`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = int(args.func(args) or 0)
        sys.stdout.flush()  # inside the try: a closed pipe surfaces here, not at interpreter exit
        return code
    except SymidError as exc:
        print(f"symid: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader went away (`symid models | head`): stop quietly, as other command-line tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
