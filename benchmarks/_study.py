"""What every benchmark shares: a resumable run log, Ctrl-C that keeps finished runs, atomic summaries.

A study is a dict of sections, each a function of a :class:`symid.runlog.RunLog` (scoped
to the section) returning the section's JSON result. Every finished run inside a section
is appended to the log as it ends (``si.compare(..., log=...)`` does this per start;
:func:`logged` for other loops), and every finished section too; running the same command
again resumes: finished sections are read back, finished runs are skipped. The summary
JSON is written only when every section is done, atomically, with ``"complete": true``,
and the log is then removed (a later run starts afresh rather than reading back results
of older code).
On Ctrl-C the script says what it kept and how to resume, and exits with status 130
without writing the summary.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from symid.runlog import RunLog, json_safe, write_json_atomic

__all__ = ["add_log_arguments", "finish_log", "git_commit", "logged", "run_study"]

RESULTS = Path(__file__).resolve().parent / "results"


def git_commit() -> str:
    """The short hash of the checked-out commit (which code a result came from), or ``"unknown"``."""
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True,
                              cwd=Path(__file__).resolve().parent).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def add_log_arguments(parser: argparse.ArgumentParser, name: str) -> None:
    """``--log PATH`` (default ``benchmarks/results/<name>.jsonl``) and ``--fresh``."""
    parser.add_argument("--log", default=str(RESULTS / f"{name}.jsonl"),
                        help="run-by-run log; an existing one is resumed (default: %(default)s)")
    parser.add_argument("--fresh", action="store_true", help="start over: discard the log")


def logged(log: RunLog, key: str, run: Callable[[], Mapping[str, Any]]) -> dict[str, Any]:
    """The record of run ``key``: read back from the log if it finished before, else run and appended."""
    rec = log.get(key)
    if rec is None:
        log.append(key, run())
        rec = log.get(key)
    return {k: v for k, v in rec.items() if k != "key"}


def run_study(sections: Mapping[str, Callable[[RunLog], dict]], *, out: Path, log_path: Path, fresh: bool,
              header: Mapping[str, Any], previous: Mapping[str, Any] | None = None) -> int:
    """Run (or resume) every section; write ``out`` atomically when all are done. Returns the exit status.

    ``previous`` holds sections not run this time (``--only``) whose earlier results the
    summary keeps.
    """
    log = RunLog(log_path, fresh=fresh)
    resumed = len(log)
    if resumed:
        print(f"resuming from {log_path}: {resumed} finished runs are read back, not run again", flush=True)
    doc: dict[str, Any] = {**dict(previous or {}), **header}
    t0 = time.perf_counter()
    try:
        for name, fn in sections.items():
            done = log.get(f"section/{name}")
            if done is None:
                print(f"== {name}", flush=True)
                t1 = time.perf_counter()
                result = {**fn(log.scoped(f"{name}/")), "wall_time": time.perf_counter() - t1}
                log.append(f"section/{name}", {"result": json_safe(result)})
                done = log.get(f"section/{name}")
            else:
                print(f"== {name}: finished before, read back from the log", flush=True)
            doc[name] = done["result"]
    except KeyboardInterrupt:
        print(f"\ninterrupted after {time.perf_counter() - t0:.0f} s: {len(RunLog(log_path))} finished runs are "
              f"kept in {log_path}; run the same command again to resume (no summary written)", file=sys.stderr)
        return 130
    doc["complete"] = True
    write_json_atomic(out, doc)
    finish_log(log_path)
    print(f"wrote {out}")
    return 0


def finish_log(log_path: Path) -> None:
    """Remove a study's log once its summary is written: a later run starts afresh instead of reading back
    results of older code."""
    Path(log_path).unlink(missing_ok=True)
