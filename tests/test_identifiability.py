"""Structural identifiability (issue 5): verdicts on the zoo and on small exact examples."""

from __future__ import annotations

import json
import threading
import time
import warnings

import numpy as np
import pytest
import sympy as sp

import symid as si
from symid.cli import main as cli_main
from symid.structural import check_local, exhaustive_summary, warn_if_not_identifiable
from symid.structural.deadline import run_with_deadline
from symid.structural.global_ import global_analysis


def _product_model():
    """y' = −a y + b u, output c y: only a and the product b·c are identifiable."""
    a, b, c = si.parameters("a b c", positive=True)
    return si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]], name="product")


def _square_model(positive: bool = True):
    """B = C = θ: only θ² is determined, so θ and −θ both fit."""
    th = si.parameters("th", positive=positive)
    return si.StateSpaceModel(A=[[-1]], B=[[th]], C=[[th]], name="square")


def _mass_damper(output: str):
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[[1], [0]], C=[[1, 0]], output=output)


# -- the zoo (item 7) ------------------------------------------------------------------

def test_belt_drive_global():
    # thesis (3-17): the belt drive is identifiable (assumption 2 of §3-3)
    rep = si.identifiability(si.load_model("belt_drive").model)
    assert rep.verdict == "global"
    assert set(rep.verdicts.values()) == {"global"}
    assert rep.n_solutions == 1
    assert rep.jacobian_ranks == (4, 4)


def test_enose_global():
    # thesis §6-6-2: (6-19) identifiable; it has n(p+m) = 6 parameters exactly
    rep = si.identifiability(si.load_model("enose").model)
    assert rep.verdict == "global"
    assert set(rep.verdicts.values()) == {"global"}
    assert rep.necessary_condition.n_parameters == rep.necessary_condition.bound == 6
    assert rep.necessary_condition.satisfied


def test_enose_overparameterized_not_identifiable():
    # thesis §6-6-3: (6-22) has 7 > n(p+m) = 6 parameters, not identifiable; f = θ7 is
    rep = si.identifiability(si.load_model("enose_overparameterized").model)
    assert rep.verdict == "none"
    assert rep.verdicts["theta7"] == "global"
    assert all(rep.verdicts[f"theta{i}"] == "none" for i in range(1, 7))
    assert not rep.necessary_condition.satisfied
    assert rep.jacobian_ranks == (6, 6)
    exprs = [c["expression"] for c in rep.combinations]
    assert "theta1 + theta4 - theta5" in exprs  # the trace of A
    assert len(exprs) == 5  # with θ7, reaches the Jacobian rank 6


def test_catenary_not_identifiable():
    # thesis (1-2) as described ([4], Bellman & Åström: θ2 at entry (1,2)): unidentifiable
    # although it has 4 < n(p+m) = 6 parameters
    rep = si.identifiability(si.load_model("compartment_catenary").model)
    assert rep.verdict == "none"
    assert set(rep.verdicts.values()) == {"none"}
    assert rep.necessary_condition.satisfied
    assert rep.n_solutions is None and rep.n_solutions_complex is None  # positive-dimensional
    exprs = {c["expression"] for c in rep.combinations}
    assert {"theta2*theta4", "theta1 + theta2 + theta3 + theta4"} <= exprs
    assert len(rep.fix) == 1


def test_catenary_as_printed_is_local_not_global():
    # thesis (1-2) exactly as printed (θ3 at entry (1,2)): locally identifiable with 7 complex
    # solutions of summary(θ) = summary(θ*), several of them real and positive — NOT global,
    # contrary to what the zoo entry's docstring and the issue expected.
    model = si.load_model("compartment_catenary").extra["model_as_printed"]
    rep = si.identifiability(model)
    assert rep.verdict == "local"
    assert set(rep.verdicts.values()) == {"local"}
    assert rep.n_solutions_complex == 7
    assert rep.n_solutions >= 2
    # every admissible solution reproduces the transfer function (checked numerically)
    w = np.array([0.1, 1.0, 3.0])
    star = {k: float(sp.Rational(v)) for k, v in rep.theta_star.items()}
    H0 = model.frequency_response(star, w)
    for sol in rep.solutions:
        assert all(v > 0 for v in sol.values())
        np.testing.assert_allclose(model.frequency_response(sol, w), H0, rtol=1e-8, atol=1e-12)


def test_mass_damper_2dof_global():
    # thesis (4-21), position of m1 measured, force on m1: measured — globally identifiable
    rep = si.identifiability(si.load_model("mass_damper_2dof").model)
    assert rep.verdict == "global"
    assert set(rep.verdicts.values()) == {"global"}
    assert rep.n_solutions_complex == 1


@pytest.mark.slow
@pytest.mark.parametrize("name", ["msd3_psd", "msd3_similarity", "belt_drive_dorf", "random5"])
def test_other_zoo_models_finish(name):
    rep = si.identifiability(si.load_model(name).model, timeout=120)
    assert rep.verdict in {"global", "local", "none"}


# -- non-identifiable models: combinations, reparameterisation (item 3) -----------------

def test_product_combination_and_reparameterisation():
    rep = si.identifiability(_product_model())
    assert rep.verdicts == {"a": "global", "b": "none", "c": "none"}
    assert rep.non_identifiable == ("b", "c")
    assert [c["expression"] for c in rep.combinations] == ["b*c"]
    assert rep.combinations[0]["global"] is True
    assert rep.reparameterisation == {"phi1": "b*c"}
    assert rep.fix == ("c",)
    assert "b*c" in rep.summary()


def test_known_changes_the_verdict():
    # item 4: with c known, b is determined
    rep = si.identifiability(_product_model(), known={"c": 2.0})
    assert rep.verdict == "global"
    assert rep.verdicts == {"a": "global", "b": "global"}
    assert rep.known == {"c": 2.0}
    assert rep.parameters == ("a", "b")


def test_positivity_discards_the_negative_solution():
    # B = C = θ: θ² determined; positivity removes −θ*
    rep = si.identifiability(_square_model(positive=True))
    assert rep.verdict == "global"
    assert rep.n_solutions == 1 and rep.n_solutions_real == 2
    assert rep.positivity_changed
    assert any("positivity" in n for n in rep.notes)
    rep_free = si.identifiability(_square_model(positive=False))
    assert rep_free.verdict == "local" and rep_free.n_solutions == 2
    assert not rep_free.positivity_changed
    # positive= overrides the declarations
    assert si.identifiability(_square_model(positive=False), positive=True).verdict == "global"
    assert si.identifiability(_square_model(positive=True), positive=False).verdict == "local"


# -- timeout (item 4) --------------------------------------------------------------------

def test_timeout_returns_local_verdict():
    model = si.load_model("random5").model
    t0 = time.perf_counter()
    rep = si.identifiability(model, timeout=0.01)
    elapsed = time.perf_counter() - t0
    assert not rep.global_determined
    assert "timeout" in rep.global_status
    assert rep.verdict == "local"  # the Jacobian has full rank 10
    assert set(rep.verdicts.values()) == {"local"}
    assert "undetermined" in rep.summary()
    assert elapsed < 20  # hang guard only (the global step alone takes minutes)


def test_timeout_in_a_worker_thread_uses_a_process():
    model = si.load_model("random5").model
    out = {}
    th = threading.Thread(target=lambda: out.setdefault("rep", si.identifiability(model, timeout=0.5)))
    th.start()
    th.join(60)
    assert not th.is_alive()
    assert not out["rep"].global_determined


def test_process_isolation_returns_results_and_errors():
    assert run_with_deadline(global_analysis, {"model": _product_model()}, 30, isolation="process")[0] == "ok"
    status, msg = run_with_deadline(float, {}, 30, isolation="process")
    assert status == "ok" and msg == 0.0
    status, msg = run_with_deadline(global_analysis, {"model": "not a model"}, 30, isolation="process")
    assert status == "error" and "ModelError" in msg


# -- necessary condition (item 5), output kinds, random points ---------------------------

def test_necessary_condition_counts():
    rep = si.identifiability(_product_model())
    nc = rep.necessary_condition
    assert (nc.n_parameters, nc.n_states, nc.n_inputs, nc.n_outputs, nc.bound) == (3, 1, 1, 1, 2)
    assert not nc.satisfied
    assert "n(p+m)" in rep.summary()


@pytest.mark.parametrize("output", ["position", "velocity", "acceleration"])
def test_second_order_output_kinds(output):
    rep = si.identifiability(_mass_damper(output))
    assert rep.verdict == "global"
    assert rep.summary_kind == "transfer-function coefficients"
    bound = 4 * 2 + (1 if output == "acceleration" else 0)  # D = C M⁻¹ B for acceleration
    assert rep.necessary_condition.bound == bound


def test_parameters_in_b_and_c_of_a_second_order_model():
    m, c, k, b, g = si.parameters("m c k b g", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[b]], C=[[g]], output="velocity")
    rep = si.identifiability(model)
    # H = g b s / (m s² + c s + k): only b g / m, c / m, k / m are determined
    assert rep.verdict == "none"
    assert rep.jacobian_ranks == (3, 3)
    assert len(rep.combinations) == 3


def test_two_random_points_agree():
    for name in ["belt_drive", "enose_overparameterized", "compartment_catenary"]:
        rep = si.identifiability(si.load_model(name).model)
        assert len(set(rep.jacobian_ranks)) == 1


def test_markov_summary_for_a_non_minimal_model():
    a, b = si.parameters("a b")
    # the second state is unobservable: the transfer-function coefficients would not be exhaustive
    model = si.StateSpaceModel(A=[[-a, 0], [0, -b]], B=[[1], [1]], C=[[1, 0]])
    summ = exhaustive_summary(model)
    assert summ.kind == "Markov parameters" and not summ.minimal
    rep = si.identifiability(model)
    assert rep.verdicts == {"a": "global", "b": "none"}
    assert any("Markov" in n for n in rep.notes)


def test_exhaustive_summary_transfer_function():
    a, b = si.parameters("a b")
    summ = exhaustive_summary(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]]))
    assert summ.kind == "transfer-function coefficients"
    assert summ.expressions() == [a, b]  # H = b / (s + a)


# -- the warning for estimators (item 6) -------------------------------------------------

def test_warning_names_the_parameters():
    with pytest.warns(si.IdentifiabilityWarning, match="b, c"):
        assert warn_if_not_identifiable(_product_model()) == ("b", "c")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert warn_if_not_identifiable(si.load_model("belt_drive").model) == ()
    assert check_local(_product_model(), known={"c": 1.0}) == ()


# -- report and CLI (item 5) ---------------------------------------------------------------

def test_report_summary_and_dict():
    rep = si.identifiability(si.load_model("enose").model)
    text = str(rep)
    assert "GLOBALLY IDENTIFIABLE" in text and "k01" in text
    d = rep.to_dict()
    json.dumps(d)
    assert d["verdict"] == "global" and d["necessary_condition"]["bound"] == 6
    with pytest.raises(si.ModelError, match="unknown"):
        si.identifiability(_product_model(), known={"zz": 1.0})


def test_cli(capsys):
    assert cli_main(["identifiability", "compartment_catenary", "--known", "theta4=0.2", "--timeout", "20"]) == 0
    out = capsys.readouterr().out
    assert "theta2" in out and "known" in out
