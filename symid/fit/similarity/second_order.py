"""Second-order models from a black box by a similarity transform: thesis §7-5, Algorithm 7.1.

The model M(θ) q'' + V(θ) q' + K(θ) q = F u, y = H q (or H q') has the first-order form
(7-2) x = [q; q'], A = [[0, I], [−M⁻¹K, −M⁻¹V]], B = [0; M⁻¹F], C = [H, 0] (or [0, H]).
A black box (𝔸, 𝔹, ℂ) of order 2n is similar to it: T𝔸 = AT, T𝔹 = B, ℂ = CT (7-5).

Linear special cases (§7-5-2), chosen automatically:

* **full set of sensors** — H known with full column rank (p ≥ n; the thesis: H
  invertible): position output gives T_top = H⁺ℂ (7-12g, h) and T_bot = T_top 𝔸
  (7-12a, b); velocity output T_bot = H⁺ℂ and T_top = T_bot 𝔸⁻¹. With T known, the
  bottom block rows of T𝔸 = AT and T𝔹 = B multiplied by M are linear in M, V, K, F:

      M T_bot 𝔸 + V T_bot + K T_top = 0,   M T_bot 𝔹 = F           (7-12c, d, f)

  one linear least squares in θ (no inversion of M: prior structure of M is kept).
* **full set of actuators** — F known with full row rank (m ≥ n; the thesis: F
  invertible). The thesis writes T₂, T₃, T₄ through T₁ (7-13), M⁻¹ = T₁Q (7-14) and
  solves (7-15) for X = KT₁, Y = VT₁, then (7-16). The same information is linear in
  M, V, K directly through S = T⁻¹ = [S_l, S_r]: 𝔹 = S B gives W := S_r M⁻¹ = 𝔹F⁺,
  then 𝔸S = SA gives S_r = WM, S_l = 𝔸WM + WV and

      𝔸²W M + 𝔸W V + W K = 0,   ℂ(𝔸WM + WV) = H,   ℂWM = 0          (position)

  (velocity: ℂ(𝔸WM + WV) = 0, ℂWM = H), one linear least squares in θ.

General case (7-10): unknowns τ (the entries of M⁻¹(τ), symmetric, or diagonal when
M(θ) is diagonal; constant when M is known), the parameters of V, K (and H), T and S:

    [T | [0; M⁻¹(τ)]] [[𝔸, 0], [0, I]] [S; [K V]] = [[0, I], [0, 0]]          (7-9)
    S T = I,  T S = I,  T𝔹 = [0; M⁻¹(τ) F],  ℂ S = [H 0],  M⁻¹(τ), V, K ⪰ 0

solved by SCR; then M = (M⁻¹(τ))⁻¹ (7-22) and θ is the least-squares fit of M(θ), V(θ),
K(θ), H(θ) to the estimates (which keeps any structure the model gives M).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symid import scr
from symid.errors import ModelError
from symid.fit.base import ScrEstimator, symmetric_map
from symid.fit.options import check_bool, check_choice, check_float, check_seed, check_time_limit
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import SimilarityData, SimilarityEstimator, budget_message
from symid.fit.similarity.scr import consistent, implied_equalities, left_times, right_times
from symid.fit.similarity.start import random_pair, start_key

__all__ = ["LinearSimilarity2nd", "ScrSimilarity2nd", "check_second_order", "second_order_case"]

_COND_MAX = 1e12


def check_second_order(model: Any) -> None:
    """Refuse what the similarity formulations of chapter 7 do not cover, with the reason."""
    if model.output not in ("position", "velocity"):
        has = (f"outputs of different kinds ({', '.join(model.outputs)})" if model.output == "mixed"
               else f"{model.output} output")
        raise ModelError("the similarity formulations of thesis ch. 7 take position or velocity outputs (7-2), "
                         f"(7-24), all of one kind; this model has {has} (thesis §7-7-3: future work). "
                         "Use method='ipopt' on a black box; on input/output records the default method "
                         "('auto') or 'oe' (output error on the samples)")


def _full_rank(X: np.ndarray, rank: int) -> bool:
    return bool(np.linalg.matrix_rank(X) == rank and np.linalg.cond(X) < _COND_MAX)


def _applies(model: Any, case: str) -> bool:
    amap = model.maps["C" if case == "sensors" else "B"]
    return bool(amap.is_constant and _full_rank(amap.X0, model.n_dof))


def second_order_case(model: Any) -> str | None:
    """``"sensors"`` (H known, full column rank), ``"actuators"`` (F known, full row rank) or ``None``."""
    return next((case for case in ("sensors", "actuators") if _applies(model, case)), None)


def _why_not(model: Any) -> str:
    maps, n = model.maps, model.n_dof
    out = []
    for name, what in (("C", "sensors"), ("B", "actuators")):
        amap = maps[name]
        if not amap.is_constant:
            out.append(f"{name} holds parameters")
        else:
            r = int(np.linalg.matrix_rank(amap.X0))
            out.append(f"{name} ({amap.shape[0]}×{amap.shape[1]}) has rank {r} < {n} (not a full set of {what})"
                       if r < n else f"{name} is ill-conditioned")
    return "; ".join(out)


def _stack(parts: list[tuple[np.ndarray, np.ndarray]], l: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Residual blocks r(θ) = r0 + Σ θi ri given as (r0, ri stacked (l, ...)) → (J, r0) flattened, and the
    block of every row."""
    r0 = np.concatenate([p[0].ravel() for p in parts])
    J = np.hstack([p[1].reshape(l, -1) for p in parts]).T
    block = np.concatenate([np.full(p[0].size, b) for b, p in enumerate(parts)])
    return J, r0, block


_REWEIGHT_MAX = 50
"""Reweighting rounds of :class:`LinearSimilarity2nd` at most (measured: 3–5 on the 2-DOF from 1 %-noise records)."""
_ROUND_OFF_BLOCK = 1e-12  # a block this much smaller than the largest holds only round-off


def _lin(maps: dict[str, Any], name: str, left: np.ndarray | None = None, right: np.ndarray | None = None
         ) -> tuple[np.ndarray, np.ndarray]:
    """(X0', Xi') for left @ X(θ) @ right, as constant part and per-parameter coefficients."""
    X0, Xi = maps[name].X0, maps[name].Xi
    if left is not None:
        X0, Xi = left @ X0, np.einsum("ab,kbc->kac", left, Xi)
    if right is not None:
        X0, Xi = X0 @ right, Xi @ right
    return X0, Xi


def _add(*terms: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    return sum(t[0] for t in terms), sum(t[1] for t in terms)


class LinearSimilarity2nd(SimilarityEstimator):
    """The linear special cases of §7-5-2 (see the module notes): exact on exact black boxes.

    The blocks of equations (the dynamics (7-12c, d), the input (7-12f) or output
    relations) carry different units, whose ratio changes with the units of time, of the
    outputs and of the black box's basis; on an estimated black box (which no θ fits
    exactly) the plain least squares then weighs them differently in every set of units
    (measured: the 2-DOF from 1 %-noise records, 3000 samples, time or outputs in units of
    1e±6: estimates 50–200 % apart). Every block is therefore weighed by the size of its
    terms, Σ |terms| at the estimate, and the estimate recomputed until it no longer
    changes (a fixed point, the same physical estimate in any units); each parameter's
    column is scaled to unit norm (its units do not matter either).

    Parameters
    ----------
    model : SecondOrderModel
    data : SimilarityData
    case : {"sensors", "actuators"}, optional
        Default: :func:`second_order_case`.
    time_limit : float, optional
        Wall-time budget of one run in seconds, checked after every reweighting round
        (status ``"time_limit"``; the last round's estimate is kept). Default: none (the
        rounds are few and cheap: 3–5 measured, at most 50).
    callback : callable, optional
        Called after every reweighting round with a :class:`symid.engine.scr.ScrProgress`
        (round, residual of the weighted equations relative to the size of their terms,
        black-box misfit, elapsed seconds, θ); a true return value stops (status
        ``"stopped"``).
    verbose : bool
        Print one line per round (round, residual, misfit, elapsed). Default False.
    """

    method = "ls"

    def __init__(self, model: Any, data: SimilarityData, *, case: str | None = None, time_limit: float | None = None,
                 callback: Any = None, verbose: bool = False):
        check_second_order(model)
        self.time_limit = check_time_limit("time_limit", time_limit)
        self._progress_options(callback, verbose)
        case = second_order_case(model) if case is None else case
        if case is None:
            raise ModelError("the linear special cases of thesis §7-5-2 need a full set of sensors (C known, rank n) "
                             f"or of actuators (B known, rank n); here: {_why_not(model)}. Use method='scr'")
        case = check_choice("case", case, ("sensors", "actuators"))
        if not _applies(model, case):
            raise ModelError(f"case={case!r} does not apply: {_why_not(model)}")
        self.model, self.data, self.frf, self.case = model, data, data.frf, case
        self.options = {"case": case, "time_limit": self.time_limit, "callback": None if callback is None else "given",
                        "verbose": self._verbose, "black_box": data.source}
        J, r0, self._block = self._sensors() if case == "sensors" else self._actuators()
        l = model.n_parameters
        # on unit-norm columns: a parameter in other units scales its column, which must not change the rank
        # test or the solution (a mass declared in units of 1e6 kg made a full-rank J look rank 5 of 6)
        norms = np.linalg.norm(J, axis=0)
        self._columns = np.where(norms > 0, norms, 1.0)
        rank = np.linalg.matrix_rank(J / self._columns)
        if rank < l:
            raise ModelError(f"the linear least squares of the {case} case has rank {rank} < {l} parameters: the "
                             "black box does not determine θ (check identifiability)")
        self._J, self._r0 = J, r0

    def _sensors(self) -> tuple[np.ndarray, np.ndarray]:
        model, bb = self.model, self.data.blackbox
        maps, l = model.maps, model.n_parameters
        Hp = np.linalg.pinv(maps["C"].X0)
        if model.output == "position":
            T_top = Hp @ bb.C
            T_bot = T_top @ bb.A
        else:
            T_bot = Hp @ bb.C
            try:
                T_top = T_bot @ np.linalg.inv(bb.A)
            except np.linalg.LinAlgError:
                raise ModelError("velocity output with a singular black-box 𝔸 (a rigid-body mode): "
                                 "the sensors case cannot recover the positions") from None
        dyn = _add(_lin(maps, "M", right=T_bot @ bb.A), _lin(maps, "V", right=T_bot), _lin(maps, "K", right=T_top))
        m_b = _lin(maps, "M", right=T_bot @ bb.B)
        inp = (m_b[0] - maps["B"].X0, m_b[1] - maps["B"].Xi)
        return _stack([dyn, inp], l)

    def _actuators(self) -> tuple[np.ndarray, np.ndarray]:
        model, bb = self.model, self.data.blackbox
        maps, l = model.maps, model.n_parameters
        W = bb.B @ np.linalg.pinv(maps["B"].X0)
        AW, AAW, CW, CAW = bb.A @ W, bb.A @ bb.A @ W, bb.C @ W, bb.C @ bb.A @ W
        dyn = _add(_lin(maps, "M", left=AAW), _lin(maps, "V", left=AW), _lin(maps, "K", left=W))
        s_l = _add(_lin(maps, "M", left=CAW), _lin(maps, "V", left=CW))
        s_r = _lin(maps, "M", left=CW)
        H0, Hi = maps["C"].X0, maps["C"].Xi
        if model.output == "position":
            out = [(s_l[0] - H0, s_l[1] - Hi), s_r]
        else:
            out = [s_l, (s_r[0] - H0, s_r[1] - Hi)]
        return _stack([dyn, *out], l)

    def block_sizes(self, theta: np.ndarray) -> np.ndarray:
        """Per block of equations, the size of its terms at θ: ‖ |r₀| + Σₖ |θₖ| |Jₖ| ‖ over its rows."""
        terms = np.abs(self._r0) + np.abs(self._J) @ np.abs(theta)
        sizes = np.sqrt(np.bincount(self._block, weights=terms**2))
        return np.where(sizes > 0, sizes, 1.0)

    def block_weights(self, theta: np.ndarray) -> np.ndarray:
        """Per block, 1 / its size at θ (:meth:`block_sizes`); 0 for a block whose terms are all at round-off
        (size ≤ 1e-12 of the largest block's): its equations vanish identically for this black box (C B = 0 when
        positions are measured), and 1 / size would blow its round-off up to the size of the real equations."""
        sizes = self.block_sizes(theta)
        return np.where(sizes > _ROUND_OFF_BLOCK * sizes.max(), 1.0 / sizes, 0.0)

    def solve(self, t0: float | None = None) -> tuple[np.ndarray, int, str]:
        """θ, the rounds of reweighting and the status: weighted least squares, every block by the size of its
        terms at the previous estimate (the first unweighted), until the estimate stops changing (to 1e-13
        relative; ``"solved"``), or ``"time_limit"`` (``time_limit`` seconds after ``t0``, default now) or
        ``"stopped"`` (by the callback) after a round."""
        t0 = time.perf_counter() if t0 is None else t0
        deadline = None if self.time_limit is None else t0 + self.time_limit
        report = self.progress_reporter(t0)
        theta = np.linalg.lstsq(self._J / self._columns, -self._r0, rcond=None)[0] / self._columns
        for k in range(1, _REWEIGHT_MAX + 1):
            w = self.block_weights(theta)[self._block]
            Jw = self._J * w[:, None]
            cols = np.linalg.norm(Jw, axis=0)
            cols = np.where(cols > 0, cols, 1.0)
            new = np.linalg.lstsq(Jw / cols, -self._r0 * w, rcond=None)[0] / cols
            done = bool(np.all(np.abs(new - theta) <= 1e-13 * np.abs(new).max()))
            theta = new
            asked = report is not None and report(k, self.relative_residual(theta, w), theta)
            if done:
                return theta, k, "solved"
            if asked:
                return theta, k, "stopped"
            if deadline is not None and time.perf_counter() >= deadline and k < _REWEIGHT_MAX:
                return theta, k, "time_limit"
        return theta, _REWEIGHT_MAX, "solved"

    def relative_residual(self, theta: np.ndarray, w: np.ndarray) -> float:
        """‖w (Jθ + r₀)‖ / ‖w (|r₀| + |J| |θ|)‖: the residual of the equations weighted by ``w`` (one weight per
        row), relative to the size of their terms at θ."""
        top = np.linalg.norm(w * (self._J @ theta + self._r0))
        size = np.linalg.norm(w * (np.abs(self._r0) + np.abs(self._J) @ np.abs(theta)))
        return float(top / size) if size > 0 else 0.0

    def run(self, x0: np.ndarray | None = None) -> StartOutcome:
        """Solve the least squares (the start is irrelevant; kept for a uniform signature)."""
        t0 = time.perf_counter()
        theta, rounds, status = self.solve(t0)
        start = np.zeros(self.model.n_parameters) if x0 is None else np.asarray(x0, dtype=float)
        message = (f"linear least squares (full set of {self.case}, thesis §7-5-2), every block of equations "
                   f"weighed by its size ({rounds} round{'s' * (rounds != 1)})")
        if status == "time_limit":
            message += "; " + budget_message(self.time_limit, rounds, "round") + " (not reweighted to its fixed point)"
        elif status == "stopped":
            message += f"; stopped by the callback after {rounds} rounds (not reweighted to its fixed point)"
        return self.outcome(start, theta, finished=status == "solved", status=status, iterations=rounds,
                            wall_time=time.perf_counter() - t0, message=message)


def _minv_structure(mmap: Any) -> tuple[np.ndarray, np.ndarray]:
    """M⁻¹(τ) = const + Σ τk Ek: (const (n, n), E (k, n, n)), per thesis §7-5-1."""
    n = mmap.shape[0]
    if mmap.is_constant:
        return np.linalg.inv(mmap.X0), np.zeros((0, n, n))
    off = ~np.eye(n, dtype=bool)
    diagonal = not np.any(mmap.X0[off]) and not np.any(mmap.Xi[:, off])
    if diagonal:
        const, basis = np.zeros((n, n)), []
        for i in range(n):
            if np.any(mmap.Xi[:, i, i]):
                E = np.zeros((n, n))
                E[i, i] = 1.0
                basis.append(E)
            else:
                const[i, i] = 1.0 / mmap.X0[i, i]
        return const, np.array(basis).reshape(-1, n, n)
    basis = []
    for d in range(n):  # diagonal by diagonal, as thesis (7-20)
        for i in range(n - d):
            E = np.zeros((n, n))
            E[i, i + d] = E[i + d, i] = 1.0
            basis.append(E)
    return np.zeros((n, n)), np.array(basis)


class ScrSimilarity2nd(ScrEstimator, SimilarityEstimator):
    """SCR on (7-10) with the M⁻¹(τ) parameterisation, built once, run per start.

    Parameters
    ----------
    model : SecondOrderModel
        B (the input matrix F) must be known; C (H) may hold parameters.
    data : SimilarityData
    weights : float
        λ on ST = I and TS = I (default 1; the thesis uses 10 in §7-6-1).
    aux_init : {"random", "zero", "identity"}
        T₀, S₀: seeded N(0, 1) draws scaled by ‖ℂ‖/‖C₀‖, zero, or identity (thesis
        Figure 7-3). θ₀ is the start; τ₀ the entries of M(θ₀)⁻¹ when M(θ₀) is positive
        definite, of the identity otherwise.
    seed : int
        Seed of the random T₀, S₀.
    lmis : bool
        M⁻¹(τ), V, K ⪰ 0 (when symmetric) and positive parameters ≥ 0 (default True).
    implied : bool
        Add the linear equalities T_top 𝔸 = T_bot (7-12a, b) and H T = ℂ for known rows of
        H (7-12g, h), implied by (7-10) (see
        :func:`~symid.fit.similarity.scr.implied_equalities`; default True),
        unless they contradict the black box (then dropped, as ``options["implied"]`` says).
    transform_scale : float, optional
        The α of the scaled unknowns T/α, αS; default ‖ℂ‖/‖C₀‖ (the known output map).
    backend, max_iter, tol, admm
        Passed to :func:`symid.engine.scr.solve` (defaults ``"admm"``, 2000, 1e-8).
    time_limit : float, optional
        Wall-time budget of one start in seconds (status ``"time_limit"``; the iteration
        under way is cut short, see :func:`symid.engine.scr.solve`). ``polish=True`` gives
        the IPOPT polish the same budget again. Default: none.
    callback : callable, optional
        Called after every SCR iteration with a :class:`symid.engine.scr.ScrProgress`
        (iteration, bilinear residual, black-box misfit, elapsed seconds, θ fitted to the
        iterate's M, V, K, H); a true return value stops the start (status ``"stopped"``).
    verbose : bool
        Print one line per SCR iteration (iteration, residual, misfit, elapsed). Default False.
    """

    method = "scr"

    def __init__(self, model: Any, data: SimilarityData, *, weights: float = 1.0, aux_init: str = "random",
                 seed: int = 0, lmis: bool = True, implied: bool = True, transform_scale: float | None = None,
                 backend: str = "admm", max_iter: int = 2000, tol: float = 1e-8, admm: Any = None,
                 time_limit: float | None = None, callback: Any = None, verbose: bool = False):
        check_second_order(model)
        self.init = check_choice("aux_init", aux_init, ("random", "zero", "identity"))
        weights = check_float("weights", weights, low=0, strict_low=True)
        self.seed = check_seed("seed", seed)
        lmis, implied = check_bool("lmis", lmis), check_bool("implied", implied)
        if transform_scale is not None:
            transform_scale = check_float("transform_scale", transform_scale, low=0, strict_low=True)
        solve_opts = self._engine_options(backend=backend, max_iter=max_iter, tol=tol, admm=admm,
                                          time_limit=time_limit)
        self._progress_options(callback, verbose)
        if not model.maps["B"].is_constant:
            raise ModelError("the second-order similarity formulation (7-10) needs the input matrix B known (thesis "
                             "§7-2: F known); B holds parameters. Use method='ipopt' on a black box; on input/output "
                             "records the default method ('auto') or 'oe' (output error on the samples)")
        self.model, self.data, self.frf = model, data, data.frf
        self.options = {"weights": weights, "aux_init": aux_init, "seed": seed, "lmis": lmis, "implied": implied,
                        "backend": backend, "max_iter": max_iter, "tol": tol, "time_limit": solve_opts["time_limit"],
                        "callback": None if callback is None else "given", "verbose": self._verbose,
                        "black_box": data.source}
        self.scale = transform_scale
        self._setup_engine(self._build(weights, lmis, implied), solve_opts)
        if implied and not consistent(self.compiled):
            self._setup_engine(self._build(weights, lmis, False), solve_opts)
            self.options["implied"] = "dropped: inconsistent with this (estimated) black box"

    def polisher(self) -> Any:
        """IPOPT on the black box's frequency response (:class:`~symid.fit.similarity.ipopt.IpoptSimilarityFRF`)."""
        from symid.fit.similarity.ipopt import IpoptSimilarityFRF

        return IpoptSimilarityFRF(self.model, self.data, time_limit=self.options["time_limit"])

    def _build(self, lam: float, lmis: bool, implied: bool) -> scr.BilinearProblem:
        model, bb = self.model, self.data.blackbox
        maps, n, l = model.maps, model.n_dof, model.n_parameters
        N = 2 * n
        Hmap = maps["C"]
        css0 = np.hstack([Hmap.X0, np.zeros_like(Hmap.X0)])
        nc = float(np.linalg.norm(css0))
        self.alpha = float(np.linalg.norm(bb.C)) / nc if nc > 0 else 1.0
        if self.scale is not None:
            self.alpha = float(self.scale)
        Bb, Cb = self.alpha * bb.B, bb.C / self.alpha
        self.minv0, self.minv_basis = _minv_structure(maps["M"])
        k = self.minv_basis.shape[0]
        theta = scr.Variable("theta", (l,)) if l else None
        tau = scr.Variable("tau", (k,)) if k else None
        T = scr.Variable("T", (N, N))
        S = scr.Variable("S", (N, N))
        ident = np.eye(N * N).reshape(N, N, N, N)

        def minv_aff(rows_before: int, rows_after: int, right: np.ndarray | None = None) -> tuple[Any, Any]:
            """Affine pieces of [0; M⁻¹(τ) X; 0]: constant and τ coefficient."""
            c = self.minv0 if right is None else self.minv0 @ right
            E = self.minv_basis if right is None else self.minv_basis @ right
            pad = ((rows_before, rows_after), (0, 0))
            return np.pad(c, pad), np.moveaxis(np.pad(E, ((0, 0), *pad)), 0, -1)

        # left factor [T | [0; M⁻¹(τ)]], (2n × 3n)
        Z0, Zc = minv_aff(n, 0)
        Lc = {T: np.concatenate([ident, np.zeros((N, n, N, N))], axis=1)}
        if tau is not None:
            Lc[tau] = np.concatenate([np.zeros((N, N, k)), Zc], axis=1)
        left = scr.Affine(np.hstack([np.zeros((N, N)), Z0]), Lc)
        # right factor [S; [K(θ) V(θ)]], (3n × 2n)
        KV0 = np.hstack([maps["K"].X0, maps["V"].X0])
        Rc = {S: np.concatenate([ident, np.zeros((n, N, N, N))], axis=0)}
        if theta is not None:
            KVc = np.concatenate([np.moveaxis(maps["K"].Xi, 0, -1), np.moveaxis(maps["V"].Xi, 0, -1)], axis=1)
            Rc[theta] = np.concatenate([np.zeros((N, N, l)), KVc], axis=0)
        right = scr.Affine(np.vstack([np.zeros((N, N)), KV0]), Rc)
        P = np.block([[bb.A, np.zeros((N, n))], [np.zeros((n, N)), np.eye(n)]])
        rhs = np.block([[np.zeros((n, n)), np.eye(n)], [np.zeros((n, N))]])
        Ta = scr.Affine(np.zeros((N, N)), {T: ident})
        Sa = scr.Affine(np.zeros((N, N)), {S: ident})
        eye = np.eye(N)
        terms = [scr.Bilinear(A=left, P=P, B=right, C=rhs, weight=1.0, name="(7-9) dynamics"),
                 scr.Bilinear(A=Sa, P=eye, B=Ta, C=eye, weight=lam, name="S T = I"),
                 scr.Bilinear(A=Ta, P=eye, B=Sa, C=eye, weight=lam, name="T S = I")]
        # T𝔹 − [0; M⁻¹(τ) F] = 0; with the implied H T_top = ℂ the top rows T_top 𝔹 = 0 follow from ℂ𝔹 = 0,
        # and on an estimated black box (ℂ𝔹 ≈ 0 only) they would contradict it: keep the bottom rows only
        F = maps["B"].X0
        b0, bc = minv_aff(n, 0, right=F)
        keep = slice(n, N) if implied else slice(0, N)
        coefs = {T: right_times(Bb, N)[keep]}
        if tau is not None:
            coefs[tau] = -bc[keep]
        eqs = [scr.Affine(-b0[keep], coefs)]
        # ℂS − [H 0] = 0 (position) or [0 H] (velocity)
        Hc = np.moveaxis(Hmap.Xi, 0, -1)
        zero = np.zeros_like(Hc)
        cc = np.concatenate([Hc, zero] if model.output == "position" else [zero, Hc], axis=1)
        c0 = css0 if model.output == "position" else np.hstack([np.zeros_like(Hmap.X0), Hmap.X0])
        coefs = {S: left_times(Cb, N)}
        if theta is not None:
            coefs[theta] = -cc
        eqs.append(scr.Affine(-c0, coefs))
        if implied:
            # known rows of A = [[0, I], [−M⁻¹K, −M⁻¹V]] and of C: T_top 𝔸 = T_bot (7-12a, b), H T = ℂ (7-12g, h)
            A0 = np.block([[np.zeros((n, n)), np.eye(n)], [np.zeros((n, N))]])
            A_unknown = np.zeros((1, N, N))
            A_unknown[0, n:, :] = 1.0
            eqs += implied_equalities(T, S, bb.A, Bb, Cb, (A0, A_unknown), None, (c0, np.moveaxis(cc, -1, 0)))
        lmi_list = []
        if lmis:
            if tau is not None:
                lmi_list.append(scr.Affine(self.minv0, {tau: np.moveaxis(self.minv_basis, 0, -1)}))
            for name in "VK":
                if not maps[name].is_constant and symmetric_map(maps[name]):
                    lmi_list.append(scr.Affine(maps[name].X0, {theta: np.moveaxis(maps[name].Xi, 0, -1)}))
            for i, pos in enumerate(model.positive):
                if pos and any(i in maps[m].depends_on for m in "VKC"):
                    coef = np.zeros((1, 1, l))
                    coef[0, 0, i] = 1.0
                    lmi_list.append(scr.Affine(np.zeros((1, 1)), {theta: coef}))
        variables = [v for v in (theta, tau, T, S) if v is not None]
        return scr.BilinearProblem(variables=variables, bilinear=terms, equalities=eqs, lmis=lmi_list)

    def minv(self, tau: np.ndarray) -> np.ndarray:
        """M⁻¹(τ)."""
        return self.minv0 + np.tensordot(np.asarray(tau, dtype=float).reshape(-1), self.minv_basis, axes=1)

    def start(self, x0: np.ndarray) -> dict[str, np.ndarray]:
        """The engine start {θ, τ, T, S} for the start x₀ (T, S in the scaled basis T/α, αS)."""
        x0 = np.asarray(x0, dtype=float)
        N = self.model.n_states
        if self.init == "random":
            try:
                ss = self.model.state_space(x0)
                key = start_key(ss.A, ss.B, ss.C, self.data.blackbox)
            except (ModelError, np.linalg.LinAlgError, ValueError, FloatingPointError):
                key = 0  # M(x₀) singular: no model to read the key off
            T0, S0 = random_pair(N, key, self.seed)
        else:
            T0 = S0 = np.eye(N) if self.init == "identity" else np.zeros((N, N))
        out: dict[str, np.ndarray] = {"T": T0, "S": S0}
        if self.model.n_parameters:
            out["theta"] = x0
        k = self.minv_basis.shape[0]
        if k:
            M = self.model.maps["M"](x0)
            Minv = np.linalg.inv(M) if np.all(np.linalg.eigvalsh((M + M.T) / 2) > 0) else np.eye(M.shape[0])
            B = self.minv_basis.reshape(k, -1).T
            out["tau"] = np.linalg.lstsq(B, (Minv - self.minv0).ravel(), rcond=None)[0]
        return out

    def solve(self, x0: np.ndarray, monitor: Any = None) -> scr.SCRSolution:
        """The raw engine solution (θ, τ and the scaled T, S in ``sol.x``) from the start x₀; ``monitor`` as
        :func:`symid.engine.scr.solve`."""
        return self.engine_solve(self.start(x0), monitor=monitor)

    def estimate(self, sol: scr.SCRSolution | Any) -> dict[str, np.ndarray]:
        """M = (M⁻¹(τ))⁻¹, V, K, H and the θ fitted to them, from an engine solution (or one iterate of it,
        a dict by variable name)."""
        x = sol.x if isinstance(sol, scr.SCRSolution) else sol
        maps, l = self.model.maps, self.model.n_parameters
        th = np.asarray(x.get("theta", np.zeros(0)), dtype=float).reshape(-1)
        Minv = self.minv(x["tau"]) if "tau" in x else self.minv0
        try:
            M = np.linalg.inv(Minv)
        except np.linalg.LinAlgError:
            M = np.full_like(Minv, np.nan)
        est = {"M": M, "V": maps["V"](th) if l else maps["V"].X0, "K": maps["K"](th) if l else maps["K"].X0,
               "C": maps["C"](th) if l else maps["C"].X0, "Minv": Minv}
        if l and np.all(np.isfinite(M)):
            J = np.hstack([maps[k].Xi.reshape(l, -1) for k in "MVKC"]).T
            r = np.concatenate([(est[k] - maps[k].X0).ravel() for k in "MVKC"])
            est["theta"] = np.linalg.lstsq(J, r, rcond=None)[0]
        else:
            est["theta"] = np.full(l, np.nan)
        return est

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start x₀; never raises on solver failure."""
        x0 = np.asarray(x0, dtype=float)
        t0 = time.perf_counter()
        sol = self.solve(x0, self.engine_monitor(lambda x: self.estimate(x)["theta"], t0))
        est = self.estimate(sol)
        T = self.alpha * np.asarray(sol.x["T"])
        return self.transform_outcome(x0, est["theta"], T, finished=self.engine_finished(sol), status=sol.status,
                                      message=sol.message, iterations=sol.iterations,
                                      wall_time=time.perf_counter() - t0, history=self.engine_history(sol))
