"""Benchmarks survive Ctrl-C (issue 12 item 4): runs are logged as they end, an interrupted run exits 130
without writing its summary, and the same command resumes to the summary an uninterrupted run writes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FRF = [sys.executable, str(ROOT / "benchmarks" / "frf.py"), "--starts", "4", "--problems", "mass_damper_2dof",
       "--no-variants"]
ENV = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"}


def _lines(path: Path) -> int:
    return len(path.read_text().splitlines()) if path.exists() else 0


def _figures(doc: dict) -> dict:
    """What must not depend on the interruption: successes and estimates per method and start."""
    out = {}
    for name, prob in doc["problems"].items():
        for m in prob["methods"]:
            out[(name, m["method"])] = (m["n_success"], [s["theta"] for s in m["starts"]])
    return out


def test_frf_benchmark_interrupted_then_resumed(tmp_path):
    out, log = tmp_path / "frf.json", tmp_path / "frf.jsonl"
    proc = subprocess.Popen([*FRF, "--out", str(out), "--log", str(log), "--fresh"], env=ENV, cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while _lines(log) < 3 and proc.poll() is None and time.monotonic() < deadline:  # zeros, setup, a first start
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, (stdout[-2000:], stderr[-2000:])
    assert "run the same command again to resume" in stderr and "Traceback" not in stderr
    assert not out.exists()
    kept = [json.loads(line) for line in log.read_text().splitlines()]  # every line is a whole record
    assert len(kept) >= 3
    resumed = subprocess.run([*FRF, "--out", str(out), "--log", str(log)], env=ENV, cwd=tmp_path,
                             capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert f"{len(kept)} finished runs are read back" in resumed.stdout
    assert not log.exists()  # done: removed, so a later run does not read back results of older code
    fresh = tmp_path / "fresh.json"
    clean = subprocess.run([*FRF, "--out", str(fresh), "--log", str(tmp_path / "fresh.jsonl"), "--fresh"],
                           env=ENV, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert clean.returncode == 0, clean.stderr[-2000:]
    a, b = json.loads(out.read_text()), json.loads(fresh.read_text())
    assert a["complete"] is True and b["complete"] is True
    fa, fb = _figures(a), _figures(b)
    assert fa.keys() == fb.keys()
    for key in fa:
        assert fa[key][0] == fb[key][0], key
        for ta, tb in zip(fa[key][1], fb[key][1], strict=True):
            assert ta == pytest.approx(tb, rel=1e-9, abs=1e-12), key  # deterministic from the same start


@pytest.mark.slow
def test_a_damaged_previous_summary_does_not_stop_a_study(tmp_path):
    # about a minute: the section runs 10 SCR starts of up to 2000 iterations
    out = tmp_path / "similarity_thesis.json"
    out.write_text('{"enose": {"starts": 10, "meth')  # what an interrupted write used to leave
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "similarity_thesis.py"), "--only",
                           "enose_over", "--out", str(out), "--log", str(tmp_path / "st.jsonl")],
                          env=ENV, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "is not valid JSON; it will be replaced" in proc.stderr
    assert json.loads(out.read_text())["complete"] is True
