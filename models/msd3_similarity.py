"""Three-DOF spring-mass-damper from I/O data via a similarity transform, thesis §7-6-1.

System
------
The M, V, K of (5-9), repeated in (7-17), with two inputs applied diagonally in the
xy-plane and the y and z positions measured (Figure 7-1)::

    M q'' + V q' + K q = F u,   y = H q
    F = [[1, 1], [-1, 1], [0, 0]],   H = [[0, 1, 0], [0, 0, 1]]

First-order form (7-2): A = [[0, I], [−M⁻¹K, −M⁻¹V]], B = [[0], [M⁻¹F]], C = [H, 0],
printed numerically in (7-18) (kept in ``extra``).

Parameterisation
----------------
Full symmetric M(θ), V(θ), K(θ) with the numbering of (7-20) (diagonal, then (1,2),
(2,3), then (1,3)): ``theta1``..``theta6`` for M, ``theta7``..``theta12`` for V,
``theta13``..``theta18`` for K; diagonal parameters positive, off-diagonal ones real.
The thesis parameterises M⁻¹(τ) instead of M (τ1..τ6), because M⁻¹ enters (7-2)
affinely; that is a choice of the estimator, not of the model, and M = (M⁻¹(τ))⁻¹
(7-22). F and H are known.

Data recipe
-----------
I/O data: sampling time 0.001 s, N = 5000 samples (5 s), zero-order-hold input
(:func:`symid.simulate_io`), then N4SID and ``d2c`` (Algorithm 7.1). The thesis does
not describe the input; we use seeded white Gaussian noise, unit variance, independent
channels, shape (5000, 2), drawn with ``numpy.random.default_rng(INPUT_SEED)``
(``INPUT_SEED = 7017``); ``seed`` only seeds the output noise. The thesis's N4SID +
d2c black box (7-19) and estimates (7-21), (7-22) are kept in ``extra``.

Discrepancies
-------------
* (7-18) and V₁₁. The −M⁻¹K block and B of the printed A, B (7-18) equal the values
  computed from (7-17) to the 4 printed decimals. The −M⁻¹V block does not: it equals
  −M⁻¹V with V₁₁ = 2 (e.g. its (1,1) entry −0.4323 is −(M⁻¹V)₁₁ for V₁₁ = 2, and
  −1.1097 for V₁₁ = 5). (7-17) prints V₁₁ = 5 and the estimate (7-21) finds 4.9664, so
  the printed (7-18) was apparently computed with a different V. We keep V₁₁ = 5; the
  tests record the discrepancy.
* The record is short for this system: the slowest mode (−0.049 ± 1.404j) decays with
  a time constant of about 20 s, four times the 5 s record. The thesis attributes its
  1e-2 errors in (7-21) to the N4SID step, which is consistent with this.
* Figure 7-1's caption says the outputs are the y and z directions, matching H; the
  related Figure 5-4 (chapter 5) measures x, y and z.
* Position output, so C = [H, 0] (7-2); (7-24) would give velocity outputs.
"""

from __future__ import annotations

import numpy as np
from symid.zoo_models._common import symmetric_by_diagonals, symmetric_truth

import symid as si

DT = 0.001  # s, thesis §7-6-1
N = 5000  # samples, thesis §7-6-1
INPUT_SEED = 7017  # our choice: the thesis does not describe the input

M_PRINTED = np.array([[5.0, -1.0, 0.0], [-1.0, 2.0, -0.5], [0.0, -0.5, 1.0]])  # thesis (7-17)
V_PRINTED = np.array([[5.0, -0.1, -0.1], [-0.1, 0.2, -0.1], [-0.1, -0.1, 1.1]])  # thesis (7-17)
K_PRINTED = np.array([[4.0, -2.0, 0.0], [-2.0, 4.0, -2.0], [0.0, -2.0, 22.0]])  # thesis (7-17)
H_PRINTED = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # thesis (7-17), output matrix
F_PRINTED = np.array([[1.0, 1.0], [-1.0, 1.0], [0.0, 0.0]])  # thesis (7-17), input matrix

A_PRINTED = np.array([  # thesis (7-18); the lower right block matches V11 = 2, not 5 (see docstring)
    [0, 0, 0, 1, 0, 0],
    [0, 0, 0, 0, 1, 0],
    [0, 0, 0, 0, 0, 1],
    [-0.6452, 0.0645, -1.1613, -0.4323, 0.0032, -0.0355],
    [0.7742, -1.6774, -5.8065, -0.1613, -0.0839, -0.2774],
    [0.3871, 1.1613, -24.9032, 0.0194, 0.0581, -1.2387],
])
B_PRINTED = np.array([[0, 0], [0, 0], [0, 0],
                      [0.0968, 0.3548], [-0.5161, 0.7742], [-0.2581, 0.3871]])  # thesis (7-18)
C_PRINTED = np.array([[0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0]], dtype=float)  # thesis (7-18)

A_BB_PRINTED = np.array([  # thesis (7-19), N4SID + ZOH estimate
    [-2.0055, 0.5081, 0.8634, 3.2443, -0.8011, -2.1785],
    [-0.2879, -1.1741, -1.0625, -1.5843, 1.3832, 0.5346],
    [-1.1301, 0.65188, 0.2561, 0.6697, -0.55112, -1.5559],
    [-3.2937, 1.2658, -0.2243, 0.4310, 0.8212, 1.7693],
    [0.8924, -1.2032, 0.33622, -1.0434, 0.0521, 0.0940],
    [2.2319, -0.4929, 1.4974, -1.7734, -0.0800, 0.0080],
])
B_BB_PRINTED = np.array([[-0.2150, 0.6992], [0.4815, 0.2971], [0.0740, -0.2028],
                         [0.1094, -0.2258], [-0.0036, 0.1005], [-0.0254, 0.0105]])  # thesis (7-19)
C_BB_PRINTED = np.array([[-0.3118, 0.0339, -0.5499, -0.6235, -0.3418, -0.9562],
                         [-0.0527, 0.0077, -0.0682, -0.0844, 0.0136, 0.0283]])  # thesis (7-19)

MINV_ESTIMATE_PRINTED = np.array([[0.2273, 0.1288, 0.0645], [0.1288, 0.6447, 0.3255],
                                  [0.0645, 0.3255, 1.1612]])  # thesis (7-21)
V_ESTIMATE_PRINTED = np.array([[4.9664, -0.0984, -0.0996], [-0.0984, 0.1998, -0.1002],
                               [-0.0996, -0.1002, 1.0992]])  # thesis (7-21)
K_ESTIMATE_PRINTED = np.array([[3.9614, -1.9816, -0.0000], [-1.9816, 3.9989, -2.008],
                               [-0.0000, -2.008, 22.0007]])  # thesis (7-21)
M_ESTIMATE_PRINTED = np.array([[4.9612, -0.9912, -0.002], [-0.9912, 1.9994, -0.5003],
                               [-0.002, -0.5003, 1.001]])  # thesis (7-22)


def _input() -> np.ndarray:
    """The input signal: seeded white Gaussian noise, shape (N, 2) (our choice, see docstring)."""
    return np.random.default_rng(INPUT_SEED).standard_normal((N, 2))


def make_data(model, truth, noise=None, seed=None):
    """I/O data: N = 5000 samples at dt = 0.001 s for a seeded white Gaussian input."""
    from symid.signal.simulate import simulate_io

    return simulate_io(model, truth, _input(), DT, noise=noise, seed=seed)


M, m_syms = symmetric_by_diagonals(3, "theta", 1)
V, v_syms = symmetric_by_diagonals(3, "theta", 7)
K, k_syms = symmetric_by_diagonals(3, "theta", 13)
model = si.SecondOrderModel(M=M, V=V, K=K, B=[[1, 1], [-1, 1], [0, 0]], C=[[0, 1, 0], [0, 0, 1]],
                            output="position", parameters=m_syms + v_syms + k_syms, name="msd3_similarity")
truth = {**symmetric_truth(M_PRINTED, "theta", 1),  # thesis (7-17)
         **symmetric_truth(V_PRINTED, "theta", 7),
         **symmetric_truth(K_PRINTED, "theta", 13)}
title = "3-DOF spring-mass-damper, full symmetric M, V, K (18 parameters), 2 inputs, y/z positions, I/O data"
source = "thesis §7-6-1, eqs. (7-17)–(7-22); Figures 7-1–7-3"
recipe = (f"I/O data: N = {N} samples at dt = {DT} s, zero-order hold, input seeded white Gaussian "
          f"noise (seed {INPUT_SEED}; the thesis does not describe the input)")
notes = ("Printed (7-18) −M⁻¹V block matches V11 = 2, not the V11 = 5 of (7-17) and of the estimate "
         "(7-21); V11 = 5 kept. Input signal is our choice.")
extra = {"dt": DT, "N": N, "input_seed": INPUT_SEED, "u": _input(),
         "M_printed": M_PRINTED, "V_printed": V_PRINTED, "K_printed": K_PRINTED,
         "H_printed": H_PRINTED, "F_printed": F_PRINTED,
         "A_printed": A_PRINTED, "B_printed": B_PRINTED, "C_printed": C_PRINTED,
         "A_bb_printed": A_BB_PRINTED, "B_bb_printed": B_BB_PRINTED, "C_bb_printed": C_BB_PRINTED,
         "Minv_estimate_printed": MINV_ESTIMATE_PRINTED, "V_estimate_printed": V_ESTIMATE_PRINTED,
         "K_estimate_printed": K_ESTIMATE_PRINTED, "M_estimate_printed": M_ESTIMATE_PRINTED}
