"""Numeric affine maps X(x) = X0 + Σ_u x[idx_u] X_u, from sympy or from arrays.

A :class:`LocalMap` stores only the entries of x a matrix depends on (``idx``), so a
problem with hundreds of terms, each touching a few shared and a few private variables,
stays linear in size. :class:`Affine` is the public numeric constructor; sympy matrices
are compiled by :func:`compile_sympy` with one expansion per entry.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from symid.engine.scr.variables import Layout
from symid.errors import ModelError, NonAffineError
from symid.model.expressions import parse_expression, sympify_value

__all__ = ["MAX_EXPANDED_TERMS", "Affine", "LocalMap", "as_map", "checked_expansion", "compile_sympy", "stack_index",
           "stack_maps", "sympy_entry", "variable_names"]

MAX_EXPANDED_TERMS = 100_000
"""Most terms an entry or objective may expand to (an upper bound, counted before like terms merge)."""


@dataclass(frozen=True, eq=False)
class LocalMap:
    """X(x) = const + Σ_u x[idx[u]] coef[:, :, u] (complex entries allowed, x real)."""

    const: np.ndarray  # (r, c) complex
    idx: np.ndarray  # (u,) int
    coef: np.ndarray  # (r, c, u) complex

    @property
    def shape(self) -> tuple[int, int]:
        return self.const.shape

    @property
    def is_complex(self) -> bool:
        return bool(np.any(self.const.imag != 0) or np.any(self.coef.imag != 0))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return self.const + self.coef @ x[self.idx]

    def rows(self, sel: np.ndarray) -> LocalMap:
        return LocalMap(self.const[sel], self.idx, self.coef[sel])

    def cols(self, sel: np.ndarray) -> LocalMap:
        return LocalMap(self.const[:, sel], self.idx, self.coef[:, sel])

    def constant_rows(self) -> np.ndarray:
        return ~np.any(self.coef != 0, axis=(1, 2))

    def constant_cols(self) -> np.ndarray:
        return ~np.any(self.coef != 0, axis=(0, 2))

    def on(self, idx: np.ndarray) -> np.ndarray:
        """Coefficients re-expressed on a (super)set of indices ``idx``: array (r, c, len(idx))."""
        out = np.zeros((*self.const.shape, len(idx)), dtype=complex)
        pos = {int(i): k for k, i in enumerate(idx)}
        for u, i in enumerate(self.idx):
            out[:, :, pos[int(i)]] += self.coef[:, :, u]
        return out


def stack_index(maps_per_term: list[list[LocalMap]]) -> np.ndarray:
    """Per term, the sorted union of the indices its maps touch, padded with −1 to a common width."""
    sets = [np.unique(np.concatenate([m.idx for m in ms])).astype(np.int64) for ms in maps_per_term]
    u = max((x.size for x in sets), default=0)
    idx = np.full((len(sets), u), -1, dtype=np.int64)
    for t, x in enumerate(sets):
        idx[t, : x.size] = x
    return idx


def stack_maps(maps: list[LocalMap], idx: np.ndarray, real: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Equal-shape maps stacked on the padded index ``idx`` of :func:`stack_index`.

    Returns the constants (s, r, c) and coefficients (s, r, c, u), zero at padding; real
    parts only when ``real``.
    """
    s, u = idx.shape
    r, c = maps[0].shape
    const = np.stack([m.const for m in maps])
    coef = np.zeros((s, r, c, u), dtype=complex)
    for t, m in enumerate(maps):
        if m.idx.size:
            pos = np.searchsorted(idx[t, : np.count_nonzero(idx[t] >= 0)], m.idx)
            coef[t][:, :, pos] = m.coef
    return (const.real.copy(), coef.real.copy()) if real else (const, coef)


def _clean(idx: np.ndarray, coef: np.ndarray, const: np.ndarray) -> LocalMap:
    """Merge duplicate indices and drop variables with all-zero coefficients."""
    idx = np.asarray(idx, dtype=np.int64).reshape(-1)
    if idx.size:
        uniq, inv = np.unique(idx, return_inverse=True)
        merged = np.zeros((*const.shape, uniq.size), dtype=complex)
        np.add.at(merged.transpose(2, 0, 1), inv, coef.transpose(2, 0, 1))
        keep = np.any(merged != 0, axis=(0, 1))
        idx, coef = uniq[keep], merged[:, :, keep]
    else:
        coef = np.zeros((*const.shape, 0), dtype=complex)
    return LocalMap(np.asarray(const, dtype=complex), idx, coef)


def _numeric_array(value: Any, what: str) -> np.ndarray:
    """An array of numbers as complex; text is refused, never read by numpy (which would parse "nan")."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"{what} cannot be read as an array of numbers: {exc}") from None
    if arr.dtype.kind == "O" and all(isinstance(v, (int, float, complex, np.number)) and not isinstance(v, bool)
                                     for v in arr.flat):
        arr = arr.astype(complex)
    if arr.dtype.kind not in "biufc":
        raise ModelError(f"{what} must hold numbers, got an array of dtype {arr.dtype} "
                         f"(write symbolic or text entries as a sympy matrix or a nested list instead of Affine)")
    return arr.astype(complex)


class Affine:
    """A numeric affine matrix map, the sympy-free way to pose problem data.

    ``Affine(const, {var: coef, ...})`` is the matrix
    ``const + Σ_var Σ_e var[e] * coef[..., e]`` where ``coef`` has shape
    ``const.shape + var.shape``. For a complex variable the map is complex-linear in it.

    Parameters
    ----------
    const : array_like, shape (r, c)
        Constant part (real or complex). A vector is taken as a column.
    coefs : mapping, optional
        Keys are variable names, sympy symbols or :class:`Variable`; values are arrays of
        shape ``const.shape + var.shape``.

    Examples
    --------
    >>> import numpy as np
    >>> from symid import scr
    >>> G = scr.Variable("G", (2, 1), complex=True)
    >>> jw = scr.Affine(np.zeros((2, 1)), {G: 1j * 0.5 * np.eye(2).reshape(2, 1, 2, 1)})
    >>> lay = scr.Layout([G])
    >>> m = jw.compile(lay)
    >>> m(lay.pack({"G": [[1.0], [2.0]]}))
    array([[0.+0.5j],
           [0.+1.j ]])
    """

    def __init__(self, const: Any, coefs: Mapping[Any, Any] | None = None):
        c0 = _numeric_array(const, "Affine: the constant part")
        if c0.ndim == 1:
            c0 = c0.reshape(-1, 1)
        if c0.ndim == 0:
            c0 = c0.reshape(1, 1)
        if c0.ndim != 2:
            raise ModelError(f"Affine: the constant part must be a matrix, got shape {c0.shape}")
        self.const = c0
        self.coefs = dict(coefs or {})

    @property
    def shape(self) -> tuple[int, int]:
        return self.const.shape

    def compile(self, layout: Layout, name: str = "matrix") -> LocalMap:
        """The :class:`LocalMap` of this map on the problem's layout."""
        if not np.all(np.isfinite(self.const)):
            raise ModelError(f"{name}: the constant part holds NaN or inf")
        r, c = self.const.shape
        idxs, cols = [], []
        for key, arr in self.coefs.items():
            v = layout.variable(key)
            a = _numeric_array(arr, f"{name}: the coefficient of {v.name}")
            want = (r, c, *v.shape)
            if a.shape != want and a.size == int(np.prod(want)):
                a = a.reshape(want)
            if a.shape != want:
                raise ModelError(f"{name}: the coefficient of {v.name} has shape {a.shape}, expected {want}")
            if not np.all(np.isfinite(a)):
                raise ModelError(f"{name}: the coefficient of {v.name} holds NaN or inf")
            a = a.reshape(r, c, -1)
            sl = layout.slice(v)
            if v.complex:
                ne = a.shape[2]
                idxs.append(np.arange(sl.start, sl.start + 2 * ne))
                cols.append(np.concatenate([a, 1j * a], axis=2))
            else:
                idxs.append(np.arange(sl.start, sl.stop))
                cols.append(a)
        if not idxs:
            return _clean(np.zeros(0, dtype=np.int64), np.zeros((r, c, 0)), self.const)
        return _clean(np.concatenate(idxs), np.concatenate(cols, axis=2), self.const)


def variable_names(layout: Layout) -> dict[str, sp.Expr]:
    """What a name in a text entry means for a problem: its scalar variables and their symbols."""
    out: dict[str, sp.Expr] = {str(s): s for s in layout.symbol_index}
    for v in layout.variables:
        if v.symbol is not None:
            out[v.name] = v.symbol
    return out


def sympy_entry(value: Any, where: str, layout: Layout) -> sp.Expr:
    """One entry as a sympy expression: text through the safe grammar (:mod:`symid.model.expressions`),
    with names resolved to the problem's variables; anything else through ``sympify(strict=True)``,
    which never parses text."""
    if isinstance(value, str):
        return parse_expression(value, where, symbol=variable_names(layout))
    out = sympify_value(value, where)  # never parses text (nor text inside a tuple or dict)
    if not isinstance(out, sp.Expr):
        raise ModelError(f"{where} = {value!r} is not a number or an expression "
                         f"(sympy reads it as {type(out).__name__})")
    if out.has(sp.oo, -sp.oo, sp.zoo, sp.nan):
        raise ModelError(f"{where} = {out} is not finite")
    return out


def _expanded_terms(expr: sp.Basic, limit: int) -> int:
    """An upper bound on the number of terms ``sympy.expand(expr)`` builds, capped at ``limit + 1``."""
    if expr.is_Add:
        return min(limit + 1, sum(_expanded_terms(a, limit) for a in expr.args))
    if expr.is_Mul:
        out = 1
        for a in expr.args:
            out = min(limit + 1, out * _expanded_terms(a, limit))
        return out
    if expr.is_Pow and expr.exp.is_Integer:
        n, k = _expanded_terms(expr.base, limit), abs(int(expr.exp))
        if n == 1:
            return 1
        if n > limit or k > limit:
            return limit + 1
        return min(limit + 1, math.comb(n + k - 1, k))  # monomials of degree k in n terms
    # a function, or a power with another exponent: one term, whose arguments expand inside
    return limit + 1 if any(_expanded_terms(a, limit) > limit for a in expr.args) else 1


def checked_expansion(expr: sp.Expr, where: str) -> sp.Expr:
    """``sympy.expand(expr)``, refused with a :class:`ModelError` when it would build over
    :data:`MAX_EXPANDED_TERMS` terms (``(x1 + … + x8)**64`` has 10⁹: expanding it never ends)."""
    if _expanded_terms(expr, MAX_EXPANDED_TERMS) > MAX_EXPANDED_TERMS:
        raise ModelError(f"{where} = {sp.sstr(expr)[:80]} would expand to more than {MAX_EXPANDED_TERMS} terms; "
                         f"write it expanded, or as scr.SumSquares for a large objective")
    return sp.expand(expr)


def _sympy_matrix(value: Any, name: str, layout: Layout) -> sp.Matrix:
    if isinstance(value, sp.MatrixBase):
        rows = value.tolist()
    elif isinstance(value, (sp.Basic, int, float, complex, str, np.number)):
        rows = [[value]]
    else:
        try:
            arr = np.asarray(value, dtype=object)
        except (TypeError, ValueError) as exc:
            raise ModelError(f"{name} cannot be read as a matrix: {exc}") from None
        if arr.ndim == 0:
            rows = [[arr.item()]]
        elif arr.ndim == 1:  # a column, as sympy.Matrix reads a flat list
            rows = [[x] for x in arr]
        elif arr.ndim == 2:
            rows = arr.tolist()
        else:
            raise ModelError(f"{name} must be a matrix; got {arr.ndim} dimensions")
    return sp.Matrix([[sympy_entry(x, f"{name}[{i}, {j}]", layout) for j, x in enumerate(r)]
                      for i, r in enumerate(rows)])


def compile_sympy(value: Any, layout: Layout, name: str) -> LocalMap:
    """Compile a sympy matrix (or scalar) affine in the layout's symbols.

    Raises
    ------
    NonAffineError
        If an entry is not affine; the message names ``name`` and the entry.
    ModelError
        If an entry holds a symbol that is not a variable of the problem.
    """
    mat = _sympy_matrix(value, name, layout)
    rows, cols = mat.shape
    index = layout.symbol_index
    syms = set(index)
    const = np.zeros((rows, cols), dtype=complex)
    idx: list[int] = []
    ent: list[tuple[int, int, complex]] = []
    for i in range(rows):
        for j in range(cols):
            expr = mat[i, j]
            fs = expr.free_symbols
            stray = fs - syms
            if stray:
                raise ModelError(f"{name}[{i}, {j}] = {expr} holds symbol(s) {', '.join(sorted(map(str, stray)))} "
                                 f"that are not variables of the problem ({', '.join(layout.names) or 'none'})")
            if not fs:
                const[i, j] = complex(sp.N(expr))
                continue
            for term in sp.Add.make_args(checked_expansion(expr, f"{name}[{i}, {j}]")):
                tfs = term.free_symbols
                if not tfs:
                    const[i, j] += complex(sp.N(term))
                    continue
                if len(tfs) == 1:
                    s = next(iter(tfs))
                    coef, dep = term.as_independent(s, as_Add=False)
                    if dep == s:
                        idx.append(index[s])
                        ent.append((i, j, complex(sp.N(coef))))
                        continue
                raise NonAffineError(
                    f"{name}, entry ({i}, {j}) = {expr} is not affine in the variables: the term {term} is "
                    f"nonlinear in {', '.join(sorted(map(str, tfs)))}. SCR needs every matrix of a bilinear term, "
                    f"equality and LMI to be affine; move products of variables into the A(x) P B(x) product",
                    matrix=name, entry=(i, j), expression=str(expr), parameters=tuple(sorted(map(str, tfs))))
    if not np.all(np.isfinite(const)):
        raise ModelError(f"{name} has a constant entry that is NaN or inf")
    coef = np.zeros((rows, cols, len(ent)), dtype=complex)
    for u, (i, j, v) in enumerate(ent):
        coef[i, j, u] = v
    return _clean(np.asarray(idx, dtype=np.int64), coef, const)


def as_map(value: Any, layout: Layout, name: str) -> LocalMap:
    """Compile any accepted matrix input: :class:`Affine`, :class:`LocalMap`, array or sympy."""
    if isinstance(value, LocalMap):
        return value
    if isinstance(value, Affine):
        return value.compile(layout, name)
    if isinstance(value, (sp.Basic, sp.MatrixBase, str)):
        return compile_sympy(value, layout, name)
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        arr = np.asarray([], dtype=object)
    if arr.size and (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        if arr.ndim > 2:
            raise ModelError(f"{name} must be a matrix, got an array of shape {arr.shape}")
        a = arr.astype(complex).reshape((1, 1) if arr.ndim == 0 else ((-1, 1) if arr.ndim == 1 else arr.shape))
        if not np.all(np.isfinite(a)):
            raise ModelError(f"{name} holds NaN or inf")
        return LocalMap(a, np.zeros(0, dtype=np.int64), np.zeros((*a.shape, 0), dtype=complex))
    return compile_sympy(value, layout, name)
