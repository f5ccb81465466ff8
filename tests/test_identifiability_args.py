"""Issue 12, item 5: every argument of si.identifiability is checked up front, with a named error.

Bad values of the model or of ``known=`` are ModelError, bad option values OptionError
(both ValueError), each message naming the argument; edge values that are valid
(``timeout=inf``, numpy scalars, exact fractions) give the correct report.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

import symid as si
from symid.structural import check_local
from symid.structural.arguments import checked_arguments, checked_known


def _belt():
    return si.load_model("belt_drive").model  # thesis (3-17): theta1..theta4, globally identifiable


_SEED = "seed must be an integer between 0 and 9223372036854775807"
_TIMEOUT = r"timeout must be a number of seconds > 0, or None or inf \(no limit\)"
_POSITIVE = r"positive must be None \(the declarations\), True or False"
_EXACT = "exact_count must be True or False"
_FINITE = r"known\['theta1'\] must be a finite real number"

BAD_ARGUMENTS = [
    # options: OptionError
    ({"seed": None}, si.OptionError, _SEED + ".*got None: the analysis is a deterministic function"),
    ({"seed": "a"}, si.OptionError, _SEED),
    ({"seed": -1}, si.OptionError, _SEED),
    ({"seed": 1.5}, si.OptionError, _SEED),
    ({"seed": np.float64(2.0)}, si.OptionError, _SEED),
    ({"seed": True}, si.OptionError, _SEED),
    ({"seed": 2**63}, si.OptionError, _SEED),
    ({"seed": 2**200}, si.OptionError, _SEED),
    ({"timeout": float("nan")}, si.OptionError, _TIMEOUT),
    ({"timeout": "5"}, si.OptionError, _TIMEOUT),
    ({"timeout": -1}, si.OptionError, _TIMEOUT),
    ({"timeout": 0}, si.OptionError, _TIMEOUT),
    ({"timeout": -float("inf")}, si.OptionError, _TIMEOUT),
    ({"timeout": -(10**400)}, si.OptionError, _TIMEOUT),
    ({"timeout": True}, si.OptionError, _TIMEOUT),
    ({"timeout": np.bool_(True)}, si.OptionError, _TIMEOUT),
    ({"timeout": 1j}, si.OptionError, _TIMEOUT),
    ({"positive": "yes"}, si.OptionError, _POSITIVE),
    ({"positive": 1}, si.OptionError, _POSITIVE),
    ({"exact_count": 2}, si.OptionError, _EXACT),
    ({"exact_count": None}, si.OptionError, _EXACT),
    ({"exact_count": "no"}, si.OptionError, _EXACT),
    # known=: ModelError
    ({"known": {"theta1": float("nan")}}, si.ModelError, _FINITE + r"; got nan \(float\)"),
    ({"known": {"theta1": float("inf")}}, si.ModelError, _FINITE),
    ({"known": {"theta1": np.float64("-inf")}}, si.ModelError, _FINITE),
    ({"known": {"theta1": None}}, si.ModelError, _FINITE + r"; got None \(NoneType\)"),
    ({"known": {"theta1": "1"}}, si.ModelError, _FINITE + r"; got '1' \(str\)"),
    ({"known": {"theta1": True}}, si.ModelError, _FINITE),
    ({"known": {"theta1": 1 + 2j}}, si.ModelError, _FINITE),
    ({"known": {"theta1": sp.sqrt(2)}}, si.ModelError, _FINITE),
    ({"known": {"theta1": sp.nan}}, si.ModelError, _FINITE),
    ({"known": {"theta1": np.array([1.0])}}, si.ModelError, _FINITE),
    ({"known": {"theta1": 10**400}}, si.ModelError, _FINITE + r" within the float range .* 401 digits"),
    ({"known": ["theta1"]}, si.ModelError, r"known must be a dict of parameter name → value; got list"),
    ({"known": "theta1=1"}, si.ModelError, r"known must be a dict .*; got str"),
    ({"known": 1.0}, si.ModelError, r"known must be a dict .*; got float"),
    ({"known": {"nope": 1.0}}, si.ModelError, r"known= names unknown parameter 'nope'; the model's parameters are "
                                              "theta1, theta2, theta3, theta4"),
    ({"known": {1: 1.0}}, si.ModelError, r"known= keys must be parameter names or symbols; got 1 \(int\)"),
    ({"known": {sp.Symbol("theta1"): 1.0, "theta1": 2.0}}, si.ModelError, "known= gives 'theta1' twice"),
    ({"known": {"theta1": 1.0, "theta2": 2.0, "theta3": 3.0, "theta4": 4.0}}, si.ModelError,
     r"every parameter \(theta1, theta2, theta3, theta4\) is given in known=: nothing is left to identify"),
]


@pytest.mark.parametrize(("kwargs", "error", "match"), BAD_ARGUMENTS)
def test_bad_arguments_are_named_errors(kwargs, error, match):
    with pytest.raises(error, match=match) as info:
        si.identifiability(_belt(), **kwargs)
    assert isinstance(info.value, ValueError)  # both types are ValueErrors too


@pytest.mark.parametrize("model", [None, "belt_drive", 3.0, "entry"])
def test_something_that_is_not_a_model_is_a_model_error(model):
    if model == "entry":
        model = si.load_model("belt_drive")
        match = r"got ZooEntry \(what si.load_model returns\? pass its .free_model\(\)"
    else:
        match = f"needs a StateSpaceModel or SecondOrderModel; got {type(model).__name__}"
    with pytest.raises(si.ModelError, match=match):
        si.identifiability(model)


def test_every_argument_is_checked_before_any_work(monkeypatch):
    # a bad last argument is refused even when the analysis itself would fail at once
    def _never(*args, **kwargs):
        raise AssertionError("the analysis started before the arguments were checked")

    monkeypatch.setattr("symid.structural.analyse.run_with_deadline", _never)
    with pytest.raises(si.OptionError, match="seed"):
        si.identifiability(_belt(), known={"theta1": 1.0}, timeout=5, positive=True, exact_count=False, seed=-3)


def test_infinite_and_huge_timeouts_mean_no_limit():
    # inf (and an int beyond the float range) is documented as "no limit": everything in this
    # process, the exact verdict of thesis (3-17)
    for timeout in (float("inf"), 10**400):
        args = checked_arguments(_belt(), known=None, timeout=timeout, positive=None, exact_count=False, seed=0)
        assert args.timeout is None
    rep = si.identifiability(_belt(), timeout=float("inf"))
    assert rep.verdict == "global" and rep.global_determined and rep.n_solutions == 1
    # a huge but finite budget is waited in slices (the OS refuses a single wait of 1e300 s)
    rep = si.identifiability(_belt(), timeout=1e300)
    assert rep.verdict == "global" and rep.global_determined


def test_numpy_and_exact_values_are_accepted():
    rep = si.identifiability(_belt(), seed=np.int64(3), positive=np.True_, exact_count=np.False_,
                             timeout=np.float64(30.0), known={sp.Symbol("theta1"): np.float64(0.5)})
    assert rep.known == {"theta1": 0.5} and rep.parameters == ("theta2", "theta3", "theta4")
    assert rep.verdict == "global"
    exact, values = checked_known(_belt(), {"theta1": Fraction(1, 3), "theta2": sp.Rational(2, 7),
                                            "theta3": 0.15, "theta4": 10**300}, require_free=False)
    assert exact == {"theta1": sp.Rational(1, 3), "theta2": sp.Rational(2, 7), "theta3": sp.Rational(3, 20),
                     "theta4": sp.Integer(10**300)}  # exact: a Fraction is not rounded through a float
    assert values["theta1"] == 1 / 3 and math.isclose(values["theta4"], 1e300, rel_tol=1e-15)
    assert checked_arguments(_belt(), known=None, timeout=30, positive=None, exact_count=False,
                             seed=2**63 - 1).seed == 2**63 - 1


def test_the_same_seed_gives_the_same_report():
    model = si.load_model("compartment_catenary").model  # not identifiable: combinations, reparameterisation
    one, two = (si.identifiability(model, seed=5).to_dict() for _ in range(2))
    one.pop("timing"), two.pop("timing")
    assert one == two


# -- degenerate models and known values ------------------------------------------------------

def test_models_without_parameters_and_unused_declared_parameters():
    with pytest.raises(si.ModelError, match="the model has no parameter: there is nothing to identify"):
        si.identifiability(si.StateSpaceModel(A=[[-1]], B=[[1]], C=[[1]]))
    a, b, unused = si.parameters("a b unused", positive=True)
    # a declared parameter that appears in no matrix is refused by the model classes themselves
    with pytest.raises(si.ModelError, match="'unused' given in parameters= does not appear in any matrix"):
        si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]], parameters=[a, b, unused])
    with pytest.raises(si.ModelError, match="'unused' given in parameters= does not appear in any matrix"):
        si.SecondOrderModel(M=[[1]], V=[[a]], K=[[b]], B=[[1]], C=[[1]], parameters=[a, b, unused])
    # a parameter that cancels out of its entry is not a parameter of the model
    model = si.StateSpaceModel(A=[[-a + unused - unused]], B=[[b]], C=[[1]])
    assert model.parameter_names == ("a", "b")


def test_known_values_that_degenerate_the_model():
    a, b = si.parameters("a b", positive=True)
    # M(θ) = [[a]] with a = 0 known: det M ≡ 0, a named model error (not a crash inside sympy)
    with pytest.raises(si.ModelError, match=r"det M\(θ\) is identically zero"):
        si.identifiability(si.SecondOrderModel(M=[[a]], V=[[1]], K=[[b]], B=[[1]], C=[[1]]), known={"a": 0})
    # B = b with b = 0 known: H ≡ 0, so a cannot be recovered (exact verdict, no combination)
    rep = si.identifiability(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]]), known={"b": 0})
    assert rep.verdicts == {"a": "none"} and rep.global_determined and rep.jacobian_ranks == (0, 0)
    # K = b with b = 0 known: H(s) = 1/(s² + a s), a is still global
    rep = si.identifiability(si.SecondOrderModel(M=[[1]], V=[[a]], K=[[b]], B=[[1]], C=[[1]]), known={"b": 0})
    assert rep.verdicts == {"a": "global"}
    # a parameter in D only: H(s) = 1/(s + 1) + a
    rep = si.identifiability(si.StateSpaceModel(A=[[-1]], B=[[1]], C=[[1]], D=[[a]]))
    assert rep.verdicts == {"a": "global"} and rep.necessary_condition.bound == 3


def test_check_local_checks_its_arguments():
    with pytest.raises(si.OptionError, match=_SEED):
        check_local(_belt(), seed=None)
    with pytest.raises(si.ModelError, match=_FINITE):
        check_local(_belt(), known={"theta1": float("nan")})
    with pytest.raises(si.ModelError, match="unknown parameter 'zz'"):
        check_local(_belt(), known={"zz": 1.0})
    # every parameter known is fine here (nothing can be unidentifiable)
    assert check_local(_belt(), known={"theta1": 1, "theta2": 2, "theta3": 3, "theta4": 4}) == ()


def test_a_negative_known_value_for_a_positive_parameter_is_refused():
    """A new user's known={"a": -1} for a mass declared positive was accepted silently (verdict 'global'); 0 stays
    allowed (an element left out), and a mass given as 0 is named as the likely cause of a singular M."""
    a, b, c = si.parameters("a b c", positive=True)
    model = si.SecondOrderModel(M=[[a]], V=[[b]], K=[[c]], B=[[1]], C=[[1]])
    with pytest.raises(si.ModelError, match=r"known\['a'\] = -1 is negative, but a is declared positive"):
        si.identifiability(model, known={"a": -1})
    with pytest.raises(si.ModelError, match=r"a mass given as 0 in known="):
        si.identifiability(model, known={"a": 0})
    assert si.identifiability(model, known={"b": 0}).verdict == "global"
