"""Second-order models whose output rows measure different kinds (an accelerometer beside a displacement sensor).

References: the same model written with one kind for every row (each row of a mixed model's response is that row of
the uniform model of its kind), central differences for derivatives, the truth the data were simulated from for
fits on exact data, and the position twin for identifiability (each row's response is (jω)ᵈ times its position's,
so the same parameters determine both).
"""

import warnings

import numpy as np
import pytest

import symid as si
from symid.fit.sensitivity import frf_sensitivity
from symid.fit.similarity.data import model_has_feedthrough
from symid.model.secondorder import output_factor

TRUTH = {"m1": 2.0, "m2": 1.0, "c1": 5.0, "c2": 3.0, "k1": 4e3, "k2": 2e3}  # SI units, modes at 6 and 18 Hz
W = np.logspace(0, 2.5, 60)  # rad/s, both modes inside
KINDS = ("position", "velocity", "acceleration")


@pytest.fixture
def mixed(grounded_two_mass):
    """Force on mass 2; the position of mass 1 and the acceleration of mass 2."""
    def build(kinds=("position", "acceleration")):
        return grounded_two_mass(B=[[0], [1]], C=[[1, 0], [0, 1]], output=list(kinds))
    return build


def test_attributes_and_errors(mixed, grounded_two_mass):
    model = mixed()
    assert model.output == "mixed" and model.outputs == ("position", "acceleration")
    assert model.output_orders == (0, 2)
    assert "2 outputs (position, acceleration)" in repr(model)
    same = mixed(("velocity", "velocity"))  # a list of one kind is that kind
    assert same.output == "velocity" and same.outputs == ("velocity", "velocity")
    uniform = grounded_two_mass(B=[[0], [1]], C=[[1, 0], [0, 1]], output="acceleration")
    assert uniform.outputs == ("acceleration", "acceleration")
    with pytest.raises(si.ModelError, match=r"output gives 3 kind\(s\) but C has 2 row\(s\)"):
        mixed(("position", "velocity", "position"))
    with pytest.raises(si.ModelError, match=r"output\[1\] must be one of"):
        mixed(("position", "displacement"))
    with pytest.raises(si.ModelError, match="non-empty list"):
        mixed(())


@pytest.mark.parametrize("kinds", [("position", "acceleration"), ("acceleration", "velocity"),
                                   ("velocity", "position")])
def test_each_row_is_the_uniform_models_row(mixed, grounded_two_mass, kinds):
    model = mixed(kinds)
    H = model.frequency_response(TRUTH, W)
    for i, kind in enumerate(kinds):
        uniform = grounded_two_mass(B=[[0], [1]], C=[[1, 0], [0, 1]], output=kind)
        np.testing.assert_allclose(H[:, i], uniform.frequency_response(TRUTH, W)[:, i], rtol=1e-13, atol=0)
        ss_u = uniform.state_space(TRUTH)
        ss = model.state_space(TRUTH)
        np.testing.assert_array_equal(ss.C[i], ss_u.C[i])
        np.testing.assert_array_equal(ss.D[i], ss_u.D[i])
    # the first-order form gives the same response, and the symbolic form the same matrices
    ss = model.state_space(TRUTH)
    H_ss = np.array([ss.C @ np.linalg.solve(1j * w * np.eye(4) - ss.A, ss.B) + ss.D for w in W])
    np.testing.assert_allclose(H_ss, H, rtol=1e-9, atol=0)
    subs = dict(zip(model.parameters, model.theta_vector(TRUTH), strict=True))
    for S, N in zip(model.symbolic_state_space(), ss, strict=True):
        np.testing.assert_allclose(np.array(S.subs(subs).evalf(), dtype=float), N, rtol=1e-12, atol=1e-12)
    assert model_has_feedthrough(model) == ("acceleration" in kinds)


def test_output_factor_is_exact():
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1], [1], [1]], output=list(KINDS))
    f = output_factor(model, np.array([3.0]))
    np.testing.assert_array_equal(f, [[1, 3j, -9]])  # no rounding in the imaginary part of −ω²
    ss = si.StateSpaceModel(A=[[-1]], B=[[1]], C=[[1], [2]])
    np.testing.assert_array_equal(output_factor(ss, np.array([1.0, 2.0])), np.ones((2, 2)))


def test_frf_sensitivity_matches_central_differences(mixed):
    model = mixed()
    theta = model.theta_vector(TRUTH)
    H, dH = frf_sensitivity(model, theta, W)
    np.testing.assert_allclose(H, model.frequency_response(theta, W), rtol=1e-12, atol=0)
    for k in range(theta.size):
        h = 1e-6 * theta[k]
        up, down = theta.copy(), theta.copy()
        up[k] += h
        down[k] -= h
        fd = (model.frequency_response(up, W) - model.frequency_response(down, W)) / (2 * h)
        # central differences: relative error O(h²) ~ 1e-12 plus rounding ~1e-16 / 1e-6 of the response's scale,
        # row by row (position in m/N, acceleration in (m/s²)/N: five decades apart)
        for i in range(2):
            scale = np.abs(fd[:, i]).max()
            np.testing.assert_allclose(dH[:, i, :, k], fd[:, i], rtol=1e-6, atol=1e-8 * scale)


@pytest.mark.parametrize("method", ["lm", "ipopt", "scr", "ls"])
def test_fits_of_exact_data_recover_the_truth(mixed, method):
    model = mixed()
    data = si.simulate_frf(model, TRUTH, W)
    x0 = {k: v * 1.3 for k, v in TRUTH.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no identifiability check wanted here: the next test makes it
        res = si.identify(model, data, method=method, x0=x0, starts=1, identifiability_check=False)
    assert res.success
    # exact data: every method's stopping rule leaves the estimate within 1e-6 of the truth (ls solves exactly)
    np.testing.assert_allclose(res.theta_vector, model.theta_vector(TRUTH), rtol=1e-6)


def test_identifiability_is_the_position_twins(mixed, grounded_two_mass):
    rep = si.identifiability(mixed())
    twin = si.identifiability(grounded_two_mass(B=[[0], [1]], C=[[1, 0], [0, 1]]))
    assert rep.verdicts == twin.verdicts == dict.fromkeys(TRUTH, "global")
    # a sensor gain on the accelerometer and an actuator gain: only their products with the chain are determined
    m1, m2, c1, c2, k1, k2, g, b = si.parameters("m1 m2 c1 c2 k1 k2 g b", positive=True)
    gains = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [b]], C=[[1, 0], [0, g]],
                                output=["position", "acceleration"])
    twin = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [b]], C=[[1, 0], [0, g]])
    assert si.identifiability(gains).verdicts == si.identifiability(twin).verdicts
    assert si.identifiability(gains).verdict == "none"


def test_output_error_on_samples(mixed):
    """Time series: the accelerometer's rows take the feedthrough D = C M⁻¹ B, the position's none."""
    model = mixed()
    rng = np.random.default_rng(0)
    io = si.simulate_io(model, TRUTH, rng.standard_normal((3000, 1)), 1e-3)
    x0 = {k: v * 1.2 for k, v in TRUTH.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = si.identify(model, io, method="oe", x0=x0, identifiability_check=False)
    assert res.success
    # noise-free samples of the model itself: the least-squares estimate is the truth, to the solver's tolerance
    np.testing.assert_allclose(res.theta_vector, model.theta_vector(TRUTH), rtol=1e-6)


def test_spectra_equations_hold_at_the_truth(mixed):
    """Algorithm 5.1's Pᵢ = C⁻¹ F⁻¹ Φyy F⁻ᴴ C⁻ᴴ with F = diag((jω)ᵈ): X Pᵢ Xᴴ = Qᵢ (thesis (5-6)) at the truth."""
    from symid.fit.spectra.equations import spectral_equations

    model = mixed()
    data = si.simulate_spectra(model, TRUTH, W, 1.0)
    eq = spectral_equations(model, data)
    scale = np.linalg.norm(eq.Q, axis=(1, 2))
    np.testing.assert_allclose(eq.residuals(model.theta_vector(TRUTH)) / scale, 0, atol=1e-10)
    assert eq.residuals(model.theta_vector(TRUTH) * 1.1).min() > 1e-3 * scale.min()


def test_similarity_refuses_mixed_outputs_by_name(mixed):
    from symid.fit.similarity.second_order import check_second_order

    with pytest.raises(si.ModelError, match=r"outputs of different kinds \(position, acceleration\)"):
        check_second_order(mixed())


def test_model_file_keeps_the_kinds(tmp_path):
    path = tmp_path / "two_sensors.py"
    path.write_text(
        "import symid as si\n"
        "m1, m2, c1, c2, k1, k2 = si.parameters('m1 m2 c1 c2 k1 k2', positive=True)\n"
        "model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],\n"
        "                            K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[1, 0], [0, 1]],\n"
        "                            output=['position', 'acceleration'])\n"
        "known = {'m1': 2.0}\n")
    spec = si.load_model(path)
    free = spec.free_model()
    assert free.outputs == ("position", "acceleration")
    np.testing.assert_allclose(free.frequency_response({k: v for k, v in TRUTH.items() if k != "m1"}, W),
                               spec.model.frequency_response(TRUTH, W), rtol=1e-13)


def test_numeric_local_check_takes_each_rows_kind(mixed):
    """The floating-point screen's Jacobian is the FRF's (each row times (jω)ᵈ): the rank of the two-mass chain's
    is full, and with the gains of the identifiability test above it loses one (b and g·b, against m's scale)."""
    from symid.structural.numeric import numeric_local_check

    full = numeric_local_check(mixed())
    assert full.rank == 6 and not full.not_identifiable
    m1, m2, c1, c2, k1, k2, g, b = si.parameters("m1 m2 c1 c2 k1 k2 g b", positive=True)
    gains = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [b]], C=[[1, 0], [0, g]],
                                output=["position", "acceleration"])
    assert numeric_local_check(gains).rank == 7


def test_a_first_order_network_in_second_order_form():
    """E x' + F x = B u written as M = E, V = F, K = 0, measured in velocity (the form the singular-mass message
    recommends; a new user's LC ladder): the response is finite at ω = 0 (it raised "singular"), equal to the
    first-order form's elsewhere, and the modes are those of −E⁻¹F, not "n poles at 0" as well. Reference: the
    first-order form's response C (jωI − A)⁻¹ B + D, and the DC gain C F⁻¹ B by hand."""
    from symid.fit.modes import modes_line

    c1, c2 = si.parameters("c1 c2", positive=True)
    F = np.array([[0.02, -0.01], [-0.01, 0.02]])
    model = si.SecondOrderModel(M=[[c1, 0], [0, c2]], V=F.tolist(), K=[[0, 0], [0, 0]], B=[[1], [0]],
                                C=[[0, 1], [1, 0]], output=["velocity", "acceleration"])
    theta = [1e-3, 2e-3]
    w = np.array([0.0, 1.0, 10.0])
    H = model.frequency_response(theta, w)
    np.testing.assert_allclose(H[0, 0, 0], (np.linalg.solve(F, [1.0, 0.0]))[1], rtol=1e-12)  # C F⁻¹ B
    assert H[0, 1, 0] == 0  # an acceleration's response vanishes at ω = 0
    ss = model.state_space(theta)
    H_ss = np.array([ss.C @ np.linalg.solve(1j * x * np.eye(4) - ss.A, ss.B) + ss.D for x in w[1:]])
    np.testing.assert_allclose(H[1:], H_ss, rtol=1e-9)
    poles = np.linalg.eigvals(-np.linalg.solve(np.diag(theta), F))
    assert modes_line(model, theta, "s") == "modes of the estimate: " + "; ".join(
        f"real pole {p:.4g} /s" for p in sorted(poles, key=abs))
