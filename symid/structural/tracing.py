"""Real solutions of a square polynomial system near a known one, by tracing curves of its subsystems.

Let ``G(u) = 0`` be n equations in n unknowns with a known simple real root u = 0 (the
point θ* of the witness search, in the coordinates below). Dropping equation i leaves
n − 1 equations whose real solutions near 0 form a smooth curve through 0 (the
Jacobian has full rank there). Along that curve the dropped equation ``G_i`` is a
smooth function; wherever it changes sign the curve meets another real root of the
whole system. :func:`trace_curves` follows the curve of every dropped equation, in both
directions from 0, by pseudo-arclength continuation (Euler predictor along the
tangent, Newton corrector on the hyperplane orthogonal to it, step-size control:
Allgower and Georg, *Introduction to Numerical Continuation Methods*, SIAM 2003, ch. 2
and 6), all curves at once in numpy, and returns the brackets where ``G_i`` changes
sign; :func:`newton` polishes them into roots of the whole system.

This finds the real roots that share a real curve with the known one — exactly the
kind a witness against global identifiability must be (real, and positive where
declared: the positive coordinates are traced in logarithmic scale, so a curve never
leaves the positive orthant) — without tracking the complex roots a homotopy from a
start system or a monodromy loop would (Duff et al., *IMA J. Numer. Anal.* 39, 2019:
the 12-parameter mass chain with the force and the sensor at opposite ends has 204
complex roots, of which 2 admissible; complex parameter homotopies from random fibres
found 2 admissible among 69 distinct roots in 1000 paths). Every budget is a fixed
number of steps, never a time: the same system gives the same brackets on any machine.

Coordinates: ``x_v = x*_v e^{u_v}`` for a positive coordinate, ``x*_v (1 + u_v)``
otherwise, x* the known root (θ*).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["CurveTracer", "ScaledSystem", "newton"]


class ScaledSystem:
    """Polynomial equations in the coordinates u (see the module notes), for vectorised double evaluation.

    Parameters
    ----------
    E : numpy.ndarray of int, shape (T, n)
        Exponents of all terms, the equations' terms contiguous.
    coef : numpy.ndarray, shape (T,)
        Coefficients of the terms in the scaled variables ``y = x / x*`` (that is,
        ``c_t Π x*^E_t``), any common factor per equation.
    starts : numpy.ndarray of int
        Offsets of the equations' terms in ``E`` (length n_equations + 1).
    log_scale : sequence of bool
        Per coordinate, whether it is traced in logarithmic scale (positive coordinates).
    """

    def __init__(self, E: np.ndarray, coef: np.ndarray, starts: np.ndarray, log_scale: Sequence[bool]):
        self.nv = E.shape[1]
        self.neq = len(starts) - 1
        self.starts = np.asarray(starts, dtype=np.int64)
        seg = [(int(a), int(b)) for a, b in zip(self.starts[:-1], self.starts[1:], strict=True)]
        scale = np.array([np.abs(coef[a:b]).sum() or 1.0 for a, b in seg])  # Σ|terms| = 1 at u = 0
        self.coef = coef / np.repeat(scale, np.diff(self.starts))
        if np.any(np.diff(self.starts) == 0):
            raise ValueError("every equation needs a term")
        self.E = np.ascontiguousarray(E, dtype=float)
        self.seg = seg
        self.log = np.asarray(log_scale, dtype=bool)
        self._reduce = self.starts[:-1]
        with np.errstate(divide="ignore"):
            self._logc = np.log(np.abs(self.coef))
        self._sign = np.sign(self.coef)

    def y(self, U: np.ndarray) -> np.ndarray:
        """Scaled coordinates y = x / x* of the rows of U."""
        return np.where(self.log, np.exp(np.minimum(U, 700.0)), 1.0 + U)

    def eval(self, U: np.ndarray, jacobian: bool = True, absolute: bool = True):
        """Values G (S, n_eq), Σ|terms| A (S, n_eq) and the Jacobian J (S, n_eq, n) ∂G/∂u at the rows of U.

        ``A`` (``absolute=False``) and ``J`` (``jacobian=False``) are None when not asked for. Terms along
        the rows: the monomials are ``exp(E log|y|ᵀ + log|c|)`` (T × S), several times faster than the
        other way round for T ≫ S (a tall product instead of a wide one).
        """
        Y = self.y(U)
        with np.errstate(all="ignore"):
            Y = np.where(Y == 0.0, 1e-300, Y)
            L = np.where(self.log, U, np.log(np.abs(Y)))
            cm = self.E @ L.T  # (T, S)
            cm += self._logc[:, None]
            np.exp(cm, out=cm)
            cm *= self._sign[:, None]
            neg = (~self.log) & (Y < 0)
            if neg.any():
                cm *= 1.0 - 2.0 * np.mod(self.E @ neg.T.astype(float), 2.0)
            G = np.add.reduceat(cm, self._reduce, axis=0).T
            A = np.add.reduceat(np.abs(cm), self._reduce, axis=0).T if absolute else None
            if not jacobian:
                return G, A, None
            J = np.empty((len(U), self.neq, self.nv))
            for i, (a, b) in enumerate(self.seg):
                J[:, i, :] = cm[a:b].T @ self.E[a:b]
            lin = ~self.log
            if lin.any():
                J[:, :, lin] /= Y[:, None, lin]
        return G, A, J


def _solve(M: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Batched solve; rows whose matrix is singular give NaN."""
    with np.errstate(all="ignore"):
        try:
            return np.linalg.solve(M, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:
            out = np.full(rhs.shape, np.nan)
            for k in range(len(M)):
                try:
                    out[k] = np.linalg.solve(M[k], rhs[k])
                except np.linalg.LinAlgError:
                    pass
            return out


class CurveTracer:
    """Follow the curves {G_j = 0, j ≠ drops[k]} from u = 0 in direction signs[k], recording sign changes of G_drop.

    Parameters
    ----------
    system : ScaledSystem
        Square, with the root u = 0 and a nonsingular Jacobian there.
    drops : array of int
        Per curve, the equation left out.
    signs : array of ±1
        Per curve, the direction of the tangent at 0 (the tangent is the null vector of
        the remaining rows, oriented so its largest entry has this sign).
    h0, hmax : float
        First and largest step (arclength in u).
    bound : float
        A curve stops when a coordinate leaves [−bound, bound] (a factor e^bound from θ*
        in logarithmic scale).
    tol : float
        Newton corrector tolerance on the step in u.
    """

    def __init__(self, system: ScaledSystem, drops: np.ndarray, signs: np.ndarray, *, h0: float = 0.05,
                 hmax: float = 0.5, bound: float = 10.0, tol: float = 1e-7):
        self.system, self.drops = system, np.asarray(drops, dtype=np.int64)
        self.hmax, self.bound, self.tol = hmax, bound, tol
        S, nv = len(self.drops), system.nv
        _, _, J0 = system.eval(np.zeros((1, nv)))
        self.T = np.empty((S, nv))
        for k, i in enumerate(self.drops):
            _, _, Vt = np.linalg.svd(np.delete(J0[0], i, axis=0))
            t = Vt[-1]
            self.T[k] = t * np.sign(t[np.argmax(np.abs(t))]) * signs[k]
        self.U = np.zeros((S, nv))
        self.J = np.repeat(J0, S, axis=0)
        self.h = np.full(S, h0)
        self.h_last = np.full(S, np.inf)  # length of the last accepted step (∞: none yet, no curvature estimate)
        self.g_prev = np.zeros(S)
        self.started = np.zeros(S, dtype=bool)  # the previous point is not θ* itself (where G_drop = 0 exactly)
        self.alive = np.ones(S, dtype=bool)
        self.steps_done = 0
        self.points = 0
        """Points evaluated so far (a measure of the work)."""
        self.accepted = self.rejected = 0

    def advance(self, steps: int) -> list[tuple[int, np.ndarray, np.ndarray, float, float, int]]:
        """``steps`` more continuation steps of every live curve (accepted or not).

        Returns
        -------
        list of (curve, u_a, u_b, g_a, g_b, step)
            Consecutive points of a curve between which ``G_drop`` changes sign, its values
            there, and the step.
        """
        system, tol, nv = self.system, self.tol, self.system.nv
        brackets = []
        for _ in range(steps):
            act = np.flatnonzero(self.alive)
            if len(act) == 0:
                break
            step = self.steps_done
            self.steps_done += 1
            n = len(act)
            r = np.arange(n)
            dr = self.drops[act]
            M = self.J[act].copy()
            M[r, dr, :] = self.T[act]
            rhs = np.zeros((n, nv))
            rhs[r, dr] = 1.0
            tau = _solve(M, rhs)
            tau /= np.linalg.norm(tau, axis=1, keepdims=True)
            tau *= np.where((tau * self.T[act]).sum(axis=1) < 0, -1.0, 1.0)[:, None]
            hh = self.h[act]
            # second-order predictor: the curvature from the change of the tangent over the last step
            kappa = (tau - self.T[act]) / self.h_last[act][:, None]
            up = self.U[act] + hh[:, None] * tau + (0.5 * hh * hh)[:, None] * kappa
            uc = up.copy()
            failed = ~np.all(np.isfinite(uc), axis=1)
            prev = np.full(n, np.inf)
            G = np.zeros((n, system.neq))
            Jc = np.zeros((n, system.neq, nv))
            pend = np.flatnonzero(~failed)
            for k in range(4):  # Newton on the hyperplane through the predicted point, orthogonal to the tangent
                if len(pend) == 0:
                    break
                g, _, j = system.eval(uc[pend], absolute=False)
                self.points += len(pend)
                G[pend], Jc[pend] = g, j
                rp = np.arange(len(pend))
                Mc = j.copy()
                Mc[rp, dr[pend], :] = tau[pend]
                res = g.copy()
                res[rp, dr[pend]] = ((uc[pend] - up[pend]) * tau[pend]).sum(axis=1)
                du = -_solve(Mc, res)
                size = np.linalg.norm(du, axis=1)
                ok = np.isfinite(size) & ((size < 0.25 * hh[pend] + tol) if k == 0
                                          else ((size < 0.5 * prev[pend]) | (size < tol)))
                failed[pend[~ok]] = True
                uc[pend[ok]] += du[ok]
                prev[pend] = size
                pend = pend[ok & (size >= tol)]
            good = ~failed & (prev < tol)
            acc, rej = act[good], act[~good]
            self.accepted += len(acc)
            self.rejected += len(rej)
            if len(acc):
                dg = dr[good]
                g = G[good, dg]
                change = self.started[acc] & (np.sign(g) != np.sign(self.g_prev[acc])) & (g != 0)
                ucg = uc[good]
                for jj in np.flatnonzero(change):
                    c = acc[jj]
                    brackets.append((int(c), self.U[c].copy(), ucg[jj].copy(), float(self.g_prev[c]), float(g[jj]),
                                     step))
                self.U[acc] = ucg
                self.J[acc] = Jc[good]
                self.T[acc] = tau[good]
                self.h_last[acc] = hh[good]
                self.g_prev[acc] = g
                self.started[acc] = True
                self.h[acc] = np.minimum(self.h[acc] * 1.5, self.hmax)
                self.alive[acc[np.abs(self.U[acc]).max(axis=1) > self.bound]] = False
            self.h[rej] *= 0.5
            self.alive[rej[self.h[rej] < 1e-6]] = False
        return brackets


def newton(system: ScaledSystem, U: np.ndarray, iterations: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Newton's method on the square system from every row of U; the points and max_i |G_i| / Σ|terms of G_i|."""
    U = U.copy()
    alive = np.all(np.isfinite(U), axis=1)
    for _ in range(iterations):
        if not alive.any():
            break
        G, _, J = system.eval(U[alive], absolute=False)
        du = _solve(J, -G)
        ok = np.all(np.isfinite(du), axis=1)
        idx = np.flatnonzero(alive)
        alive[idx[~ok]] = False
        U[idx[ok]] += np.clip(du[ok], -2.0, 2.0)
    U[~alive] = np.nan
    G, A, _ = system.eval(np.nan_to_num(U))
    with np.errstate(all="ignore"):
        rel = np.abs(G / np.maximum(A, 1e-300)).max(axis=1)
    rel[~alive] = np.inf
    return U, rel
