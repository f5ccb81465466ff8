"""Write the README's results tables from the benchmark JSON files, so they cannot drift.

Each table sits in README.md between two markers naming its source (a JSON file, or
``options`` for the options of every method, read from the estimators' signatures and
docstrings by :func:`symid.fit.catalog.options_table`)::

    <!-- table: benchmarks/results/identifiability.json -->
    | model | wall s | ... |
    <!-- /table -->

Run ``python benchmarks/readme_tables.py`` to rewrite every such table from its JSON;
``--check`` only compares and exits with status 1 when a table differs (the test suite
runs the check). A table whose JSON is missing is an error.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
_BLOCK = re.compile(r"(<!-- table: (?P<src>[^ ]+) -->\n)(?P<body>.*?)(<!-- /table -->)", re.DOTALL)


def _k(row: dict) -> str:
    if row["verdict"] == "none" and row.get("global_determined"):
        return "∞"  # not identifiable: a positive-dimensional solution set
    if row.get("n_solutions_complex") is not None:
        return str(row["n_solutions_complex"])  # complex solutions: the structural count
    if row.get("n_solutions") is None:
        at_least = row.get("n_solutions_at_least")
        return f"≥ {at_least}" if at_least else "not found"
    return str(row["n_solutions"])


def identifiability_table(doc: dict) -> str:
    """The identifiability benchmark: one row per model (cold process, import included)."""
    lines = ["| model | parameters | wall s | cpu s | verdict | solutions |", "|---|---|---|---|---|---|"]
    for row in doc["rows"]:
        name = row["model"] + (" with `exact_count=True`" if row.get("exact_count") else "")
        verdict = {"none": "not identifiable"}.get(row["verdict"], row["verdict"])
        if verdict == "local" and row.get("verdicts_proven") and not row.get("global_determined"):
            verdict = "local, not global (proven by certified witnesses)"
        elif not row.get("global_determined") and not row.get("verdicts_proven") and "undetermined" not in verdict:
            verdict += " (global undetermined)"
        wall = f"{row['wall_s']:.2f}" + (f" (timeout {doc['timeout_s']:g} s)"
                                          if row["report_s"] >= doc["timeout_s"] else "")
        lines.append(f"| {name} | {row['n_parameters']} | {wall} | {row['cpu_s']:.2f} | {verdict} | {_k(row)} |")
    lines.append(f"\nLoad average (1 min) {doc['load_average_before']:.2f} before, {doc['load_average_after']:.2f} "
                 f"after, on {doc['cores']} cores.")
    return "\n".join(lines) + "\n"


def _family_complete(row: dict) -> bool:
    return "error" not in row and "local, global undetermined" not in (row["verdict"], *row["verdicts"].values())


def identifiability_families_table(doc: dict) -> str:
    """The model families of the identifiability benchmark: per family, how many full reports within 2 s."""
    lines = ["| family | models | parameters | complete within 2 s | complete (any time) | median wall s | "
             "median cpu s | verdicts (complete reports) |", "|---|---|---|---|---|---|---|---|"]
    fams: dict[str, list] = {}
    for row in doc["rows"]:
        fams.setdefault(row["model"].split("-")[0], []).append(row)
    for fam, rows in fams.items():
        pars = [r["n_parameters"] for r in rows if "n_parameters" in r]
        done = [r for r in rows if _family_complete(r)]
        fast = [r for r in done if r["wall_s"] <= doc["target_s"]]
        walls = sorted(r["wall_s"] for r in rows)
        cpus = sorted(r["cpu_s"] for r in rows)
        counts: dict[str, int] = {}
        for r in done:
            counts[r["verdict"]] = counts.get(r["verdict"], 0) + 1
        verdicts = ", ".join(f"{v} {c}" for v, c in sorted(counts.items()))
        lines.append(f"| {fam} | {len(rows)} | {min(pars)}–{max(pars)} | {len(fast)} | {len(done)} | "
                     f"{walls[len(walls) // 2]:.2f} | {cpus[len(cpus) // 2]:.2f} | {verdicts} |")
    lines.append(f"\nBudget {doc['timeout_s']:g} s per model; load average (1 min) {doc['load_average_before']:.2f} "
                 f"before, {doc['load_average_after']:.2f} after, on {doc['cores']} cores.")
    return "\n".join(lines) + "\n"


_PROBLEM_LABELS = {"belt_drive": "belt drive (3-17), 10 points", "mass_damper_2dof": "2-DOF (4-21), 30 points"}


def frf_table(doc: dict) -> str:
    """SCR, SCR + polish and IPOPT from the same starts on the FRF problems, and IPOPT's configurations."""
    lines = ["| problem | method | successes | median ms/start | time to solution s | / IPOPT's |",
             "|---|---|---|---|---|---|"]
    for name, prob in doc["problems"].items():
        rows = {m["method"]: m for m in prob["methods"]}
        ipopt_tts = rows.get("ipopt", {}).get("time_to_solution")
        for k, (method, m) in enumerate(rows.items()):
            tts = m["time_to_solution"]
            ratio = "" if method == "ipopt" or tts is None or not ipopt_tts else f"{tts / ipopt_tts:.2g}"
            lines.append(f"| {_PROBLEM_LABELS.get(name, name) if k == 0 else ''} | {method} | "
                         f"{m['n_success']}/{m['n_starts']} | {1e3 * m['median_time']:.3g} | "
                         f"{'∞' if tts is None else f'{tts:.3g}'} | {ratio} |")
    lines.append("")
    names = [_PROBLEM_LABELS.get(p, p) for p in doc["ipopt_variants"]]
    lines.append("| IPOPT configuration | " + " | ".join(names) + " |")
    lines.append("|---|" + "---|" * len(doc["ipopt_variants"]))
    labels = list(next(iter(doc["ipopt_variants"].values())))
    for label in labels:
        cells = [f"{v[label]['n_success']}/{doc['starts']}" for v in doc["ipopt_variants"].values()]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    z = doc["belt_drive_from_zeros"]
    lines.append(f"\nSCR from θ = 0 on the belt drive: ‖θ̂ − θ*‖₂ = {z['error']:.2g} in {z['wall_time']:.2f} s. "
                 f"{doc['starts']} starts, seed {doc['seed']}; load average (1 min) "
                 f"{doc['machine']['load_average_start'][0]:.2f} at the start.")
    return "\n".join(lines) + "\n"


def similarity_table(doc: dict) -> str:
    """Success rate (%) per number of unknown entries of random5, per method (thesis Figure 6-3)."""
    rates = doc["random"]["rate"]
    ks = sorted({int(k) for m in rates.values() for k in m})
    n = doc["random"].get("experiments_per_count", "")
    lines = [f"| unknowns (random5, {n} experiments each) | " + " | ".join(map(str, ks)) + " |",
             "|---|" + "---|" * len(ks)]
    for method, rate in rates.items():
        lines.append(f"| {method.upper()} | " + " | ".join(f"{100 * rate[str(k)]:.0f}" if str(k) in rate else "—"
                                                          for k in ks) + " |")
    return "\n".join(lines) + "\n"


_PSD_LABELS = {"scr-cvxpy": "SCR, Clarabel (default), Yᵢ = −ZᵢZᵢᵀ", "scr-admm": "SCR, ADMM back end",
               "ipopt": "IPOPT on (5-13)", "scr-no-lmi": "SCR without the LMIs and bounds",
               "ipopt-weighted": "IPOPT, (5-13) weighted per frequency",
               "ipopt-equation": "IPOPT, equation error of (5-8)", "scr-printed-sign": "SCR, Yᵢ = +ZᵢZᵢᵀ as printed"}
_PSD_SIBLINGS = ("psd_no_lmi_admm.json", "psd_ipopt_variants.json")


def psd_table(doc: dict) -> str:
    """The spectral variants of benchmarks/psd.py: psd.json, then the separate runs saved beside it."""
    docs = [("psd.json", doc)]
    for name in _PSD_SIBLINGS:
        path = ROOT / "benchmarks" / "results" / name
        if path.is_file():
            docs.append((name, json.loads(path.read_text(encoding="utf-8"))))
    lines = ["| variant | successes | median s/start | median iterations | best max-entry error | file |",
             "|---|---|---|---|---|---|"]
    for name, d in docs:
        for r in d["results"]:
            lines.append(f"| {_PSD_LABELS.get(r['variant'], r['variant'])} | {r['successes']}/{r['starts']} | "
                         f"{r['median_time_per_start']:.3g} | {r['median_iterations']:.0f} | "
                         f"{r['best_max_entry_error']:.2g} | `{name}` |")
    return "\n".join(lines) + "\n"


def n4sid_oversampling_table(doc: dict) -> str:
    """benchmarks/n4sid_oversampling.py: worst relative error of f and ζ per route and oversampling ratio."""
    def cell(c: dict) -> str:
        if c["f_error_worst"] is None:
            return f"failed {c['failed']}/{len(doc['seeds'])}"
        return f"{c['f_error_worst']:.0e} / {c['zeta_error_worst']:.0e}"

    lines = ["| fs / highest mode | samples | default horizon | longer horizon (i) | decimated (q), horizon 10 | "
             "decimated, horizon 20 |", "|---|---|---|---|---|---|"]
    for r in doc["rows"]:
        lines.append(f"| {r['ratio']} | {r['N']} | {cell(r['default'])} | {cell(r['horizon'])} ({r['horizon_i']}) | "
                     f"{cell(r['decimated'])} ({r['q']}) | {cell(r['decimated + i=20'])} |")
    return "\n".join(lines) + "\n"


def population_table(doc: dict) -> str:
    """benchmarks/population.py: per class (then per size) × method, successes per noise level and kind of
    start, and the time figures of the uninformed noise-free starts."""
    cols = [(0.0, "informed"), (0.0, "uninformed"), (0.01, "informed"), (0.01, "uninformed")]
    head = ["| class | method | exact, informed | exact, uninformed | 1 %, informed | 1 %, uninformed | "
            "median s/start (exact, uninf.) | time to solution s (exact, uninf.) |",
            "|---|---|---|---|---|---|---|---|"]

    def block(rows: list[dict]) -> list[str]:
        out = []
        index = {(r["class"], r["method"], r["noise"], r["starts_kind"]): r for r in rows}
        keys = sorted({(r["class"], r["method"]) for r in rows},
                      key=lambda k: (k[0].startswith("n=") and int(k[0][2:]), k[0], k[1]))
        last = None
        for cls, method in keys:
            cells = []
            for noise, kind in cols:
                r = index.get((cls, method, noise, kind))
                cells.append("—" if r is None else f"{r['successes']}/{r['starts']}")
            r = index.get((cls, method, 0.0, "uninformed"))
            med = "—" if r is None or r["median_time"] is None else f"{r['median_time']:.3g}"
            tts = "—" if r is None else ("∞" if r["time_to_solution"] is None else f"{r['time_to_solution']:.3g}")
            out.append(f"| {cls if cls != last else ''} | {method} | " + " | ".join(cells) + f" | {med} | {tts} |")
            last = cls
        return out

    lines = [*head, *block(doc["rows"]), "", "By size (masses, states or compartments; every class):", "", *head,
             *block(doc["size_rows"])]
    sizes = "; ".join(f"{k} {', '.join(map(str, v))}" for k, v in sorted(doc["sizes"].items()))
    runs = "; ".join(f"{r['commit']} ({', '.join(r['methods'])}; n = {', '.join(map(str, r.get('sizes') or []))}"
                     + (f"; {', '.join(r['rerun'])} run again, superseding earlier rows" if r.get("rerun") else "")
                     + ")" for r in doc.get("runs", []))
    code = f"runs at {runs}" if runs else f"code {doc['commit']}"
    lines.append(f"\n{doc['problems']} problems (sizes: {sizes}); {code}.")
    skipped = doc.get("unresolved") or {}
    if skipped:
        cells: dict[tuple[str, int], list[float]] = {}
        for name, value in skipped.items():
            cls, size, _ = name.rsplit("-", 2)
            cells.setdefault((cls, int(size.removeprefix("n"))), []).append(float(value))
        parts = [f"{cls} n = {n}: {len(v)} (resolution {max(v):.0e} at most)" for (cls, n), v in sorted(cells.items())]
        lines.append(f"Skipped, the grid does not resolve a 1e-3 error (resolution ≤ 1e-20; `unresolved` in the JSON): "
                     f"{'; '.join(parts)}.")
    return "\n".join(lines) + "\n"


def chain_start_table(doc: dict) -> str:
    """``benchmarks/chain_start.py``: the table it prints (per size and driven mass)."""
    from types import SimpleNamespace

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from chain_start import table

    first = doc["summary"][0]
    noise = sorted({float(k.removeprefix("read_")) for k in first if k.startswith("read_") and "_s_" not in k})
    return table(doc["summary"], SimpleNamespace(noise=noise)) + "\n"


def frf_estimated_variance_table(doc: dict) -> str:
    """``benchmarks/frf_estimated_variance.py``: coverage of the 95 % intervals per problem and periods."""
    def span(v: list[float]) -> str:
        return f"{100 * min(v):.0f}–{100 * max(v):.0f} %"

    lines = ["| problem | periods | ν | successes | spread / median SE | coverage, σ̂² as exact | "
             "coverage, × ν/(ν − 4) |", "|---|---|---|---|---|---|---|"]
    for r in doc["rows"]:
        lines.append(f"| {r['problem']} | {r['periods']} | {r['dof']:g} | {r['successes']}/{r['records']} | "
                     f"{min(r['spread_over_se']):.2f}–{max(r['spread_over_se']):.2f} | "
                     f"{span(r['coverage_as_exact'])} | {span(r['coverage_inflated'])} |")
    return "\n".join(lines) + "\n"


TABLES: dict[str, Callable[[dict], str]] = {
    "benchmarks/results/frf_estimated_variance.json": frf_estimated_variance_table,
    "benchmarks/results/chain_start.json": chain_start_table,
    "benchmarks/results/population.json": population_table,
    "benchmarks/results/n4sid_oversampling.json": n4sid_oversampling_table,
    "benchmarks/results/psd.json": psd_table,
    "benchmarks/results/similarity_study.json": similarity_table,
    "benchmarks/results/identifiability.json": identifiability_table,
    "benchmarks/results/identifiability_families.json": identifiability_families_table,
    "benchmarks/results/frf.json": frf_table,
}

CODE_TABLES: dict[str, Callable[[], str]] = {
    "options": lambda: __import__("symid.fit.catalog", fromlist=["options_table"]).options_table(),
}
"""Tables written from the code rather than a benchmark (``<!-- table: options -->``)."""


def render(text: str) -> str:
    """README text with every marked table rewritten from its JSON."""
    def one(m: re.Match) -> str:
        src = m.group("src")
        if src in CODE_TABLES:
            return m.group(1) + CODE_TABLES[src]() + m.group(4)
        if src not in TABLES:
            raise SystemExit(f"README.md: no table writer for {src}")
        path = ROOT / src
        if not path.is_file():
            raise SystemExit(f"README.md: {src} is missing; run its benchmark first")
        return m.group(1) + TABLES[src](json.loads(path.read_text(encoding="utf-8"))) + m.group(4)

    return _BLOCK.sub(one, text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare only; exit 1 when a table differs")
    args = parser.parse_args(argv)
    text = README.read_text(encoding="utf-8")
    new = render(text)
    if args.check:
        if new != text:
            print("README.md tables differ from benchmarks/results; run python benchmarks/readme_tables.py",
                  file=sys.stderr)
            return 1
        return 0
    if new != text:
        README.write_text(new, encoding="utf-8")
        print("README.md tables rewritten")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
