"""Docstring examples run (numpydoc ``Examples`` sections), and the package list is complete."""

from __future__ import annotations

import doctest
import importlib
import pkgutil
import tomllib
from pathlib import Path

import pytest

import symid

ROOT = Path(__file__).resolve().parents[1]


def _modules() -> list[str]:
    names = []
    for info in pkgutil.walk_packages(symid.__path__, prefix="symid."):
        if info.name.startswith("symid.zoo_models"):
            continue
        names.append(info.name)
    return sorted(names)


@pytest.mark.parametrize("name", _modules())
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.failed == 0, f"{result.failed} docstring example(s) failed in {name}"


def test_pyproject_lists_every_package():
    """A subpackage missing from [tool.setuptools] packages would be missing from the wheel."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    listed = set(config["tool"]["setuptools"]["packages"])
    on_disk = {p.parent.relative_to(ROOT).as_posix().replace("/", ".") for p in (ROOT / "symid").rglob("__init__.py")}
    assert on_disk - listed == set(), f"add to pyproject packages: {sorted(on_disk - listed)}"
    assert "symid.zoo_models" in listed


def test_public_api_of_the_design_contract():
    """The names design.md's public API section promises exist at the top level."""
    for name in ("parameters", "StateSpaceModel", "SecondOrderModel", "simulate_frf", "simulate_spectra",
                 "simulate_io", "identify", "compare", "identifiability", "load_model", "FrequencyData",
                 "SpectralData", "IOData", "BlackBox", "NonAffineError", "DataError"):
        assert hasattr(symid, name), name
    from symid import scr

    for name in ("BilinearProblem", "Bilinear", "solve"):
        assert hasattr(scr, name), name
