"""Exact affine parameter maps X(θ) = X0 + Σ θi Xi extracted with sympy."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from symid.errors import ModelError, NonAffineError

__all__ = ["AffineMap", "affine_map", "order_parameters"]


@dataclass(frozen=True, eq=False)
class AffineMap:
    """An affine matrix function of the parameter vector, X(θ) = X0 + Σ θi Xi.

    Attributes
    ----------
    name : str
        Name of the matrix (``"A"``, ``"M"``, ...).
    constant : sympy.Matrix
        Exact constant part X0.
    coefficients : tuple of sympy.Matrix
        Exact coefficient Xi of each parameter, in the order of ``parameters``.
    parameters : tuple of sympy.Symbol
        The parameter vector θ.
    X0 : numpy.ndarray
        ``constant`` as floats, shape (rows, cols).
    Xi : numpy.ndarray
        ``coefficients`` stacked as floats, shape (len(parameters), rows, cols).

    Examples
    --------
    >>> import sympy as sp
    >>> from symid.model.affine import affine_map
    >>> a, b = sp.symbols("a b", real=True)
    >>> amap = affine_map(sp.Matrix([[a + 1, 2 * b]]), (a, b), "X")
    >>> amap([1.0, 2.0])
    array([[2., 4.]])
    """

    name: str
    constant: sp.Matrix
    coefficients: tuple[sp.Matrix, ...]
    parameters: tuple[sp.Symbol, ...]
    X0: np.ndarray = field(repr=False)
    Xi: np.ndarray = field(repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        """Shape (rows, cols) of the matrix."""
        return self.X0.shape

    @property
    def is_constant(self) -> bool:
        """True when no parameter appears in the matrix."""
        return not np.any(self.Xi)

    @property
    def depends_on(self) -> tuple[int, ...]:
        """Indices of the parameters that appear in the matrix."""
        return tuple(int(i) for i in np.flatnonzero(np.any(self.Xi != 0, axis=(1, 2))))

    def __call__(self, theta: Sequence[float] | np.ndarray) -> np.ndarray:
        """Evaluate X(θ) for a parameter vector in ``parameters`` order."""
        th = np.asarray(theta, dtype=float).reshape(-1)
        if th.size != len(self.parameters):
            raise ModelError(f"{self.name}(θ) needs {len(self.parameters)} parameter values, got {th.size}")
        if th.size == 0:
            return self.X0.copy()
        return self.X0 + np.tensordot(th, self.Xi, axes=1)

    def symbolic(self) -> sp.Matrix:
        """Rebuild the symbolic matrix X0 + Σ θi Xi."""
        out = sp.Matrix(self.constant)
        for p, c in zip(self.parameters, self.coefficients, strict=True):
            out += p * c
        return out


def _is_affine(expr: sp.Expr, symbols: Sequence[sp.Symbol]) -> bool:
    """Whether ``expr`` is affine in ``symbols`` (every first derivative free of them)."""
    return not any(sp.simplify(sp.diff(expr, s)).free_symbols & set(symbols) for s in symbols)


def _hint(expr: sp.Expr, involved: Sequence[sp.Symbol]) -> str:
    names = [str(p) for p in involved]
    _, den = sp.fraction(sp.together(expr))
    if den in set(involved):
        inv = sp.Symbol(f"{den}inv")
        if _is_affine(expr.subs(den, 1 / inv), [*(set(involved) - {den}), inv]):  # 1/m, 1 + 2/m
            return f"introduce a new parameter such as `{inv} = 1/{den}` and write the entry in it"
    if len(involved) > 1:
        # a sum of reciprocals (1/R01 + 1/R12: conductances of resistances in series with a node): one reciprocal
        # parameter per symbol keeps them apart (a new user was told r = 1/R01 + 1/R12, one parameter for the sum)
        invs = {p: sp.Symbol(f"{p}inv") for p in involved}
        if _is_affine(expr.subs({p: 1 / q for p, q in invs.items()}), list(invs.values())):
            new = ", ".join(f"`{q} = 1/{p}`" for p, q in invs.items())
            return (f"introduce a reciprocal parameter for each ({new}: a conductance for a resistance) and write "
                    f"the entry in them")
    # a ratio written with its sign (-k/m in A) is suggested without it: the new parameter can then be declared
    # positive like the physical ones, and the entry is -r (a new user's hint read r = -ks/ms)
    neg = expr.could_extract_minus_sign()
    shown, entry = (sp.sstr(-expr), "as its negative") if neg else (sp.sstr(expr), "in it")
    if den.free_symbols & set(involved):  # c/m, 1/(a + b), k/(m1*m2)
        return (f"introduce a new parameter for the whole ratio (for example `r = {shown}`) "
                f"and write the entry {entry}" + (" (-r)" if neg else ""))
    if len(involved) == 1:
        return (f"introduce a new parameter for the nonlinear function of {names[0]} (for example `f = {shown}`"
                + (", the entry -f)" if neg else ")"))
    return (f"introduce a new parameter for the nonlinear combination of {', '.join(names)} "
            f"(for example `{''.join(names)} = {'*'.join(names)}` when the entry holds a product)")


def _descriptor_hint(name: str, expr: sp.Expr, involved: Sequence[sp.Symbol]) -> str:
    """For a ratio in a first-order model's A (a conductance over a capacity, a friction over an inertia): the
    second-order form that keeps the physical parameters (E x' = F x + G u as M q'' + V q' = B u with x = q')."""
    if name != "A":
        return ""
    _, den = sp.fraction(sp.together(expr))
    if not den.free_symbols & set(involved):
        return ""
    return (" Or keep the physical parameters: a model E x' = F x + G u whose E holds them (capacities, "
            "inertias) is SecondOrderModel(M=E, V=-F, K=0, B=G, C=C, output='velocity'), its velocity being x.")


def order_parameters(matrices: Sequence[tuple[str, sp.Matrix]]) -> tuple[sp.Symbol, ...]:
    """Parameters in order of first appearance, row by row, through the given matrices.

    Within one entry, symbols are taken in sympy's canonical order (alphabetical for
    plain names).
    """
    seen: dict[sp.Symbol, None] = {}
    for _, mat in matrices:
        for i in range(mat.rows):
            for j in range(mat.cols):
                for s in sorted(mat[i, j].free_symbols, key=sp.default_sort_key):
                    seen.setdefault(s, None)
    return tuple(seen)


def affine_map(matrix: sp.Matrix, parameters: Sequence[sp.Symbol], name: str) -> AffineMap:
    """Extract the exact affine map of a symbolic matrix.

    Parameters
    ----------
    matrix : sympy.Matrix
        The symbolic matrix.
    parameters : sequence of sympy.Symbol
        The parameter vector θ; every free symbol of ``matrix`` must be in it.
    name : str
        Name of the matrix, used in error messages.

    Returns
    -------
    AffineMap

    Raises
    ------
    NonAffineError
        If an entry is not affine in the parameters (``1/m``, ``k*c``, ``sin(a)``); the
        message names the matrix, the entry, the parameters involved and a hint.
    ModelError
        If an entry holds a symbol that is not a parameter, or a complex number.
    """
    params = tuple(parameters)
    pset = set(params)
    rows, cols = matrix.shape
    const = sp.zeros(rows, cols)
    coefs = [sp.zeros(rows, cols) for _ in params]
    for i in range(rows):
        for j in range(cols):
            expr = matrix[i, j]
            stray = expr.free_symbols - pset
            if stray:
                raise ModelError(
                    f"{name}[{i}, {j}] = {expr} holds symbol(s) {', '.join(sorted(map(str, stray)))} that are "
                    f"not among the model's parameters ({', '.join(map(str, params)) or 'none'})")
            involved = []
            derivs: dict[int, sp.Expr] = {}
            present = expr.free_symbols
            for k, p in enumerate(params):
                if p not in present:
                    continue
                d = sp.diff(expr, p)
                if d.free_symbols & pset:
                    d = sp.simplify(d)
                if d.free_symbols & pset:
                    involved.append(p)
                derivs[k] = d
            if involved:
                others = {s for p in present for s in sp.diff(expr, p).free_symbols & pset}
                involved = sorted(set(involved) | others, key=sp.default_sort_key)
                names = ", ".join(map(str, involved))
                raise NonAffineError(
                    f"matrix {name}, entry ({i}, {j}) = {expr} is not affine in the parameters: it is nonlinear "
                    f"in {names}. symid needs every entry to be affine, X(θ) = X0 + Σ θi Xi. "
                    f"Hint: {_hint(expr, involved)}.{_descriptor_hint(name, expr, involved)} A value you know "
                    f"(a gain, a mass) is a number in the matrix, not a parameter: known= is applied to a model "
                    f"already built, so it cannot make an entry affine.",
                    matrix=name, entry=(i, j), expression=str(expr),
                    parameters=tuple(str(p) for p in involved))
            c0 = expr.xreplace({p: 0 for p in present}) if present else expr
            for k, d in derivs.items():
                coefs[k][i, j] = d
            const[i, j] = c0
    parts = [("constant part", const)] + [(f"coefficient of {p}", c) for p, c in zip(params, coefs, strict=True)]
    for label, m in parts:
        for i in range(rows):
            for j in range(cols):
                v = m[i, j]
                if v.has(sp.I) or not v.is_number or v.is_real is False:
                    raise ModelError(f"{name}[{i}, {j}]: the {label} is {v}; matrices must be real")
    X0 = np.array(const.evalf(), dtype=float).reshape(rows, cols)
    Xi = np.array([np.array(c.evalf(), dtype=float).reshape(rows, cols) for c in coefs])
    Xi = Xi.reshape(len(params), rows, cols)
    return AffineMap(name=name, constant=const, coefficients=tuple(coefs), parameters=params, X0=X0, Xi=Xi)
