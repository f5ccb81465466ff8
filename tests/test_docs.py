"""Docstring examples run (numpydoc ``Examples`` sections), and the package list is complete."""

from __future__ import annotations

import doctest
import importlib
import inspect
import os
import pkgutil
import re
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


# The foundation's public API (issue 2): every function documents its parameters, what it returns and
# an example that runs (test_docstring_examples_run); every class documents its parameters or attributes.
FOUNDATION_FUNCTIONS = ("parameters", "load_model", "list_models", "simulate_frf", "simulate_spectra", "simulate_io")
FOUNDATION_CLASSES = ("StateSpaceModel", "SecondOrderModel", "FrequencyData", "SpectralData", "IOData", "BlackBox",
                      "ZooEntry", "StateSpaceMatrices", "NonAffineError")
MODEL_METHODS = ("state_space", "frequency_response", "theta_vector")


def _sections(obj) -> set[str]:
    doc = inspect.getdoc(obj) or ""
    return set(re.findall(r"^(\w[\w ]*)\n-{3,}$", doc, flags=re.MULTILINE))


@pytest.mark.parametrize("name", FOUNDATION_FUNCTIONS)
def test_public_functions_have_numpydoc_sections(name):
    obj = getattr(symid, name)
    missing = {"Returns", "Examples"} - _sections(obj)
    if inspect.signature(obj).parameters:
        missing |= {"Parameters"} - _sections(obj)
    assert not missing, f"{name} lacks numpydoc section(s) {sorted(missing)}"


@pytest.mark.parametrize("name", FOUNDATION_CLASSES)
def test_public_classes_have_numpydoc_sections(name):
    sections = _sections(getattr(symid, name))
    assert sections & {"Parameters", "Attributes"}, f"{name} documents neither Parameters nor Attributes"


@pytest.mark.parametrize("cls", ["StateSpaceModel", "SecondOrderModel"])
@pytest.mark.parametrize("method", MODEL_METHODS)
def test_model_methods_have_numpydoc_sections(cls, method):
    missing = {"Parameters", "Returns", "Raises", "Examples"} - _sections(getattr(getattr(symid, cls), method))
    assert not missing, f"{cls}.{method} lacks numpydoc section(s) {sorted(missing)}"


# -- README -----------------------------------------------------------------------------------

README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_readme_tour_runs(tmp_path):
    """Every python block of README.md runs as written (in a scratch directory: the tour writes files)."""
    blocks = re.findall(r"```python\n(.*?)```", README, flags=re.DOTALL)
    assert blocks, "README.md has no python block"
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        namespace: dict = {}
        for block in blocks:
            exec(compile(block, "README.md", "exec"), namespace)  # the README is ours
    finally:
        os.chdir(cwd)
    assert (tmp_path / "frf.csv").exists()
    assert namespace["H"].shape == (30, 1, 1)  # "complex, shape (30, 1, 1)" as the tour says
    assert namespace["model"].parameter_names == ("m1", "m2", "c1", "c2", "k1", "k2")


def test_readme_non_affine_message_is_what_symid_says():
    quoted = re.search(r"```\n(NonAffineError: .*?)```", README, flags=re.DOTALL).group(1)
    with pytest.raises(symid.NonAffineError) as info:
        symid.SecondOrderModel(M=[[1]], V=[[1]], K=[["k/m"]], B=[[1]], C=[[1]])
    actual = f"NonAffineError: {info.value}"
    for fragment in quoted.split("..."):
        assert " ".join(fragment.split()) in actual, fragment


def test_readme_quick_start_is_two_commands():
    """Exactly two quick-start commands: install + demo, install with the test extra + the test suite."""
    quick = README.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)\n```", quick, flags=re.DOTALL)
    assert commands == ["python3 -m venv .venv && .venv/bin/pip install . && .venv/bin/symid demo",
                        'python3 -m venv .venv && .venv/bin/pip install ".[test]" && .venv/bin/pytest']
    ci = (ROOT / ".ci" / "run").read_text()
    assert f"TEST_CMD='{commands[1]}'" in ci  # .ci/run runs exactly the README's test command
