"""Global identifiability of a mass-spring-damper chain driven and measured at an interior mass.

A chain driven and measured at an interior mass j (a collocated sensor and actuator in
the middle of a structure) has the dynamic stiffness

    D(s) = m_j s² + Z_L(s) + Z_R(s),

Z_L and Z_R the impedances of the two sub-chains as seen from mass j, each through the
element e = c s + k that ties it to j. Unlike an end-driven chain
(:mod:`~symid.structural.ladder`), D does not say which of its poles belong to which
side: a solution of D(θ) = D(θ*) could split them differently. The inversion is

1. every split of D's 2n − 2 poles into 2a for Z_L and 2b for Z_R (a, b masses on either
   side; C(2n − 2, 2b) of them, 3003 for 8 masses) is tested against two necessary
   conditions (:mod:`~symid.structural.pole_split`): a free side's impedance vanishes to
   second order at s = 0, and e − Z has a double zero at −k/c. Exactly one split must pass,
   and it must be θ*'s: the poles of Z_R(θ*). One exception: with both sides free and of
   the same length the sides swapped pass too, and their solution is θ*'s mirror image,
   ruled out when a known value, or an element present on one side only, does not fit it
   (:func:`_mirror_excluded`);
2. on it, in exact rational arithmetic: Z_R and Z_L (the split's partial fractions with
   c s + β fixed by condition 1) are θ*'s; the numerators G = N′F − N F′ and
   H = N + (c s + β) F of each side have a greatest common divisor of degree 1, whose root
   −k/c gives k (one choice of s₀); then D′ = 1/(1/Z − 1/e) is the impedance of the side's
   own chain, driven at its end, inverted node by node by
   :func:`~symid.structural.ladder.peel` (one solution, module notes there).

Every solution θ of D(θ) = D(θ*) for a generic θ* goes through exactly these steps, so θ*
is the only one. Step 1 is a floating-point test with wide margins, not an interval proof
(see :mod:`~symid.structural.pole_split`); step 2 is exact. As for the Gröbner step, the
claim is confirmed at a second random point θ** (:func:`~symid.structural.global_.generic_global`).

Structure recognised: :func:`~symid.structural.ladder.ladder_of` with
``driven_anywhere=True`` and the driven mass interior (ground elements at most at one end,
never at the driven mass), both elements at the driven mass with a damper and a spring,
at most :data:`~symid.structural.pole_split.MAX_SPLITS` splits (up to 9 masses). Anything
else returns False and the usual global step decides.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mpmath
import sympy as sp

from symid.structural.ladder import _RF, _S, Ladder, _lin, _matches_model, impedance, peel, series, values_at
from symid.structural.pole_split import DPS, possible_splits, split_residuals

__all__ = ["invert_interior", "split_margins"]


def _side(ladder: Ladder, nodes: list[int], m: list, e: list, g: list) -> tuple[Ladder, list, list, list]:
    """The sub-chain on ``nodes`` (positions in ``ladder.order``, from the driven mass outwards) as a Ladder driven
    at its first node, with its values at θ*."""
    step = 1 if nodes[0] > ladder.at else -1
    # edge i of the ladder joins positions i and i + 1
    idx = [min(p, p + step) for p in nodes[:-1]]
    side = Ladder(tuple(ladder.order[p] for p in nodes), tuple(ladder.masses[p] for p in nodes),
                  tuple(ladder.edges[i] for i in idx), tuple(ladder.grounds[p] for p in nodes), ladder.shift,
                  ladder.gain)
    return side, [m[p] for p in nodes], [e[i] for i in idx], [g[p] for p in nodes]


def _side_unique(Z: _RF, edge: tuple, free: bool) -> bool:
    """Step 2 on one side (module notes): Z's polynomial part is c s + β with c θ*'s damper, a free side has
    Z(0) = Z′(0) = 0, and gcd(G, H) has degree 1 with root −k/c."""
    c, k = edge
    q, N = Z.num.div(Z.den)
    F = Z.den
    if q.degree() > 1 or q.coeff_monomial(_S) != c:
        return False
    beta = q.coeff_monomial(1)
    if free:  # Z(0) = 0 and Z'(0) = 0: β = −g(0), c = −g'(0) with g = N/F
        f0, n0 = F.eval(0), N.eval(0)
        if f0 == 0 or beta != -n0 / f0 or c != -(N.diff(_S).eval(0) * f0 - n0 * F.diff(_S).eval(0)) / f0**2:
            return False
    G = N.diff(_S) * F - N * F.diff(_S)
    common = G.gcd(Z.num)
    return common.degree() == 1 and -common.coeff_monomial(1) / common.LC() == -k / c


def invert_interior(ladder: Ladder, model, known: Mapping[str, object] | None, star: Sequence[object]) -> bool:
    """Whether the inversion of the module notes shows θ* = ``star`` to be the only solution.

    ``ladder`` from :func:`~symid.structural.ladder.ladder_of` with ``driven_anywhere=True``.
    True proves (step 1 up to floating point, see the module notes) that summary(θ) =
    summary(θ*) has one complex solution; False proves nothing (the usual global step
    decides).

    Examples
    --------
    >>> import sympy as sp
    >>> import symid as si
    >>> from symid.structural.ladder import ladder_of
    >>> from symid.structural.ladder_interior import invert_interior
    >>> m1, m2, m3, c1, c2, c3, k1, k2, k3 = si.parameters("m1 m2 m3 c1 c2 c3 k1 k2 k3", positive=True)
    >>> chain = si.SecondOrderModel(M=sp.diag(m1, m2, m3), V=[[c1 + c2, -c2, 0], [-c2, c2 + c3, -c3], [0, -c3, c3]],
    ...                             K=[[k1 + k2, -k2, 0], [-k2, k2 + k3, -k3], [0, -k3, k3]],
    ...                             B=[[0], [1], [0]], C=[[0, 1, 0]])
    >>> lad = ladder_of(chain, driven_anywhere=True)
    >>> lad.at
    1
    >>> invert_interior(lad, chain, None, [3, 5, 7, sp.Rational(1, 2), 11, 2, 13, 17, 19])
    True
    """
    setup = _setup(ladder, model, known, star)
    if setup is None:
        return False
    found = possible_splits(*setup.split_args)
    if found is None:
        return False
    theirs = [_poles_of(setup.ZR, p) for p in found[0]]
    mine = [p for p, t in zip(found[0], theirs, strict=True) if t]
    others = [p for p, t in zip(found[0], theirs, strict=True) if not t]
    if len(mine) != 1 or (others and not (len(others) == 1 and _mirror_excluded(ladder, setup, others[0]))):
        return False  # undecided, θ*'s split not passing, or another split some solution could have
    ZL, ZR, e, at, subs = setup.ZL, setup.ZR, setup.e, ladder.at, setup.subs
    left, right = setup.left, setup.right
    left_free = setup.split_args[-1]
    if not (_side_unique(ZR, e[at], True) and _side_unique(ZL, e[at - 1], left_free)):
        return False
    for Z, edge, (side, *vals) in ((ZR, e[at], right), (ZL, e[at - 1], left)):
        own = (Z.inv() - _RF.poly(_lin(*edge)).inv()).inv()
        if not peel(own, side, *vals, subs):
            return False
    return True


def _mirror_excluded(ladder: Ladder, setup: _Setup, other) -> bool:
    """Whether the other passing split is the two sides swapped and no solution can have it.

    Both sides free and of the same length: the split that gives Z_R the poles of Z_L(θ*)
    passes both conditions (each side's c and β come from its own poles), and on it the
    continued fraction recovers θ*'s left values in the right side's slots and vice versa
    (each step is unique). That is a solution iff every slot can take the other side's
    value: a free parameter can; a known number (or an absent element, 0) only if equal.
    Declared excluded when some known number differs, or when an element is present on one
    side and absent in the mirrored place of the other: the absent place would have to take
    the present element's value at θ*, which is not 0 (a known 0 reads as absent).
    """
    at = ladder.at
    if not setup.split_args[-1] or len(setup.left[1]) != len(setup.right[1]) or not _poles_of(setup.ZL, other):
        return False

    def slots(side: tuple, join: tuple, join_value: tuple) -> tuple[list, list]:
        lad, m, e, g = side  # mirrored order: masses outwards, the joining element, edges outwards, grounds
        return ([*lad.masses, *join, *(x for p in lad.edges for x in p), *(x for p in lad.grounds for x in p)],
                [*m, *join_value, *(x for p in e for x in p), *(x for p in g for x in p)])

    sl, vl = slots(setup.left, ladder.edges[at - 1], setup.e[at - 1])
    sr, vr = slots(setup.right, ladder.edges[at], setup.e[at])
    if any((a == 0) != (b == 0) for a, b in zip(sl, sr, strict=True)):
        return True  # an element present on one side only: its value at θ* cannot go where the other has none
    free = set(setup.subs)
    return any((a not in free or b not in free) and va != vb for a, va, b, vb in zip(sl, vl, sr, vr, strict=True))


@dataclass(frozen=True)
class _Setup:
    subs: dict
    e: list
    left: tuple  # (Ladder, m, e, g) of the side from the driven mass to the grounded end (if any)
    right: tuple
    ZL: _RF
    ZR: _RF
    split_args: tuple  # the arguments of possible_splits


def _setup(ladder: Ladder, model, known, star) -> _Setup | None:
    """θ*'s values, the two sides, their impedances and D (checked against the model), or None when the
    structure or θ* is outside the cases of the module notes."""
    n, at = len(ladder.masses), ladder.at
    if not 0 < at < n - 1 or ladder.grounds[at] != (0, 0):
        return None
    if any(x == 0 for x in (*ladder.edges[at - 1], *ladder.edges[at])):
        return None  # an element at the driven mass without a damper or a spring: condition 2 does not apply
    subs, m, e, g = values_at(ladder, model, known, star)
    present = [*ladder.masses, *(x for pair in ladder.edges for x in pair),
               *(x for pair in ladder.grounds for x in pair)]
    slots = [*m, *(x for pair in e for x in pair), *(x for pair in g for x in pair)]
    if any(x == 0 and p != 0 for x, p in zip(slots, present, strict=True)):
        return None  # an element of the structure is 0 at θ*: not a generic point
    left = _side(ladder, list(range(at - 1, -1, -1)), m, e, g)
    right = _side(ladder, list(range(at + 1, n)), m, e, g)
    ZL, ZR = series(e[at - 1], impedance(*left[1:])), series(e[at], impedance(*right[1:]))
    D = _RF.poly(sp.Poly(m[at] * _S**2, _S, domain="QQ")) + ZL + ZR
    if not _matches_model(D, ladder, model, known, subs):
        return None
    P = D.den
    # each side's poles: twice its masses, fewer by the factors s an element without a spring cancels
    # (ladder._degree_drops); a solution's sides cannot have more (θ* is generic), so they have as many
    n_left, n_right = ZL.den.degree(), ZR.den.degree()
    if P.degree() != n_left + n_right or D.num.degree() != P.degree() + 2 or D.num.LC() / P.LC() != m[at]:
        return None
    q, rem = (D - _RF.poly(sp.Poly(m[at] * _S**2, _S, domain="QQ"))).num.div(P)
    if q.degree() > 1:
        return None
    left_free = all(x == (0, 0) for x in left[3])
    return _Setup(subs, e, left, right, ZL, ZR,
                  (P, rem, q.coeff_monomial(_S), q.coeff_monomial(1), n_right, left_free))


def _poles_of(Z: _RF, poles) -> bool:
    """Whether every one of ``poles`` (complex) is a root of Z's denominator, to 1e-12 of the size of its terms."""
    mp = mpmath.MPContext()  # a context of its own: mpmath's global one is shared with other threads
    mp.dps = DPS
    den = [mp.mpf(int(c.p)) / int(c.q) for c in Z.den.all_coeffs()]
    for z in poles:
        size = mp.fsum(abs(c) * abs(z) ** i for i, c in enumerate(reversed(den)))
        if abs(mp.polyval(den, mp.mpc(z))) > 1e-12 * size:
            return False
    return True


def split_margins(ladder: Ladder, model, known: Mapping[str, object] | None, star: Sequence[object]) -> dict | None:
    """How clearly the split test of step 1 separates θ*'s split from the others, at θ* = ``star``.

    Returns ``{"splits": number tested, "true": θ*'s 40-digit residual, "nearest": the
    smallest residual of any other split (40 digits where it was rechecked, else
    double)}``, or None outside the cases of the module notes. For the benchmarks
    (the residuals are defined in :mod:`~symid.structural.pole_split`).
    """
    setup = _setup(ladder, model, known, star)
    found = None if setup is None else split_residuals(*setup.split_args)
    if found is None:
        return None
    roots, splits, double, fine = found
    mine = [k for k in range(len(splits)) if _poles_of(setup.ZR, [complex(roots[i]) for i in splits[k]])]
    if len(mine) != 1 or mine[0] not in fine:
        return None
    others = [fine[k] if k in fine and fine[k] is not None else float(double[k])
              for k in range(len(splits)) if k != mine[0]]
    return {"splits": len(splits), "true": fine[mine[0]], "nearest": min(others, default=float("inf"))}
