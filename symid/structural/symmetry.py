"""Permutations of the parameters that leave the exhaustive summary unchanged, and the orbit of θ* under them.

A permutation σ of the free parameters with summary(σθ) ≡ summary(θ) maps the point θ*
to another exact solution σθ* of summary(θ) = summary(θ*): rational, so real, and
admissible exactly when its coordinates are. Interchangeable compartments of a
mammillary model (the peripheral ones, when the input and the output are at the centre)
or the rates around a one-way cycle are such permutations; their solutions are then
the orbit of θ*, e.g. all 5! = 120 of a 6-compartment mammillary model.

Candidates (:func:`symmetries`): every transposition of two parameters, and the
permutation of the parameters induced by every transposition of two states (two masses
or compartments) that leaves the input and output maps and the constant parts of the
matrices unchanged and maps each parameter's coefficient pattern onto another's. Each
candidate is *checked exactly* on the summary's polynomials (the permuted numerator and
denominator of every entry equal the originals), so every generator returned is a
symmetry, and every point of :func:`orbit` is an exact solution. Used by the global step
(:mod:`~symid.structural.global_`): when the orbit has as many points as the system has
solutions (counted modulo a prime), the orbit *is* the solution set.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from fractions import Fraction

import sympy as sp

from symid.structural.summary import model_kind, model_matrices

__all__ = ["orbit", "symmetries"]

_MATRICES = {"state-space": ("A", "B", "C", "D"), "second-order": ("M", "V", "K", "B", "C")}


def _permuted_poly(poly, perm: Sequence[int]):
    """poly(σθ) with (σθ)_a = θ_{perm[a]}: the exponent of θ_a moves to position perm[a]."""
    n = len(perm)
    out = {}
    for mono, c in poly.terms():
        new = [0] * n
        for a, e in enumerate(mono):
            if e:
                new[perm[a]] = e
        out[tuple(new)] = c
    return out


def _leaves_summary(summ, perm: Sequence[int]) -> bool:
    """Exact: every entry's numerator and denominator are unchanged by the permutation."""
    return all(_permuted_poly(p, perm) == dict(p.terms())
               for pair in zip(summ.numerators, summ.denominators, strict=True) for p in pair)


def _state_candidates(model, known, params) -> list[tuple[int, ...]]:
    """Parameter permutations induced by transpositions of two states (see the module docstring)."""
    kind = model_kind(model)
    mats = model_matrices(model, known)
    names = _MATRICES[kind]
    mats = {k: mats[k] for k in names if k in mats}
    zero = dict.fromkeys(params, 0)

    def pattern(key_mats) -> tuple[dict, dict]:
        const, coef = {}, {a: [] for a in range(len(params))}
        for name, M in key_mats.items():
            for i in range(M.rows):
                for j in range(M.cols):
                    e = sp.expand(M[i, j])
                    c0 = e.xreplace(zero)
                    if c0 != 0:
                        const[(name, i, j)] = c0
                    for a, q in enumerate(params):
                        d = e.coeff(q)
                        if d != 0:
                            coef[a].append((name, i, j, d))
        return const, {a: tuple(sorted(v, key=str)) for a, v in coef.items()}

    const0, coef0 = pattern(mats)
    by_pattern = {v: a for a, v in coef0.items()}
    if len(by_pattern) < len(params):
        return []
    n = mats["A" if kind == "state-space" else "M"].rows
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            P = sp.eye(n)
            P[i, i] = P[j, j] = 0
            P[i, j] = P[j, i] = 1
            swapped = {}
            for name, M in mats.items():  # states index the rows of A, M, V, K, B and the columns of A, M, V, K, C
                rows = name not in ("C", "D")
                cols = name not in ("B", "D")
                swapped[name] = (P if rows else sp.eye(M.rows)) * M * (P.T if cols else sp.eye(M.cols))
            const1, coef1 = pattern(swapped)
            if const1 != const0:
                continue
            perm = [by_pattern.get(coef1[a]) for a in range(len(params))]
            if None in perm or sorted(perm) != list(range(len(params))) or perm == list(range(len(params))):
                continue
            out.append(tuple(perm))
    return out


def symmetries(model, known, summ) -> list[tuple[int, ...]]:
    """Generators of parameter permutations that leave ``summ`` (the model's exhaustive summary) unchanged.

    Each is a tuple ``perm`` of indices into ``summ.parameters``: (σθ)_a = θ_{perm[a]}.
    Candidates are the parameter transpositions and the permutations induced by state
    transpositions; each is checked exactly on the summary (module docstring).

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.summary import exhaustive_summary
    >>> from symid.structural.symmetry import symmetries
    >>> a, b = si.parameters("a b")
    >>> model = si.StateSpaceModel(A=[[-a, 0], [0, -b]], B=[[1], [1]], C=[[1, 1]])  # 1/(s+a) + 1/(s+b)
    >>> symmetries(model, {}, exhaustive_summary(model))
    [(1, 0)]
    """
    n = len(summ.parameters)
    cands = []
    for a in range(n):
        for b in range(a + 1, n):
            perm = list(range(n))
            perm[a], perm[b] = b, a
            cands.append(tuple(perm))
    cands += _state_candidates(model, known, list(summ.parameters))
    seen, out = set(), []
    for perm in cands:
        if perm in seen:
            continue
        seen.add(perm)
        if _leaves_summary(summ, perm):
            out.append(perm)
    return out


def orbit(point: Sequence[Fraction], generators: Sequence[Sequence[int]], cap: int) -> list[tuple] | None:
    """The distinct points σθ reached from ``point`` by the group the generators make (θ first); None past ``cap``.

    Examples
    --------
    >>> from symid.structural.symmetry import orbit
    >>> orbit((1, 2, 3), [(1, 0, 2), (0, 2, 1)], 10)
    [(1, 2, 3), (2, 1, 3), (1, 3, 2), (2, 3, 1), (3, 1, 2), (3, 2, 1)]
    """
    start = tuple(point)
    found = {start}
    order = [start]
    todo = deque([start])
    while todo:
        x = todo.popleft()
        for perm in generators:
            y = tuple(x[perm[a]] for a in range(len(x)))
            if y not in found:
                if len(found) >= cap:
                    return None
                found.add(y)
                order.append(y)
                todo.append(y)
    return order
