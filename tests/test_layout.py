"""The package layout and its import rules (issue 13): written down in symid/fit/__init__.py, checked here
by reading every module's import statements (no import is executed)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "symid"
KIND_PACKAGES = ("symid.fit.frf", "symid.fit.spectra", "symid.fit.similarity")


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> list[tuple[str, tuple[str, ...]]]:
    """(module imported, names imported) for every import statement of a file, absolute."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.extend((a.name, ()) for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.append((node.module, tuple(a.name for a in node.names)))
    return out


MODULES = {_module_name(p): _imports(p) for p in sorted(ROOT.rglob("*.py"))}


def _under(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _under(m, "symid.engine")))
def test_engines_import_no_fit_package(module):
    bad = [m for m, _ in MODULES[module] if _under(m, "symid.fit")]
    assert not bad, f"{module} imports {bad}"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _under(m, "symid.data")))
def test_data_layer_does_not_import_symbolic_models(module):
    bad = [m for m, _ in MODULES[module]
           if (_under(m, "symid.model") and m != "symid.model.lti") or _under(m, "symid.fit")
           or m in ("symid.model.symbols", "sympy") or _under(m, "symid.signal")]
    assert not bad, f"{module} imports {bad}"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if any(_under(m, k) for k in KIND_PACKAGES)))
def test_no_fit_package_uses_another_ones_private_names(module):
    own = next(k for k in KIND_PACKAGES if _under(module, k))
    bad = [(m, n) for m, names in MODULES[module] for n in names
           if any(_under(m, k) for k in KIND_PACKAGES if k != own) and n.startswith("_")]
    assert not bad, f"{module} imports private names {bad}"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_module_imports_a_private_name_from_another_package(module):
    package = module.rsplit(".", 1)[0]
    bad = [(m, n) for m, names in MODULES[module] for n in names
           if n.startswith("_") and _under(m, "symid") and not _under(m, package) and n != "__version__"]
    assert not bad, f"{module} imports private names {bad}"


def test_every_data_kind_is_one_package_with_methods_and_prepare():
    from importlib import import_module

    for name in KIND_PACKAGES:
        pkg = import_module(name)
        assert pkg.METHODS and callable(pkg.prepare), name
