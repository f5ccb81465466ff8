"""Random stable fifth-order SISO system of the comparison study, thesis §6-7-1, eqs. (6-29), (6-30).

System
------
The thesis draws a stable continuous-time SISO system of order 5 with MATLAB ``rss``
and prints it as (6-29) (A*, B*, C*, three decimals; kept in ``extra``). Its study
(Figure 6-3) marks k = 1 … 10 randomly chosen entries of (A*, B*, C*) as unknown
(10 = n(p + m) is the most a state-space structure can identify), 100 draws per k,
and counts how often each method recovers them (NEE ≤ 1e-3, (6-32), (6-33)).

A zoo entry needs one model: this one has the maximal k = 10 unknown entries, drawn
once with ``numpy.random.default_rng(629).choice(35, 10, replace=False)`` over the
entries of (A, B, C) in the order A row-major, B, C, and written out here so that the
model does not depend on numpy's generator (0-based positions)::

    theta1  A[0, 2]    theta6  A[4, 2]
    theta2  A[2, 0]    theta7  A[4, 3]
    theta3  A[3, 3]    theta8  A[4, 4]
    theta4  A[3, 4]    theta9  B[2, 0]
    theta5  A[4, 0]    theta10 C[0, 1]

All other entries are fixed at their (6-29) values. The truth is the (6-29) values of
these entries; the parameters are real (any sign). The structure is locally
identifiable at the truth (the Jacobian of the FRF with respect to θ has full rank 10,
condition number about 1e5). For the study of Figure 6-3, ``extra["random_parameterisation"](k, seed)``
returns ``(model, truth)`` with k entries drawn by ``default_rng(seed)`` in the same way.

Data recipe
-----------
Chapter 6 setting: the continuous-time black box (𝔸, 𝔹, ℂ) obtained by balancing
the true system (MATLAB ``balreal``), printed as (6-30). ``data()`` balances (6-29)
itself (``_common.balanced_realisation``: square-root method, Gramians equal and
diagonal, Hankel singular values decreasing, signs fixed so that each row of 𝔹 starts
positive). ``noise`` perturbs the black-box entries (relative to each matrix's rms).
I/O data can also be simulated (:func:`symid.simulate_io`), then N4SID + d2c, which
the thesis notes would give the same model up to similarity.

Discrepancy: (6-30) is not a realisation of (6-29)
--------------------------------------------------
The printed (6-30) is balanced (its Gramians are diagonal and equal to 3e-5), and its
𝔸 has the eigenvalues of A* to 7e-4 (rounding), but its transfer function is not that
of (6-29): the first Markov parameter CB is −0.7833 for (6-29) and ℂ𝔹 = −3.3324 for
(6-30); the DC gains are 0.0254 and 0.3034; the Hankel singular values are
(0.327, 0.215, 0.188, 0.090, 0.0014) against (0.420, 0.257, 0.053, 0.044, 0.020). No
similarity transform maps one onto the other, and rounding cannot explain it: B* and
C* as printed do not belong to the system that was balanced. We take (6-29) as the
truth (it is what the thesis calls the actual system) and balance it; the printed
(6-30) is kept verbatim in ``extra["A_bb_printed"]`` etc.
"""

from __future__ import annotations

import numpy as np
from symid.zoo_models._common import balanced_realisation, blackbox_data

import symid as si

A_PRINTED = np.array([  # thesis (6-29)
    [-3.486, 3.635, 3.689, -3.899, -1.933],
    [-2.634, -1.386, 4.419, 4.286, -0.859],
    [-0.874, -5.314, -2.373, 5.46, 5.883],
    [1.213, -0.935, -6.277, -3.904, 5.637],
    [6.049, 1.803, -4.571, -3.182, -3.719],
])
B_PRINTED = np.array([[-1.636], [0.173], [0.828], [0.217], [-1.909]])  # thesis (6-29)
C_PRINTED = np.array([[0.205, 1.193, -0.802, -1.266, -0.149]])  # thesis (6-29)

A_BB_PRINTED = np.array([  # thesis (6-30): balanced, but not a realisation of (6-29) (see docstring)
    [-0.007884, 0.9789, 0.1331, 0.01995, 0.05165],
    [-0.9789, -7.531, -7.473, -0.6011, -1.801],
    [0.1331, 7.473, -5.651, -8.332, -6.007],
    [-0.01995, -0.6011, 8.332, -0.09533, -0.3607],
    [-0.05165, -1.801, 6.007, -0.3607, -1.585],
])
B_BB_PRINTED = np.array([[-0.08139], [-1.966], [0.774], [-0.09207], [-0.2538]])  # thesis (6-30)
C_BB_PRINTED = np.array([[-0.08139, 1.966, 0.774, 0.09207, 0.2538]])  # thesis (6-30)

# The 10 unknown entries (matrix, row, col), drawn once with default_rng(629).choice(35, 10, replace=False).
UNKNOWN_ENTRIES = (("A", 0, 2), ("A", 2, 0), ("A", 3, 3), ("A", 3, 4), ("A", 4, 0),
                   ("A", 4, 2), ("A", 4, 3), ("A", 4, 4), ("B", 2, 0), ("C", 0, 1))


def _all_entries() -> list[tuple[str, int, int]]:
    """Entries of (A, B, C) in the order A row-major, B, C (35 of them)."""
    return ([("A", i, j) for i in range(5) for j in range(5)]
            + [("B", i, 0) for i in range(5)] + [("C", 0, j) for j in range(5)])


def _parameterise(entries, name: str = "random5"):
    """StateSpaceModel with the given entries of (6-29) unknown (theta1, … in the given order) and its truth."""
    printed = {"A": A_PRINTED, "B": B_PRINTED, "C": C_PRINTED}
    mats = {key: value.astype(object) for key, value in printed.items()}
    names = [f"theta{k + 1}" for k in range(len(entries))]
    symbols = si.parameters(names)
    symbols = [symbols] if len(names) == 1 else list(symbols)
    truth = {}
    for sym, (key, i, j) in zip(symbols, entries, strict=True):
        mats[key][i, j] = sym
        truth[str(sym)] = float(printed[key][i, j])  # thesis (6-29)
    model = si.StateSpaceModel(A=mats["A"], B=mats["B"], C=mats["C"], parameters=symbols, name=name)
    return model, truth


def _random_parameterisation(k: int, seed: int):
    """(model, truth) with k entries of (6-29) unknown, drawn as in the study of Figure 6-3.

    Parameters
    ----------
    k : int
        Number of unknown entries, 1 … 35 (the thesis uses 1 … 10).
    seed : int
        Seed of ``numpy.random.default_rng``; the entries are
        ``choice(35, k, replace=False)`` over A row-major, B, C, sorted.
    """
    picks = np.sort(np.random.default_rng(seed).choice(35, k, replace=False))
    everything = _all_entries()
    return _parameterise([everything[p] for p in picks], name=f"random5_k{k}_seed{seed}")


def make_data(model, truth, noise=None, seed=None):
    """Black box: the balanced realisation of the truth (optionally perturbed)."""
    A, B, C, _ = model.state_space(truth)
    return blackbox_data(*balanced_realisation(A, B, C), noise=noise, seed=seed)


model, truth = _parameterise(list(UNKNOWN_ENTRIES))
title = "Random stable 5th-order SISO system (rss), 10 unknown entries, balanced black box"
source = "thesis §6-7-1, eqs. (6-29)–(6-33); Figure 6-3"
recipe = "continuous-time black box: balanced realisation of the true (A, B, C) (as MATLAB balreal)"
notes = ("The 10 unknown entries are a seeded draw (seed 629). The printed balanced (6-30) is not a "
         "realisation of (6-29) (CB −0.7833 vs −3.3324); data() balances (6-29) itself.")
extra = {"A_printed": A_PRINTED, "B_printed": B_PRINTED, "C_printed": C_PRINTED,
         "A_bb_printed": A_BB_PRINTED, "B_bb_printed": B_BB_PRINTED, "C_bb_printed": C_BB_PRINTED,
         "unknown_entries": UNKNOWN_ENTRIES, "random_parameterisation": _random_parameterisation}
