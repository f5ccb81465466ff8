"""Two-dimensional truss with 8 unrestrained DOFs, thesis §4-6-1, eqs. (4-15)–(4-17) (ref. [1]).

System
------
Eight nodes, four of them fully restrained; the displacement vector is
q = [u1, v1, u2, v2, u3, v3, u4, v4] (horizontal u, vertical v of the free nodes
1..4, Figure 4-1). The numeric mass, damping and stiffness matrices are (4-15)
(M = 100 I₈; V, K as printed, kept in ``extra["M_printed"]`` etc.). The model is

    M(θ) q'' + V(θ) q' + K(θ) q = B u,   y = C q,   B = C = I₈

with the full symmetric parameterisation (4-16) of each of M, V, K: 36 parameters
per matrix, 108 in all. The truth is (4-15), which the estimate (4-17) reproduces.

Parameter names and the printed (4-16)
--------------------------------------
(4-16) numbers the upper triangle diagonal by diagonal: θ1…θ8 on the main diagonal,
θ9…θ15 on the first super-diagonal, θ16…θ21 on the second, …, θ36 in the corner (1, 8).
As printed it repeats indices: entries (3, 8), (4, 8), (5, 8) (and their mirrors) carry
θ31, θ28, θ24, which already sit at (1, 6), (2, 6), (3, 6); θ26, θ30, θ33 never appear.
That printed structure (33 distinct parameters) could not even represent the printed
V, whose (5, 8) entry is −50.0 while (3, 6) is 17.7. Following the text ("full
symmetric parameterizations"), every upper-triangular entry gets its own parameter,
with the numbering pattern of (4-16): (3, 8) → θ33, (4, 8) → θ30, (5, 8) → θ26.
"Similarly for V(θ), K(θ)" is read as: V uses ``theta37`` … ``theta72`` and K
``theta73`` … ``theta108``, the same pattern shifted by 36 and 72. Diagonal
parameters are declared positive (M, V, K are positive definite), off-diagonal ones real.

Input and output matrices
-------------------------
"Full set of actuators": B = I₈ (the case of the LS formulation (4-11), B full rank).
The thesis does not state C; (4-11) needs it known. We take C = I₈ (all eight
displacements measured), output "position".

Data recipe
-----------
FRF at 20 log-spaced frequencies in 5–25 rad/s
(``np.logspace(np.log10(5), np.log10(25), 20)``), where the thesis sees "most
information" (the modes have damped natural frequencies between 5.6 and 20.4 rad/s).

Discrepancies and remarks
-------------------------
* The thesis simulates the FRF "by casting M, V, K into state-space form, see (4-3)";
  (4-3) prints the input block as −M⁻¹B, which contradicts (4-2) and (7-2). Since the
  LS estimate (4-17) came out equal to (4-15) (not its negative), the simulation must
  have used +M⁻¹B, as symid does.
* In (4-15) the off-diagonal pattern of V differs from that of K in one place: V has
  −50.0 at (5, 8)/(8, 5) where K has 0, and K has −10000.0 at (6, 8)/(8, 6) where V has
  0. Elsewhere V's off-diagonal entries are K's divided by 200. This looks like a slip in
  one of the two matrices, but both are symmetric and positive definite, (4-17) repeats
  them, and we keep them exactly as printed.
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from symid.zoo_models._common import symmetric_by_diagonals, symmetric_truth

import symid as si

W = np.logspace(np.log10(5), np.log10(25), 20)  # rad/s, thesis §4-6-1

M_PRINTED = 100.0 * np.eye(8)  # thesis (4-15)
V_PRINTED = np.array([  # thesis (4-15)
    [136.0, 0, 0, 0, -50.0, 0, -17.7, -17.7],
    [0, 86.4, 0, -50.0, 0, 0, -17.7, -17.7],
    [0, 0, 136.0, 0, -17.7, 17.7, -50.0, 0],
    [0, -50.0, 0, 86.4, 17.7, -17.7, 0, 0],
    [-50.0, 0, -17.7, 17.7, 136.0, 0, 0, -50.0],
    [0, 0, 17.7, -17.7, 0, 86.4, 0, 0],
    [-17.7, -17.7, -50.0, 0, 0, 0, 136.0, 0],
    [-17.7, -17.7, 0, 0, -50.0, 0, 0, 86.4],
])
K_PRINTED = np.array([  # thesis (4-15)
    [27071.0, 0, 0, 0, -10000.0, 0, -3535.5, -3535.5],
    [0, 17071.0, 0, -10000.0, 0, 0, -3535.5, -3535.5],
    [0, 0, 27071.0, 0, -3535.5, 3535.5, -10000.0, 0],
    [0, -10000.0, 0, 17071.0, 3535.5, -3535.5, 0, 0],
    [-10000.0, 0, -3535.5, 3535.5, 27071.0, 0, 0, 0],
    [0, 0, 3535.5, -3535.5, 0, 17071.0, 0, -10000.0],
    [-3535.5, -3535.5, -10000.0, 0, 0, 0, 27071.0, 0],
    [-3535.5, -3535.5, 0, 0, 0, -10000.0, 0, 17071.0],
])


def make_data(model, truth, noise=None, seed=None):
    """FRF (8 x 8) of the truth at 20 log-spaced frequencies in 5–25 rad/s."""
    from symid.signal.simulate import simulate_frf

    return simulate_frf(model, truth, W, noise=noise, seed=seed)


M, m_syms = symmetric_by_diagonals(8, "theta", 1)
V, v_syms = symmetric_by_diagonals(8, "theta", 37)
K, k_syms = symmetric_by_diagonals(8, "theta", 73)
eye = sp.eye(8)
model = si.SecondOrderModel(M=M, V=V, K=K, B=eye, C=eye, output="position",
                            parameters=m_syms + v_syms + k_syms, name="truss8")
truth = {**symmetric_truth(M_PRINTED, "theta", 1),  # thesis (4-15)
         **symmetric_truth(V_PRINTED, "theta", 37),
         **symmetric_truth(K_PRINTED, "theta", 73)}
title = "2-D truss, 8 DOFs, full symmetric M, V, K (108 parameters), B = C = I8"
source = "thesis §4-6-1, eqs. (4-15)–(4-18); Figures 4-1, 4-2"
recipe = "FRF (position, 8 x 8) at 20 log-spaced frequencies in 5–25 rad/s"
notes = ("(4-16) as printed repeats θ31, θ28, θ24 at (3,8), (4,8), (5,8); each entry gets its own "
         "parameter (θ33, θ30, θ26). C = I8 is our choice (thesis silent). V and K of (4-15) differ "
         "in sparsity at (5,8) vs (6,8); kept as printed.")
extra = {"w": W, "M_printed": M_PRINTED, "V_printed": V_PRINTED, "K_printed": K_PRINTED}
