"""Shared fixtures."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture
def groebner(monkeypatch):
    """The global step with every chain inversion turned off (``proves_global`` says nothing): the reference the
    inversions of :mod:`symid.structural.ladder` and its neighbours are checked against. A function of a model."""
    import symid.structural.global_ as gg
    from symid.structural.msolve import msolve_binary

    def run(model):
        with monkeypatch.context() as patch:
            patch.setattr(gg, "proves_global", lambda *a, **k: "")
            return gg.generic_global(model, rank=len(model.parameters), msolve=msolve_binary())

    return run


@pytest.fixture(scope="session")
def families():
    """``benchmarks/identifiability_models.py``: the model families of the identifiability benchmark (issue 17)."""
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module("identifiability_models")
    finally:
        sys.path.remove(str(BENCH))


@pytest.fixture
def motor(tmp_path):
    """A DC motor's model file (inertia J, friction b; torque in N m, speed in rad/s) at ``tmp_path / "motor.py"``,
    and a function giving its record's CSV rows ``t,tau,w`` (a square-wave torque, the exact response at the file's
    start J = 1e-3, b = 1e-2, 100 samples a second) for a number of samples."""
    import numpy as np

    import symid as si

    path = tmp_path / "motor.py"
    path.write_text(
        "import symid as si\n"
        "J, b = si.parameters('J b', positive=True)\n"
        "model = si.SecondOrderModel(M=[[J]], V=[[b]], K=[[0]], B=[[1]], C=[[1]], output='velocity')\n"
        "start = {'J': 1e-3, 'b': 1e-2}\n"
        "input_units, output_units = 'N m', 'rad/s'\n")
    J, b = si.parameters("J b", positive=True)
    model = si.SecondOrderModel(M=[[J]], V=[[b]], K=[[0]], B=[[1]], C=[[1]], output="velocity")

    def rows(samples: int = 200) -> str:
        t = np.arange(samples) * 0.01
        u = np.where((t * 3).astype(int) % 2 == 0, 1.0, -1.0)
        y = si.simulate_io(model, {"J": 1e-3, "b": 1e-2}, u, 0.01).y[:, 0]
        return "\n".join(f"{a:.2f},{c},{float(d)!r}" for a, c, d in zip(t, u, y, strict=True))

    return path, rows


@pytest.fixture
def free_chain():
    """A builder of chains of n masses joined by n − 1 spring-damper elements with nothing to the ground:
    ``free_chain(n, force, sensor)`` puts the force on mass ``force`` and measures the position of mass ``sensor``
    (0-based)."""
    import sympy as sp

    import symid as si

    def build(n: int, force: int, sensor: int):
        m = si.parameters(" ".join(f"m{i + 1}" for i in range(n)), positive=True)
        c = si.parameters(" ".join(f"c{i + 1}" for i in range(n - 1)), positive=True)
        k = si.parameters(" ".join(f"k{i + 1}" for i in range(n - 1)), positive=True)
        c, k = (c,) if n == 2 else c, (k,) if n == 2 else k
        V, K = sp.zeros(n, n), sp.zeros(n, n)
        for X, v in ((V, c), (K, k)):
            for i, x in enumerate(v):  # element i joins masses i and i + 1
                X[i, i] += x
                X[i + 1, i + 1] += x
                X[i, i + 1] -= x
                X[i + 1, i] -= x
        B, C = sp.zeros(n, 1), sp.zeros(1, n)
        B[force], C[sensor] = 1, 1
        return si.SecondOrderModel(M=sp.diag(*m), V=V, K=K, B=B, C=C)

    return build


@pytest.fixture
def grounded_two_mass():
    """A builder of the two-mass chain tied to the ground at mass 1 (m1, m2, c1, c2, k1, k2; element 1 to the
    ground, element 2 between the masses): ``grounded_two_mass(B, C, output="position")``."""
    import symid as si

    def build(B, C, output: str = "position"):
        m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
        return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                   K=[[k1 + k2, -k2], [-k2, k2]], B=B, C=C, output=output)

    return build
