"""examples/emps.py (issue 15, item 5): how it finds the benchmark files, and what the committed cut holds.

The full run needs the benchmark's two .mat files (not in the repository); these tests check that a missing
folder is an error that says what to do, never a silent pass, and that the committed cut is the benchmark's
samples (read back against the files when they are on this machine).
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "emps.py"
SHARED = Path(os.environ.get("SYMID_EMPS_DATA", "/nonexistent"))


def load_example():
    spec = importlib.util.spec_from_file_location("example_emps", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_missing_data_is_an_error_that_says_what_to_do(tmp_path, capsys, monkeypatch):
    emps = load_example()
    monkeypatch.delenv("SYMID_EMPS_DATA", raising=False)
    assert emps.main([]) == 2
    assert "pass --data DIR" in capsys.readouterr().err
    assert emps.main(["--data", str(tmp_path)]) == 2
    assert "does not hold DATA_EMPS.mat" in capsys.readouterr().err


def test_the_committed_cut_is_there_and_whole():
    emps = load_example()
    est, val = emps.read_subset()
    assert est["t"].size == emps.CUT[0] and val["t"].size == emps.CUT[1]
    assert est["gtau"] == pytest.approx(35.15, abs=0.01) and set(np.unique(val["pulses"])) <= {0.0, 5.0}
    if (SHARED / emps.ESTIMATION).is_file():  # against the benchmark files where they are
        full = emps.read_record(SHARED / emps.ESTIMATION)
        np.testing.assert_array_equal(est["qm"], full["qm"][: emps.CUT[0]])
        np.testing.assert_allclose(est["vir"], full["vir"][: emps.CUT[0]], rtol=1e-7)
