"""Model families for ``benchmarks/identifiability.py``: the structures users write (issue 17).

Each builder returns a symid model with every physical parameter unknown and declared
positive; inputs and sensors are unit vectors (known gains). Names: ``family-n-variant``.

- ``chain``: n masses in a line, mass 1 tied to the ground; spring and damper i join
  mass i − 1 (the ground for i = 1) and mass i. 3n parameters (m, c, k). Variants:
  ``11`` force on mass 1, position of mass 1 (driving point at the grounded end);
  ``nn`` force and position at the free end; ``1n`` force on mass 1, position of mass n.
- ``chain_mid``: the same chains driven or measured at an interior mass k = ⌈n/2⌉ (n ≥ 3).
  Variants ``mm`` force and position of mass k; ``1m`` force on mass 1, position of
  mass k.
- ``chain_at``: the same chains with the force on mass a and the position of mass b
  measured, every placement a ≤ b (variant ``a.b``); run only when named.
- ``shear``: a shear building of n storeys (the same topology as the chain, storey 1 on
  the ground), force on the roof, acceleration of the roof measured. 3n parameters.
- ``rlc``: an RLC ladder of n meshes (mesh charges q): inductance and series resistance
  per mesh, a capacitor joining meshes i and i + 1 and one to ground in the last mesh
  (elastances S = 1/C as parameters, so the model is affine), a voltage source in mesh 1
  and the current of mesh n measured (velocity output). 3n parameters (L, R, S).
- ``catenary`` / ``mammillary`` / ``cycle``: linear compartment models with n
  compartments: exchange rates both ways between neighbours (catenary), between the
  centre and each peripheral compartment (mammillary), one way around a ring (cycle);
  a leak from compartment 1 (variant ``leak1``) or from compartments 1 and 2
  (``leak12``); a dose into compartment 1, compartment 1 observed.
"""

from __future__ import annotations

import sympy as sp

import symid as si

__all__ = ["FAMILIES", "build"]


def _names(prefix: str, n: int) -> list[sp.Symbol]:
    out = si.parameters(" ".join(f"{prefix}{i + 1}" for i in range(n)), positive=True)
    return list(out) if n > 1 else [out]


def _ground_chain(v: list) -> sp.Matrix:
    """Stiffness-like matrix of a chain grounded at element 1: element i joins i − 1 and i."""
    n = len(v)
    X = sp.zeros(n, n)
    for i in range(n):
        X[i, i] += v[i]
        if i >= 1:
            X[i - 1, i - 1] += v[i]
            X[i - 1, i] -= v[i]
            X[i, i - 1] -= v[i]
    return X


def _unit(n: int, k: int, column: bool) -> sp.Matrix:
    X = sp.zeros(n, 1) if column else sp.zeros(1, n)
    X[k] = 1
    return X


def chain(n: int, variant: str = "11"):
    m, c, k = _names("m", n), _names("c", n), _names("k", n)
    a, s = {"11": (0, 0), "nn": (n - 1, n - 1), "1n": (0, n - 1)}[variant]
    return si.SecondOrderModel(M=sp.diag(*m), V=_ground_chain(c), K=_ground_chain(k), B=_unit(n, a, True),
                               C=_unit(n, s, False), output="position", name=f"chain-{n}-{variant}")


def chain_mid(n: int, variant: str = "mm"):
    m, c, k = _names("m", n), _names("c", n), _names("k", n)
    mid = (n + 1) // 2 - 1
    a, s = {"mm": (mid, mid), "1m": (0, mid)}[variant]
    return si.SecondOrderModel(M=sp.diag(*m), V=_ground_chain(c), K=_ground_chain(k), B=_unit(n, a, True),
                               C=_unit(n, s, False), output="position", name=f"chain_mid-{n}-{variant}")


def chain_at(n: int, variant: str = "1.1"):
    """The chain of :func:`chain` driven at mass a and measured (position) at mass b, variant ``"a.b"`` (1-based)."""
    a, b = (int(v) - 1 for v in variant.split("."))
    m, c, k = _names("m", n), _names("c", n), _names("k", n)
    return si.SecondOrderModel(M=sp.diag(*m), V=_ground_chain(c), K=_ground_chain(k), B=_unit(n, a, True),
                               C=_unit(n, b, False), output="position", name=f"chain_at-{n}-{variant}")


def _pairs(n: int) -> tuple[str, ...]:
    """Every placement a ≤ b of force and sensor on n masses (H_ba = H_ab: the other half is the same map)."""
    return tuple(f"{a}.{b}" for a in range(1, n + 1) for b in range(a, n + 1))


def shear(n: int, variant: str = "roof"):
    m, c, k = _names("m", n), _names("c", n), _names("k", n)
    return si.SecondOrderModel(M=sp.diag(*m), V=_ground_chain(c), K=_ground_chain(k), B=_unit(n, n - 1, True),
                               C=_unit(n, n - 1, False), output="acceleration", name=f"shear-{n}-{variant}")


def rlc(n: int, variant: str = "ladder"):
    L, R, S = _names("L", n), _names("R", n), _names("S", n)
    K = sp.zeros(n, n)
    for i in range(n - 1):  # capacitor i between meshes i and i + 1
        K[i, i] += S[i]
        K[i + 1, i + 1] += S[i]
        K[i, i + 1] -= S[i]
        K[i + 1, i] -= S[i]
    K[n - 1, n - 1] += S[n - 1]  # the last capacitor to ground
    return si.SecondOrderModel(M=sp.diag(*L), V=sp.diag(*R), K=K, B=_unit(n, 0, True), C=_unit(n, n - 1, False),
                               output="velocity", name=f"rlc-{n}-{variant}")


def _compartments(kind: str, n: int, variant: str):
    if kind == "catenary":
        edges = [e for i in range(n - 1) for e in ((i, i + 1), (i + 1, i))]
    elif kind == "mammillary":
        edges = [e for i in range(1, n) for e in ((0, i), (i, 0))]
    else:
        edges = [(i, (i + 1) % n) for i in range(n)]
    leaks = {"leak1": (0,), "leak12": (0, 1)}[variant]
    A = sp.zeros(n, n)
    for i, j in edges:  # rate k_ji from compartment i to j
        k = si.parameters(f"k{j + 1}_{i + 1}", positive=True)
        A[j, i] += k
        A[i, i] -= k
    for i in leaks:
        k = si.parameters(f"k0_{i + 1}", positive=True)
        A[i, i] -= k
    return si.StateSpaceModel(A=A, B=_unit(n, 0, True), C=_unit(n, 0, False), name=f"{kind}-{n}-{variant}")


FAMILIES = {
    "chain": (chain, range(2, 9), ("11", "nn", "1n")),
    "chain_mid": (chain_mid, range(3, 9), ("mm", "1m")),
    "chain_at": (chain_at, range(3, 9), _pairs),
    "shear": (shear, range(2, 9), ("roof",)),
    "rlc": (rlc, range(2, 9), ("ladder",)),
    "catenary": (lambda n, v: _compartments("catenary", n, v), range(2, 7), ("leak1", "leak12")),
    "mammillary": (lambda n, v: _compartments("mammillary", n, v), range(2, 7), ("leak1", "leak12")),
    "cycle": (lambda n, v: _compartments("cycle", n, v), range(2, 7), ("leak1", "leak12")),
}
"""family → (builder(n, variant), sizes, variants (or a function of n giving them))."""

DEFAULT_FAMILIES = tuple(f for f in FAMILIES if f != "chain_at")
"""The families ``benchmarks/identifiability.py --families`` runs when none is named (``chain_at``, every
placement of force and sensor on chains of 3 to 8 masses, 116 models, runs only when named)."""


def build(name: str):
    """The model ``family-n-variant`` (e.g. ``chain-3-1n``, ``cycle-5-leak1``)."""
    family, n, variant = name.split("-")
    return FAMILIES[family][0](int(n), variant)


def names(families=None, max_parameters: int = 24) -> list[str]:
    """Every model name of the families, up to ``max_parameters`` parameters."""
    out = []
    for fam, (builder, sizes, variants) in FAMILIES.items():
        if fam not in (families or DEFAULT_FAMILIES):
            continue
        for n in sizes:
            for v in variants(n) if callable(variants) else variants:
                if builder(n, v).n_parameters <= max_parameters:
                    out.append(f"{fam}-{n}-{v}")
    return out
