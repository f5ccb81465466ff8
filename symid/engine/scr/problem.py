"""The bilinear problem (2-1): A(x) P B(x) = C(x), D(x) = 0, E(x) ⪰ 0, convex quadratic objective."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sps
import sympy as sp

from symid.engine.scr.maps import LocalMap, as_map, checked_expansion, stack_index, stack_maps, sympy_entry
from symid.engine.scr.variables import Layout, Variable
from symid.errors import ModelError

__all__ = ["Bilinear", "BilinearProblem", "SumSquares"]


@dataclass(frozen=True, eq=False)
class Bilinear:
    """One bilinear matrix equation A(x) P B(x) = C(x) of problem (2-1).

    Parameters
    ----------
    A, B, C : sympy matrix or expression, array_like, or :class:`Affine`
        Affine maps of the variables (complex entries allowed). Numbers and arrays are
        constants; :class:`Affine` is the numeric path for large problems.
    P : array_like
        Constant nonzero matrix (real or complex).
    weight : float, optional
        Weight λ of the term's nuclear-norm relaxation (default 1). See
        :func:`symid.engine.scr.solve` for how terms are normalised.
    name : str, optional
        Name used in messages and in ``sol.history`` (default ``"bilinear[i]"``).

    Examples
    --------
    >>> import sympy as sp
    >>> from symid import scr
    >>> x, y, a = sp.symbols("x y a")
    >>> term = scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y - a]], weight=0.1)
    """

    A: Any
    P: Any
    B: Any
    C: Any
    weight: float = 1.0
    name: str | None = None


@dataclass(frozen=True, eq=False)
class SumSquares:
    """Objective term ``weight * ||F(x)||_F^2`` for an affine (possibly complex) map F.

    Parameters
    ----------
    F : Affine or sympy matrix
        The affine map F(x).
    weight : float, optional
        Its weight (default 1).

    Examples
    --------
    >>> import numpy as np
    >>> from symid import scr
    >>> fit = scr.SumSquares(scr.Affine([[-1.0]], {"x": [[1.0]]}))   # (x - 1)^2
    """

    F: Any
    weight: float = 1.0


@dataclass(frozen=True, eq=False)
class CompiledTerm:
    """A bilinear term compiled to local maps on the full x (complex allowed)."""

    name: str
    A: LocalMap
    P: np.ndarray
    B: LocalMap
    C: LocalMap
    weight: float


def _quadratic_from_sympy(expr: Any, layout: Layout) -> tuple[sps.csr_matrix, np.ndarray, float]:
    e = checked_expansion(sympy_entry(expr, "objective", layout), "objective")
    index = layout.symbol_index
    stray = e.free_symbols - set(index)
    if stray:
        raise ModelError(f"objective holds symbol(s) {', '.join(sorted(map(str, stray)))} that are not variables")
    n = layout.n
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    g = np.zeros(n)
    c = 0.0
    for term in sp.Add.make_args(e):
        fs = sorted(term.free_symbols, key=sp.default_sort_key)
        coef, dep = term.as_independent(*fs, as_Add=False) if fs else (term, sp.Integer(1))
        cv = complex(sp.N(coef))
        if cv.imag != 0:
            raise ModelError(f"objective term {term} has a complex coefficient; the objective must be real")
        powers = dep.as_powers_dict() if fs else {}
        degree = 0
        for base, ex in powers.items():
            if base not in index or not (ex.is_Integer and ex > 0):
                raise ModelError(f"objective term {term} is not a polynomial of degree ≤ 2 in the variables")
            degree += int(ex)
        if degree > 2:
            raise ModelError(f"objective term {term} has degree {degree}; SCR needs a convex quadratic objective")
        if degree == 0:
            c += cv.real
        elif degree == 1:
            g[index[fs[0]]] += cv.real
        elif len(powers) == 1:
            i = index[fs[0]]
            rows.append(i)
            cols.append(i)
            vals.append(cv.real)
        else:
            i, j = index[fs[0]], index[fs[1]]
            rows += [i, j]
            cols += [j, i]
            vals += [cv.real / 2, cv.real / 2]
    H = sps.csr_matrix((vals, (rows, cols)), shape=(n, n))
    if H.nnz:
        used = np.unique(rows)
        ev = np.linalg.eigvalsh(H[used][:, used].toarray())
        if ev[0] < -1e-10 * max(1.0, abs(ev[-1])):
            raise ModelError(f"the objective is not convex: its Hessian has eigenvalue {ev[0]:.3g} < 0")
    return H, g, c


def _quadratic_from_sumsquares(term: SumSquares, layout: Layout, name: str) -> tuple[sps.csr_matrix, np.ndarray, float]:
    w = float(term.weight)
    if not np.isfinite(w) or w < 0:
        raise ModelError(f"{name}: weight must be finite and ≥ 0, got {term.weight}")
    m = as_map(term.F, layout, name)
    f0 = m.const.reshape(-1)
    J = m.coef.reshape(f0.size, m.idx.size)  # no column when F does not depend on the variables (a constant)
    Hl = w * (J.conj().T @ J).real
    gl = 2 * w * (f0.conj() @ J).real
    ii, jj = np.meshgrid(m.idx, m.idx, indexing="ij")
    H = sps.csr_matrix((Hl.ravel(), (ii.ravel(), jj.ravel())), shape=(layout.n, layout.n))
    g = np.zeros(layout.n)
    np.add.at(g, m.idx, gl)
    return H, g, w * float(np.vdot(f0, f0).real)


def _residual_groups(terms: list[CompiledTerm]) -> list[tuple[np.ndarray, ...]]:
    """The user's bilinear terms stacked by shape (complex), for batched residuals."""
    by: dict[tuple[tuple[int, int], ...], list[int]] = {}
    for i, t in enumerate(terms):
        by.setdefault((t.A.shape, t.P.shape, t.B.shape), []).append(i)
    out = []
    for members in by.values():
        ts = [terms[i] for i in members]
        idx = stack_index([[t.A, t.B, t.C] for t in ts])
        stacked = [stack_maps([getattr(t, k) for t in ts], idx, real=False) for k in "ABC"]
        P = np.stack([t.P for t in ts])
        out.append((np.asarray(members), idx, *stacked[0], P, *stacked[1], *stacked[2]))
    return out


def _as_list(value: Any) -> list[Any]:
    if value is None:
        return []
    if isinstance(value, (list, tuple)):
        return list(value)
    return [value]


class BilinearProblem:
    """Problem (2-1) of the thesis, with an optional convex quadratic objective.

    minimise f(x) subject to A_i(x) P_i B_i(x) = C_i(x), D(x) = 0, E(x) ⪰ 0.

    Everything is compiled and checked at construction, so a malformed problem fails
    here, with a message naming the term and entry.

    Parameters
    ----------
    variables : sequence of sympy.Symbol or Variable
        Decision variables; real scalars may be plain sympy symbols.
    bilinear : sequence of Bilinear
        The bilinear terms (any number, each with its own weight).
    objective : sympy expression, SumSquares or list of them, optional
        Convex quadratic objective f(x) (default 0: a feasibility problem).
    equalities : sequence, optional
        Affine matrices (sympy, arrays or :class:`Affine`) constrained to zero. Complex
        entries give two real equalities.
    lmis : sequence, optional
        Symmetric (or Hermitian) affine matrices constrained to be positive semidefinite.

    Raises
    ------
    NonAffineError
        A matrix entry is not affine in the variables.
    ModelError
        Shapes of A, P, B, C do not chain, an LMI is not symmetric, P is zero, or an
        unknown symbol appears.

    Examples
    --------
    Rosenbrock as thesis (2-17):

    >>> import sympy as sp
    >>> from symid import scr
    >>> x, y, a = sp.symbols("x y a")
    >>> prob = scr.BilinearProblem(
    ...     variables=[x, y, a],
    ...     bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y - a]], weight=0.1)],
    ...     objective=100 * a**2 + (1 - x)**2)
    >>> prob.n
    3
    """

    def __init__(self, variables: Sequence[Variable | sp.Symbol], bilinear: Iterable[Bilinear] = (),
                 objective: Any = None, equalities: Iterable[Any] = (), lmis: Iterable[Any] = ()):
        self.layout = Layout(variables)
        lay = self.layout
        self.terms: list[CompiledTerm] = []
        for i, b in enumerate(_as_list(list(bilinear))):
            if not isinstance(b, Bilinear):
                raise ModelError(f"bilinear[{i}] must be a scr.Bilinear, got {type(b).__name__}")
            name = b.name or f"bilinear[{i}]"
            A = as_map(b.A, lay, f"{name}.A")
            B = as_map(b.B, lay, f"{name}.B")
            C = as_map(b.C, lay, f"{name}.C")
            Pm = as_map(b.P, lay, f"{name}.P")
            if Pm.idx.size:
                raise ModelError(f"{name}.P must be constant; it depends on "
                                 f"{', '.join(lay.labels[i] for i in Pm.idx)}")
            P = Pm.const
            if not np.any(P != 0):
                raise ModelError(f"{name}.P is zero; (2-1) needs a nonzero P")
            if A.shape[1] != P.shape[0] or P.shape[1] != B.shape[0] or C.shape != (A.shape[0], B.shape[1]):
                raise ModelError(f"{name}: shapes do not chain: A {A.shape}, P {P.shape}, B {B.shape}, C {C.shape}; "
                                 f"need A (j×k), P (k×l), B (l×m), C (j×m)")
            w = float(b.weight)
            if not np.isfinite(w) or w <= 0:
                raise ModelError(f"{name}: weight must be finite and > 0, got {b.weight}")
            self.terms.append(CompiledTerm(name, A, P, B, C, w))
        self.equalities: list[LocalMap] = []
        for i, e in enumerate(_as_list(equalities)):
            self.equalities.append(as_map(e, lay, f"equalities[{i}]"))
        self.lmis: list[LocalMap] = []
        for i, e in enumerate(_as_list(lmis)):
            m = as_map(e, lay, f"lmis[{i}]")
            r, c = m.shape
            if r != c:
                raise ModelError(f"lmis[{i}] must be square, got shape {m.shape}")
            for arr, what in [(m.const, "constant part")] + [(m.coef[:, :, u], f"coefficient of {lay.labels[k]}")
                                                           for u, k in enumerate(m.idx)]:
                bad = np.abs(arr - arr.conj().T) > 1e-12 * max(1.0, float(np.abs(arr).max()))
                if np.any(bad):
                    i0, j0 = np.argwhere(bad)[0]
                    raise ModelError(f"lmis[{i}] is not symmetric (Hermitian): its {what} differs at entries "
                                     f"({i0}, {j0}) and ({j0}, {i0})")
            self.lmis.append(m)
        n = lay.n
        H = sps.csr_matrix((n, n))
        g = np.zeros(n)
        c = 0.0
        for k, o in enumerate(_as_list(objective)):
            if isinstance(o, SumSquares):
                Hk, gk, ck = _quadratic_from_sumsquares(o, lay, f"objective[{k}]")
            else:
                Hk, gk, ck = _quadratic_from_sympy(o, lay)
            H, g, c = H + Hk, g + gk, c + ck
        self._residual_groups: list[tuple[np.ndarray, ...]] | None = None
        self.H: sps.csr_matrix = sps.csr_matrix(H)
        self.g: np.ndarray = g
        self.c: float = c

    @property
    def n(self) -> int:
        """Number of real scalar unknowns."""
        return self.layout.n

    @property
    def variables(self) -> tuple[Variable, ...]:
        return self.layout.variables

    def objective_value(self, x: np.ndarray) -> float:
        """f(x) = xᵀHx + gᵀx + c."""
        return float(x @ (self.H @ x) + self.g @ x + self.c)

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Frobenius norm of A(x) P B(x) − C(x) for every bilinear term (batched over equal shapes)."""
        if self._residual_groups is None:
            self._residual_groups = _residual_groups(self.terms)
        x = np.asarray(x, dtype=float)
        out = np.zeros(len(self.terms))
        for members, idx, A0, Ac, P, B0, Bc, C0, Cc in self._residual_groups:
            xl = np.where(idx >= 0, x[np.maximum(idx, 0)], 0.0)
            A = A0 + np.einsum("sjku,su->sjk", Ac, xl)
            B = B0 + np.einsum("slmu,su->slm", Bc, xl)
            C = C0 + np.einsum("sjmu,su->sjm", Cc, xl)
            r = A @ P @ B - C
            out[members] = np.sqrt(np.einsum("sij,sij->s", r.conj(), r).real)
        return out

    def __repr__(self) -> str:
        return (f"BilinearProblem(n={self.n}, variables={list(self.layout.names)}, bilinear={len(self.terms)}, "
                f"equalities={len(self.equalities)}, lmis={len(self.lmis)})")

