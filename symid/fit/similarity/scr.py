"""SCR on the similarity transformation: thesis Algorithm 6.1, formulation (6-13)/(6-14).

Given a black box (𝔸, 𝔹, ℂ, 𝔻) and a structured model A(θ), B(θ), C(θ), D(θ) of the
same order, find θ, T and S with (6-10)/(6-13)

    T 𝔸 S = A(θ),   S T = I,   T S = I,   T 𝔹 = B(θ),   ℂ S = C(θ)   (and D(θ) = 𝔻).

The three products are bilinear terms of the engine (each relaxed by the nuclear norm
of (2-6) with Q = −T̄, R = −S̄, exactly the blocks printed in (6-14)); the two identities
carry the weight λ, the dynamics term weight 1; T𝔹 = B(θ), ℂS = C(θ) and D(θ) = 𝔻 are
linear equalities. Requiring both ST = I and TS = I makes T invertible at any solution
(Definition 6.1), so a solution is a similarity transform and (6-7) holds.

Scaling. The relaxation penalises the steps T − T̄ and S − S̄ on the same footing (the
off-diagonal blocks of (6-14)), so its progress depends on how ‖T‖ compares with
‖S‖ = ‖T⁻¹‖. The engine works on T' = T/α and S' = αS, i.e. on the black box
(𝔸, α𝔹, ℂ/α), with α the data-implied scale of T
(:func:`~symid.fit.similarity.start.transform_scale`), which makes the two
comparable. Measured on the e-nose from one start (θ* + 0.1 N(0, 1), T₀ by (C-7)),
parameter error after 600 iterations: 2.3e-1 with α = 1, 2e-5 with α = 3, 4.5e-4 with
α = 5, 6e-2 with α = 10 (the automatic α is 5.8). :meth:`ScrSimilarity.transform`
returns T and S for ``data.blackbox`` (balanced when stable) or the black box as given.

Units. Each start's problem is built in that start's units
(:meth:`ScrSimilarity.start_problem`, tens of milliseconds): time in units of 1/ρ(𝔸), the
black box's states scaled by the size of T that the start implies
(:func:`~symid.fit.similarity.start.working_problem` with ``keep_states=True,
keep_io=True``), and each parameter in units of its value at the start (θ = |x₀|·θ̃,
:func:`unit_columns`; where x₀ is 0, a bound or 1). From the same start, SCR's iterations then do not depend on the
units of the parameters, of time, of the inputs or of the outputs (a unit that changes all
the model's states alike, as a fixed 1 in B does when the input changes unit, is absorbed
by the size of T), and the random T₀ is drawn alike
(:func:`~symid.fit.similarity.start.start_key`). The model's states otherwise keep the
units it declares them in: SCR's relaxation is sensitive to how T is scaled, and state
sizes taken at a random start are noise to it. On the e-nose (6-19), 40 random starts
(seeds 0–3, ``max_iter=2000``): the truth from 15 with these units, 5 with the states also
of size one at the start (as ALS, GB and IPOPT have them), 6 with those sizes rounded to
powers of ten, 12 in the model's own units before. Before, on a two-compartment model,
time in ms took one start from 37 iterations to its 30 s budget, and a rate declared in
units of 1e-6 made the implied equalities below look inconsistent (they are checked once,
with the parameters' coefficients of norm one).

Implied equalities (option ``implied``, default on) add the rows and columns of the
similarity relations that the model's known entries make linear
(:func:`implied_equalities`); on the 3-D mass-spring-damper of §7-6-1 the engine's
presolve then fixes 28 of the 96 unknowns before the first iteration (none without), and
from the same start the bilinear residual after 300 iterations was 3e-2 instead of 3e-1.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from symid import scr
from symid.engine.ipopt import start_scale
from symid.fit.base import ScrEstimator, identity_coef, positivity_lmis, theta_coef
from symid.fit.options import check_bool, check_choice, check_float, check_seed
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import SimilarityData, SimilarityEstimator
from symid.fit.similarity.start import (
    INITS,
    WorkingProblem,
    initial_point,
    io_time_normalised,
    transform_scale,
    working_problem,
)

__all__ = ["ScrSimilarity"]


def _constant_rows(Xi: np.ndarray) -> np.ndarray:
    return np.flatnonzero(~np.any(Xi != 0, axis=(0, 2)))


def _constant_cols(Xi: np.ndarray) -> np.ndarray:
    return np.flatnonzero(~np.any(Xi != 0, axis=(0, 1)))


def implied_equalities(T: scr.Variable, S: scr.Variable, bbA: np.ndarray, Bb: np.ndarray, Cb: np.ndarray,
                       A: tuple[np.ndarray, np.ndarray], B: tuple[np.ndarray, np.ndarray] | None,
                       C: tuple[np.ndarray, np.ndarray]) -> list[scr.Affine]:
    """Linear equalities that every solution of (6-13) satisfies, from the known rows and columns of the model.

    With S = T⁻¹, (6-8) also reads 𝔸S = S A(θ), 𝔹 = S B(θ) and ℂ = C(θ) T. Where a row of
    A(θ) or C(θ), or a column of A(θ) or B(θ), holds no parameter, the matching rows of
    T𝔸 = A(θ)T and ℂ = C(θ)T, or columns of 𝔸S = SA(θ) and 𝔹 = SB(θ), are linear in T
    or S. Adding them changes no solution but tightens every convex sub-problem, and
    the engine's presolve eliminates what they determine (:mod:`symid.engine.scr.presolve`; thesis
    §7-7-1 suggests the same reduction for chapter 7, where (7-12a, b) fix half of T).

    ``A``, ``B``, ``C`` are (constant part, coefficients (l, r, c)) of the model maps; ``B``
    may be ``None`` (not used). ``Bb``, ``Cb`` are the black box's 𝔹, ℂ in the scaled basis.
    """
    n = bbA.shape[0]
    out = []
    rows = _constant_rows(A[1])
    if rows.size:  # rows of T𝔸 − A₀T
        coef = right_times(bbA, n) - left_times(A[0], n)
        out.append(scr.Affine(np.zeros((rows.size, n)), {T: coef[rows]}))
    cols = _constant_cols(A[1])
    if cols.size:  # columns of 𝔸S − S A₀
        coef = left_times(bbA, n) - right_times(A[0], n)
        out.append(scr.Affine(np.zeros((n, cols.size)), {S: coef[:, cols]}))
    rows = _constant_rows(C[1])
    if rows.size:  # rows of ℂ − C₀T
        out.append(scr.Affine(Cb[rows], {T: -left_times(C[0], n)[rows]}))
    if B is not None:
        cols = _constant_cols(B[1])
        if cols.size:  # columns of 𝔹 − S B₀
            out.append(scr.Affine(Bb[:, cols], {S: -right_times(B[0], n)[:, cols]}))
    return out


def consistent(compiled: scr.CompiledProblem) -> bool:
    """Whether the engine's presolve found the linear equalities of a compiled problem consistent.

    On an estimated black box (N4SID on noisy records) the relations the implied
    equalities add hold only approximately, and together with T𝔹 = B(θ) they can
    over-determine T; the engine would then report the problem infeasible.
    """
    return compiled.reduced.inconsistent <= scr.INCONSISTENT_TOL


def unit_columns(maps: dict[str, Any], unit: np.ndarray) -> dict[str, Any]:
    """The maps in parameters θ̃ = θ / unit (each parameter's coefficients times its unit)."""
    out = dict(maps)
    for k in (k for k in "ABCD" if k in maps):
        out[k] = dataclasses.replace(maps[k], Xi=maps[k].Xi * unit[:, None, None])
    return out


@dataclasses.dataclass(frozen=True)
class StartProblem:
    """The engine problem of one start of :class:`ScrSimilarity`, in the units of that start.

    Attributes
    ----------
    work : WorkingProblem
        The similarity problem in units where its blocks weigh alike (:func:`working_problem`).
    maps : dict
        ``work.maps`` in parameters θ̃ = θ / ``unit`` (:func:`unit_columns`).
    unit : numpy.ndarray
        θ = unit · θ̃, unit = |x₀| (:func:`symid.engine.ipopt.start_scale`).
    alpha : float
        The engine works on T/α and αS (:func:`~symid.fit.similarity.start.transform_scale`).
    compiled : CompiledProblem
        The engine's problem.
    """

    work: WorkingProblem
    maps: dict[str, Any]
    unit: np.ndarray
    alpha: float
    compiled: Any


def left_times(X: np.ndarray, n: int) -> np.ndarray:
    """Coefficients of Y ↦ X Y for an (n, n) variable Y: array (r, n, n, n)."""
    return np.einsum("rb,cd->rcbd", X, np.eye(n))


def right_times(X: np.ndarray, n: int) -> np.ndarray:
    """Coefficients of Y ↦ Y X for an (n, n) variable Y: array (n, c, n, n)."""
    return np.einsum("ax,bc->acxb", np.eye(n), X)


class ScrSimilarity(ScrEstimator, SimilarityEstimator):
    """Sequential convex relaxation of (6-13)/(6-14), built once, run per start.

    Parameters
    ----------
    model : StateSpaceModel
    data : SimilarityData
        The checked black box (:func:`~symid.formulations.similarity_data.similarity_data`).
    weights : float
        λ of (6-14) on the relaxations of ST = I and TS = I (default 1; the thesis uses 10
        in §6-7-1 and §7-6-1, but on the e-nose λ = 1 reached the truth from 3 of 10
        random starts within 1000 iterations and λ = 10 from none).
    aux_init : {"random", "model", "zero", "identity"}
        How T₀, S₀ follow from a start θ₀ (:mod:`~symid.fit.similarity.start`).
    seed : int
        Seed of the random T₀, S₀.
    positivity : bool
        Parameters declared positive are constrained ≥ 0 (1×1 LMIs; default True).
    implied : bool
        Add the linear equalities implied by the known rows and columns of the model
        (:func:`implied_equalities`; default True), unless they contradict the black box
        (:func:`consistent`; then ``options["implied"]`` says they were dropped).
        ``False`` is (6-14) exactly.
    backend : {"admm", "cvxpy"}
        Engine back end (default ``"admm"``).
    max_iter, tol, heuristic, truncate_after, admm
        Passed to :func:`symid.engine.scr.solve` (defaults 1000, 1e-8, ``"nuclear"``, 0, None).
    time_limit : float, optional
        Wall-time budget of one start in seconds (status ``"time_limit"``; the iteration
        under way is cut short: ADMM checks the clock, Clarabel gets the time left, see
        :func:`symid.engine.scr.solve`). ``polish=True`` gives the IPOPT polish the same
        budget again. Default: none.
    callback : callable, optional
        Called after every SCR iteration with a :class:`symid.engine.scr.ScrProgress`
        (iteration, bilinear residual, black-box misfit, elapsed seconds, θ); a true
        return value stops the start (status ``"stopped"``).
    verbose : bool
        Print one line per SCR iteration (iteration, residual, misfit, elapsed). Default False.
    """

    def __init__(self, model: Any, data: SimilarityData, *, weights: float = 1.0, aux_init: str = "random",
                 seed: int = 0, positivity: bool = True, implied: bool = True, backend: str = "admm",
                 max_iter: int = 1000, tol: float = 1e-8, heuristic: str = "nuclear", truncate_after: int = 0,
                 admm: Any = None, time_limit: float | None = None, callback: Any = None, verbose: bool = False):
        self.init = check_choice("aux_init", aux_init, INITS)
        weights = check_float("weights", weights, low=0, strict_low=True)
        self.seed = check_seed("seed", seed)
        positivity, implied = check_bool("positivity", positivity), check_bool("implied", implied)
        solve_opts = self._engine_options(backend=backend, max_iter=max_iter, tol=tol, heuristic=heuristic,
                                          truncate_after=truncate_after, admm=admm, time_limit=time_limit)
        self._progress_options(callback, verbose)
        self.model, self.data = model, data
        self.frf = data.frf
        self.options = {"weights": weights, "aux_init": aux_init, "seed": seed, "positivity": positivity,
                        "implied": implied, "backend": backend, "max_iter": max_iter, "tol": tol,
                        "heuristic": heuristic, "truncate_after": truncate_after,
                        "time_limit": solve_opts["time_limit"], "callback": None if callback is None else "given",
                        "verbose": self._verbose, "black_box": data.source, "basis": data.basis}
        self._weights, self._positivity, self._implied = weights, positivity, implied
        # the implied equalities are checked once, with time, inputs, outputs and parameters in units of their
        # size (coefficients of norm one; in the model's units, a parameter in units of 1e-6 made them look
        # inconsistent); each start then builds its own problem (start_problem)
        self._lower = np.where(np.asarray(self.model.positive, dtype=bool), 0.0, -np.inf)
        maps, bb = io_time_normalised(self.model.maps, self.data.blackbox)
        size = np.sqrt(sum(np.sum(np.abs(maps[k].Xi) ** 2, axis=(1, 2)) for k in "ABCD" if k in maps))
        maps = unit_columns(maps, 1.0 / np.where(size > 0, size, 1.0))  # coefficients of norm one
        self._equalities = "exact"
        self._setup_engine(self._build(maps, bb, implied)[0], solve_opts)
        if implied and not consistent(self.compiled):
            self._implied = False
            self._setup_engine(self._build(maps, bb, False)[0], solve_opts)
            self.options["implied"] = "dropped: inconsistent with this (estimated) black box"
        if not consistent(self.compiled):
            # T𝔹 = B(θ) and ℂS = C(θ) themselves contradict an estimated black box (known B and C rows, e.g. every
            # state measured): they are kept in the least-squares sense (found by a new user: on 1 % noisy records
            # of a DC motor with C = I, SCR stopped 'infeasible' at iteration 0, from the truth too)
            self._equalities = "least_squares"
            self._setup_engine(self._build(maps, bb, False)[0], solve_opts, equalities="least_squares")
            self.options["equalities"] = "least squares: T𝔹 = B(θ), ℂS = C(θ) contradict this (estimated) black box"

    def polisher(self) -> Any:
        """IPOPT on (6-9), T₀ from the SCR estimate by (C-7) (:class:`~symid.fit.similarity.ipopt.IpoptSimilarity`)."""
        from symid.fit.similarity.ipopt import IpoptSimilarity

        return IpoptSimilarity(self.model, self.data, aux_init="model", positivity=self.options["positivity"],
                               time_limit=self.options["time_limit"])

    def _build(self, maps: dict[str, Any], bb: Any, implied: bool) -> tuple[scr.BilinearProblem, float]:
        """The engine problem on these maps and black box, and the α of T/α, αS."""
        lam, positivity = self._weights, self._positivity
        alpha = transform_scale(maps, bb)
        Bb, Cb = alpha * bb.B, bb.C / alpha
        n, l = bb.n_states, self.model.n_parameters
        theta = scr.Variable("theta", (l,))
        T = scr.Variable("T", (n, n))
        S = scr.Variable("S", (n, n))
        Ta = scr.Affine(np.zeros((n, n)), {T: identity_coef((n, n))})
        Sa = scr.Affine(np.zeros((n, n)), {S: identity_coef((n, n))})
        A_theta = scr.Affine(maps["A"].X0, {theta: theta_coef(maps["A"])})
        eye = np.eye(n)
        terms = [scr.Bilinear(A=Ta, P=bb.A, B=Sa, C=A_theta, weight=1.0, name="T A S = A(θ)"),
                 scr.Bilinear(A=Sa, P=eye, B=Ta, C=eye, weight=lam, name="S T = I"),
                 scr.Bilinear(A=Ta, P=eye, B=Sa, C=eye, weight=lam, name="T S = I")]
        # T 𝔹 − B(θ) = 0 and ℂ S − C(θ) = 0
        eqs = [scr.Affine(-maps["B"].X0, {T: right_times(Bb, n), theta: -theta_coef(maps["B"])}),
               scr.Affine(-maps["C"].X0, {S: left_times(Cb, n), theta: -theta_coef(maps["C"])})]
        Dmap = maps["D"]
        if not Dmap.is_constant:  # a fixed D that differs from the black box's is refused by similarity_data
            eqs.append(scr.Affine(Dmap.X0 - bb.D, {theta: theta_coef(Dmap)}))
        if implied:
            eqs += implied_equalities(T, S, bb.A, Bb, Cb, *((maps[k].X0, maps[k].Xi) for k in "ABC"))
        lmis = positivity_lmis(self.model, theta) if positivity else []
        return scr.BilinearProblem(variables=[theta, T, S], bilinear=terms, equalities=eqs, lmis=lmis), alpha

    def start_problem(self, x0: np.ndarray) -> StartProblem:
        """The engine problem for the start x₀, in its units (module notes: Units); built per start (tens of
        milliseconds): θ in units of |x₀|, and the black box's states of the size of T that x₀ implies."""
        x0 = np.asarray(x0, dtype=float)
        work = working_problem(self.model.maps, self.data.blackbox, x0, keep_states=True, keep_io=True)
        unit = start_scale(x0, self._lower, np.full(x0.shape, np.inf))  # |x₀|; where 0, a bound, else 1
        maps = unit_columns(work.maps, unit)
        problem, alpha = self._build(maps, work.bb, self._implied)
        compiled = scr.compile(problem, presolve=True, normalize=True, equalities=self._equalities)
        if self._implied and not consistent(compiled):  # consistent in the model's units, not in these
            problem, alpha = self._build(maps, work.bb, False)
            compiled = scr.compile(problem, presolve=True, normalize=True, equalities=self._equalities)
        return StartProblem(work=work, maps=maps, unit=unit, alpha=alpha, compiled=compiled)

    def start(self, x0: np.ndarray, setup: StartProblem | None = None) -> dict[str, np.ndarray]:
        """The engine start {θ̃, T/α, αS} for the start x₀ (:func:`~.similarity_start.initial_point` on the
        start's problem, ``setup`` or :meth:`start_problem`)."""
        x0 = np.asarray(x0, dtype=float)
        setup = self.start_problem(x0) if setup is None else setup
        theta0, T0, S0 = initial_point(self.init, x0 / setup.unit, self.seed, setup.maps, setup.work.bb)
        return {"theta": theta0, "T": T0 / setup.alpha, "S": S0 * setup.alpha}

    def solve(self, x0: np.ndarray, monitor: Any = None) -> scr.SCRSolution:
        """The engine solution from the start x₀, translated to the model's units: ``x["theta"]`` is θ, and
        ``x["T"]``, ``x["S"]`` are T and S for ``data.blackbox`` (:meth:`transform`). ``monitor`` as
        :func:`symid.engine.scr.solve` (its iterates' θ in the model's units)."""
        x0 = np.asarray(x0, dtype=float)
        setup = self.start_problem(x0)
        if monitor is not None:
            inner = monitor

            def monitor(k: int, x: dict[str, Any], it: Any, elapsed: float) -> Any:
                return inner(k, {**x, "theta": setup.unit * np.asarray(x["theta"], dtype=float)}, it, elapsed)

        sol = self.engine_solve(self.start(x0, setup), compiled=setup.compiled, monitor=monitor)
        theta = setup.unit * np.asarray(sol.x["theta"], dtype=float).reshape(-1)
        Tw, Sw = setup.alpha * np.asarray(sol.x["T"]), np.asarray(sol.x["S"]) / setup.alpha
        sizes, a = setup.work.sizes, setup.work.alpha
        sol.x.update(theta=theta, T=setup.work.original_T(Tw), S=Sw / sizes[None, :] / a)
        return sol

    def transform(self, sol: scr.SCRSolution, original: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(T, S) of a :meth:`solve` solution for ``data.blackbox`` (the balanced one when stable), or with
        ``original=True`` for the black box as given (estimated)."""
        T, S = np.asarray(sol.x["T"]), np.asarray(sol.x["S"])
        if original:
            P = self.data.to_basis
            T, S = T @ P, np.linalg.solve(P, S)
        return T, S

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start θ₀; never raises on solver failure."""
        x0 = np.asarray(x0, dtype=float)
        t0 = time.perf_counter()
        sol = self.solve(x0, self.engine_monitor(lambda x: x["theta"], t0))
        theta = np.asarray(sol.x["theta"], dtype=float).reshape(-1)
        T, S = self.transform(sol)
        n = T.shape[0]
        inv_err = max(np.linalg.norm(T @ S - np.eye(n)), np.linalg.norm(S @ T - np.eye(n)))
        return self.solved_outcome(x0, theta, sol, t0, message=f"{sol.message}; ‖TS − I‖, ‖ST − I‖ ≤ {inv_err:.2e}")
