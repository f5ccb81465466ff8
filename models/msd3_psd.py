"""Three-DOF spring-mass-damper from output power spectra, thesis §5-6, eqs. (5-9)–(5-11).

System
------
A mass with three translational DOFs (x, y, z; Figure 5-4) and a non-diagonal mass
matrix::

    M q'' + V q' + K q = F u,   y = H q

with (5-9)::

    M = [[5, -1, 0], [-1, 2, -0.5], [0, -0.5, 1]]
    V = [[5, -0.1, -0.1], [-0.1, 0.2, -0.1], [-0.1, -0.1, 1.1]]
    K = [[4, -2, 0], [-2, 4, -2], [0, -2, 22]]

and (5-10): H = I₃ (all DOFs measured, positions), F = [1, 0, 0]ᵀ (input in x).
The input u is not measured: only its spectrum is known (chapter 5).

Parameterisation
----------------
Full symmetric M(θ), V(θ), K(θ): 6 parameters each, 18 in all. The thesis does not
print the parameterisation of chapter 5 (its estimates (5-12), (5-14), (5-15) are full
symmetric matrices); we number as (7-20) does for the same system: in each matrix the
diagonal first, then (1,2), (2,3), then (1,3) — ``theta1``..``theta6`` for M,
``theta7``..``theta12`` for V, ``theta13``..``theta18`` for K. Diagonal parameters are
positive, off-diagonal ones real. F and H are known.

Data recipe
-----------
Output spectra Φʸʸ(ωᵢ) = H(ωᵢ) Φᵘᵘ(ωᵢ) H(ωᵢ)ᴴ (5-3) at 170 log-spaced frequencies in
0.1–100 rad/s, with the "pink" input spectrum Φᵘᵘ(ω) = ω^(−0.5) (5-11)
(:func:`symid.simulate_spectra`, Φᵘᵘ passed as an (s, 1, 1) array).

Notation and discrepancies
--------------------------
* In (5-10) H is the output matrix and F the input matrix; the rest of chapter 5
  calls them C and B ((5-4), (5-6)), and (5-13) even writes C X⁻¹ H Φᵘᵘ Hᴴ X⁻ᴴ Cᴴ with
  H in the role of the input matrix. Here B = F = [1, 0, 0]ᵀ and C = H = I₃.
* §5-3 says "a full set of actuators, i.e. p = n"; p = n is a full set of sensors
  (C square and invertible, which §5-5 uses). The example has one actuator.
* The text calls Φᵘᵘ = ω^(−0.5) pink or 1/f noise "inversely proportional to the
  frequency"; a 1/f spectrum would be ω^(−1). We keep the printed exponent −0.5.
* Figures 5-2/5-3 plot 0.01 ≤ ω ≤ 100 while the data use 0.1–100 rad/s; we follow the
  text (170 points in 0.1–100 rad/s).
* (5-9) is the same system as (7-17) of ``msd3_similarity`` (which has other F, H).
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from symid.zoo_models._common import symmetric_by_diagonals, symmetric_truth

import symid as si

W = np.logspace(np.log10(0.1), np.log10(100), 170)  # rad/s, thesis §5-6
PHI_UU = (W**-0.5)[:, None, None]  # thesis (5-11), shape (s, 1, 1)

M_PRINTED = np.array([[5.0, -1.0, 0.0], [-1.0, 2.0, -0.5], [0.0, -0.5, 1.0]])  # thesis (5-9)
V_PRINTED = np.array([[5.0, -0.1, -0.1], [-0.1, 0.2, -0.1], [-0.1, -0.1, 1.1]])  # thesis (5-9)
K_PRINTED = np.array([[4.0, -2.0, 0.0], [-2.0, 4.0, -2.0], [0.0, -2.0, 22.0]])  # thesis (5-9)
H_PRINTED = np.eye(3)  # thesis (5-10), output matrix
F_PRINTED = np.array([[1.0], [0.0], [0.0]])  # thesis (5-10), input matrix


def make_data(model, truth, noise=None, seed=None):
    """Output spectra for the pink input ω^-0.5 at 170 log-spaced frequencies in 0.1–100 rad/s."""
    from symid.signal.simulate import simulate_spectra

    return simulate_spectra(model, truth, W, PHI_UU, noise=noise, seed=seed)


M, m_syms = symmetric_by_diagonals(3, "theta", 1)
V, v_syms = symmetric_by_diagonals(3, "theta", 7)
K, k_syms = symmetric_by_diagonals(3, "theta", 13)
model = si.SecondOrderModel(M=M, V=V, K=K, B=[[1], [0], [0]], C=sp.eye(3),
                            output="position", parameters=m_syms + v_syms + k_syms, name="msd3_psd")
truth = {**symmetric_truth(M_PRINTED, "theta", 1),  # thesis (5-9)
         **symmetric_truth(V_PRINTED, "theta", 7),
         **symmetric_truth(K_PRINTED, "theta", 13)}
title = "3-DOF spring-mass-damper, full symmetric M, V, K (18 parameters), output spectra"
source = "thesis §5-6, eqs. (5-9)–(5-12); Figures 5-1–5-5"
recipe = ("output power spectra (3 x 3) at 170 log-spaced frequencies in 0.1–100 rad/s for the "
          "input spectrum Φuu(ω) = ω^-0.5")
notes = ("(5-10) names the output matrix H and the input matrix F (C and B elsewhere in ch. 5). "
         "Parameterisation not printed in ch. 5; numbered as (7-20). 'Pink' spectrum is ω^-0.5 as printed.")
extra = {"w": W, "Phi_uu": PHI_UU, "M_printed": M_PRINTED, "V_printed": V_PRINTED,
         "K_printed": K_PRINTED, "H_printed": H_PRINTED, "F_printed": F_PRINTED}
