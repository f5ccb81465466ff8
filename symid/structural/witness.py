"""Numerical witnesses against global identifiability, for when the Gröbner basis does not finish.

When the exact global step exceeds its deadline, the model may still be shown *not*
globally identifiable by exhibiting a second admissible solution θ ≠ θ* of
summary(θ) = summary(θ*). The search:

1. writes the equations ``F_i(θ) = n_i(θ) d_i(θ*) − d_i(θ) n_i(θ*)`` of the
   exhaustive summary (the same θ* as the Gröbner step);
2. **traces real curves** (:mod:`~symid.structural.tracing`): dropping one equation
   leaves a real curve of solutions through θ*; it is followed from θ* in both
   directions, for every equation, by pseudo-arclength continuation (positive
   parameters in logarithmic scale, so the curve stays in the positive orthant), and
   wherever the dropped equation changes sign the curve crosses another real solution,
   polished by Newton's method. A fixed number of steps per curve;
3. if certified witnesses do not yet move every parameter, runs Gauss–Newton from
   random starts around θ* (log-normal in magnitude, random sign for parameters not
   declared positive; positive parameters in logarithmic scale), all starts at once in
   numpy, in a fixed number of batches;
4. keeps converged points that differ from θ* and satisfy the declared positivity,
   with every summary denominator away from zero (a true solution of
   summary(θ) = summary(θ*), not of the cross-multiplied equations only);
5. when the system is square (as many equations as unknowns, e.g. the 2n normalised
   transfer-function coefficients of a SISO model with 2n unknowns), *certifies* each
   point with the Krawczyk test (:mod:`~symid.structural.certify`): after a Newton
   step with a compensated (double-double accurate) residual, a box of relative radius
   1e-14 … 1e-6 around the point is proven to hold exactly one real root of F, to
   exclude θ*, to lie in the declared positive orthant and to keep every summary
   denominator away from zero (Krawczyk 1969; Neumaier, *Interval Methods for Systems
   of Equations*, Thm. 5.1.7; every bound rigorous in IEEE double arithmetic), and
   certified boxes are pairwise disjoint, so each certified witness is a distinct
   admissible solution, proven. For a system with more equations than unknowns, a
   point is kept (not certified) when its compensated residual is below 1e-12 of the
   size of the terms at a well-conditioned Jacobian.

A witness shows the model is not globally identifiable at θ* (the solution count is
at least 1 + the number of witnesses); a certified one proves it. Finding none proves
nothing. Every budget is a number of steps or starts, never a time: the same model and
seed give the same witnesses on any machine.
"""

from __future__ import annotations

import random
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from symid.structural.certify import SummarySystem
from symid.structural.global_ import POSITIVE_TOL, star_and_summary
from symid.structural.tracing import CurveTracer, ScaledSystem, newton

__all__ = ["METHOD", "WitnessResult", "find_witnesses"]

_MAX_WITNESSES = 8
CURVE_STEPS = 40
"""Continuation steps per traced curve (two curves per equation)."""
CHUNK = 5
"""Steps of every curve per round of the search (candidates are certified after each round)."""
GN_TERMS = 2000
"""Systems with more terms get proportionally fewer random Gauss–Newton starts (48 starts on this many terms: about
0.1 s), and none after certified witnesses from the curves: random starts in 20 and more dimensions find little."""
METHOD = ("found by tracing the real curves through θ* of the system with one equation dropped (and Gauss–Newton "
          "from random starts), polished by Newton's method")
"""How the witnesses are found, for the report's notes."""


@dataclass(frozen=True)
class WitnessResult:
    """Other admissible solutions of summary(θ) = summary(θ*) found numerically.

    Attributes
    ----------
    theta_star : dict of str to str
        The point θ* (rational, as strings).
    witnesses : tuple of dict
        Verified solutions θ ≠ θ* (floats), at most eight.
    n_starts : int
        Curves traced plus random starts tried.
    seconds : float
        Wall time of the search.
    certified : tuple of bool
        Per witness, whether the Krawczyk test proved an exact admissible solution in a
        box of relative radius at most 1e-6 around it (only for square systems).
    square : bool
        Whether the system had as many equations as unknowns (certification possible).
    """

    theta_star: dict
    witnesses: tuple
    n_starts: int
    seconds: float
    certified: tuple = ()
    square: bool = False


def _scaled_system(system: SummarySystem, star: np.ndarray, log_scale: Sequence[bool]) -> ScaledSystem:
    """The equations F_i in the coordinates of :mod:`~symid.structural.tracing` (y = θ / θ*).

    Coefficients ``c_t Π θ*^E`` times ``d_i(θ*)`` (terms of n_i) or ``−n_i(θ*)`` (terms of d_i).
    """
    ps = system.polys
    with np.errstate(all="ignore"):
        logs = np.log(np.abs(star))
        scale = np.exp(ps.Ef @ logs) * (1.0 - 2.0 * np.mod(ps.Ef @ (star < 0).astype(float), 2.0))
    factor = np.empty(ps.n_polys)
    factor[0::2] = system.den_star_f
    factor[1::2] = -system.num_star_f
    coef = ps.c_hi * scale * np.repeat(factor, ps.sizes)
    starts = ps.starts[0::2]  # equation i: the terms of n_i then those of d_i, contiguous
    return ScaledSystem(ps.E, coef, starts, log_scale)


def _gauss_newton(system: ScaledSystem, U: np.ndarray, iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Newton from every row of U at once; the points and max |G_i| / A_i.

    Steps are capped at half of |y| + 1 in the linear coordinates and at 1 in the logarithmic ones.
    """
    U = U.copy()
    alive = np.ones(len(U), dtype=bool)
    for _ in range(iterations):
        idx = np.flatnonzero(alive)
        if len(idx) == 0:
            break
        G, _, J = system.eval(U[idx], absolute=False)
        ok = np.all(np.isfinite(G), axis=1) & np.all(np.isfinite(J), axis=(1, 2))
        alive[idx[~ok]] = False
        idx, G, J = idx[ok], G[ok], J[ok]
        if len(idx) == 0:
            break
        with np.errstate(all="ignore"):
            step = -np.einsum("sij,sj->si", np.linalg.pinv(J), G)
            size = np.linalg.norm(step, axis=1, keepdims=True)
            lin = ~system.log
            cap = (0.5 * (np.linalg.norm((1.0 + U[idx])[:, lin], axis=1, keepdims=True) + 1.0) if lin.any()
                   else np.ones((len(idx), 1)))
            step = np.where(size > cap, step * cap / size, step)
        U[idx] += step
    G, A, _ = system.eval(np.where(alive[:, None], U, 0.0), jacobian=False)
    with np.errstate(all="ignore"):
        rel = np.abs(G / np.maximum(A, 1e-300)).max(axis=1)
    rel[~alive] = np.inf
    return U, rel


class _Collector:
    """Candidates → verified (and, for a square system, certified) witnesses, in the order given."""

    def __init__(self, system: SummarySystem, star: np.ndarray, pos: np.ndarray, square: bool):
        self.system, self.star, self.pos, self.square = system, star, pos, square
        self.found: list[np.ndarray] = []
        self.certified: list[bool] = []
        self.boxes: list[tuple[np.ndarray, np.ndarray]] = []

    def full(self) -> bool:
        return len(self.found) >= _MAX_WITNESSES

    def moved(self) -> np.ndarray:
        """The parameters moved by certified witnesses."""
        out = np.zeros(len(self.star), dtype=bool)
        for f, ok in zip(self.found, self.certified, strict=True):
            if ok:
                out |= np.abs(f - self.star) > 1e-6 * np.maximum(1.0, np.abs(self.star))
        return out

    def _near(self, x: np.ndarray, rel: float) -> bool:
        if np.all(np.abs(x - self.star) <= rel * np.maximum(1.0, np.abs(self.star))):
            return True  # θ* itself
        return any(np.all(np.abs(x - f) <= rel * np.maximum(1.0, np.abs(f))) for f in self.found)

    def offer(self, x: np.ndarray) -> None:
        if self.full() or not np.all(np.isfinite(x)) or np.any(x[self.pos] <= POSITIVE_TOL) or self._near(x, 1e-6):
            return
        if self.square:
            sol, box = self._certify(x)
        else:
            sol, box = self._least_squares(x), None
        if sol is None or np.any(sol[self.pos] <= POSITIVE_TOL) or not self._denominators_nonzero(sol):
            return
        if self._near(sol, 1e-9):
            return
        if box is not None and not all(np.any(np.abs(sol - c) > box + rc) for c, rc in self.boxes):
            box = None  # cannot happen for distinct certified points; kept for rigour
        if box is not None:
            self.boxes.append((sol, box))
        self.certified.append(box is not None)
        self.found.append(sol)

    def _denominators_nonzero(self, x: np.ndarray) -> bool:
        """Every summary denominator is away from zero at x, relative to the size of its terms."""
        f, fabs, _, _, _ = self.system.polys.evaluate(x)
        return bool(np.all(np.abs(f[1::2]) > 1e-9 * fabs[1::2]))

    def _certify(self, x: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
        """One or two Newton steps with the compensated residual, then the Krawczyk test."""
        for _ in range(2):
            nxt = self.system.newton_step(x)
            if nxt is None:
                break
            x = nxt
            box = self.system.certify(x, self.pos)
            if box is not None:
                return x, box
        return self._verify(x), None

    def _least_squares(self, x: np.ndarray) -> np.ndarray | None:
        """Two Gauss–Newton steps with the compensated residual, then :meth:`_verify`."""
        for _ in range(2):
            res = self.system.residual(x)
            if res is None:
                return None
            JF = self.system.jacobian(x)[0]
            step = np.linalg.lstsq(JF, np.array([float(c) for c in res[0]]), rcond=None)[0]
            if not np.all(np.isfinite(step)):
                return None
            x = x - step
        return self._verify(x)

    def _verify(self, x: np.ndarray) -> np.ndarray | None:
        """x when its compensated residual is below 1e-12 of the terms' size and the Jacobian is well-conditioned."""
        res = self.system.residual(x)
        if res is None:
            return None
        centre, radius, _ = res
        JF, _, _, (_, fabs) = self.system.jacobian(x)
        size = fabs[0::2] * np.abs(self.system.den_star_f) + fabs[1::2] * np.abs(self.system.num_star_f)
        resid = np.array([abs(float(c)) for c in centre]) + radius
        if np.any(resid > 1e-12 * np.maximum(size, 1e-300)):
            return None
        cond = np.linalg.cond(JF / np.maximum(np.abs(JF).max(axis=1, keepdims=True), 1e-300))
        return x if np.isfinite(cond) and cond < 1e12 else None


def _terms(p) -> list:
    """The (exponents, coefficient) pairs of a polynomial, in its own (deterministic) order: unsorted, 20× faster."""
    return list(p.items())


def _curve_candidates(scaled: ScaledSystem, xs: np.ndarray, brackets) -> list[np.ndarray]:
    """Newton's method on the whole system from the sign change of each bracket (linear interpolation)."""
    if not brackets:
        return []
    starts = np.array([ua + (ga / (ga - gb)) * (ub - ua) for _, ua, ub, ga, gb, _ in brackets])
    U, rel = newton(scaled, starts)
    return [xs * scaled.y(u[None, :])[0] for u, r in zip(U, rel, strict=True)
            if r <= 1e-10 and np.abs(u).max() > 1e-6]


def find_witnesses(model, known: Mapping[str, object] | None = None, *, positive: Sequence[bool] | None = None,
                   seed: int = 0, batches: int = 8, batch: int = 48, steps: int = CURVE_STEPS,
                   prepared: tuple | None = None) -> WitnessResult:
    """Search for admissible solutions θ ≠ θ* of summary(θ) = summary(θ*), and certify them.

    The search runs in rounds — the traced curves ``CHUNK`` steps at a time, then
    batches of random starts — and stops when eight witnesses are found or certified
    witnesses move every parameter; each of the two phases also ends after a *quiet*
    round, one that moves no parameter certified witnesses had not moved already (once
    there is one). Every round is a fixed amount of work, never a time: the same model
    and seed give the same witnesses on any machine.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    known : dict, optional
        Fixed parameter values.
    positive : sequence of bool, optional
        Per free parameter, whether only positive values are admissible.
    seed : int
        Seed of θ* (the same as :func:`~symid.structural.global_.global_analysis`) and of the starts.
    batches : int
        Number of batches of random Gauss–Newton starts after the curves.
    batch : int
        Starts per batch (for systems of more than ``GN_TERMS`` terms, ``batches · batch``
        scaled down in proportion, at least 8, and none when the curves found
        certified witnesses).
    steps : int
        Continuation steps per traced curve (0: no curves).
    prepared : tuple, optional
        The result of :func:`~symid.structural.global_.star_and_summary` for the same
        model, ``known`` and ``seed``.

    Returns
    -------
    WitnessResult

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.witness import find_witnesses
    >>> th = si.parameters("th")
    >>> model = si.StateSpaceModel(A=[[-1]], B=[[th]], C=[[th]])  # θ and −θ give the same H
    >>> res = find_witnesses(model, batches=1)
    >>> from fractions import Fraction
    >>> [round(w["th"] / float(Fraction(res.theta_star["th"])), 9) for w in res.witnesses], res.certified
    ([-1.0], (True,))
    """
    t0 = time.perf_counter()
    params, star, _, summ, _ = prepared if prepared is not None else star_and_summary(model, known, seed=seed)
    names = [p.name for p in params]
    theta_star = {n: str(v) for n, v in zip(names, star, strict=True)}
    nv = len(params)
    positive = list(positive) if positive is not None else [False] * nv
    if nv == 0 or len(summ) == 0:
        return WitnessResult(theta_star, (), 0, time.perf_counter() - t0)
    system = SummarySystem([_terms(p) for p in summ.numerators], [_terms(p) for p in summ.denominators], star)
    xs = np.array([float(v) for v in star])
    pos = np.array(positive, dtype=bool)
    square = system.neq == nv
    col = _Collector(system, xs, pos, square)
    n_starts = 0

    def round_(candidates) -> tuple[bool, bool]:
        """Offer a round's candidates: (the search is over, the round was quiet)."""
        before = col.moved()
        for x in candidates:
            col.offer(x)
            if col.full():
                break
        after = col.moved()
        quiet = bool(after.any()) and not bool((after & ~before).any())
        return col.full() or bool(after.all()), quiet

    over = False
    if square and steps > 0:  # real curves through θ*, CHUNK steps at a time, until a quiet round
        scaled = _scaled_system(system, xs, pos)
        tracer = CurveTracer(scaled, np.repeat(np.arange(nv), 2), np.tile([1.0, -1.0], nv), hmax=1.0, tol=1e-4)
        n_starts += 2 * nv
        while tracer.steps_done < steps and tracer.alive.any():
            over, quiet = round_(_curve_candidates(scaled, xs, tracer.advance(min(CHUNK, steps - tracer.steps_done))))
            if over or quiet:
                break
    gn = _scaled_system(system, xs, pos) if not over and batches > 0 else None
    n_terms = len(gn.coef) if gn is not None else 0
    # Gauss–Newton from random starts (positive parameters in logarithmic scale), batch by batch until a quiet one;
    # for a system of more than GN_TERMS terms the starts shrink in proportion, and none after certified witnesses
    # from the curves
    total = (batches * batch if n_terms <= GN_TERMS else
             0 if any(col.certified) else max(8, batches * batch * GN_TERMS // n_terms))
    if gn is not None and total > 0:
        size = min(batch, total)
        rng = np.random.default_rng(random.Random(seed).randrange(2**32))
        for _ in range(-(-total // size)):
            z = rng.normal(0.0, 1.5, (size, nv))
            sign = np.where(pos, 1.0, rng.choice([-1.0, 1.0], (size, nv)))
            U, rel = _gauss_newton(gn, np.where(pos, z, np.exp(z) * sign - 1.0), 40)
            n_starts += size
            over, quiet = round_([xs * gn.y(u[None, :])[0] for u, r in zip(U, rel, strict=True)
                                  if np.isfinite(r) and r <= 1e-9])
            if over or quiet:
                break
    witnesses = tuple({n: float(v) for n, v in zip(names, sol, strict=True)} for sol in col.found)
    return WitnessResult(theta_star, witnesses, n_starts, time.perf_counter() - t0, tuple(col.certified), square)
