"""The wheel ships every symid package and the model zoo, and works when installed (slow: about a minute)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import numpy
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel `pip install .` would build (isolated build), from a copy of the checkout.

    Building from a copy keeps setuptools' build/ folder out of the checkout, where stale files
    of earlier builds could slip into later wheels.
    """
    out = tmp_path_factory.mktemp("wheel")
    src = out / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "dist", "*.egg-info", "__pycache__", ".*_cache", ".hypothesis", "results"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "-q", "-w", str(out)],
                   check=True, cwd=out)
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


_CHECK_INSTALLED = """
import sys
from pathlib import Path
import symid
import symid.zoo_models
venv = Path(sys.argv[1]).resolve()
assert venv in Path(symid.__file__).resolve().parents, symid.__file__
assert venv in Path(symid.zoo_models.__file__).resolve().parents, symid.zoo_models.__file__
entry = symid.load_model("belt_drive")
assert entry.model.parameter_names == ("theta1", "theta2", "theta3", "theta4")
assert entry.data().H.shape == (10, 1, 1)
assert len(symid.list_models()) == 10
print("installed ok")
"""


@pytest.mark.slow
def test_non_editable_install_loads_the_zoo_from_any_directory(wheel, tmp_path):
    """Issue 2: after a non-editable install into a fresh venv, load_model("belt_drive") works elsewhere.

    The venv is fresh and the wheel is installed into it without dependencies (offline); the
    dependencies are borrowed from the running environment through a .pth file that lists its
    site-packages *after* the venv's own, so the installed symid, not the source tree or an
    editable install, is the one imported. (.ci/run does the full `pip install ".[test]"`.)
    """
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)], check=True)
    purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             check=True, capture_output=True, text=True).stdout.strip()
    deps = {sysconfig.get_paths()["purelib"], str(Path(numpy.__file__).resolve().parents[1])}
    (Path(purelib) / "zz_borrowed_dependencies.pth").write_text("\n".join(sorted(deps)) + "\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")} | {"MPLBACKEND": "Agg"}
    run = subprocess.run([str(python), "-c", _CHECK_INSTALLED, str(venv)], cwd=elsewhere, env=env,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "installed ok" in run.stdout
    listing = subprocess.run([str(venv / "bin" / "symid"), "models"], cwd=elsewhere, env=env,
                             capture_output=True, text=True)
    assert listing.returncode == 0, listing.stderr
    assert "belt_drive" in listing.stdout and "truss8" in listing.stdout
    show = subprocess.run([str(venv / "bin" / "symid"), "show", "belt_drive"], cwd=elsewhere, env=env,
                          capture_output=True, text=True)
    assert show.returncode == 0, show.stderr
    assert "theta4 = -0.15" in show.stdout  # thesis (3-18)
