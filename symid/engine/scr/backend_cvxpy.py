"""cvxpy + Clarabel back end: the SDP (2-9) of every SCR sub-problem, compiled once.

M_t(z) = m0_t + G_t z[idx_t] (2-6) depends on Q, R only through the numbers m0_t and
G_t, which are cvxpy ``Parameter``s, one pair per block, multiplying the block's own
entries of z. Parameter × variable is DPP, and no product of two parameters appears
(such a product is not DPP and would force a new compilation), so cvxpy compiles the
problem once per ``solve`` and every SCR iteration only refreshes the parameter values
and re-solves. Per-block parameters keep
the compiled parameter tensor linear in the number of blocks (slicing one long
parameter vector per block made compilation quadratic).
"""

from __future__ import annotations

import time
import warnings

import cvxpy as cp
import numpy as np

from symid.engine.scr.blocks import LMIGroup, TermGroup
from symid.engine.scr.clarabel_solver import INTERRUPTIBLE_CLARABEL
from symid.engine.scr.presolve import Reduced
from symid.errors import ModelError
from symid.interrupt import native_interrupts

__all__ = ["CvxpyBackend"]


def _local(z: cp.Variable, idx: np.ndarray) -> tuple[cp.Expression | None, int]:
    """The entries z[idx] of one block (padding −1 dropped) and how many there are."""
    live = idx[idx >= 0]
    return (z[live] if live.size else None), int(live.size)


class CvxpyBackend:
    """Solve the SCR sub-problems as SDPs with cvxpy and Clarabel."""

    name = "cvxpy"

    def __init__(self, red: Reduced, groups: list[TermGroup], lmis: list[LMIGroup], solver: str = "CLARABEL",
                 solver_options: dict | None = None):
        """Build the parametrised SDP; cvxpy compiles it at the first :meth:`step`.

        Every step solves with ``warm_start=False`` unless ``solver_options`` says
        otherwise: cvxpy's default would update the previous Clarabel solver in place,
        and the iterates would then depend (in the last digits) on what was solved before.
        """
        self.red, self.groups = red, groups
        self.solver = solver
        self.solver_options = dict(solver_options or {})
        nz = red.nz
        z = cp.Variable(nz, name="z")
        self.z = z
        nucs: list[cp.Expression] = []
        self.m0p: list[list[cp.Parameter]] = []
        self.Gp: list[list[tuple[cp.Parameter, int] | None]] = []
        t0 = time.perf_counter()
        for g in groups:
            p, q = g.pq
            m0s, gps = [], []
            for t in range(g.s):
                m0 = cp.Parameter((p, q), name=f"m0_{len(self.m0p)}_{t}")
                zt, u = _local(z, g.idx[t])
                Mt: cp.Expression = m0
                if u:
                    Gt = cp.Parameter((p * q, u), name=f"G_{len(self.m0p)}_{t}")
                    Mt = m0 + cp.reshape(Gt @ zt, (p, q), order="C")
                    gps.append((Gt, u))
                else:
                    gps.append(None)
                m0s.append(m0)
                nucs.append(float(g.weight[t]) * cp.normNuc(Mt))
            self.m0p.append(m0s)
            self.Gp.append(gps)
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
            s, e, _, _ = g.Ec.shape
            for t in range(s):
                zt, u = _local(z, g.idx[t])
                Et: cp.Expression = cp.Constant(g.E0[t])
                if u:
                    Et = Et + cp.reshape(g.Ec[t].reshape(e * e, -1)[:, :u] @ zt, (e, e), order="C")
                cons.append(0.5 * (Et + Et.T) >> 0)
        self.problem = cp.Problem(cp.Minimize(obj), cons)
        self.build_time = time.perf_counter() - t0
        self.compilations = 0
        self.compile_time = 0.0

    def on_stall(self) -> None:
        """Nothing to adapt: the interior-point solve is exact."""

    def step(self, built: list[tuple[np.ndarray, np.ndarray]], W: list[np.ndarray] | None,
             z0: np.ndarray, residual: float = np.inf, deadline: float | None = None
             ) -> tuple[np.ndarray, bool, str, dict]:
        """One SCR sub-problem for the blocks M = m0 + G z of ``built``; returns (z, ok, message, timing).

        ``residual`` (the last bilinear residual) is not needed: the interior-point solve is exact.
        ``deadline`` (a ``time.perf_counter()`` value): Clarabel gets the time left as its
        ``time_limit``; a solve it cuts short is discarded (``ok`` false, ``timing["time_limit"]`` true).
        """
        tm = {"build": 0.0, "solve": 0.0}
        t = time.perf_counter()
        glin = np.zeros(self.red.nz)
        for k, g in enumerate(self.groups):
            m0, G = built[k]
            for t_, (mp, gp) in enumerate(zip(self.m0p[k], self.Gp[k], strict=True)):
                mp.value = m0[t_]
                if gp is not None:
                    gp[0].value = G[t_, :, : gp[1]]
            if W is not None:
                gl = np.einsum("spu,sp->su", G, (g.weight[:, None, None] * W[k]).reshape(g.s, -1))
                m = g.idx >= 0
                glin -= np.bincount(g.idx[m], weights=gl[m], minlength=self.red.nz)
        self.glin.value = glin
        tm["build"] = time.perf_counter() - t
        cache = getattr(self.problem, "_cache", None)
        prog_before = getattr(cache, "param_prog", None)
        t = time.perf_counter()
        solver = self.solver
        if solver == "CLARABEL" and INTERRUPTIBLE_CLARABEL is not None:
            solver = INTERRUPTIBLE_CLARABEL  # the same solve, stopped by Ctrl-C within an iteration
        opts = {"warm_start": False, **self.solver_options}
        if deadline is not None:
            left = deadline - time.perf_counter()
            if left <= 0:
                tm["time_limit"] = True
                return z0, False, "the time limit was spent before the sub-problem started", tm
            if self.solver == "CLARABEL":
                opts["time_limit"] = min(float(opts.get("time_limit", np.inf)), left)
        try:
            with warnings.catch_warnings(), native_interrupts(raise_now=False):
                # an inaccurate solve is reported through the status below
                warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
                self.problem.solve(solver=solver, **opts)
        except cp.error.SolverError as exc:
            tm["solve"] = time.perf_counter() - t
            return z0, False, f"cvxpy/{self.solver} failed: {exc}", tm
        except (TypeError, ValueError) as exc:
            if not self.solver_options:
                raise
            raise ModelError(f"solver_options {self.solver_options} were refused by {self.solver}: {exc}") from None
        tm["solve"] = time.perf_counter() - t
        # a solve compiles unless it reused the cached parametrised program (DPP fast path)
        prog_after = getattr(getattr(self.problem, "_cache", None), "param_prog", None)
        compiled = prog_before is None or prog_after is not prog_before
        tm["compilation"] = float(self.problem.compilation_time or 0.0)
        if compiled:
            self.compilations += 1
            self.compile_time += tm["compilation"]
        st = self.problem.status
        if st not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or self.z.value is None:
            if deadline is not None and time.perf_counter() >= deadline:
                tm["time_limit"] = True
                return z0, False, f"cvxpy/{self.solver} stopped by the time limit (status {st!r})", tm
            return z0, False, f"cvxpy/{self.solver} returned status {st!r}", tm
        msg = "" if st == cp.OPTIMAL else f"cvxpy/{self.solver}: {st}"
        return np.asarray(self.z.value, dtype=float).copy(), True, msg, tm
