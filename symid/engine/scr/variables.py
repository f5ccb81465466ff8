"""Decision variables of a bilinear problem and their place in the real vector x.

Every variable, scalar or matrix, real or complex, occupies a contiguous slice of one
real vector ``x``: a real (r, c) block takes r·c entries in row-major order, a complex
block takes 2·r·c entries, the real parts first and then the imaginary parts.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError

__all__ = ["Layout", "Variable"]


@dataclass(frozen=True, eq=False)
class Variable:
    """A named (matrix) decision variable, real or complex.

    Parameters
    ----------
    name : str
        Name used in results (``sol.x[name]``) and error messages.
    shape : tuple of int, optional
        ``()`` for a scalar (default), ``(r,)`` or ``(r, c)`` for a block.
    complex : bool, optional
        Complex-valued entries, stored as real and imaginary parts (default ``False``).

    Examples
    --------
    >>> from symid import scr
    >>> G = scr.Variable("G", shape=(2, 1), complex=True)
    >>> G.size, G.sym.shape
    (4, (2, 1))
    """

    name: str
    shape: tuple[int, ...] = ()
    complex: bool = False
    symbol: sp.Symbol | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ModelError(f"a variable needs a non-empty string name, got {self.name!r}")
        shape = tuple(int(s) for s in self.shape)
        if len(shape) > 2 or any(s <= 0 for s in shape):
            raise ModelError(f"variable {self.name!r}: shape must be (), (r,) or (r, c) with positive sizes, "
                             f"got {self.shape}")
        object.__setattr__(self, "shape", shape)
        if self.symbol is not None and shape:
            raise ModelError(f"variable {self.name!r}: a sympy symbol can only stand for a scalar")
        re = self._make_symbols("re" if self.complex else "")
        im = self._make_symbols("im") if self.complex else ()
        object.__setattr__(self, "_re", re)
        object.__setattr__(self, "_im", im)

    def _make_symbols(self, part: str) -> tuple[sp.Symbol, ...]:
        if self.symbol is not None and not self.complex:
            return (self.symbol,)
        n = int(np.prod(self.shape)) if self.shape else 1
        out = []
        for k in range(n):
            idx = np.unravel_index(k, self.shape) if self.shape else ()
            label = self.name + (f"[{','.join(map(str, idx))}]" if idx else "")
            out.append(sp.Symbol(f"{part}({label})" if part else label, real=True))
        return tuple(out)

    @property
    def size(self) -> int:
        """Number of real entries the variable takes in x."""
        return len(self._re) + len(self._im)

    @property
    def real_symbols(self) -> tuple[sp.Symbol, ...]:
        """The real sympy symbols of the variable in x order (real parts, then imaginary parts)."""
        return self._re + self._im

    @property
    def sym(self) -> sp.Expr | sp.Matrix:
        """The variable as a sympy scalar or matrix, for writing expressions."""
        ent = list(self._re)
        if self.complex:
            ent = [r + sp.I * i for r, i in zip(self._re, self._im, strict=True)]
        if not self.shape:
            return ent[0]
        r, c = (self.shape[0], 1) if len(self.shape) == 1 else self.shape
        return sp.Matrix(r, c, ent)

    def to_real(self, value: Any) -> np.ndarray:
        """Turn a user value (number or array) into the variable's real entries."""
        arr = np.asarray(value)
        if arr.dtype == object:
            try:
                arr = arr.astype(complex)
            except (TypeError, ValueError):
                raise ModelError(f"x0[{self.name!r}] holds non-numeric entries") from None
        shape = self.shape
        if arr.shape != shape and not (arr.size == (int(np.prod(shape)) if shape else 1) and arr.ndim <= 2):
            raise ModelError(f"x0[{self.name!r}] has shape {arr.shape}, the variable has shape {shape}")
        flat = arr.reshape(-1)
        if not np.all(np.isfinite(flat)):
            bad = int(np.flatnonzero(~np.isfinite(flat))[0])
            raise ModelError(f"x0[{self.name!r}] entry {bad} is {flat[bad]}; starting values must be finite")
        if np.iscomplexobj(flat):
            if not self.complex and np.any(flat.imag != 0):
                raise ModelError(f"x0[{self.name!r}] is complex but the variable is real")
            if not self.complex:
                flat = flat.real
        if self.complex:
            flat = flat.astype(complex)
            return np.concatenate([flat.real, flat.imag]).astype(float)
        return flat.astype(float)

    def from_real(self, x: np.ndarray) -> Any:
        """Turn the variable's real entries back into a float, complex or array."""
        n = len(self._re)
        val = x[:n] + 1j * x[n:] if self.complex else x[:n].copy()
        if not self.shape:
            return complex(val[0]) if self.complex else float(val[0])
        return val.reshape(self.shape)


class Layout:
    """Where each variable lives in the real decision vector x.

    Parameters
    ----------
    variables : iterable of Variable or sympy.Symbol
        Scalars may be given as real sympy symbols.

    Examples
    --------
    >>> import sympy as sp
    >>> from symid import scr
    >>> a = sp.Symbol("a")
    >>> lay = scr.Layout([a, scr.Variable("G", (2,), complex=True)])
    >>> lay.n, lay.slice("G")
    (5, slice(1, 5, None))
    """

    def __init__(self, variables: Iterable[Variable | sp.Symbol]):
        vs: list[Variable] = []
        for v in variables:
            if isinstance(v, Variable):
                vs.append(v)
            elif isinstance(v, sp.Symbol):
                if v.is_real is False:
                    raise ModelError(f"variable {v} is declared complex; use scr.Variable({str(v)!r}, complex=True)")
                vs.append(Variable(str(v), (), False, symbol=v))
            else:
                raise ModelError(f"variables must be sympy Symbols or scr.Variable, got {type(v).__name__}: {v!r}")
        names = [v.name for v in vs]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ModelError(f"variable names are repeated: {', '.join(dup)}")
        self.variables: tuple[Variable, ...] = tuple(vs)
        self._slices: dict[str, slice] = {}
        start = 0
        for v in vs:
            self._slices[v.name] = slice(start, start + v.size)
            start += v.size
        self.n: int = start
        self.symbol_index: dict[sp.Symbol, int] = {}
        for v in vs:
            for k, s in enumerate(v.real_symbols):
                if s in self.symbol_index:
                    raise ModelError(f"symbol {s} belongs to two variables")
                self.symbol_index[s] = self._slices[v.name].start + k
        self._by_key: dict[Any, Variable] = {}
        for v in vs:
            self._by_key[v.name] = v
            self._by_key[v] = v
            if v.symbol is not None:
                self._by_key[v.symbol] = v
        self.names: tuple[str, ...] = tuple(names)
        labels = []
        for v in vs:
            labels.extend(str(s) for s in v.real_symbols)
        self.labels: tuple[str, ...] = tuple(labels)

    def variable(self, key: Any) -> Variable:
        """The variable for a name, a sympy symbol or a Variable; ModelError if unknown."""
        try:
            return self._by_key[key]
        except (KeyError, TypeError):
            pass
        raise ModelError(f"unknown variable {key!r}; the problem's variables are {', '.join(self.names) or 'none'}")

    def slice(self, key: Any) -> slice:
        """Slice of x holding the variable."""
        return self._slices[self.variable(key).name]

    def pack(self, values: Mapping[Any, Any] | None) -> np.ndarray:
        """Real vector x from a dict {name | symbol | Variable: value}; missing variables are 0."""
        x = np.zeros(self.n)
        if values is None:
            return x
        if not isinstance(values, Mapping):
            raise ModelError(f"x0 must be a dict of variable values, got {type(values).__name__}")
        for key, val in values.items():
            v = self.variable(key)
            x[self._slices[v.name]] = v.to_real(val)
        return x

    def unpack(self, x: np.ndarray) -> dict[str, Any]:
        """Dict {name: value} from the real vector x."""
        return {v.name: v.from_real(x[self._slices[v.name]]) for v in self.variables}
