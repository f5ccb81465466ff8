"""Every example in examples/ runs, in its reduced variant, in the default test run.

The full runs (minutes) stay with the slow tests (tests/test_identify_frf.py) and the
examples' own command lines; the reduced variants still assert what they claim.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

QUICK = {  # example → arguments of its reduced variant
    "belt_drive_ipopt.py": [],
    "belt_drive_scr.py": ["--quick"],
    "emps.py": ["--quick", "--out", "{tmp}"],
    "f16_gvt.py": ["--quick", "--out", "{tmp}"],
    "mass_damper_2dof_scr.py": ["--quick"],
    "psd_output_only.py": ["--quick", "--out", "{tmp}"],
}


def test_every_example_has_a_reduced_variant_here():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(QUICK)


@pytest.mark.parametrize("name", sorted(QUICK))
def test_example_runs(name, tmp_path, capsys):
    spec = importlib.util.spec_from_file_location(f"example_{name[:-3]}", EXAMPLES / name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    argv = [a.format(tmp=tmp_path) for a in QUICK[name]]
    assert module.main(argv) == 0
    assert capsys.readouterr().out.strip(), f"{name} printed nothing"
