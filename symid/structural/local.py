"""Local identifiability: exact rank of the Jacobian of the Markov parameters at random rational points.

The Markov parameters ``h_k = C Aᵏ B`` (k < 2n) and ``D`` are an exhaustive summary of
the input-output map. Their Jacobian with respect to θ is computed in forward mode,
in exact rational arithmetic, at a rational point θ₀ — no symbolic expression is built,
so the test is cheap enough to run before every estimation. For a second-order model
the first-order form holds ``M⁻¹``, whose derivative is ``−M⁻¹ (∂M) M⁻¹``.

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

import sympy as sp
from sympy import QQ
from sympy.polys.matrices import DomainMatrix

from symid.errors import ModelError
from symid.structural.summary import free_parameters, model_kind, rational

__all__ = ["LocalResult", "jacobian_at", "local_analysis", "random_point"]


def random_point(rng: random.Random, n: int, *, numerators: tuple[int, int] = (2, 40),
                 denominators: tuple[int, int] = (1, 7)) -> list:
    """A random positive rational point (small numerators and denominators), as QQ elements."""
    return [QQ(rng.randint(*numerators), rng.randint(*denominators)) for _ in range(n)]


def _dm(mat: sp.Matrix) -> DomainMatrix:
    return DomainMatrix([[QQ.from_sympy(rational(e)) for e in mat.row(i)] for i in range(mat.rows)], mat.shape, QQ)


def _affine_parts(model, known: Mapping[str, object] | None):
    """Per matrix: exact constant part (known values folded in) and one coefficient per free parameter."""
    known = dict(known or {})
    free = free_parameters(model, known)
    free_idx = [model.parameters.index(p) for p in free]
    parts = {}
    for name, amap in model.maps.items():
        const = amap.constant.applyfunc(rational)
        for i, p in enumerate(model.parameters):
            if p.name in known:
                const = const + rational(known[p.name]) * amap.coefficients[i].applyfunc(rational)
        parts[name] = (_dm(const), [_dm(amap.coefficients[i]) for i in free_idx])
    return free, parts


def _at(parts, name, point):
    X0, Xs = parts[name]
    X = X0
    for v, Xi in zip(point, Xs, strict=True):
        if v:
            X = X + Xi * v
    return X, Xs


def jacobian_at(model, point: Sequence, known: Mapping[str, object] | None = None, *, _parts=None
                ) -> DomainMatrix:
    """Exact Jacobian (rows: entries of h_0..h_{2n−1} and D; columns: free parameters) at ``point``.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    point : sequence
        One rational value (``QQ``, int, ``Fraction`` or sympy Rational) per free parameter.
    known : dict, optional
        Fixed parameter values.

    Raises
    ------
    ModelError
        If M(θ) is singular at the point (second-order models).
    """
    kind = model_kind(model)
    if _parts is None:
        _, parts = _affine_parts(model, known)
    else:
        parts = _parts
    point = [QQ.convert(v) if not isinstance(v, sp.Basic) else QQ.from_sympy(v) for v in point]
    npar = len(point)
    if kind == "state-space":
        A, dA = _at(parts, "A", point)
        B, dB = _at(parts, "B", point)
        C, dC = _at(parts, "C", point)
        D, dD = _at(parts, "D", point)
    else:
        M, dM = _at(parts, "M", point)
        V, dV = _at(parts, "V", point)
        K, dK = _at(parts, "K", point)
        B0, dB0 = _at(parts, "B", point)
        C0, dC0 = _at(parts, "C", point)
        n = M.shape[0]
        try:
            Mi = M.inv()
        except Exception:
            raise ModelError("M(θ) is singular at the test point") from None
        Z = DomainMatrix.zeros((n, n), QQ)
        I = DomainMatrix.eye(n, QQ)
        MiK, MiV = Mi * K, Mi * V
        A = Z.hstack(I).vstack((-MiK).hstack(-MiV))
        B = DomainMatrix.zeros(B0.shape, QQ).vstack(Mi * B0)
        zc = DomainMatrix.zeros(C0.shape, QQ)
        out = model.output
        if out == "position":
            C = C0.hstack(zc)
        elif out == "velocity":
            C = zc.hstack(C0)
        else:
            C = (-(C0 * MiK)).hstack(-(C0 * MiV))
        D = C0 * Mi * B0 if out == "acceleration" else DomainMatrix.zeros((C0.shape[0], B0.shape[1]), QQ)
        dA, dB, dC, dD = [], [], [], []
        zb = DomainMatrix.zeros(B0.shape, QQ)
        for j in range(npar):
            dMi = -(Mi * dM[j] * Mi)
            dMiK = dMi * K + Mi * dK[j]
            dMiV = dMi * V + Mi * dV[j]
            dA.append(Z.hstack(Z).vstack((-dMiK).hstack(-dMiV)))
            dB.append(zb.vstack(dMi * B0 + Mi * dB0[j]))
            if out == "position":
                dC.append(dC0[j].hstack(zc))
                dD.append(DomainMatrix.zeros(D.shape, QQ))
            elif out == "velocity":
                dC.append(zc.hstack(dC0[j]))
                dD.append(DomainMatrix.zeros(D.shape, QQ))
            else:
                dC.append((-(dC0[j] * MiK + C0 * dMiK)).hstack(-(dC0[j] * MiV + C0 * dMiV)))
                dD.append(dC0[j] * Mi * B0 + C0 * dMi * B0 + C0 * Mi * dB0[j])
    nstates = A.shape[0]
    columns = []
    for j in range(npar):
        x, dx = B, dB[j]
        col = []
        for _ in range(2 * nstates):
            dh = dC[j] * x + C * dx
            col.extend(e for row in dh.to_list() for e in row)
            dx = dA[j] * x + A * dx
            x = A * x
        col.extend(e for row in dD[j].to_list() for e in row)
        columns.append(col)
    nrows = len(columns[0]) if columns else 0
    rows = [[columns[j][i] for j in range(npar)] for i in range(nrows)]
    return DomainMatrix(rows, (nrows, npar), QQ)


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
    """

    parameters: tuple[sp.Symbol, ...]
    points: tuple[tuple, ...]
    ranks: tuple[int, ...]
    rank: int
    nullspaces: tuple[list, ...]
    identifiable: tuple[bool, ...]

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
    free, parts = _affine_parts(model, known)
    rng = random.Random(seed)
    points, ranks, nulls = [], [], []
    for _ in range(n_points):
        for _attempt in range(20):
            pt = random_point(rng, len(free))
            try:
                J = jacobian_at(model, pt, known, _parts=parts)
            except ModelError:
                continue
            break
        else:
            raise ModelError("M(θ) is singular at every random test point; is the model degenerate?")
        points.append(tuple(pt))
        if len(free) == 0:
            ranks.append(0)
            nulls.append([])
            continue
        ranks.append(J.rank())
        ns = J.nullspace().to_list() if J.shape[0] else [[QQ(int(i == j)) for j in range(len(free))]
                                                          for i in range(len(free))]
        nulls.append([list(v) for v in ns])
    rank = max(ranks)
    best = ranks.index(rank)
    ident = tuple(all(vec[k] == 0 for vec in nulls[best]) for k in range(len(free)))
    return LocalResult(tuple(free), tuple(points), tuple(ranks), rank, tuple(nulls), ident)
