"""Safe parsing of matrix entries written as text: a small whitelisted grammar, never ``eval``.

A string entry is parsed by Python's :mod:`ast` (which only builds a tree, it runs
nothing) and every node is checked against this grammar before the sympy expression
is built from it node by node:

* numbers: decimal integers and decimals (``3``, ``0.5``, ``.5``, ``2e-3``); no
  ``0x``/``0o``/``0b`` forms, no ``_`` digit separators, no complex literals;
* names: identifiers, each a real parameter (or, for :mod:`symid.scr` problems, a
  declared variable); ``pi`` is π. Refused: names sympy or numpy read as special
  values (``oo``, ``zoo``, and ``nan``, ``inf``, ``infinity`` in any case), names
  starting with ``_``, and names Python would silently rewrite (Unicode NFKC: ``ａ``
  or ``𝐚`` would read as ``a``, the micro sign ``µ`` as Greek ``μ``);
* ``+ - * /``, unary ``+``/``-``, parentheses;
* powers ``**`` or ``^`` whose exponent is a number: an integer or a fraction p/q with
  |p|, q ≤ 64 (``sqrt(x)`` and ``x**(1/2)`` are the same). Powers combined by sympy
  count too: ``(a**64)**64`` is ``a**4096`` and is refused;
* calls of the functions in :data:`FUNCTIONS` with one argument.

Every constant part (a number, or a sub-expression without names such as
``exp(1000)`` or ``sqrt(-1)``) is evaluated in double precision as it is built, and
must be real and finite there: ``10**400``, ``exp(1000)``, ``sqrt(-1)``, ``log(0)``,
a division by zero and a nonzero number that would round to 0 (``1e-400``) are
refused. So are ``nan``, ``oo`` and ``zoo`` wherever sympy would produce them.

Everything else — attribute access, subscripts, other calls, keywords, lambdas,
comprehensions, strings, comparisons, ``and``/``or``, comments — is a
:class:`~symid.errors.ModelError` that names the entry and the construct. Texts longer
than :data:`MAX_LENGTH` characters, with more than :data:`MAX_NODES` syntax nodes or
nested deeper than :data:`MAX_DEPTH` are refused before anything is built, so every
entry is accepted or refused in milliseconds.

:func:`sympify_value` is the other half: a value that is *not* text (a number, a numpy
scalar, a sympy expression) becomes sympy without ever reaching sympy's text parser.
"""

from __future__ import annotations

import ast
import math
import re
import warnings
from collections.abc import Callable, Iterable, Mapping

import numpy as np
import sympy as sp

from symid.errors import ModelError

__all__ = ["FUNCTIONS", "MAX_DEPTH", "MAX_EXPONENT", "MAX_LENGTH", "MAX_NODES", "RESERVED_NAMES",
           "parse_expression", "sympify_value"]

MAX_LENGTH = 10_000
"""Longest entry text accepted (characters)."""

MAX_NODES = 2_000
"""Most syntax nodes accepted in one entry."""

MAX_DEPTH = 100
"""Deepest nesting of syntax nodes accepted in one entry."""

MAX_EXPONENT = 64
"""Largest numerator and denominator of an exponent, as written or after sympy combines powers."""

FUNCTIONS: dict[str, Callable[[sp.Expr], sp.Expr]] = {
    "sqrt": sp.sqrt, "exp": sp.exp, "log": sp.log, "sin": sp.sin, "cos": sp.cos, "tan": sp.tan,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh, "asin": sp.asin, "acos": sp.acos, "atan": sp.atan,
    "abs": sp.Abs,
}
"""The functions an entry may call, by name (one argument each)."""

# the same functions in double precision, to check constant parts as they are built
_FLOAT_FUNCTIONS: dict[str, Callable[[float], float]] = {
    "sqrt": math.sqrt, "exp": math.exp, "log": math.log, "sin": math.sin, "cos": math.cos, "tan": math.tan,
    "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh, "asin": math.asin, "acos": math.acos,
    "atan": math.atan, "abs": math.fabs,
}

RESERVED_NAMES = frozenset({"oo", "zoo", "nan", "NaN", "inf", "Inf", "infinity", "Infinity", "None", "True",
                            "False"})
"""Names refused in an entry: they read as infinities, NaN or Python constants elsewhere
(``nan``, ``inf`` and ``infinity`` are refused in any case, as ``float()`` reads them)."""

_FLOAT_WORDS = frozenset({"nan", "inf", "infinity"})
_DECIMAL = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")

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
    # one line (so that column offsets locate every node), ^ a power as in sympy: replaced before parsing
    # so that it binds like ** (Python's ^ is xor, of lower precedence than +)
    return text.replace("\r", " ").replace("\n", " ").replace("^", "**")


def _describe_number(x: sp.Expr) -> str:
    return sp.sstr(x) if len(sp.sstr(x)) <= 40 else sp.sstr(sp.Float(x, 6))


class _Builder:
    """Builds the sympy expression of a checked syntax tree, node by node.

    Each step returns the expression and, when it has no names, its value in double
    precision (``None`` otherwise): constant parts are checked as soon as they are built.
    """

    def __init__(self, text: str, source: str, where: str, symbol: Callable[[str], sp.Expr]):
        self.text, self.where, self.symbol = text, where, symbol
        self.source = source
        self.encoded = source.encode("utf-8")  # ast column offsets count UTF-8 bytes

    def fail(self, why: str) -> ModelError:
        return _fail(self.where, self.text, why)

    def segment(self, node: ast.AST) -> str:
        return self.encoded[node.col_offset:node.end_col_offset].decode("utf-8", "replace")

    def value(self, expr: sp.Expr, computed: float | complex | None, what: str) -> float | None:
        """The double-precision value of a constant part, checked real and finite; None for non-constants."""
        if computed is None:
            if expr.free_symbols:
                return None
            try:  # a constant made of names that cancelled, e.g. (a + pi) - a: its parts are checked already
                computed = complex(expr.evalf(17))
            except (TypeError, ValueError, ArithmeticError):
                raise self.fail(f"{what} has no finite real value") from None
        if isinstance(computed, complex):
            if computed.imag != 0:
                raise self.fail(f"{what} is not real (entries are real)")
            computed = computed.real
        if not math.isfinite(computed):
            raise self.fail(f"{what} is beyond double precision (magnitude over 1.8e308)")
        return computed

    def build(self, node: ast.AST) -> tuple[sp.Expr, float | None]:
        if isinstance(node, ast.Constant):
            return self.constant(node)
        if isinstance(node, ast.Name):
            return self.name(node)
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, (ast.USub, ast.UAdd)):
                expr, val = self.build(node.operand)
                if isinstance(node.op, ast.USub):
                    return -expr, (None if val is None else -val)
                return expr, val
            raise self.fail(f"the operator {type(node.op).__name__} ('not' or '~')")
        if isinstance(node, ast.BinOp):
            return self.binary(node)
        if isinstance(node, ast.Call):
            return self.call(node)
        what = _DESCRIBE.get(type(node), type(node).__name__)
        segment = self.segment(node) if hasattr(node, "col_offset") else ""
        raise self.fail(f"{what} ({segment!r})" if segment else what)

    def constant(self, node: ast.Constant) -> tuple[sp.Expr, float]:
        value = node.value
        if isinstance(value, bool) or value is None or value is Ellipsis:
            raise self.fail(f"the constant {value!r}")
        if isinstance(value, complex):
            raise self.fail("complex numbers (entries are real)")
        if not isinstance(value, (int, float)):
            raise self.fail(f"a {type(value).__name__} constant ({value!r})")
        written = self.segment(node)
        if not _DECIMAL.fullmatch(written):
            raise self.fail(f"the number {written!r} (write numbers in decimal: 12, 0.5, 2e-3)")
        try:
            val = float(value)
        except OverflowError:
            raise self.fail(f"the number {_describe_number(sp.Integer(value))} is beyond double precision "
                            f"(magnitude over 1.8e308)") from None
        if not math.isfinite(val):
            raise self.fail(f"the number {written} is beyond double precision (magnitude over 1.8e308)")
        mantissa = written.lower().split("e")[0]
        if val == 0 and mantissa.strip("0.") != "":
            raise self.fail(f"the number {written} rounds to 0 in double precision (magnitude under 5e-324)")
        if isinstance(value, int):
            return sp.Integer(value), val
        return sp.Float(val), val  # the double the text denotes (as a float entry would be)

    def name(self, node: ast.Name) -> tuple[sp.Expr, float | None]:
        name = node.id
        written = self.segment(node)
        if written != name:  # Python reads identifiers in Unicode NFKC form: 'ａ' is 'a', 'µ' is 'μ'
            raise self.fail(f"the name {written!r} {written!a}, which Python reads as {name!r} "
                            f"{name!a}; write {name!r}")
        if name == "pi":
            return sp.pi, math.pi
        if name in RESERVED_NAMES or name.lower() in _FLOAT_WORDS:
            raise self.fail(f"the name {name!r} (it would read as an infinity, NaN or a Python constant)")
        if name.startswith("_"):
            raise self.fail(f"the name {name!r} (names may not start with '_')")
        if name in FUNCTIONS:
            raise self.fail(f"the function name {name!r} used without a call")
        return self.symbol(name), None

    def binary(self, node: ast.BinOp) -> tuple[sp.Expr, float | None]:
        op = node.op
        if isinstance(op, ast.Pow):
            return self.power(node)
        if not isinstance(op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
            symbol = {ast.FloorDiv: "//", ast.Mod: "%", ast.MatMult: "@", ast.LShift: "<<", ast.RShift: ">>",
                      ast.BitOr: "|", ast.BitAnd: "&"}.get(type(op), type(op).__name__)
            raise self.fail(f"the operator {symbol!r}")
        (left, lv), (right, rv) = self.build(node.left), self.build(node.right)
        known = lv is not None and rv is not None
        if isinstance(op, ast.Add):
            expr, val = left + right, (lv + rv if known else None)
        elif isinstance(op, ast.Sub):
            expr, val = left - right, (lv - rv if known else None)
        elif isinstance(op, ast.Mult):
            expr, val = left * right, (lv * rv if known else None)
        else:
            if right == 0 or rv == 0:
                raise self.fail(f"a division by zero ({self.segment(node.right)!r} is 0)")
            expr, val = left / right, (lv / rv if known else None)
        return expr, self.value(expr, val, repr(self.segment(node)))

    def power(self, node: ast.BinOp) -> tuple[sp.Expr, float | None]:
        exponent, ev = self.build(node.right)
        if not exponent.is_Rational:
            raise self.fail("a power whose exponent is not a number (write exp(x*log(a)) if you mean that)")
        if abs(exponent.p) > MAX_EXPONENT or exponent.q > MAX_EXPONENT:
            raise self.fail(f"the exponent {exponent} (numerator and denominator at most {MAX_EXPONENT})")
        base, bv = self.build(node.left)
        val = None
        if bv is not None:  # in double precision first, so that no huge exact number is ever computed
            try:
                val = bv ** (int(exponent) if exponent.is_Integer else ev)
            except ZeroDivisionError:
                raise self.fail(f"a division by zero ({self.segment(node)!r})") from None
            except OverflowError:
                val = math.inf
            self.value(sp.S.Zero, val, repr(self.segment(node)))
        expr = base**exponent
        return expr, self.value(expr, val, repr(self.segment(node)))

    def call(self, node: ast.Call) -> tuple[sp.Expr, float | None]:
        if not isinstance(node.func, ast.Name):
            raise self.fail(f"a call of {self.segment(node.func)!r}")
        name = node.func.id
        if name not in FUNCTIONS:
            raise self.fail(f"a call of {self.segment(node.func)!r} (allowed functions: {', '.join(FUNCTIONS)})")
        if node.keywords or len(node.args) != 1:
            raise self.fail(f"{name}() takes exactly one argument and no keywords")
        arg, av = self.build(node.args[0])
        val = None
        if av is not None:
            try:
                val = _FLOAT_FUNCTIONS[name](av)
            except ValueError:
                raise self.fail(f"{self.segment(node)!r}: {name} is not real or not finite there") from None
            except OverflowError:
                val = math.inf
            self.value(sp.S.Zero, val, repr(self.segment(node)))
        expr = FUNCTIONS[name](arg)
        return expr, self.value(expr, val, repr(self.segment(node)))


def _depth(tree: ast.AST, where: str) -> None:
    """Refuse a tree with too many nodes or nested too deeply, without recursion."""
    count = 0
    stack = [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        count += 1
        if count > MAX_NODES:
            raise ModelError(f"{where} has more than {MAX_NODES} syntax elements; write a simpler entry")
        if depth > MAX_DEPTH:
            raise ModelError(f"{where} is nested more than {MAX_DEPTH} levels deep; write a simpler entry")
        stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))


def _check_result(builder: _Builder, out: sp.Expr) -> None:
    """What sympy made of the parts: combined powers bounded, every constant part finite in double precision."""
    if out.has(sp.oo, -sp.oo, sp.zoo, sp.nan):
        raise builder.fail("a value that is infinite or NaN")
    for p in out.atoms(sp.Pow):
        e = p.exp
        if e.is_Rational and (abs(e.p) > MAX_EXPONENT or e.q > MAX_EXPONENT):
            raise builder.fail(f"the power {p} after sympy combined powers (exponents at most {MAX_EXPONENT})")
    stack = [out]
    while stack:  # the largest parts without names, e.g. the coefficient 1e600 of a*1e300*1e300
        part = stack.pop()
        if part.free_symbols:
            stack.extend(a for a in part.args if isinstance(a, sp.Expr))
            continue
        if part.is_Number:
            val = float(part)
            if not math.isfinite(val):
                raise builder.fail(f"the number {_describe_number(part)} is beyond double precision "
                                   f"(magnitude over 1.8e308)")
            if val == 0 and not part.is_zero:
                raise builder.fail(f"the number {_describe_number(part)} rounds to 0 in double precision")
        else:
            builder.value(part, None, repr(sp.sstr(part)[:60]))


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
        A finite real expression (no infinity or NaN; constant parts finite and real in
        double precision).

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
    >>> parse_expression("a*10**10**10")
    Traceback (most recent call last):
    ...
    symid.errors.ModelError: entry = 'a*10**10**10' is not allowed: the exponent 10000000000 ...
    """
    if not isinstance(text, str):
        raise ModelError(f"{where} must be text to be parsed; got {type(text).__name__}")
    text = str.__str__(text)  # a plain str: a subclass's methods are never called
    if len(text) > MAX_LENGTH:
        raise ModelError(f"{where} is {len(text)} characters long; entries are limited to {MAX_LENGTH}")
    if "\x00" in text:
        raise _fail(where, text, "a NUL character")
    if "#" in text:  # a comment would silently drop the rest of the entry
        raise _fail(where, text, "a comment ('#')")
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
    source = _source(stripped)
    try:
        with warnings.catch_warnings():  # "2and 3", "'\\o'": Python warns of the literal; the errors below say it
            warnings.simplefilter("ignore", SyntaxWarning)
            warnings.simplefilter("ignore", DeprecationWarning)  # Python 3.11's word for an invalid escape
            tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        raise ModelError(f"{where} = {text!r} cannot be parsed: {exc.msg}") from None
    except (ValueError, RecursionError, MemoryError) as exc:  # too many digits, too deeply nested
        raise ModelError(f"{where} cannot be parsed: {type(exc).__name__}: {str(exc)[:100]}") from None
    _depth(tree, where)
    builder = _Builder(text, source, where, make)
    out, _ = builder.build(tree.body)
    if not isinstance(out, sp.Expr):
        raise ModelError(f"{where} = {text!r} is not an expression")
    _check_result(builder, out)
    return out


def sympify_value(value: object, where: str = "entry") -> sp.Basic:
    """A value that is not text — a number, numpy scalar or sympy object — as sympy, never parsing text.

    ``sympy.sympify(value, strict=True)`` refuses a string, but it still converts a
    tuple, dict or set element by element with the *non*-strict :func:`sympy.sympify`
    (sympy's converters for containers call ``Tuple``, ``Dict`` and ``FiniteSet``),
    which hands the strings inside to ``eval``. So containers, bytes and text are
    refused here before sympy sees them; text goes through :func:`parse_expression`.

    Parameters
    ----------
    value : object
        A Python or numpy number, a sympy object, or an object with ``_sympy_``.
    where : str, optional
        Where the value sits, for error messages.

    Returns
    -------
    sympy.Basic
        The value as sympy (callers check that it is an expression).

    Raises
    ------
    ModelError
        For text, bytes, containers (list, tuple, dict, set, arrays of more than one
        element) and anything sympy cannot convert without parsing.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.model.expressions import sympify_value
    >>> sympify_value(np.float64(0.5))
    0.500000000000000
    >>> sympify_value(("__import__('os')",), "A[0, 0]")
    Traceback (most recent call last):
    ...
    symid.errors.ModelError: A[0, 0] is a tuple; expected a number or a sympy expression
    """
    if isinstance(value, (bool, np.bool_)):
        raise ModelError(f"{where} is a boolean ({value}); expected a number or a sympy expression")
    if isinstance(value, sp.Basic):
        return value
    if isinstance(value, str):
        raise ModelError(f"{where} is text; text is read by parse_expression, never by sympify")
    if isinstance(value, (bytes, bytearray, memoryview)):
        raise ModelError(f"{where} is bytes; write it as text (str), a number or a sympy expression")
    if (isinstance(value, np.ndarray) and value.ndim == 0) or isinstance(value, np.generic):
        value = value.item()
        if isinstance(value, (str, bytes)):
            raise ModelError(f"{where} is text in a numpy array; give the text itself or a number")
    if isinstance(value, (Iterable, Mapping, sp.MatrixBase)):
        raise ModelError(f"{where} is a {type(value).__name__}; expected a number or a sympy expression")
    try:
        return sp.sympify(value, strict=True)
    except (sp.SympifyError, TypeError, ValueError, ArithmeticError) as exc:
        raise ModelError(f"{where} = {value!r} is not a number or a sympy expression "
                         f"({type(exc).__name__})") from None
