"""Shared fixtures."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="session")
def families():
    """``benchmarks/identifiability_models.py``: the model families of the identifiability benchmark (issue 17)."""
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module("identifiability_models")
    finally:
        sys.path.remove(str(BENCH))
