"""No code is ever executed from text (issue 12 item 2): every place that accepts a string entry parses a
whitelisted grammar (symid.model.expressions) and refuses the rest with a ModelError, fast and without side
effects; non-text values reach sympy only through sympify_value, which never parses text."""

from __future__ import annotations

import collections
import re
import string
import time
import types
import warnings
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import symid as si
from symid import scr
from symid.errors import ModelError, SymidError
from symid.model.expressions import MAX_DEPTH, MAX_LENGTH, parse_expression, sympify_value
from symid.model.symbols import parse_entry
from symid.structural.summary import rational

TIME_BOUND = 5.0  # s per entry, generous on a shared machine; measured figures are in the test docstrings


def _attacks(target: Path) -> list[str]:
    cmd = f"touch {target}"
    return [
        f"a + 0*__import__('os').system('{cmd}')",
        f"exec(\"__import__('os').system('{cmd}')\")",
        f"eval(\"__import__('os').system('{cmd}')\")",
        f"open('{target}', 'w')",
        f"a + (lambda: __import__('os').system('{cmd}'))()",
        "a.__class__.__base__.__subclasses__()",
        f"[__import__('os').system('{cmd}') for _ in 'x'][0]",
        f"getattr(__builtins__, 'exec')(\"open('{target}', 'w')\")",
        f"sin(__import__('os').system('{cmd}'))",
        f"(x := __import__('os')).system('{cmd}')",
        f"a + 0*Float('nan') + 0*__import__('os').system('{cmd}')",
        f"f'{{__import__(\"os\").system(\"{cmd}\")}}'",
        f"sqrt(*[__import__('os').system('{cmd}')])",
        f"a # {cmd}",
    ]


def _text_entry_points(text: str):
    """Every public place that takes an entry as text, labelled."""
    x, y = sp.symbols("x y")
    return {
        "StateSpaceModel A[0, 0]": lambda: si.StateSpaceModel(A=[[text]], B=[[1]], C=[[1]]),
        "StateSpaceModel scalar A": lambda: si.StateSpaceModel(A=text, B=[[1]], C=[[1]]),
        "StateSpaceModel D": lambda: si.StateSpaceModel(A=[[-1]], B=[[1]], C=[[1]], D=[[text]]),
        "SecondOrderModel V": lambda: si.SecondOrderModel(M=[[1]], V=[[text]], K=[[1]], B=[[1]], C=[[1]]),
        "SecondOrderModel scalar M": lambda: si.SecondOrderModel(M=text, V=[[1]], K=[[1]], B=[[1]], C=[[1]]),
        "numpy object array": lambda: si.StateSpaceModel(A=np.array([[text]], dtype=object), B=[[1]], C=[[1]]),
        "numpy str_ array": lambda: si.StateSpaceModel(A=np.array([[text]]), B=[[1]], C=[[1]]),
        "numpy 0-d str array": lambda: si.StateSpaceModel(A=np.array(text), B=[[1]], C=[[1]]),
        "parse_entry": lambda: parse_entry(text),
        "scr Bilinear A entry": lambda: scr.BilinearProblem(
            variables=[x, y], bilinear=[scr.Bilinear(A=[[text]], P=[[1]], B=[[x]], C=[[y]])]),
        "scr Bilinear scalar A": lambda: scr.BilinearProblem(
            variables=[x, y], bilinear=[scr.Bilinear(A=text, P=[[1]], B=[[x]], C=[[y]])]),
        "scr Bilinear P": lambda: scr.BilinearProblem(
            variables=[x, y], bilinear=[scr.Bilinear(A=[[x]], P=[[text]], B=[[x]], C=[[y]])]),
        "scr objective": lambda: scr.BilinearProblem(variables=[x, y], objective=text),
        "scr objective list": lambda: scr.BilinearProblem(variables=[x, y], objective=[text]),
        "scr SumSquares": lambda: scr.BilinearProblem(variables=[x, y], objective=scr.SumSquares([[text]])),
        "scr equalities": lambda: scr.BilinearProblem(variables=[x, y], equalities=[[[text]]]),
        "scr lmis": lambda: scr.BilinearProblem(variables=[x, y], lmis=[[[text]]]),
        "scr Affine constant": lambda: scr.BilinearProblem(variables=[x, y], equalities=[scr.Affine([[text]])]),
    }


def _container_entry_points(value):
    """Places that take a non-text value: sympy's strict sympify would parse text inside a tuple or dict."""
    x, y = sp.symbols("x y")
    return {
        "StateSpaceModel entry": lambda: si.StateSpaceModel(A=[[value]], B=[[1]], C=[[1]]),
        "scr entry": lambda: scr.BilinearProblem(variables=[x, y], equalities=[[[value]]]),
        "scr objective term": lambda: scr.BilinearProblem(variables=[x, y], objective=[value]),
        "structural rational": lambda: rational(value),
        "sympify_value": lambda: sympify_value(value),
    }


@pytest.mark.parametrize("k", range(14))
def test_attack_strings_run_nothing_anywhere(tmp_path, k):
    target = tmp_path / "pwned"
    text = _attacks(target)[k]
    for label, call in _text_entry_points(text).items():
        with pytest.raises(SymidError):
            call()
        assert not target.exists(), (label, text)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("wrap", ["tuple", "dict", "set", "frozenset", "namedtuple", "OrderedDict", "nested list",
                                  "object array in a list"])
def test_text_inside_containers_is_never_sympified(tmp_path, wrap):
    # sympy.sympify(("...",), strict=True) parses the string with eval (sympy's Tuple converter): this made
    # A=[[("a + 0*__import__('os').system(...)",)]] run the command before the entry was refused
    target = tmp_path / "pwned"
    text = f"a + 0*__import__('os').system('touch {target}')"
    obj_array = np.empty(1, dtype=object)
    obj_array[0] = text
    value = {"tuple": (text,), "dict": {1: text}, "set": {text}, "frozenset": frozenset({text}),
             "namedtuple": collections.namedtuple("Pair", "p q")(text, text),
             "OrderedDict": collections.OrderedDict(k=text), "nested list": [[text]],
             "object array in a list": obj_array}[wrap]
    for label, call in _container_entry_points(value).items():
        with pytest.raises(SymidError):
            call()
        assert not target.exists(), label


@pytest.mark.parametrize("text", ["10**10**10", "a*9**9**9", "2**(2**64)", "a**100000", "9" * 5000,
                                  "(" * 1000 + "a" + ")" * 1000, "-" * 5000 + "a", "a" + "+a" * 3000,
                                  "1" + "*1" * 3000, "sqrt(" * 150 + "a" + ")" * 150, "exp(exp(exp(exp(10))))",
                                  "(a**64)**64", "((a+1)**64)**64", "a**64*a**64", "a" * (MAX_LENGTH + 1)])
def test_huge_powers_and_deep_or_long_texts_are_refused_in_milliseconds(text):
    """Measured (python -m pytest -s ... -k milliseconds prints nothing; see the hypothesis test for the
    worst time): each of these is refused in under 5 ms; the parser they replaced hung for minutes."""
    t0 = time.perf_counter()
    with pytest.raises(si.ModelError):
        si.StateSpaceModel(A=[[text]], B=[[1]], C=[[1]])
    assert time.perf_counter() - t0 < TIME_BOUND


def test_nesting_depth_is_bounded():
    parse_entry("sin(" * 40 + "a" + ")" * 40)  # within MAX_DEPTH
    with pytest.raises(si.ModelError, match=f"nested more than {MAX_DEPTH} levels"):
        parse_entry("-(" * 120 + "a" + ")" * 120)


@pytest.mark.parametrize(("text", "phrase"), [
    ("Float('nan')", "a call of 'Float'"), ("-a + 0*Float('nan')", "a call of 'Float'"),
    ("oo", "the name 'oo'"), ("a + zoo", "the name 'zoo'"), ("nan", "the name 'nan'"), ("NaN*a", "the name 'NaN'"),
    ("Inf", "the name 'Inf'"), ("INFINITY", "the name 'INFINITY'"), ("inf*a", "the name 'inf'"),
    ("1e400", "beyond double precision"), ("a*1e300*1e300", "beyond double precision"),
    ("exp(1000)*a", "'exp(1000)' is beyond double precision"), ("a*exp(700)*exp(700)", "beyond double precision"),
    ("(2**60)**16*(2**60)**2", "beyond double precision"), ("1e-400*a", "rounds to 0"),
    ("a*1e-300*1e-300", "rounds to 0"),
    ("a/0", "division by zero"), ("a/(b - b)", "division by zero"), ("0**-1", "division by zero"),
    ("log(0)", "log is not real or not finite"), ("sqrt(-1)*a", "sqrt is not real"), ("log(-1)", "log is not real"),
    ("asin(2)", "asin is not real"), ("(-8)**(1/3)", "is not real"), ("1j*a", "complex numbers"),
    ("a + True", "the constant True"), ("None", "the constant None"),
    ("(a**64)**64", "the power a**4096 after sympy combined powers"),
])
def test_non_finite_and_non_real_entries_are_refused(text, phrase):
    with pytest.raises(si.ModelError, match=re.escape(phrase)):
        si.StateSpaceModel(A=[[text]], B=[[1]], C=[[1]])


@pytest.mark.parametrize(("text", "phrase"), [
    ("0x10*a", "the number '0x10'"), ("1_000*a", "the number '1_000'"), ("0b11", "the number '0b11'"),
    ("0o7", "the number '0o7'"), ("a # + b", "a comment"), ("a.real", "attribute access"), ("a[0]", "subscripts"),
    ("a if b else c", "if/else"), ("a < b", "comparisons"), ("a and b", "and/or"), ("a % b", "the operator '%'"),
    ("a // b", "the operator '//'"), ("a @ b", "the operator '@'"), ("a | b", "the operator '|'"),
    ("~a", "the operator Invert"), ("not a", "the operator Not"), ("sqrt(a, b)", "exactly one argument"),
    ("sqrt(x=a)", "exactly one argument"), ("Abs(a)", "a call of 'Abs'"), ("sqrt", "used without a call"),
    ("a**b", "exponent is not a number"), ("a**0.5", "exponent is not a number"), ("_a", "may not start with '_'"),
    ("'a'", "a str constant"), ("b'a'", "a bytes constant"), ("...", "the constant Ellipsis"),
    ("(a, b)", "tuples"), ("[a]", "lists"), ("{a}", "sets"), ("{a: b}", "dicts"),
])
def test_every_construct_outside_the_grammar_is_named(text, phrase):
    with pytest.raises(si.ModelError, match=r"A\[0, 0\] = .* is not allowed: .*" + re.escape(phrase)):
        si.StateSpaceModel(A=[[text]], B=[[1]], C=[[1]])


@pytest.mark.parametrize(("text", "normal"), [("ａ", "a"), ("𝐚", "a"), ("ｐｉ", "pi"), ("µ", "μ"), ("\u2126", "Ω"),
                                              ("ﬁ", "fi"), ("ｏｏ", "oo")])
def test_names_python_would_rewrite_are_refused(text, normal):
    # Python reads identifiers in NFKC form: 'ａ' would silently be the parameter 'a', 'ｐｉ' would be π
    with pytest.raises(si.ModelError, match=f"which Python reads as '{normal}'"):
        parse_entry(f"2*{text}")
    if normal.isidentifier() and normal not in ("pi", "oo"):
        with pytest.raises(si.ModelError, match="is read by Python as"):
            si.parameters(f"k {text}")


def test_greek_and_accented_names_are_parameters():
    alpha, omega, e_acute = (sp.Symbol(n, real=True) for n in ("α", "ω", "é"))
    assert parse_entry("α*ω + é") == alpha * omega + e_acute
    model = si.StateSpaceModel(A=[["-α"]], B=[[si.parameters("ω")]], C=[[1]])
    assert model.parameter_names == ("α", "ω")


a_, b_, c1, c2, k1, k2, m_, x_, E_, I_, L_ = (sp.Symbol(n, real=True) for n in
                                             ("a", "b", "c1", "c2", "k1", "k2", "m", "x", "E", "I", "L"))


@pytest.mark.parametrize(("text", "expected"), [
    # reference: the same expressions built by hand with real sympy symbols (nothing parsed)
    ("c1 + c2", c1 + c2), ("-(k1 + k2)/m", -(k1 + k2) / m_), ("2^3*a", 8 * a_), ("a**2/2", a_**2 / 2),
    ("sqrt(4) + exp(0) - pi*a", 3 - sp.pi * a_), ("3.5e-2*b", sp.Float(0.035) * b_), ("a^-1", 1 / a_),
    ("x**(1/2)", sp.sqrt(x_)), ("E*I/L**3", E_ * I_ / L_**3), ("+a - -b", a_ + b_), ("abs(a)", sp.Abs(a_)),
    ("-a^2", -(a_**2)), ("2*a^2^1", 2 * a_**2), (".5*a + 1.", sp.Float(0.5) * a_ + sp.Float(1.0)),
    ("exp(1)*a", sp.E * a_), ("sin(a)*cos(b) - tan(pi/4)", sp.sin(a_) * sp.cos(b_) - 1),
    ("log(a)/log(2)", sp.log(a_) / sp.log(2)), ("a\n+ b", a_ + b_), ("  a\t*b  ", a_ * b_),
    ("(a + b)**64", (a_ + b_) ** 64), ("2**64*a", sp.Integer(2) ** 64 * a_), ("(1/2)**64", sp.Rational(1, 2**64)),
    ("1e308", sp.Float(1e308)), ("1e-300*a", sp.Float(1e-300) * a_),
    ("0.0*a + 0e5", sp.Float(0.0) * a_ + sp.Float(0.0)),
])
def test_the_grammar_builds_the_expressions_sympy_would(text, expected):
    assert parse_entry(text) == expected


@st.composite
def _grammar_tree(draw, depth=0):
    """A random expression of the grammar as (text, the sympy expression built by hand from the same tree)."""
    names = st.sampled_from(["a", "b", "k1", "pi"])
    leaves = [names.map(lambda n: (n, sp.pi if n == "pi" else sp.Symbol(n, real=True))),
              st.integers(0, 1000).map(lambda i: (str(i), sp.Integer(i))),
              st.sampled_from([0.5, 2.5e-3, 10.0, 0.125]).map(lambda f: (repr(f), sp.Float(f)))]
    if depth >= 4 or draw(st.booleans()):
        return draw(st.one_of(leaves))
    kind = draw(st.sampled_from(["+", "-", "*", "/", "**", "^", "neg", "call"]))
    left_text, left = draw(_grammar_tree(depth + 1))
    if kind == "neg":
        return f"-({left_text})", -left
    if kind == "call":
        name = draw(st.sampled_from(["sin", "cos", "atan", "abs", "tanh"]))
        return f"{name}({left_text})", {"sin": sp.sin, "cos": sp.cos, "atan": sp.atan, "abs": sp.Abs,
                                         "tanh": sp.tanh}[name](left)
    if kind in ("**", "^"):
        n = draw(st.integers(-2, 2))  # at most 2**4 = 16 once nested powers combine: within the grammar
        if n < 0 and left == 0:
            n = -n
        return f"({left_text}){kind}({n})", left**n
    right_text, right = draw(_grammar_tree(depth + 1))
    if kind == "/" and right == 0:
        right_text, right = "7", sp.Integer(7)
    op = {"+": lambda p, q: p + q, "-": lambda p, q: p - q, "*": lambda p, q: p * q, "/": lambda p, q: p / q}[kind]
    return f"({left_text}) {kind} ({right_text})", op(left, right)


@settings(max_examples=150, deadline=None)
@given(_grammar_tree())
def test_random_expressions_of_the_grammar_equal_the_hand_built_ones(case):
    """Leaves ≤ 1000, exponents |n| ≤ 2, depth ≤ 4: every constant stays within double precision, so each
    generated text is inside the grammar and must give exactly the hand-built expression."""
    text, expected = case
    assert parse_entry(text) == expected


def test_scr_text_names_resolve_to_declared_variables_only():
    x, y = sp.symbols("x y")
    prob = scr.BilinearProblem(variables=[x, y], bilinear=[scr.Bilinear(A=[["x"]], P=[[1]], B=[["x"]], C=[["y"]])],
                               objective="(1 - x)^2")
    sol = scr.solve(prob, x0={x: 0.5, y: 0.3}, backend="cvxpy", max_iter=20)
    assert abs(sol.x["x"] - 1) < 1e-3  # min (1 − x)² with x² = y: the minimiser x = 1, y = 1 by hand
    with pytest.raises(si.ModelError, match="'z', which is not a declared variable"):
        scr.BilinearProblem(variables=[x, y], objective="z**2")


def test_scr_entries_that_would_expand_forever_are_refused_fast():
    xs = sp.symbols("x1:9")
    text = "(" + " + ".join(map(str, xs)) + ")**64"  # C(71, 7) ≈ 1.1e9 terms once expanded
    for kw in (dict(objective=text), dict(equalities=[[[text]]]), dict(objective=sp.Add(*xs) ** 64)):
        t0 = time.perf_counter()
        with pytest.raises(si.ModelError, match="would expand to more than"):
            scr.BilinearProblem(variables=list(xs), **kw)
        assert time.perf_counter() - t0 < TIME_BOUND  # measured: about 1 ms (it never finished before)
    prob = scr.BilinearProblem(variables=list(xs), objective="(x1 + x2 - 1)**2")  # small expansions still work
    assert prob.c == 1.0 and prob.g[0] == -2.0  # (x1 + x2 − 1)² = … − 2 x1 − 2 x2 + 1, by hand


def test_scr_affine_refuses_text_arrays():
    x = sp.Symbol("x")
    lay = scr.Layout([x])
    for bad in (np.array([["nan"]]), [["1+2j"]]):  # numpy would read these strings as numbers
        with pytest.raises(si.ModelError, match="must hold numbers"):
            scr.Affine(bad)
        with pytest.raises(si.ModelError, match="must hold numbers"):
            scr.Affine(np.zeros((1, 1)), {"x": bad}).compile(lay)
    assert scr.Affine(np.array([[1, 2.5]], dtype=object)).const.tolist() == [[1 + 0j, 2.5 + 0j]]


@pytest.mark.parametrize(("value", "expected"), [
    (np.float64(2.5), sp.Float(2.5)), (np.int32(3), sp.Integer(3)), (Fraction(1, 3), sp.Rational(1, 3)),
    (np.array(0.5), sp.Float(0.5)), (sp.Symbol("a") + 1, sp.Symbol("a") + 1), (7, sp.Integer(7)),
])
def test_non_text_values_still_convert(value, expected):
    assert sympify_value(value) == expected


@pytest.mark.parametrize("value", [True, np.bool_(False), None, object(), b"a", bytearray(b"a"), "a",
                                   np.array(["a"]), sp.Matrix([[1]]), [1], (1,), range(2)])
def test_sympify_value_refuses_everything_else(value):
    with pytest.raises(si.ModelError):
        sympify_value(value, "A[0, 0]")


def test_overlong_text_is_refused_before_parsing():
    with pytest.raises(si.ModelError, match="characters long"):
        parse_expression("a+" * (MAX_LENGTH // 2) + "a")


def test_a_str_subclass_is_read_as_plain_text():
    class Sneaky(str):
        def strip(self, chars=None):  # never called: the parser reads a plain copy of the text
            raise AssertionError("a str subclass's method was called")

    assert parse_entry(Sneaky("a + 1")) == a_ + 1


# --- hostile text, generated ------------------------------------------------------------------------------
# SENTINEL stands for a fresh directory, substituted in the test: an attack that ran would create a file there.
_DANGER = ["__import__('os').system('touch SENTINEL/x')", "open('SENTINEL/y', 'w')", "exec", "eval", "open",
           "getattr", "__import__", "__builtins__", "globals", "compile", "breakpoint", "print", "Float", "Symbol"]
_ATOMS = st.sampled_from(["a", "b", "x", "pi", "oo", "nan", "zoo", "inf", "1e999", "9" * 400, "0x1f", "1_0", "3j",
                          "'a'", "\"s\"", "f'{a}'", "None", "True", "...", "ａ", "𝕒", "µ", "_a", "1e-400", "64",
                          *_DANGER])


def _hostile_expression():
    def extend(inner):
        pair = st.tuples(inner, inner)
        return st.one_of(
            pair.map(lambda p: f"({p[0]})**({p[1]})"),
            st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "**", "^", "//", "%", "@", "|", " and ", " if "
                                              "a else ", "<", "==", ","]), inner).map("".join),
            st.tuples(inner, st.sampled_from(["system", "__class__", "__subclasses__()", "real", "T"]))
            .map(lambda p: f"({p[0]}).{p[1]}"),
            pair.map(lambda p: f"({p[0]})[{p[1]}]"),
            st.tuples(st.sampled_from(["sqrt", "exp", "log", "sin", "abs", *_DANGER]), st.lists(inner, max_size=3))
            .map(lambda p: f"{p[0]}({', '.join(p[1])})"),
            inner.map(lambda s: f"(lambda: {s})()"),
            inner.map(lambda s: f"[{s} for _ in 'ab'][0]"),
            inner.map(lambda s: f"f'{{{s}}}'"),
            inner.map(lambda s: f"(w := {s})"),
            inner.map(lambda s: f"sqrt(*[{s}])"),
            inner.map(lambda s: f"sqrt(x={s})"),
            inner.map(lambda s: f"-{s}"),
            st.tuples(inner, st.integers(1, 250)).map(lambda p: "(" * p[1] + p[0] + ")" * p[1]),
            st.tuples(inner, st.sampled_from([64, 65, 10**10, 9**9])).map(lambda p: f"({p[0]})**{p[1]}"),
        )
    return st.recursive(_ATOMS, extend, max_leaves=12)


_HOSTILE = st.one_of(
    st.text(alphabet=string.printable + "αβ𝕒ａµ\u200b\u00a0", max_size=80),
    st.lists(st.sampled_from([*_DANGER, "(", ")", "[", "]", "{", "}", "lambda ", ":", ".", ",", "=", ":=", "*", "**",
                              "^", "9", "99999", "a", "b", " for ", " in ", " if ", " else ", "not ", "~", "@", "%",
                              "\\", "\n", "#", ";", "import os", "yield", "'", '"']),
             min_size=1, max_size=25).map("".join),
    _hostile_expression(),
    st.tuples(st.sampled_from(["a+", "(", "-", "9"]), st.integers(2000, 6000)).map(lambda p: p[0] * p[1]),
)



@pytest.fixture(scope="module")
def sentinel(tmp_path_factory):
    """A directory an attack that ran would write into, and the time taken by each entry (printed at the end)."""
    watch = types.SimpleNamespace(path=tmp_path_factory.mktemp("sentinel"), times=[])
    yield watch
    if watch.times:
        times = sorted(watch.times)
        print(f"\nhostile text: {len(times)} entries, worst {times[-1] * 1e3:.1f} ms, "
              f"median {times[len(times) // 2] * 1e3:.2f} ms")


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=_HOSTILE, data=st.data())
def test_hostile_text_gives_an_expression_or_a_symid_error_fast(sentinel, text, data):
    """Measured on the shared 2-core machine (pytest -s prints it): worst 12 ms over 200 examples × 3 entry
    points."""
    text = text.replace("SENTINEL", str(sentinel.path))
    labels = sorted(_text_entry_points(text))
    for label in ["parse_entry", *data.draw(st.lists(st.sampled_from(labels), min_size=2, max_size=2,
                                                     unique=True), label="entry points")]:
        call = _text_entry_points(text)[label]
        t0 = time.perf_counter()
        try:
            out = call()
        except SymidError:
            pass
        else:
            if label == "parse_entry":
                assert isinstance(out, sp.Expr) and not out.has(sp.oo, -sp.oo, sp.zoo, sp.nan, sp.I)
        elapsed = time.perf_counter() - t0
        sentinel.times.append(elapsed)
        assert elapsed < TIME_BOUND, (label, text)
        assert list(sentinel.path.iterdir()) == [], (label, text)


@pytest.mark.parametrize("text", ["2and 3", "1if 2 else 3", "0x1for"])
def test_a_number_run_into_a_keyword_is_an_error_without_a_python_warning(text):
    # Python's parser warns on stderr of "invalid decimal literal" before it fails or parses; the user gets the
    # ModelError only (found in CI: hypothesis drew such strings and 18 SyntaxWarnings were printed)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(si.ModelError):
            parse_expression(text)
    assert not [w for w in seen if issubclass(w.category, SyntaxWarning)]


def test_an_invalid_escape_in_a_string_is_a_named_error_without_a_warning():
    # found by the hostile-text property test: Python 3.11 warns of "\o" (DeprecationWarning) while parsing
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ModelError, match="str constant"):
            parse_expression("'\\o'")
