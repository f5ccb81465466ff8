"""No code is ever executed from text (issue 12 item 2): every place that accepts a string entry parses a
whitelisted grammar (symid.model.expressions) and refuses the rest with a ModelError, fast and without side
effects."""

from __future__ import annotations

import string
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import symid as si
from symid import scr
from symid.errors import SymidError
from symid.model.expressions import MAX_LENGTH, parse_expression
from symid.model.symbols import parse_entry


def _attacks(target: str) -> list[str]:
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
    ]


def _entry_points(text: str):
    """Every public place that takes an entry as text."""
    x, y = sp.symbols("x y")
    return [
        lambda: si.StateSpaceModel(A=[[text]], B=[[1]], C=[[1]]),
        lambda: si.StateSpaceModel(A=text, B=[[1]], C=[[1]]),  # a scalar string
        lambda: si.SecondOrderModel(M=[[1]], V=[[text]], K=[[1]], B=[[1]], C=[[1]]),
        lambda: si.StateSpaceModel(A=np.array([[text]], dtype=object), B=[[1]], C=[[1]]),
        lambda: si.StateSpaceModel(A=np.array([[text]]), B=[[1]], C=[[1]]),  # numpy str_ entries
        lambda: parse_entry(text),
        lambda: scr.BilinearProblem(variables=[x, y], bilinear=[scr.Bilinear(A=[[text]], P=[[1]], B=[[x]], C=[[y]])]),
        lambda: scr.BilinearProblem(variables=[x, y], bilinear=[scr.Bilinear(A=text, P=[[1]], B=[[x]], C=[[y]])]),
        lambda: scr.BilinearProblem(variables=[x, y], objective=text),
        lambda: scr.BilinearProblem(variables=[x, y], equalities=[[[text]]]),
        lambda: scr.BilinearProblem(variables=[x, y], lmis=[[[text]]]),
    ]


@pytest.mark.parametrize("k", range(10))
def test_attack_strings_run_nothing_anywhere(tmp_path, k):
    target = tmp_path / "pwned"
    text = _attacks(str(target))[k]
    for call in _entry_points(text):
        with pytest.raises(SymidError):
            call()
        assert not target.exists(), text


@pytest.mark.parametrize("text", ["10**10**10", "a*9**9**9", "2**(2**64)", "a**100000", "9" * 5000,
                                  "(" * 1000 + "a" + ")" * 1000, "-" * 5000 + "a", "a" + "+a" * 3000,
                                  "1" + "*1" * 3000])
def test_huge_powers_and_deep_or_long_texts_are_refused_in_milliseconds(text):
    t0 = time.perf_counter()
    with pytest.raises(si.ModelError):
        si.StateSpaceModel(A=[[text]], B=[[1]], C=[[1]])
    assert time.perf_counter() - t0 < 1.0  # measured: a few ms (the old parser hung for minutes)


@pytest.mark.parametrize("text", ["Float('nan')", "-a + 0*Float('nan')", "oo", "a + zoo", "nan", "inf*a", "1e400",
                                  "a/0", "0**-1", "log(0)", "1j*a", "a + True", "None"])
def test_non_finite_and_non_real_entries_are_refused(text):
    with pytest.raises(si.ModelError):
        si.StateSpaceModel(A=[[text]], B=[[1]], C=[[1]])


@pytest.mark.parametrize(("text", "expected"), [
    # reference: the same expressions built by hand with real sympy symbols
    ("c1 + c2", "c1 + c2"), ("-(k1 + k2)/m", "-(k1 + k2)/m"), ("2^3*a", "8*a"), ("a**2/2", "a**2/2"),
    ("sqrt(4) + exp(0) - pi*a", "3 - pi*a"), ("3.5e-2*b", "0.035*b"), ("a^-1", "1/a"), ("x**(1/2)", "sqrt(x)"),
    ("E*I/L**3", "E*I/L**3"), ("+a - -b", "a + b"), ("abs(a)", "Abs(a)"),
])
def test_the_grammar_builds_the_expressions_sympy_would(text, expected):
    names = {n: sp.Symbol(n, real=True) for n in ("a", "b", "c1", "c2", "k1", "k2", "m", "x", "E", "I", "L")}
    want = sp.sympify(expected, locals=names)  # a fixed, trusted reference string (not user input)
    assert sp.simplify(parse_entry(text) - want) == 0


def test_scr_text_names_resolve_to_declared_variables_only():
    x, y = sp.symbols("x y")
    prob = scr.BilinearProblem(variables=[x, y], bilinear=[scr.Bilinear(A=[["x"]], P=[[1]], B=[["x"]], C=[["y"]])],
                               objective="(1 - x)^2")
    sol = scr.solve(prob, x0={x: 0.5, y: 0.3}, backend="cvxpy", max_iter=20)
    assert abs(sol.x["x"] - 1) < 1e-3  # min (1 − x)² with x² = y: the Rosenbrock-like valley bottom
    with pytest.raises(si.ModelError, match="'z', which is not a declared variable"):
        scr.BilinearProblem(variables=[x, y], objective="z**2")


def test_overlong_text_is_refused_before_parsing():
    with pytest.raises(si.ModelError, match="characters long"):
        parse_expression("a+" * (MAX_LENGTH // 2) + "a")


# Hostile text: random characters, and random expressions assembled from dangerous pieces.
_SENTINEL = Path(tempfile.mkdtemp()) / "sentinel"
_PIECES = [f"('touch {_SENTINEL}')", f"(\"open('{_SENTINEL}', 'w')\")",
           "__import__", "('os')", ".system", "(", ")", "[", "]", "{", "}", "lambda ", ":", "exec", "eval", "open",
           "getattr", "__class__", "__subclasses__", "'x'", '"y"', "f'{a}'", ":=", "*", "**", "^", "9", "99999",
           "a", "b", " for ", " in ", " if ", " else ", ",", ".", "=", "==", "not ", "~", "@", "%", "//", "\\",
           "\n", "1e999", "nan", "oo", "sin", "sqrt", "𝕒", "ａ", "\u200b", "#", ";", "import os", "yield"]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(st.text(alphabet=string.printable + "αβ𝕒ａ\u200b", max_size=60),
                 st.lists(st.sampled_from(_PIECES), min_size=1, max_size=25).map("".join)))
def test_hostile_text_gives_an_expression_or_a_symid_error_fast(text):
    t0 = time.perf_counter()
    try:
        out = parse_entry(text)
    except SymidError:
        pass
    else:
        assert isinstance(out, sp.Expr) and not out.has(sp.oo, -sp.oo, sp.zoo, sp.nan)
    assert time.perf_counter() - t0 < 1.0  # measured: worst case a few ms
    assert not _SENTINEL.exists()
