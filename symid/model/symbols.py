"""Declaring parameters and turning user input into sympy matrices."""

from __future__ import annotations

import keyword
import unicodedata
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError
from symid.model.expressions import parse_expression, sympify_value

__all__ = ["as_symbolic_matrix", "parameters", "parse_entry"]

def parameters(names: str | Sequence[str], *, positive: bool = False):
    """Declare the unknown physical parameters of a model.

    Parameters
    ----------
    names : str or sequence of str
        Names separated by spaces or commas (``"m1 m2 k"``), or a sequence of names.
    positive : bool, optional
        Declare the parameters positive. Estimators use this as a bound
        (``theta > 0``) and the identifiability report uses it to discard
        solutions. Default ``False`` (real, any sign).

    Returns
    -------
    sympy.Symbol or tuple of sympy.Symbol
        One real sympy symbol per name; a single symbol when one name is given,
        as :func:`sympy.symbols` does.

    Examples
    --------
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> m.is_positive
    True
    """
    if isinstance(names, str):
        parts = [p for p in names.replace(",", " ").split() if p]
    else:
        parts = [str(p).strip() for p in names]
    if not parts:
        raise ModelError("parameters() needs at least one name, got an empty string")
    for p in parts:
        if not p.isidentifier():
            raise ModelError(f"parameter name {p!r} is not a valid identifier")
        if keyword.iskeyword(p):
            raise ModelError(f"parameter name {p!r} is a Python keyword; choose another (e.g. {p + '_'!r})")
        normal = unicodedata.normalize("NFKC", p)
        if normal != p:  # a text entry could never name it: Python reads identifiers in NFKC form
            raise ModelError(f"parameter name {p!r} {p!a} is read by Python as {normal!r} {normal!a}; "
                             f"write {normal!r}")
    if len(set(parts)) != len(parts):
        dup = sorted({p for p in parts if parts.count(p) > 1})
        raise ModelError(f"parameter names are repeated: {', '.join(dup)}")
    assumptions = {"positive": True} if positive else {"real": True}
    symbols = tuple(sp.Symbol(p, **assumptions) for p in parts)
    return symbols[0] if len(symbols) == 1 else symbols


def parse_entry(text: str, where: str = "entry") -> sp.Expr:
    """Parse a matrix entry written as text, every bare name being a real parameter.

    The text is never evaluated: it is read by the whitelisted grammar of
    :mod:`symid.model.expressions` (numbers, names, ``+ - * /``, numeric powers with
    ``**`` or ``^``, parentheses, a few functions). Unlike :func:`sympy.sympify`, a name
    is always a symbol, so ``"E*A/L"``, ``"I"``, ``"N"``, ``"S"``, ``"beta"`` or
    ``"gamma"`` are parameters, not sympy's constants, singletons or special functions
    (a physical model is more likely to mean Young's modulus than Euler's number by
    ``E``). The one exception is ``pi`` (π); write ``exp(1)`` for e.

    Parameters
    ----------
    text : str
        The entry, e.g. ``"c1 + c2"``.
    where : str, optional
        Where the entry sits, for error messages (``"A[1, 0]"``).

    Returns
    -------
    sympy.Expr
        The expression; its symbols are real (``real=True``).

    Raises
    ------
    ModelError
        If the text is outside the grammar, naming the entry and the construct.

    Examples
    --------
    >>> from symid.model.symbols import parse_entry
    >>> expr = parse_entry("E*I/L**3 + pi")
    >>> sorted(map(str, expr.free_symbols))
    ['E', 'I', 'L']
    """
    return parse_expression(text, where)


def _entry(value: Any, name: str, i: int, j: int) -> sp.Expr:
    if isinstance(value, str):
        return parse_entry(value, f"{name}[{i}, {j}]")
    if isinstance(value, (np.floating, np.integer, np.complexfloating)):
        value = value.item()
    if isinstance(value, float):
        if not np.isfinite(value):
            raise ModelError(f"{name}[{i}, {j}] is {value}; entries must be finite")
        return sp.Float(value)
    out = sympify_value(value, f"{name}[{i}, {j}]")  # never parses text (nor text inside a tuple or dict)
    if not isinstance(out, sp.Expr):
        raise ModelError(f"{name}[{i}, {j}] = {value!r} is not a number or an expression "
                         f"(sympy reads it as {type(out).__name__})")
    if out.has(sp.oo, -sp.oo, sp.zoo, sp.nan):
        raise ModelError(f"{name}[{i}, {j}] = {out} is not finite")
    return out


def as_symbolic_matrix(value: Any, name: str, *, shape: tuple[int | None, int | None] | None = None
                       ) -> sp.Matrix:
    """Convert a nested list, numpy array, sympy matrix or scalar to a 2-D sympy matrix.

    Parameters
    ----------
    value : array_like, sympy.Matrix, number, str or sympy expression
        The matrix. A scalar becomes a 1x1 matrix. A 1-D sequence is refused, because
        it is ambiguous between a row and a column.
    name : str
        Name used in error messages (``"A"``, ``"M"``, ...).
    shape : tuple, optional
        Expected shape; ``None`` in a slot accepts any size.

    Raises
    ------
    ModelError
        If the value is not a 2-D matrix, is ragged, holds a non-finite or unparsable
        entry, or has the wrong shape.
    """
    if isinstance(value, sp.MatrixBase):
        rows = [[value[i, j] for j in range(value.cols)] for i in range(value.rows)]
    elif isinstance(value, np.ndarray):
        if value.ndim == 0:
            rows = [[value.item()]]
        elif value.ndim != 2:
            raise ModelError(f"{name} must be a 2-D matrix; got an array with {value.ndim} dimension(s) "
                             f"of shape {value.shape}")
        else:
            rows = value.tolist()
    elif isinstance(value, (str, int, float, complex, sp.Basic, np.number)):
        rows = [[value]]
    elif isinstance(value, Iterable):
        rows = list(value)
        if not rows:
            raise ModelError(f"{name} is empty; write a matrix as a nested list, e.g. [[1, 0]]")
        if not all(isinstance(r, (list, tuple, np.ndarray)) for r in rows):
            raise ModelError(
                f"{name} must be a 2-D matrix (a list of rows); got a 1-D sequence of length {len(rows)}. "
                f"Write [[a, b]] for a row or [[a], [b]] for a column.")
        rows = [list(r) for r in rows]
        widths = {len(r) for r in rows}
        if len(widths) != 1:
            raise ModelError(f"{name} is ragged: its rows have lengths {[len(r) for r in rows]}")
    else:
        raise ModelError(f"{name} must be a matrix (nested list, numpy array or sympy Matrix); "
                         f"got {type(value).__name__}")
    if len(rows) == 0 or len(rows[0]) == 0:
        raise ModelError(f"{name} has a zero dimension; every matrix needs at least one row and column")
    mat = sp.Matrix([[_entry(v, name, i, j) for j, v in enumerate(r)] for i, r in enumerate(rows)])
    if shape is not None:
        r, c = shape
        if (r is not None and mat.rows != r) or (c is not None and mat.cols != c):
            want = f"({'any' if r is None else r}, {'any' if c is None else c})"
            raise ModelError(f"{name} has shape {mat.shape}; expected {want}")
    return mat
