"""Safe parsing of matrix entries written as text: a small whitelisted grammar, never ``eval``.

A string entry is parsed by Python's :mod:`ast` (which only builds a tree, it runs
nothing) and every node is checked against this grammar before the sympy expression
is built from it node by node:

* numbers: integers and decimals (``3``, ``0.5``, ``2e-3``), finite;
* names: identifiers, each a real parameter (or, for :func:`symid.scr` problems, a
  declared variable); ``pi`` is π. Names sympy or numpy read as special values
  (``oo``, ``zoo``, ``nan``, ``inf``, ...) and names starting with ``_`` are refused;
* ``+ - * /``, unary ``+``/``-``, parentheses;
* powers ``**`` or ``^`` whose exponent is a number: an integer or a fraction p/q with
  |p|, q ≤ 64 (``sqrt(x)`` and ``x**(1/2)`` are the same), and a numeric base may not
  grow past 4096 bits, so ``10**10**10`` is refused at once rather than computed;
* calls of the functions in :data:`FUNCTIONS` with one argument.

Everything else — attribute access, subscripts, other calls, keywords, lambdas,
comprehensions, strings, complex literals, comparisons, ``and``/``or`` — is a
:class:`~symid.errors.ModelError` that names the entry and the construct. Texts longer
than :data:`MAX_LENGTH` characters or with more than :data:`MAX_NODES` syntax nodes are
refused before they are parsed further, so every entry is accepted or refused in
milliseconds.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable, Mapping

import sympy as sp

from symid.errors import ModelError

__all__ = ["FUNCTIONS", "MAX_LENGTH", "MAX_NODES", "RESERVED_NAMES", "parse_expression"]

MAX_LENGTH = 10_000
"""Longest entry text accepted (characters)."""

MAX_NODES = 2_000
"""Most syntax nodes accepted in one entry."""

_MAX_EXPONENT = 64
_MAX_BITS = 4096

FUNCTIONS: dict[str, Callable[[sp.Expr], sp.Expr]] = {
    "sqrt": sp.sqrt, "exp": sp.exp, "log": sp.log, "sin": sp.sin, "cos": sp.cos, "tan": sp.tan,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh, "asin": sp.asin, "acos": sp.acos, "atan": sp.atan,
    "abs": sp.Abs,
}
"""The functions an entry may call, by name (one argument each)."""

RESERVED_NAMES = frozenset({"oo", "zoo", "nan", "NaN", "inf", "Inf", "infinity", "Infinity", "None", "True",
                            "False"})
"""Names refused in an entry: they read as infinities, NaN or Python constants elsewhere."""

_DESCRIBE = {
    ast.Attribute: "attribute access", ast.Subscript: "subscripts", ast.Lambda: "lambda", ast.IfExp: "if/else",
    ast.BoolOp: "and/or", ast.Compare: "comparisons", ast.ListComp: "comprehensions",
    ast.SetComp: "comprehensions", ast.DictComp: "comprehensions", ast.GeneratorExp: "comprehensions",
    ast.List: "lists", ast.Tuple: "tuples", ast.Dict: "dicts", ast.Set: "sets", ast.Starred: "starred arguments",
    ast.NamedExpr: "assignment (:=)", ast.JoinedStr: "f-strings", ast.Await: "await", ast.Yield: "yield",
}


def _fail(where: str, text: str, why: str) -> ModelError:
    shown = text if len(text) <= 80 else text[:77] + "..."
    return ModelError(f"{where} = {shown!r} is not allowed: {why}. Entries may hold numbers, names, + - * /, "
                      f"powers with a numeric exponent, parentheses and {', '.join(FUNCTIONS)}(…)")


def _source(text: str) -> str:
    return text.replace("\n", " ").replace("^", "**")


def _bits(x: sp.Rational) -> int:
    return int(abs(x.p)).bit_length() + int(abs(x.q)).bit_length()


class _Builder:
    """Builds the sympy expression of a checked syntax tree, node by node."""

    def __init__(self, text: str, where: str, symbol: Callable[[str], sp.Expr]):
        self.text, self.where, self.symbol = text, where, symbol

    def fail(self, why: str) -> ModelError:
        return _fail(self.where, self.text, why)

    def build(self, node: ast.AST) -> sp.Expr:
        if isinstance(node, ast.Constant):
            return self.constant(node.value)
        if isinstance(node, ast.Name):
            return self.name(node.id)
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.USub):
                return -self.build(node.operand)
            if isinstance(node.op, ast.UAdd):
                return self.build(node.operand)
            raise self.fail(f"the operator {type(node.op).__name__} ('not' or '~')")
        if isinstance(node, ast.BinOp):
            return self.binary(node)
        if isinstance(node, ast.Call):
            return self.call(node)
        what = _DESCRIBE.get(type(node), type(node).__name__)
        segment = ast.get_source_segment(self.text, node) or ""
        raise self.fail(f"{what} ({segment!r})" if segment else what)

    def constant(self, value: object) -> sp.Expr:
        if isinstance(value, bool) or value is None or value is Ellipsis:
            raise self.fail(f"the constant {value!r}")
        if isinstance(value, int):
            if value.bit_length() > _MAX_BITS:
                raise self.fail(f"an integer of {value.bit_length()} bits (at most {_MAX_BITS})")
            return sp.Integer(value)
        if isinstance(value, float):
            if not math.isfinite(value):
                raise self.fail(f"the number {value!r} is not finite")
            return sp.Float(repr(value))
        if isinstance(value, complex):
            raise self.fail("complex numbers (entries are real)")
        raise self.fail(f"a {type(value).__name__} constant ({value!r})")

    def name(self, name: str) -> sp.Expr:
        if name == "pi":
            return sp.pi
        if name in RESERVED_NAMES:
            raise self.fail(f"the name {name!r} (it would read as an infinity, NaN or a Python constant)")
        if name.startswith("_"):
            raise self.fail(f"the name {name!r} (names may not start with '_')")
        if name in FUNCTIONS:
            raise self.fail(f"the function name {name!r} used without a call")
        return self.symbol(name)

    def binary(self, node: ast.BinOp) -> sp.Expr:
        op = node.op
        if isinstance(op, ast.Pow):
            return self.power(node)
        left, right = self.build(node.left), self.build(node.right)
        if isinstance(op, ast.Add):
            return left + right
        if isinstance(op, ast.Sub):
            return left - right
        if isinstance(op, ast.Mult):
            return left * right
        if isinstance(op, ast.Div):
            if right == 0:
                raise self.fail("a division by zero")
            return left / right
        symbol = {ast.FloorDiv: "//", ast.Mod: "%", ast.MatMult: "@", ast.LShift: "<<", ast.RShift: ">>",
                  ast.BitOr: "|", ast.BitAnd: "&"}.get(type(op), type(op).__name__)
        raise self.fail(f"the operator {symbol!r}")

    def power(self, node: ast.BinOp) -> sp.Expr:
        exponent = self.build(node.right)
        if not exponent.is_Rational:
            raise self.fail("a power whose exponent is not a number (write exp(x*log(a)) if you mean that)")
        if abs(exponent.p) > _MAX_EXPONENT or exponent.q > _MAX_EXPONENT:
            raise self.fail(f"the exponent {exponent} (numerator and denominator at most {_MAX_EXPONENT})")
        base = self.build(node.left)
        if base == 0 and exponent < 0:
            raise self.fail("a division by zero")
        if base.is_Rational and _bits(base) * abs(exponent.p) > _MAX_BITS:
            raise self.fail(f"the number {base}**{exponent} is too large (over {_MAX_BITS} bits)")
        return base**exponent

    def call(self, node: ast.Call) -> sp.Expr:
        if not isinstance(node.func, ast.Name):
            segment = ast.get_source_segment(self.text, node.func) or "?"
            raise self.fail(f"a call of {segment!r}")
        name = node.func.id
        if name not in FUNCTIONS:
            raise self.fail(f"a call of {name!r} (allowed functions: {', '.join(FUNCTIONS)})")
        if node.keywords or len(node.args) != 1:
            raise self.fail(f"{name}() takes exactly one argument and no keywords")
        arg = self.build(node.args[0])
        if name == "log" and arg == 0:
            raise self.fail("log(0)")
        return FUNCTIONS[name](arg)


def parse_expression(text: str, where: str = "entry", *,
                     symbol: Callable[[str], sp.Expr] | Mapping[str, sp.Expr] | None = None) -> sp.Expr:
    """Parse one entry of the whitelisted grammar (see the module text) into a sympy expression.

    Parameters
    ----------
    text : str
        The entry, e.g. ``"c1 + c2"`` or ``"k/2 - 3.5e-2*m^2"``.
    where : str, optional
        Where the entry sits, for error messages (``"A[1, 0]"``).
    symbol : callable or mapping, optional
        What a name means: a function of the name, or a mapping (a name it lacks is an
        error). Default: a real sympy symbol of that name.

    Returns
    -------
    sympy.Expr
        A finite expression (no infinity or NaN).

    Raises
    ------
    ModelError
        Anything outside the grammar, named with its place and the offending construct.

    Examples
    --------
    >>> from symid.model.expressions import parse_expression
    >>> parse_expression("E*I/L**3 + pi")
    E*I/L**3 + pi
    >>> parse_expression("__import__('os').system('x')", "A[0, 0]")
    Traceback (most recent call last):
    ...
    symid.errors.ModelError: A[0, 0] = "__import__('os').system('x')" is not allowed: a call of ...
    """
    if not isinstance(text, str):
        raise ModelError(f"{where} must be text to be parsed; got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ModelError(f"{where} is {len(text)} characters long; entries are limited to {MAX_LENGTH}")
    if "\x00" in text:
        raise _fail(where, text, "a NUL character")
    if symbol is None:
        def make(name: str) -> sp.Expr:
            return sp.Symbol(name, real=True)
    elif isinstance(symbol, Mapping):
        known = symbol

        def make(name: str) -> sp.Expr:
            if name not in known:
                raise _fail(where, text, f"the name {name!r}, which is not a declared variable "
                                         f"({', '.join(sorted(known)) or 'none'})")
            return known[name]
    else:
        make = symbol
    stripped = text.strip()
    if not stripped:
        raise ModelError(f"{where} = {text!r} cannot be parsed: it is empty")
    try:
        # ^ is a power, as in sympy: replaced before parsing so that it binds like ** (Python's ^ is xor,
        # of lower precedence than +)
        tree = ast.parse(_source(stripped), mode="eval")
    except SyntaxError as exc:
        raise ModelError(f"{where} = {text!r} cannot be parsed: {exc.msg}") from None
    except (ValueError, RecursionError, MemoryError) as exc:  # too many digits, too deeply nested
        raise ModelError(f"{where} cannot be parsed: {type(exc).__name__}: {str(exc)[:100]}") from None
    count = 0
    for _ in ast.walk(tree):
        count += 1
        if count > MAX_NODES:
            raise ModelError(f"{where} has more than {MAX_NODES} syntax elements; write a simpler entry")
    builder = _Builder(_source(stripped), where, make)
    try:
        out = builder.build(tree.body)
    except RecursionError:
        raise ModelError(f"{where} is nested too deeply") from None
    if not isinstance(out, sp.Expr):
        raise ModelError(f"{where} = {text!r} is not an expression")
    if out.has(sp.oo, -sp.oo, sp.zoo, sp.nan):
        raise _fail(where, text, "a value that is infinite or NaN")
    return out
