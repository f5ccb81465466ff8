"""Two-degree-of-freedom mass-spring-damper of thesis §4-6-2, eqs. (4-19)–(4-21).

System
------
Two masses in a chain (Figure 4-3), force f on m1, position of m1 measured::

    [[m1, 0], [0, m2]] q'' + [[c1 + c2, -c2], [-c2, c2]] q' + [[k1 + k2, -k2], [-k2, k2]] q = [[1], [0]] f
    y = [1, 0] q

The parameterisation (4-21) is θ = (θ1, …, θ6) = (m1, m2, c1, c2, k1, k2); we use the
physical names of (4-20), all positive. Truth (4-20): {m1, m2, c1, c2, k1, k2} =
{1, 1, 0.1, 0.3, 2, 1}, so M = I, V = [[0.4, −0.3], [−0.3, 0.3]],
K = [[3, −1], [−1, 1]] (in ``extra``).

Data recipe
-----------
FRF (position output) at 30 log-spaced frequencies in 0.5–2 rad/s
(``np.logspace(np.log10(0.5), np.log10(2), 30)``), as the text of §4-6-2 says;
uniform weights λᵢ = 1; SCR started from a Gaussian random vector (a zero start lands
in a local minimum with m1 = k1 = c1 = 0).

Discrepancies in the thesis (recorded, not "fixed")
---------------------------------------------------
* The caption of Figure 4-4 speaks of "10 data points … log-spaced between 0.6 and
  2 rad/s", the text of 30 points in 0.5–2 rad/s. We follow the text.
* The printed estimate (4-22) has V = [[0.40, −0.10], [−0.10, 0.10]], which is
  c1 = 0.3, c2 = 0.1, while the truth (4-20) has c1 = 0.1, c2 = 0.3
  (V = [[0.4, −0.3], [−0.3, 0.3]]). The thesis calls (4-22) "consistent with the true
  parameter vector"; the FRF of the two differs, so (4-22) must carry a transcription
  slip (c1, c2 swapped). We keep the truth (4-20); (4-22) is in
  ``extra["V_estimate_printed"]``.
* (4-19) prints the equation without the "+" signs between the terms.
"""

from __future__ import annotations

import numpy as np

import symid as si

W = np.logspace(np.log10(0.5), np.log10(2), 30)  # rad/s, thesis §4-6-2 text

M_TRUE = np.eye(2)  # from thesis (4-20)
V_TRUE = np.array([[0.4, -0.3], [-0.3, 0.3]])  # from thesis (4-20): c1 + c2, -c2, c2
K_TRUE = np.array([[3.0, -1.0], [-1.0, 1.0]])  # from thesis (4-20): k1 + k2, -k2, k2
V_ESTIMATE_PRINTED = np.array([[0.40, -0.10], [-0.10, 0.10]])  # thesis (4-22): c1, c2 swapped


def make_data(model, truth, noise=None, seed=None):
    """FRF of the truth at 30 log-spaced frequencies in 0.5–2 rad/s."""
    from symid.signal.simulate import simulate_frf

    return simulate_frf(model, truth, W, noise=noise, seed=seed)


m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
model = si.SecondOrderModel(
    M=[[m1, 0], [0, m2]],
    V=[[c1 + c2, -c2], [-c2, c2]],
    K=[[k1 + k2, -k2], [-k2, k2]],
    B=[[1], [0]],
    C=[[1, 0]],
    output="position",
    parameters=[m1, m2, c1, c2, k1, k2],
    name="mass_damper_2dof",
)
truth = {"m1": 1.0, "m2": 1.0, "c1": 0.1, "c2": 0.3, "k1": 2.0, "k2": 1.0}  # thesis (4-20)
title = "2-DOF mass-spring-damper, force on m1, position of m1 measured"
source = "thesis §4-6-2, eqs. (4-19)–(4-22); Figures 4-3, 4-4"
recipe = "FRF (position) at 30 log-spaced frequencies in 0.5–2 rad/s"
notes = ("Figure 4-4 caption says 10 points in 0.6–2 rad/s, the text 30 in 0.5–2: text followed. "
         "Printed estimate (4-22) has c1, c2 swapped relative to the truth (4-20).")
extra = {"w": W, "M_true": M_TRUE, "V_true": V_TRUE, "K_true": K_TRUE,
         "V_estimate_printed": V_ESTIMATE_PRINTED}
