"""ADMM back end (Algorithm 2.2 extended with LMIs), pure numpy/scipy, vectorised over blocks.

One SCR sub-problem, for fixed Q, R, is

    min_z  f(z) + Σ_t w_t (||Y_t||_* − <W_t, Y_t>)
    s.t.   Y_t = M_t(z),  S_e = E_e(z),  S_e ⪰ 0,  D z = d

(W_t = 0 for the plain nuclear norm). Scaled-form ADMM with one shared ρ:

* z-update: the equality-constrained least squares of appendix B, solved from one
  factorisation of the KKT matrix [[2H + ρ(GᵀG + LᵀL) + δI, Dᵀ], [D, 0]] per SCR
  iteration (δ is a tiny proximal term keeping it nonsingular);
* Y-update: singular value thresholding (2-12), batched with one ``np.linalg.svd`` call
  per group of equal-shape blocks;
* S-update: projection onto the PSD cone by eigenvalue clipping, batched likewise, so
  LMI problems need no interior-point solver;
* stop on the primal and dual residuals (Boyd et al. 2011, §3.3.1).

The state (z, Y, S and the scaled duals) is kept between SCR iterations (warm start);
the inner-iteration budget is raised by the SCR loop when the residual stalls
(scr-lessons 8).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from symid.scr.blocks import LMIGroup, TermGroup
from symid.scr.presolve import Reduced

__all__ = ["ADMMBackend", "ADMMOptions"]


@dataclass(frozen=True)
class ADMMOptions:
    """Options of the ADMM back end.

    Attributes
    ----------
    rho : float or None
        Penalty ρ shared by all blocks; ``None`` uses 2 × the median term weight.
    inner : int
        Initial cap on ADMM iterations per SCR iteration (raised ×2 on stalls).
    inner_first : int
        Cap for the first (cold-started) sub-problem.
    inner_max : int
        Largest cap.
    eps_abs, eps_rel : float
        Absolute and relative tolerances on the primal and dual residuals.
    """

    rho: float | None = None
    inner: int = 50
    inner_first: int = 2000
    inner_max: int = 1000
    eps_abs: float = 1e-7
    eps_rel: float = 1e-6


class _KKT:
    """Factorisation of the KKT matrix; dense LU when small, SuperLU otherwise."""

    def __init__(self, N: sps.spmatrix, D: sps.spmatrix):
        nz, m = N.shape[0], D.shape[0]
        self.nz = nz
        K = sps.bmat([[N, D.T], [D, None]], format="csc") if m else sps.csc_matrix(N)
        if K.shape[0] <= 400:
            self.lu = sla.lu_factor(K.toarray(), check_finite=False)
            self.sparse = None
        else:
            self.lu = None
            self.sparse = spla.splu(K)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if self.lu is not None:
            return sla.lu_solve(self.lu, rhs, check_finite=False)
        return self.sparse.solve(rhs)


def _scatter(idx: np.ndarray, vals: np.ndarray, n: int) -> np.ndarray:
    """Sum vals (s, u) into a length-n vector at idx (s, u); padding (-1) is dropped."""
    m = idx >= 0
    return np.bincount(idx[m], weights=vals[m], minlength=n)


def _svt(X: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Singular value thresholding (2-12) of a stack X (s, p, q) with thresholds tau (s,).

    Uses the eigen-decomposition of the smaller Gram matrix (one batched ``eigh``, about
    twice as fast as a batched SVD for the small blocks SCR produces):
    Y = X V diag(max(1 − τ/σ, 0)) Vᵀ.
    """
    transpose = X.shape[1] < X.shape[2]
    Xt = X.transpose(0, 2, 1) if transpose else X
    lam, V = np.linalg.eigh(Xt.transpose(0, 2, 1) @ Xt)
    sig = np.sqrt(np.maximum(lam, 0.0))
    f = np.where(sig > tau[:, None], 1.0 - tau[:, None] / np.where(sig > 0, sig, 1.0), 0.0)
    Y = (Xt @ (V * f[:, None, :])) @ V.transpose(0, 2, 1)
    return Y.transpose(0, 2, 1) if transpose else Y


def _psd(X: np.ndarray) -> np.ndarray:
    ev, V = np.linalg.eigh(0.5 * (X + X.transpose(0, 2, 1)))
    return (V * np.maximum(ev, 0.0)[:, None, :]) @ V.transpose(0, 2, 1)


class ADMMBackend:
    """Solve the SCR sub-problems by ADMM; see the module docstring."""

    name = "admm"

    def __init__(self, red: Reduced, groups: list[TermGroup], lmis: list[LMIGroup], options: ADMMOptions):
        self.red, self.groups, self.lgroups, self.opt = red, groups, lmis, options
        ws = np.concatenate([g.weight for g in groups]) if groups else np.ones(1)
        self.rho = float(options.rho) if options.rho is not None else 2.0 * float(np.median(ws))
        self.inner = int(options.inner)
        self.z: np.ndarray | None = None
        self.U = [np.zeros((g.s, *g.pq)) for g in groups]
        self.S = [g.E0.copy() for g in lmis]
        self.V = [np.zeros_like(g.E0) for g in lmis]
        self.iterations: list[int] = []
        self.hit_cap = False
        self.LG = [g.G() for g in lmis]
        nz = red.nz
        rho = self.rho
        NL = sps.csr_matrix((nz, nz))
        for g, L in zip(lmis, self.LG, strict=True):
            NL = NL + self._normal(g.idx, L, nz)
        self.N_fixed = 2 * red.H + rho * NL

    @staticmethod
    def _normal(idx: np.ndarray, G: np.ndarray, nz: int) -> sps.csr_matrix:
        loc = np.einsum("spu,spv->suv", G, G)
        ii = np.broadcast_to(idx[:, :, None], loc.shape)
        jj = np.broadcast_to(idx[:, None, :], loc.shape)
        m = (ii >= 0) & (jj >= 0)
        return sps.csr_matrix((loc[m], (ii[m], jj[m])), shape=(nz, nz))

    def on_stall(self) -> None:
        """Double the inner-iteration cap if the last sub-problem hit it (scr-lessons 8)."""
        if self.hit_cap:
            self.inner = min(2 * self.inner, self.opt.inner_max)

    def step(self, Q: list[np.ndarray], R: list[np.ndarray], W: list[np.ndarray] | None,
             z0: np.ndarray) -> tuple[np.ndarray, bool, str, dict]:
        red, rho, opt = self.red, self.rho, self.opt
        nz = red.nz
        tm = {"build": 0.0, "factor": 0.0, "solve": 0.0, "svd": 0.0, "projection": 0.0}
        t = time.perf_counter()
        built = [g.build(q, r) for g, q, r in zip(self.groups, Q, R, strict=True)]
        m0s = [b[0] for b in built]
        Gs = [b[1] for b in built]
        N = self.N_fixed
        for g, G in zip(self.groups, Gs, strict=True):
            N = N + rho * self._normal(g.idx, G, nz)
        N = sps.csr_matrix(N)
        diag = N.diagonal()
        delta = 1e-10 * max(1.0, float(diag.max(initial=0.0)))
        N = N + delta * sps.identity(nz, format="csr")
        tm["build"] += time.perf_counter() - t
        t = time.perf_counter()
        try:
            kkt = _KKT(N, red.D)
        except (RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
            return z0, False, f"ADMM: the KKT matrix could not be factorised ({exc})", tm
        tm["factor"] += time.perf_counter() - t
        z = (self.z if self.z is not None else z0).copy()
        taus = [g.weight / rho for g in self.groups]
        shifts = [None if W is None else (g.weight / rho)[:, None, None] * w
                  for g, w in zip(self.groups, W or [None] * len(self.groups), strict=True)]

        def Mz(k: int, zz: np.ndarray) -> np.ndarray:
            g = self.groups[k]
            return m0s[k] + np.einsum("spu,su->sp", Gs[k], g.gather(zz)).reshape(m0s[k].shape)

        Y = [Mz(k, z) for k in range(len(self.groups))]
        U, S, V = self.U, self.S, self.V
        neq = red.D.shape[0]
        rhs = np.zeros(nz + neq)
        rhs[nz:] = red.d
        m_tot = sum(y.size for y in Y) + sum(s_.size for s_ in S)
        ok = False
        it = 0
        rp = rd = np.inf
        cap = self.inner if self.z is not None else max(self.inner, self.opt.inner_first)
        for it in range(1, cap + 1):  # noqa: B007
            t = time.perf_counter()
            b = -red.g + delta * z
            for k, g in enumerate(self.groups):
                b += rho * _scatter(g.idx, np.einsum("spu,sp->su", Gs[k], (Y[k] - U[k] - m0s[k]).reshape(g.s, -1)), nz)
            for k, g in enumerate(self.lgroups):
                b += rho * _scatter(g.idx, np.einsum("spu,sp->su", self.LG[k], (S[k] - V[k] - g.E0).reshape(g.s, -1)),
                                    nz)
            rhs[:nz] = b
            z = kkt.solve(rhs)[:nz]
            tm["solve"] += time.perf_counter() - t
            t = time.perf_counter()
            rp2 = 0.0
            dual = np.zeros(nz)
            nm = ny = nu = 0.0
            for k, g in enumerate(self.groups):
                M = Mz(k, z)
                X = M + U[k] if shifts[k] is None else M + U[k] + shifts[k]
                Ynew = _svt(X, taus[k])
                dual += _scatter(g.idx, np.einsum("spu,sp->su", Gs[k], (Ynew - Y[k]).reshape(g.s, -1)), nz)
                Y[k] = Ynew
                U[k] += M - Ynew
                rp2 += float(np.sum((M - Ynew) ** 2))
                nm += float(np.sum(M**2))
                ny += float(np.sum(Ynew**2))
                nu += float(np.sum(U[k] ** 2))
            tm["svd"] += time.perf_counter() - t
            t = time.perf_counter()
            for k, g in enumerate(self.lgroups):
                E = g.E(z)
                Snew = _psd(E + V[k])
                dual += _scatter(g.idx, np.einsum("spu,sp->su", self.LG[k], (Snew - S[k]).reshape(g.s, -1)), nz)
                S[k] = Snew
                V[k] += E - Snew
                rp2 += float(np.sum((E - Snew) ** 2))
                nm += float(np.sum(E**2))
                ny += float(np.sum(Snew**2))
                nu += float(np.sum(V[k] ** 2))
            tm["projection"] += time.perf_counter() - t
            rp = np.sqrt(rp2)
            rd = rho * float(np.linalg.norm(dual))
            eps_p = np.sqrt(m_tot) * opt.eps_abs + opt.eps_rel * np.sqrt(max(nm, ny))
            eps_d = np.sqrt(nz) * opt.eps_abs + opt.eps_rel * rho * np.sqrt(nu)
            if rp <= eps_p and rd <= eps_d:
                ok = True
                break
        self.z = z
        self.hit_cap = not ok
        self.iterations.append(it)
        tm["inner_iterations"] = it
        tm["primal_residual"] = float(rp)
        tm["dual_residual"] = float(rd)
        if not np.all(np.isfinite(z)):
            return z0, False, "ADMM diverged (non-finite iterate)", tm
        msg = "" if ok else f"ADMM stopped at its cap of {cap} inner iterations (primal {rp:.2e}, dual {rd:.2e})"
        return z, True, msg, tm
