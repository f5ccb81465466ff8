"""Closed three-compartment catenary of Bellman and Åström, thesis §1-2 eq. (1-2) (ref. [4]).

System
------
Three compartments in a chain, input into compartment 3, output of compartment 1::

    A(θ) = [[-θ1,  θ2,         0 ],    B = [[0], [0], [1]],   C = [1, 0, 0]
            [ θ1, -(θ2 + θ3),  θ4],
            [ 0,   θ3,        -θ4]]

θ1 is the rate 1→2, θ2 the rate 2→1, θ3 the rate 2→3, θ4 the rate 3→2; all positive.
Every column of A sums to zero (a closed system conserves mass), so A is singular: one
pole sits at s = 0.

This structure is NOT identifiable, although it has 4 < n(p + m) = 6 parameters. Its
transfer function is::

    H(s) = θ2 θ4 / ( s (s² + (θ1 + θ2 + θ3 + θ4) s + θ1 θ3 + θ1 θ4 + θ2 θ4) )

three coefficients for four parameters: a one-dimensional family of θ gives the same
H. Only θ2 θ4, θ1 + θ2 + θ3 + θ4 and θ1 θ3 + θ1 θ4 + θ2 θ4 are identifiable.

The printed (1-2) and this model: a deliberate difference
---------------------------------------------------------
The thesis prints (1-2) with θ3 at entry (1, 2), as the classic unidentifiable
example of [4]. As printed, column 2 sums to θ3 − θ2 (not a mass balance) and the
model is identifiable, locally: H(s) = θ3 θ4 / (s³ + (θ1 + θ2 + θ3 + θ4) s²
+ (θ1 θ2 + θ1 θ4 + θ2 θ4) s + θ1 θ4 (θ2 − θ3)) gives four equations in the four θ,
with finitely many solutions. It is not globally identifiable: at our truth below the
equations have 7 complex solutions, 4 of them real and positive, e.g.
θ ≈ (0.0363, 0.8017, 0.1433, 0.4188) has the same H(s) as (0.5, 0.4, 0.3, 0.2)
(Gröbner basis; the issue statement expected "globally identifiable"). Either way it
is not the infinite family the text describes. The catenary of Bellman and Åström,
which the text describes ("unidentifiable even though the number of parameters is
strictly less than n(p + m)"), has θ2 at (1, 2). This entry carries that
unidentifiable model. The structure exactly as printed is in
``extra["model_as_printed"]``.

Truth and data recipe
---------------------
The thesis gives no numbers. We choose θ = (θ1, θ2, θ3, θ4) = (0.5, 0.4, 0.3, 0.2)
(poles 0, −0.3, −1.1). ``data()`` is the FRF at 20 log-spaced frequencies in
0.05–5 rad/s (``np.logspace(np.log10(0.05), np.log10(5), 20)``), a band that brackets
the two nonzero poles and avoids the pole at ω = 0.
"""

from __future__ import annotations

import numpy as np

import symid as si

W = np.logspace(np.log10(0.05), np.log10(5), 20)  # rad/s; our choice, the thesis has no data recipe


def make_data(model, truth, noise=None, seed=None):
    """FRF of the truth at 20 log-spaced frequencies in 0.05–5 rad/s."""
    from symid.signal.simulate import simulate_frf

    return simulate_frf(model, truth, W, noise=noise, seed=seed)


def _model_as_printed():
    """Thesis (1-2) exactly as printed (θ3 at entry (1, 2)): locally, not globally, identifiable."""
    theta1, theta2, theta3, theta4 = si.parameters("theta1 theta2 theta3 theta4", positive=True)
    return si.StateSpaceModel(
        A=[[-theta1, theta3, 0], [theta1, -(theta2 + theta3), theta4], [0, theta3, -theta4]],
        B=[[0], [0], [1]],
        C=[[1, 0, 0]],
        parameters=[theta1, theta2, theta3, theta4],
        name="compartment_catenary_as_printed",
    )


theta1, theta2, theta3, theta4 = si.parameters("theta1 theta2 theta3 theta4", positive=True)
model = si.StateSpaceModel(
    A=[[-theta1, theta2, 0], [theta1, -(theta2 + theta3), theta4], [0, theta3, -theta4]],
    B=[[0], [0], [1]],
    C=[[1, 0, 0]],
    parameters=[theta1, theta2, theta3, theta4],
    name="compartment_catenary",
)
truth = {"theta1": 0.5, "theta2": 0.4, "theta3": 0.3, "theta4": 0.2}  # our choice; the thesis has none
title = "Closed 3-compartment catenary (Bellman & Åström), 4 rates, NOT identifiable"
source = "thesis §1-2, eq. (1-2) and ref. [4] (Bellman & Åström 1970)"
recipe = "FRF at 20 log-spaced frequencies in 0.05–5 rad/s (our choice; the thesis gives no data)"
notes = ("(1-2) as printed has θ3 at (1,2) and is locally (not globally) identifiable; the classic "
         "unidentifiable catenary of [4] has θ2 there, which is what this entry carries. Truth values are ours.")
extra = {"model_as_printed": _model_as_printed(), "w": W}
