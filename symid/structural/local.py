"""Local identifiability: exact rank of the Jacobian of an exhaustive summary at random rational points.

The summary used here is the transfer matrix H(s, θ) evaluated at K = 2N + 1 + r
distinct rational frequencies s₁ … s_K, where N is the order of the first-order form
(n for a state-space model, 2n for a second-order one) and r the power of s in front of
a second-order response (0, 1, 2 for position, velocity, acceleration output). It is
exhaustive in the sense that matters for the Jacobian: a direction δθ leaves every
H(s_i) unchanged to first order iff it leaves H(·, θ) unchanged, because the first-order
change δH is a rational function whose numerator has degree at most 2N + r − 1 (state
space with D: 2N) and vanishes at K points — so the null space, and hence the rank, is
that of the Jacobian of the Markov parameters C Aᵏ B (k < 2n) and D, at every point.

Evaluating at points avoids matrix powers and, for a second-order model, M⁻¹: with
X = Z⁻¹B and Y = C Z⁻¹,

- state space, Z = sI − A:  ∂H = ∂C X + Y ∂A X + Y ∂B + ∂D;
- second order, Z = P(s) = Ms² + Vs + K:  ∂H = sʳ (∂C X − Y ∂P X + Y ∂B), ∂P = s²∂M + s∂V + ∂K,

each ∂ a sparse coefficient matrix of the affine map, so a column costs a few scalar
products. Everything is exact rational arithmetic at a rational θ₀.

At a random point the rank equals the generic rank with probability one; the test is
repeated at two independent points and the larger rank is kept (a lower rank can only
come from an unlucky point). θ_k is locally identifiable if and only if every vector
of the Jacobian's null space has a zero k-th entry (equivalently, removing column k
lowers the rank by one).
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy import QQ
from sympy.polys.matrices import DomainMatrix
from sympy.polys.matrices.exceptions import DMNonInvertibleMatrixError

from symid.errors import ModelError
from symid.structural.modp import PRIME, BadPrime, inverse_mod_p, matmul_mod_p, rank_mod_p, residue
from symid.structural.summary import analysed_output, free_parameters, model_kind, rational

__all__ = ["LocalResult", "PoleError", "jacobian_at", "local_analysis", "random_point", "rank_at"]


class PoleError(ModelError):
    """A test frequency is a pole of H(s, θ) at the test point (:func:`local_analysis` then draws again)."""


_SHIFT = {"position": 0, "velocity": 1, "acceleration": 2}


def random_point(rng: random.Random, n: int, *, numerators: tuple[int, int] = (2, 40),
                 denominators: tuple[int, int] = (1, 7)) -> list:
    """A random positive rational point (small numerators and denominators), as QQ elements."""
    return [QQ(rng.randint(*numerators), rng.randint(*denominators)) for _ in range(n)]


def _dm(mat: sp.Matrix) -> DomainMatrix:
    return DomainMatrix([[QQ.from_sympy(rational(e)) for e in mat.row(i)] for i in range(mat.rows)], mat.shape, QQ)


def _sparse(mat: sp.Matrix) -> tuple[tuple[int, int, object], ...]:
    """Nonzero entries ``(row, column, value)`` of an exact matrix, values in QQ."""
    return tuple((i, j, QQ.from_sympy(rational(mat[i, j]))) for i in range(mat.rows) for j in range(mat.cols)
                 if mat[i, j] != 0)


@dataclass(frozen=True)
class _Parts:
    """Per matrix: exact constant part (known values folded in) and sparse coefficients per free parameter."""

    kind: str
    output: str | None
    n_order: int
    constant: dict
    coefficients: dict


def _affine_parts(model, known: Mapping[str, object] | None) -> _Parts:
    known = dict(known or {})
    kind = model_kind(model)
    free = free_parameters(model, known)
    free_idx = [model.parameters.index(p) for p in free]
    const, coefs = {}, {}
    for name, amap in model.maps.items():
        c = amap.constant.applyfunc(rational)
        for i, p in enumerate(model.parameters):
            if p.name in known:
                c = c + rational(known[p.name]) * amap.coefficients[i].applyfunc(rational)
        const[name] = _dm(c)
        coefs[name] = [_sparse(amap.coefficients[i]) for i in free_idx]
    return _Parts(kind, analysed_output(model), model.n_states, const, coefs)


def _at(parts: _Parts, name: str, point: Sequence) -> DomainMatrix:
    X = parts.constant[name].to_list()
    for v, entries in zip(point, parts.coefficients[name], strict=True):
        if v:
            for i, j, c in entries:
                X[i][j] += v * c
    return DomainMatrix(X, parts.constant[name].shape, QQ)


def _frequencies(rng: random.Random, count: int) -> list:
    """Distinct random rational frequencies (QQ)."""
    out: set = set()
    while len(out) < count:
        out.add(QQ(rng.randint(1, 60), rng.randint(1, 9)))
    return sorted(out)


def jacobian_at(model, point: Sequence, known: Mapping[str, object] | None = None, *,
                frequencies: Sequence | None = None, _parts: _Parts | None = None) -> DomainMatrix:
    """Exact Jacobian of H(s_i, θ) (rows: entries at each frequency; columns: free parameters) at ``point``.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    point : sequence
        One rational value (``QQ``, int, ``Fraction`` or sympy Rational) per free parameter.
    known : dict, optional
        Fixed parameter values.
    frequencies : sequence, optional
        The rational frequencies s_i; default 2N + 1 + r fixed pseudo-random ones.

    Raises
    ------
    PoleError
        If a frequency is a pole at the point (then draw other frequencies); a
        :class:`~symid.errors.ModelError`.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.local import jacobian_at
    >>> a, b = si.parameters("a b")
    >>> J = jacobian_at(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]]), [1, 2], frequencies=[0, 1, 2])
    >>> J.to_Matrix()  # H = b / (s + a): ∂H/∂a = −b/(s + a)², ∂H/∂b = 1/(s + a)
    Matrix([
    [  -2,   1],
    [-1/2, 1/2],
    [-2/9, 1/3]])
    """
    parts = _affine_parts(model, known) if _parts is None else _parts
    point = [QQ.convert(v) if not isinstance(v, sp.Basic) else QQ.from_sympy(v) for v in point]
    npar = len(point)
    shift = _SHIFT.get(parts.output, 0)
    if frequencies is None:
        frequencies = _frequencies(random.Random(1), 2 * parts.n_order + 1 + shift)
    if parts.kind == "state-space":
        A, B, C = (_at(parts, k, point) for k in "ABC")
        eye = DomainMatrix.eye(A.shape[0], QQ)
    else:
        M, V, K, B, C = (_at(parts, k, point) for k in "MVKBC")
    co = parts.coefficients
    p, m = C.shape[0], B.shape[1]
    rows = []
    for s in frequencies:
        s = QQ.convert(s)
        Z = eye * s - A if parts.kind == "state-space" else M * (s * s) + V * s + K
        try:
            Zi = Z.inv()
        except DMNonInvertibleMatrixError:
            raise PoleError(f"s = {s} is a pole at the test point") from None
        X, Y = (Zi * B).to_list(), (C * Zi).to_list()
        if parts.kind == "state-space":
            dZ = co["A"]
            scale, sign = QQ(1), QQ(1)
        else:
            dZ = [(*a, *b, *c) for a, b, c in
                  zip(*[[tuple((i, j, v * f) for i, j, v in e) for e in co[k]] for k, f in
                        (("M", s * s), ("V", s), ("K", QQ(1)))], strict=True)]
            scale, sign = s**shift, QQ(-1)
        block = [[QQ(0)] * npar for _ in range(p * m)]
        for col in range(npar):
            dH = [[QQ(0)] * m for _ in range(p)]
            for i, j, v in co["C"][col]:  # ∂C X
                for c in range(m):
                    dH[i][c] += v * X[j][c]
            for i, j, v in co["B"][col]:  # Y ∂B
                for r in range(p):
                    dH[r][j] += v * Y[r][i]
            for i, j, v in dZ[col]:  # ± Y ∂Z X
                v = v * sign
                for r in range(p):
                    yv = Y[r][i] * v
                    if yv:
                        for c in range(m):
                            dH[r][c] += yv * X[j][c]
            if parts.kind == "state-space":
                for i, j, v in co["D"][col]:
                    dH[i][j] += v
            for r in range(p):
                for c in range(m):
                    block[r * m + c][col] = dH[r][c] * scale
        rows.extend(block)
    return DomainMatrix(rows, (len(rows), npar), QQ)


def _full_rank_mod_p(parts: _Parts, point: Sequence, frequencies: Sequence, p: int = PRIME) -> bool:
    """Whether the Jacobian of :func:`jacobian_at` has full column rank modulo p (True proves it over ℚ).

    A minor non-zero modulo p is non-zero. False (a frequency that is a pole modulo p, p
    dividing a denominator, or a rank drop modulo p) proves nothing: the caller decides
    over ℚ.
    """
    J = _jacobian_mod_p(parts, point, frequencies, p)
    return J is not None and rank_mod_p(J.tolist(), p) == len(point)


def _jacobian_mod_p(parts: _Parts, point: Sequence, frequencies: Sequence, p: int = PRIME) -> np.ndarray | None:
    """The Jacobian of :func:`jacobian_at` modulo p, computed on residues; None where it has no residue.

    (Z mod p)⁻¹ = Z⁻¹ mod p when det Z is a unit modulo p, so this is the exact Jacobian
    reduced modulo p. None: a frequency is a pole modulo p, or p divides a denominator.
    """
    npar = len(point)
    try:
        pt = [residue(QQ.convert(v) if not isinstance(v, sp.Basic) else QQ.from_sympy(v), p) for v in point]

        def at(name: str) -> np.ndarray:
            X = np.array([[residue(v, p) for v in row] for row in parts.constant[name].to_list()],
                         dtype=object).reshape(parts.constant[name].shape)
            for v, entries in zip(pt, parts.coefficients[name], strict=True):
                for i, j, c in entries:
                    X[i, j] += v * residue(c, p)
            return (X % p).astype(np.int64)

        co = {k: [[(i, j, residue(c, p)) for i, j, c in e] for e in parts.coefficients[k]]
              for k in parts.coefficients}
        shift = _SHIFT.get(parts.output, 0)
        if parts.kind == "state-space":
            A, B, C = (at(k) for k in "ABC")
        else:
            M, V, K, B, C = (at(k) for k in "MVKBC")
        rows = []
        for s_q in frequencies:
            s = residue(QQ.convert(s_q), p)
            if parts.kind == "state-space":
                Z = (s * np.eye(A.shape[0], dtype=object) - A.astype(object)) % p
                dZ, scale, sign = co["A"], 1, 1
            else:
                Z = (M.astype(object) * (s * s) + V.astype(object) * s + K.astype(object)) % p
                dZ = [[(i, j, v * f % p) for k, f in (("M", s * s), ("V", s), ("K", 1)) for i, j, v in co[k][col]]
                      for col in range(npar)]
                scale, sign = pow(s, shift, p), p - 1
            Zi = inverse_mod_p(Z.astype(np.int64), p)
            if Zi is None:
                return None
            X, Y = matmul_mod_p(Zi, B, p).astype(object), matmul_mod_p(C, Zi, p).astype(object)
            block = np.zeros((C.shape[0] * B.shape[1], npar), dtype=object)
            for col in range(npar):
                dH = np.zeros((C.shape[0], B.shape[1]), dtype=object)
                for i, j, v in co["C"][col]:
                    dH[i, :] += v * X[j, :]
                for i, j, v in co["B"][col]:
                    dH[:, j] += v * Y[:, i]
                for i, j, v in dZ[col]:
                    dH += np.outer(Y[:, i], X[j, :]) * (v * sign)
                if parts.kind == "state-space":
                    for i, j, v in co["D"][col]:
                        dH[i, j] += v
                block[:, col] = (dH * scale % p).reshape(-1)
            rows.append(block)
    except BadPrime:
        return None
    return np.vstack(rows).astype(np.int64).reshape(-1, npar)


@dataclass(frozen=True, eq=False)
class LocalResult:
    """Outcome of the local test.

    Attributes
    ----------
    parameters : tuple of sympy.Symbol
        Free parameters (columns of the Jacobian).
    points : tuple of tuple
        The random rational points (QQ elements), one per test.
    ranks : tuple of int
        Rank of the Jacobian at each point.
    rank : int
        The generic rank (the largest).
    nullspaces : tuple of list of list
        A rational basis of the Jacobian's null space at each point (vectors over θ).
    identifiable : tuple of bool
        Per free parameter, locally identifiable.
    silent : tuple of bool
        Per free parameter, its column of the Jacobian is zero at every test point: the
        response does not depend on it at all (e.g. a rate out of a compartment the output
        never sees).
    """

    parameters: tuple[sp.Symbol, ...]
    points: tuple[tuple, ...]
    ranks: tuple[int, ...]
    rank: int
    nullspaces: tuple[list, ...]
    identifiable: tuple[bool, ...]
    silent: tuple[bool, ...] = ()

    @property
    def best(self) -> int:
        """Index of the point with the generic (largest) rank."""
        return self.ranks.index(self.rank)

    @property
    def nullspace(self) -> list:
        """Null space basis at the generic point."""
        return self.nullspaces[self.best]

    def in_rowspace(self, gradient: Sequence, which: int | None = None) -> bool:
        """Whether a gradient (exact, at point ``which``) lies in the Jacobian's row space."""
        idx = self.best if which is None else which
        return all(sum((g * v for g, v in zip(gradient, vec, strict=True)), QQ(0)) == 0
                   for vec in self.nullspaces[idx])


def local_analysis(model, known: Mapping[str, object] | None = None, *, seed: int = 0, n_points: int = 2
                   ) -> LocalResult:
    """Exact local identifiability test at ``n_points`` independent random rational points.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.local import local_analysis
    >>> a, b, c = si.parameters("a b c")
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[b * 1]], C=[[1]])
    >>> local_analysis(model).identifiable
    (True, True)
    """
    free = free_parameters(model, known)
    parts = _affine_parts(model, known)
    shift = _SHIFT.get(parts.output, 0)
    rng = random.Random(seed)
    points, ranks, nulls = [], [], []
    silent = [bool(free)] * len(free)
    for _ in range(n_points):
        for _attempt in range(20):
            pt = random_point(rng, len(free))
            freqs = _frequencies(rng, 2 * parts.n_order + 1 + shift)
            if free and _full_rank_mod_p(parts, pt, freqs):  # full rank modulo p: no pole, null space {0}
                J = None
                break
            try:
                J = jacobian_at(model, pt, known, frequencies=freqs, _parts=parts)
            except PoleError:  # a frequency hit a pole (or M(θ) is singular): draw again
                continue
            break
        else:
            raise ModelError("the transfer function has a pole at every random test frequency; "
                             "is M(θ) singular for every θ?")
        points.append(tuple(pt))
        rows = J.to_list() if free and J is not None else None
        silent = [q and rows is not None and all(r[k] == 0 for r in rows) for k, q in enumerate(silent)]
        ns = [list(v) for v in J.nullspace().to_list()] if free and J is not None else []
        ranks.append(len(free) - len(ns))
        nulls.append(ns)
    rank = max(ranks)
    best = ranks.index(rank)
    ident = tuple(all(vec[k] == 0 for vec in nulls[best]) for k in range(len(free)))
    return LocalResult(tuple(free), tuple(points), tuple(ranks), rank, tuple(nulls), ident, tuple(silent))


def rank_at(model, point: Sequence, known: Mapping[str, object] | None = None, *, rng: random.Random | None = None
            ) -> int:
    """Exact rank of the summary's Jacobian at ``point`` (random frequencies, redrawn when one is a pole).

    Used to check that the point θ* of the global step is not special: a rank below the
    generic rank there means θ* lies where solutions of summary(θ) = summary(θ*) merge.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.local import rank_at
    >>> a, b = si.parameters("a b")
    >>> rank_at(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]]), [1, 2])
    2
    """
    parts = _affine_parts(model, known)
    shift = _SHIFT.get(parts.output, 0)
    rng = random.Random(0) if rng is None else rng
    for _ in range(20):
        freqs = _frequencies(rng, 2 * parts.n_order + 1 + shift)
        if point and _full_rank_mod_p(parts, point, freqs):
            return len(point)
        try:
            J = jacobian_at(model, point, known, frequencies=freqs, _parts=parts)
        except PoleError:
            continue
        full = min(J.shape)
        if rank_mod_p(J.to_list()) == full:  # the rank modulo p never exceeds the rank over ℚ, nor that `full`
            return full
        return J.rank()
    raise ModelError("the transfer function has a pole at every random test frequency; is M(θ) singular?")
