"""The wheel ships every symid package and the model zoo (slow: builds a wheel, about a minute)."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "--no-build-isolation",
                    "-q", "-w", str(out)], check=True, cwd=out)
    (path,) = out.glob("symid-*.whl")
    return path


@pytest.mark.slow
def test_wheel_ships_the_zoo(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    zoo = sorted(p.name for p in (ROOT / "models").glob("*.py"))
    assert "belt_drive.py" in zoo
    missing = [f for f in zoo if f"symid/zoo_models/{f}" not in names]
    assert not missing, f"zoo files missing from the wheel: {missing}"


@pytest.mark.slow
def test_wheel_ships_every_symid_package(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    packages = sorted(p.parent.relative_to(ROOT).as_posix() for p in (ROOT / "symid").rglob("__init__.py"))
    missing = [p for p in packages if f"{p}/__init__.py" not in names]
    assert not missing, f"packages missing from the wheel (add them to [tool.setuptools] packages): {missing}"
