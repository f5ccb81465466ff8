"""Driver belt of thesis §6-7-2, eqs. (6-37) and (6-38) (after reference [48] there, Dorf).

System
------
A third-order SISO state-space model::

    A(θ) = [[0,  1,  -1],      B(θ) = [[0 ],      C = [0, 1, 0]
            [1,  0,   0],              [0 ],
            [θ1, θ2, θ3]]              [θ4]]

with all true values equal to −10 (6-38), chosen in the thesis "in order to let the
offsets induced by σ²ε have the same effect on all θᵢ". The θ are negative, so the
parameters are real, not positive.

Data recipe
-----------
Chapter 6 setting: the data are a continuous-time black box (𝔸, 𝔹, ℂ), a similarity
transform of the true (A, B, C). The thesis does not print it. ``data()`` returns
``T A T⁻¹, T B, C T⁻¹`` with the seeded random, well-conditioned T of
``_common.random_similarity(..., seed=638)`` (T = Q₁ diag(d) Q₂, Q orthogonal,
d ∈ [0.5, 2]). The thesis's experiment (Figure 6-4) starts the estimators at
θ₀ = θ* + ε, ε ~ N(0, σ² I), σ² ∈ {0.01, 0.1, 1, 10, 100} (6-34)–(6-36), 10 runs per σ²;
those values are in ``extra["sigma2"]``. ``noise`` perturbs the black-box entries
(relative to each matrix's rms). I/O data could be simulated too, but see below: the
system is unstable.

Transcription choices and discrepancies
---------------------------------------
* The printed indices are garbled: (6-37) puts θ2 at both A[3,2] and A[3,3] and has
  no θ3, and (6-38) lists "{θ1*, θ2*, θ2*, θ3*}" for four values. We read the intended
  structure as four distinct parameters, θ3 at A[3,3] and θ4 in B (as in the chapter-3
  belt drive (3-17)). Since every true value is −10, both readings give the same true
  matrices.
* This is not the belt drive of (3-17): A[1, :], A[2, :] differ (here [0, 1, −1] and
  [1, 0, 0]).
* At the truth the system is unstable: A has eigenvalues −10.844, −1 and +1.844. The
  thesis only uses the black-box triplet, for which this does not matter, but a
  balanced realisation (as for ``random5``) does not exist, hence the random T, and an
  I/O experiment would diverge.
"""

from __future__ import annotations

from symid.zoo_models._common import blackbox_data, random_similarity

import symid as si

SEED = 638  # seed of the similarity transform of the black-box data
SIGMA2 = (0.01, 0.1, 1.0, 10.0, 100.0)  # thesis (6-36): variances of the initial-guess offsets


def make_data(model, truth, noise=None, seed=None):
    """Black box: the truth under a seeded random similarity transform (optionally perturbed)."""
    A, B, C, _ = model.state_space(truth)
    return blackbox_data(*random_similarity(A, B, C, seed=SEED), noise=noise, seed=seed)


theta1, theta2, theta3, theta4 = si.parameters("theta1 theta2 theta3 theta4")
model = si.StateSpaceModel(
    A=[[0, 1, -1], [1, 0, 0], [theta1, theta2, theta3]],
    B=[[0], [0], [theta4]],
    C=[[0, 1, 0]],
    name="belt_drive_dorf",
)
truth = {"theta1": -10.0, "theta2": -10.0, "theta3": -10.0, "theta4": -10.0}  # thesis (6-38)
title = "Driver belt (Dorf), 3 states, 4 unknown entries (SISO), black-box data"
source = "thesis §6-7-2, eqs. (6-37), (6-38); Figure 6-4"
recipe = (f"continuous-time black box: the true (A, B, C) under a seeded (seed {SEED}) random "
          "well-conditioned similarity transform; initial guesses θ* + N(0, σ²I), "
          "σ² ∈ {0.01, 0.1, 1, 10, 100}")
notes = ("(6-37)/(6-38) repeat θ2 and skip θ3; read as four distinct parameters (θ3 at A[3,3], "
         "θ4 in B); the truth is the same either way. Unstable at the truth (eigenvalue +1.844).")
extra = {"sigma2": SIGMA2, "similarity_seed": SEED}
