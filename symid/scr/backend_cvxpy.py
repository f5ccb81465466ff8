"""cvxpy + Clarabel back end: the SDP (2-9) of every SCR sub-problem, compiled once.

M_t(z) = m0_t + G_t z[idx_t] (2-6) depends on Q, R only through the numbers m0_t and
G_t, which are cvxpy ``Parameter``s (per group of equal-shape terms: one vector for m0
and one per local variable slot u, multiplied elementwise with a constant selection of
z). Parameter × variable is DPP, and no product of two parameters appears (scr-lessons
10), so cvxpy compiles the problem once per ``solve`` and every SCR iteration only
refreshes the parameter values and re-solves.
"""

from __future__ import annotations

import time

import cvxpy as cp
import numpy as np
import scipy.sparse as sps

from symid.scr.blocks import LMIGroup, TermGroup
from symid.scr.presolve import Reduced

__all__ = ["CvxpyBackend"]


def _selection(idx: np.ndarray, pq: int, u: int, nz: int) -> sps.csr_matrix:
    """Rows t*pq + r pick z[idx[t, u]] (zero rows at padding)."""
    s = idx.shape[0]
    col = np.repeat(idx[:, u], pq)
    row = np.arange(s * pq)
    m = col >= 0
    return sps.csr_matrix((np.ones(int(m.sum())), (row[m], col[m])), shape=(s * pq, nz))


class CvxpyBackend:
    """Solve the SCR sub-problems as SDPs with cvxpy and Clarabel."""

    name = "cvxpy"

    def __init__(self, red: Reduced, groups: list[TermGroup], lmis: list[LMIGroup], solver: str = "CLARABEL",
                 solver_options: dict | None = None):
        self.red, self.groups = red, groups
        self.solver = solver
        self.solver_options = dict(solver_options or {})
        nz = red.nz
        z = cp.Variable(nz, name="z")
        self.z = z
        nucs: list[cp.Expression] = []
        self.m0p: list[cp.Parameter] = []
        self.Gp: list[list[cp.Parameter]] = []
        t0 = time.perf_counter()
        for g in groups:
            p, q = g.pq
            pq = p * q
            m0 = cp.Parameter(g.s * pq, name=f"m0_{len(self.m0p)}")
            vec = m0
            gps = []
            for u in range(g.idx.shape[1]):
                Gu = cp.Parameter(g.s * pq, name=f"G_{len(self.m0p)}_{u}")
                gps.append(Gu)
                vec = vec + cp.multiply(Gu, _selection(g.idx, pq, u, nz) @ z)
            self.m0p.append(m0)
            self.Gp.append(gps)
            for t in range(g.s):
                Mt = cp.reshape(vec[t * pq:(t + 1) * pq], (p, q), order="C")
                nucs.append(float(g.weight[t]) * cp.normNuc(Mt))
        obj = cp.sum(cp.hstack(nucs)) if nucs else 0
        self.glin = cp.Parameter(nz, name="glin")
        self.glin.value = np.zeros(nz)
        obj = obj + self.glin @ z
        if red.H.nnz:
            obj = obj + cp.quad_form(z, cp.psd_wrap(red.H))
        if np.any(red.g):
            obj = obj + red.g @ z
        cons = []
        if red.D.shape[0]:
            cons.append(red.D @ z == red.d)
        for g in lmis:
            s, e, _, u = g.Ec.shape
            L = sps.csr_matrix((e * e * s, nz))
            for uu in range(u):
                L = L + sps.diags(g.Ec[:, :, :, uu].reshape(-1)) @ _selection(g.idx, e * e, uu, nz)
            vecE = g.E0.reshape(-1) + L @ z
            for t in range(s):
                Et = cp.reshape(vecE[t * e * e:(t + 1) * e * e], (e, e), order="C")
                cons.append(0.5 * (Et + Et.T) >> 0)
        self.problem = cp.Problem(cp.Minimize(obj), cons)
        self.build_time = time.perf_counter() - t0
        self.compilations = 0
        self._prog = None

    def on_stall(self) -> None:
        """Nothing to adapt: the interior-point solve is exact."""

    def step(self, Q: list[np.ndarray], R: list[np.ndarray], W: list[np.ndarray] | None,
             z0: np.ndarray) -> tuple[np.ndarray, bool, str, dict]:
        tm = {"build": 0.0, "solve": 0.0}
        t = time.perf_counter()
        glin = np.zeros(self.red.nz)
        for k, g in enumerate(self.groups):
            m0, G = g.build(Q[k], R[k])
            self.m0p[k].value = m0.reshape(-1)
            for u, Gu in enumerate(self.Gp[k]):
                Gu.value = G[:, :, u].reshape(-1)
            if W is not None:
                gl = np.einsum("spu,sp->su", G, (g.weight[:, None, None] * W[k]).reshape(g.s, -1))
                m = g.idx >= 0
                glin -= np.bincount(g.idx[m], weights=gl[m], minlength=self.red.nz)
        self.glin.value = glin
        tm["build"] = time.perf_counter() - t
        t = time.perf_counter()
        try:
            self.problem.solve(solver=self.solver, **self.solver_options)
        except cp.error.SolverError as exc:
            tm["solve"] = time.perf_counter() - t
            return z0, False, f"cvxpy/{self.solver} failed: {exc}", tm
        tm["solve"] = time.perf_counter() - t
        cache = getattr(self.problem, "_cache", None)
        prog = getattr(cache, "param_prog", None)
        if prog is not self._prog:
            self.compilations += 1
            self._prog = prog
        st = self.problem.status
        tm["compilation"] = float(self.problem.compilation_time or 0.0)
        if st not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or self.z.value is None:
            return z0, False, f"cvxpy/{self.solver} returned status {st!r}", tm
        msg = "" if st == cp.OPTIMAL else f"cvxpy/{self.solver}: {st}"
        return np.asarray(self.z.value, dtype=float).copy(), True, msg, tm
