"""Three-compartment e-nose sensor of thesis §6-6-3, over-parameterised form (6-22).

System
------
The e-nose of ``enose`` (6-15)–(6-17), reparameterised with seven parameters::

    A(θ̂) = [[θ̂1, θ̂2,  0  ],    B = [[1], [0], [0]]
            [θ̂3, θ̂4,  θ̂5],    C = [θ̂7, θ̂7, θ̂7]
            [0,  θ̂6, -θ̂5]]

related to the physical parameters by (6-23): θ̂1 = −(k01 + k21), θ̂2 = k12,
θ̂3 = k21, θ̂4 = −(k12 + k32), θ̂5 = k23, θ̂6 = k32, θ̂7 = f. With (6-16) the truth is
θ̂ = (−0.4, 0.2, 0.3, −0.6, 0.25, 0.4, 0.15), which reproduces (6-17). θ̂2, θ̂3, θ̂5,
θ̂6, θ̂7 are rates or a gain and are declared positive; θ̂1 and θ̂4 are negative sums
of rates and are declared real.

The structure is NOT identifiable: 7 parameters exceed n(p + m) = 6 (the thesis's
argument). The solutions form a manifold; the physical point is singled out by the
constraint θ̂2 + θ̂4 + θ̂6 = 0 (mass conservation of compartment 2), which the thesis
imposes afterwards through the similarity transform Q of (6-26)–(6-28). The thesis's
estimate (6-24) is one point of the manifold (its eigenvalues equal the truth's to
1e-5, but θ̂2 + θ̂4 + θ̂6 = 0.0098); it is kept in ``extra["A_estimate_printed"]``.

Data recipe
-----------
Same as ``enose``: the continuous-time black box that is the similarity transform of
the true (A, B, C) closest to the printed N4SID + d2c estimate (6-18) (kept verbatim
in ``extra``); ``noise`` perturbs the black-box entries (relative to each matrix's
rms). I/O data can be simulated from the model with :func:`symid.simulate_io`.

Transcription notes
-------------------
* Names ``theta1`` … ``theta7`` stand for the hatted θ̂1 … θ̂7 of (6-22).
* (6-25) prints T and S with TS = I only to about 4e-3 (rounding of the printed digits).
"""

from __future__ import annotations

import numpy as np
from symid.zoo_models._common import blackbox_data, similar_to

import symid as si

A_PRINTED = np.array([[-0.4, 0.2, 0.0], [0.3, -0.6, 0.25], [0.0, 0.4, -0.25]])  # thesis (6-17)
B_PRINTED = np.array([[1.0], [0.0], [0.0]])  # thesis (6-17)
C_PRINTED = np.array([[0.15, 0.15, 0.15]])  # thesis (6-17)

A_BB_PRINTED = np.array([[-0.6773, 0.7994, -0.1172],
                         [0.2979, -0.4156, -0.2437],
                         [-0.6528, 0.7859, -0.1571]])  # thesis (6-18)
B_BB_PRINTED = np.array([[0.1233], [-0.1025], [0.0645]])  # thesis (6-18)
C_BB_PRINTED = np.array([[2.4717, -0.0417, -2.4254]])  # thesis (6-18)

A_ESTIMATE_PRINTED = np.array([[-0.3732, 0.2024, 0.0],
                               [0.2732, -0.5753, 0.3015],
                               [0.0, 0.3827, -0.3015]])  # thesis (6-24), a point of the solution manifold


def make_data(model, truth, noise=None, seed=None):
    """Black box: the similarity transform of the truth closest to the printed (6-18)."""
    A, B, C, _ = model.state_space(truth)
    return blackbox_data(*similar_to(A, B, C, A_BB_PRINTED, B_BB_PRINTED, C_BB_PRINTED), noise=noise, seed=seed)


theta1, theta4 = si.parameters("theta1 theta4")
theta2, theta3, theta5, theta6, theta7 = si.parameters("theta2 theta3 theta5 theta6 theta7", positive=True)
model = si.StateSpaceModel(
    A=[[theta1, theta2, 0], [theta3, theta4, theta5], [0, theta6, -theta5]],
    B=[[1], [0], [0]],
    C=[[theta7, theta7, theta7]],
    parameters=[theta1, theta2, theta3, theta4, theta5, theta6, theta7],
    name="enose_overparameterized",
)
# thesis (6-23) applied to (6-16): -(k01 + k21), k12, k21, -(k12 + k32), k23, k32, f
truth = {"theta1": -0.4, "theta2": 0.2, "theta3": 0.3, "theta4": -0.6,
         "theta5": 0.25, "theta6": 0.4, "theta7": 0.15}
title = "Three-compartment e-nose sensor, over-parameterised (7 parameters, not identifiable)"
source = "thesis §6-6-3, eqs. (6-22)–(6-28); truth from (6-16); black box (6-18)"
recipe = ("continuous-time black box: the similarity transform of the true (A, B, C) closest to the "
          "thesis's N4SID + d2c estimate (6-18) (printed (6-18) kept in extra)")
notes = ("Not identifiable (7 > n(p+m) = 6); the physical point satisfies θ̂2 + θ̂4 + θ̂6 = 0. "
         "(6-18) is a noisy estimate; data() is an exact transform of the truth close to it.")
extra = {"A_printed": A_PRINTED, "B_printed": B_PRINTED, "C_printed": C_PRINTED,
         "A_bb_printed": A_BB_PRINTED, "B_bb_printed": B_BB_PRINTED, "C_bb_printed": C_BB_PRINTED,
         "A_estimate_printed": A_ESTIMATE_PRINTED}
