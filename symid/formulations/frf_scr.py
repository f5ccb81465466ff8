"""SCR formulations for frequency responses: thesis Algorithm 3.1 (state space) and (4-8) (second order).

State space, for every frequency ωᵢ (thesis (3-15)):

- Γ substitution (3-10): A(θ) Γᵢ = jωᵢ Γᵢ − B(θ) and Hᵢ − D(θ) = C(θ) Γᵢ;
- Ψ substitution (3-12): Ψᵢ A(θ) = jωᵢ Ψᵢ − C(θ) and Hᵢ − D(θ) = Ψᵢ B(θ).

Second order (4-8): [M(θ) V(θ) K(θ)] Pᵢ Γᵢ = B(θ) with Pᵢ = [−ωᵢ² I; jωᵢ I; I] (the thesis
prints −jωᵢ in (4-7)/(4-8); the sign must be + for Z = −ω²M + jωV + K of (4-5)), and
Hᵢ = fᵢ C(θ) Γᵢ with fᵢ = 1, jωᵢ or −ωᵢ² for position, velocity or acceleration output
(4-9); M, V, K ⪰ 0 as LMIs when they are symmetric.

Every equation is posed as a bilinear term; the engine's presolve turns the rows that
hold no product of unknowns into linear equalities and eliminates what they determine
(scr-lessons 1 and 7), so only what is truly bilinear is relaxed.

Choices, measured (``examples/belt_drive_scr.py``, ``examples/mass_damper_2dof_scr.py``,
``benchmarks/frf.py``):

- Γ alone by default. On the belt drive from zero, every equation relaxed, Γ reaches
  ‖θ − θ*‖₂ ≤ 1e-6 (ADMM: iteration 131; Clarabel: 84); Γ and Ψ with unit weights
  stall (ADMM 2e-2, Clarabel 0.26 after 1000 / 300 iterations); with the Ψ families
  weighed δ = ρ = 0.01 they converge (1e-6 at iteration 95).
- Unit weights λᵢ = γᵢ = 1 otherwise, as the thesis; the engine equilibrates every block
  (rows, columns, P), which is the block scaling.
- Γᵢ started at seeded N(0, 1) draws: on the 2-DOF the zero start and 10 of 10 default
  starts (seed 0) converge with them; with Γᵢ computed from the model at θ0, 2 of the
  same 10 stalled.
- ADMM back end, tolerance 1e-6 on the normalised residual (relative parameter error
  about 3e-6 on the 2-DOF): Clarabel costs ~1 s per iteration there, and the ADMM
  cannot go much below 1e-7; ``polish`` finishes to machine precision.
- Second-order models: ADMM sub-problems to a relative tolerance of 1e-2 instead of the
  engine's 1e-6 (the engine tightens it to the bilinear residual as that falls). On
  the 2-DOF, 3 seeds × 20 starts: the same successes (19, 20, 20 of 20), about the
  same SCR iterations (median 42–50 against 39–46) and 4–5× fewer inner ADMM
  iterations (22–23 thousand against 108–121 thousand per 20 starts). State-space
  models keep the engine's tolerance: on the belt drive without presolve, Γ and Ψ with
  δ = ρ = 0.01 from zero end at ‖θ − θ*‖₂ = 1e-1 (1e-3) or 3e-2 (1e-2) after 400
  iterations, against 5e-8 with the engine's 1e-6.
- ``"scr+polish"`` (:meth:`ScrFRF.run_polished`) hands over to IPOPT as soon as a
  trial polish from the current SCR estimate fits the data (misfit ≤ 1e-8); on the
  2-DOF that is after the first SCR iteration from most starts (``benchmarks/frf.py``).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from symid import scr
from symid.errors import ModelError
from symid.misfit import relative_misfit
from symid.polish import polish_outcome
from symid.result import StartOutcome

__all__ = ["ScrFRF"]

# constraint families: key of ``weights`` → label in plots (thesis Algorithm 3.1 weights λ, γ, δ, ρ)
_FAMILIES_STATE_SPACE = {"gamma_dynamics": "f1: A Γ = jωΓ − B  (λ)", "gamma_output": "f2: H − D = C Γ  (γ)",
                         "psi_dynamics": "f3: Ψ A = jωΨ − C  (δ)", "psi_output": "f4: H − D = Ψ B  (ρ)"}
_FAMILIES_SECOND_ORDER = {"dynamics": "[M V K] P Γ = B", "output": "H = f C Γ"}


def _theta_coef(amap: Any) -> np.ndarray:
    """Coefficient array (r, c, l) of an affine model map, as scr.Affine wants it."""
    return np.moveaxis(amap.Xi, 0, -1)


def _identity(shape: tuple[int, int]) -> np.ndarray:
    r, c = shape
    return np.eye(r * c).reshape(r, c, r, c)


def _symmetric(amap: Any) -> bool:
    return bool(np.allclose(amap.X0, amap.X0.T) and np.allclose(amap.Xi, np.swapaxes(amap.Xi, 1, 2)))


def _mvk_lmis(maps: Any, theta: Any, options: dict[str, Any]) -> list[scr.Affine]:
    """M, V, K ⪰ 0 as LMIs in θ, for each non-constant symmetric map; a non-symmetric one is
    skipped and recorded in ``options`` (``lmi_M`` … ``"skipped: not symmetric"``)."""
    out = []
    for name in "MVK":
        if maps[name].is_constant:
            continue
        if not _symmetric(maps[name]):
            options[f"lmi_{name}"] = "skipped: not symmetric"
            continue
        out.append(scr.Affine(maps[name].X0, {theta: _theta_coef(maps[name])}))
    return out


class ScrFRF:
    """Sequential convex relaxation on a frequency response, built once, run per start.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData
    substitution : {"gamma", "psi", "both"}, optional
        State-space models: which substitution of thesis (3-10)/(3-12) to use
        (default ``"gamma"``; the thesis uses both, but with C known Ψ only slows
        convergence, scr-lessons 7). Second-order models always use Γ.
    weights : array_like or dict, optional
        Weights of the nuclear-norm relaxations (Algorithm 3.1's λᵢ, γᵢ, δᵢ, ρᵢ). An
        array of one positive number per frequency weighs every constraint family at
        that frequency alike (3-15); a dict weighs families apart, by key
        ``"gamma_dynamics"`` (λ), ``"gamma_output"`` (γ), ``"psi_dynamics"`` (δ),
        ``"psi_output"`` (ρ) for a state-space model and ``"dynamics"``, ``"output"``
        for a second-order one, each a number or one number per frequency (missing
        families weigh 1). Default: 1 everywhere, as the thesis's examples. The engine
        first equilibrates every term (:mod:`symid.scr.presolve`), so a weight means the
        same whatever the units of H.
    lmis : bool, optional
        Second-order models: M, V, K ⪰ 0 (default True; thesis §5-7 and scr-lessons 2
        show they are decisive).
    backend : {"admm", "cvxpy"}
        Engine back end (default ``"admm"``: numpy ADMM, LMIs by projection, tens of
        milliseconds per SCR iteration here; ``"cvxpy"``, Clarabel, solves each
        sub-problem exactly and needs fewer iterations but costs about a second per
        iteration on the 2-DOF problem, see ``benchmarks/frf.py``).
    max_iter : int
        SCR iterations per start (default 500).
    tol : float
        Stop when the largest normalised bilinear residual is ≤ ``tol`` and the step is
        small (default 1e-6: the ADMM back end is inexact near 1e-7, scr-lessons 8; use
        ``polish`` in :func:`symid.identify` / ``"scr+polish"`` in :func:`symid.compare`
        for full precision).
    gamma0 : {"random", "model", "zero"}
        Initial Γᵢ (and Ψᵢ): seeded N(0, 1) draws (default; scr-lessons 9: zero or
        model-consistent Γ made some 2-DOF starts stall), computed from the start θ
        (``"model"``), or zero (thesis ch. 3: "all matrices initialised as zero").
    seed : int
        Seed of the random Γᵢ, combined with the start θ (so a start gives the same run
        every time).
    presolve : bool
        Let the engine turn the rows that hold no product of unknowns into linear
        equalities and eliminate what they fix (default True; ``False`` relaxes every
        equation, as the thesis posed (3-15)).
    heuristic : {"nuclear", "truncated"}
        Rank surrogate of the engine (:func:`symid.scr.solve`).
    admm : symid.scr.ADMMOptions, optional
        Options of the ADMM back end. Default: the engine's, except ``eps_rel=1e-2`` for
        second-order models (sub-problems solved to 1% while the bilinear residual is
        large, to the residual's level once it is smaller, through the engine's
        ``tighten``; see the module docstring).
    polish_misfit : float or None
        ``"scr+polish"`` (:meth:`run_polished`): after SCR iterations 1, 2, 4, 8, … a
        trial polish runs from the current SCR estimate, and SCR stops as soon as one
        reaches a relative data misfit ≤ ``polish_misfit`` (default 1e-8, the misfit
        criterion of :func:`symid.compare`); otherwise SCR runs to its own end and is
        polished then. ``None``: no trial, polish the final SCR estimate only. Noisy
        data whose best misfit lies above the threshold never switch early.
    """

    method = "scr"

    def __init__(self, model: Any, data: Any, *, substitution: str = "gamma", weights: Any = None,
                 lmis: bool = True, backend: str = "admm", max_iter: int = 500, tol: float = 1e-6,
                 gamma0: str = "random", seed: int = 0, presolve: bool = True, heuristic: str = "nuclear",
                 admm: Any = None, polish_misfit: float | None = 1e-8):
        if substitution not in ("gamma", "psi", "both"):
            raise ModelError(f"substitution must be 'gamma', 'psi' or 'both'; got {substitution!r}")
        if gamma0 not in ("model", "zero", "random"):
            raise ModelError(f"gamma0 must be 'random', 'model' or 'zero'; got {gamma0!r}")
        if backend not in ("admm", "cvxpy"):
            raise ModelError(f"backend must be 'admm' or 'cvxpy'; got {backend!r}")
        if polish_misfit is not None and not (np.isfinite(polish_misfit) and polish_misfit > 0):
            raise ModelError(f"polish_misfit must be a positive number or None; got {polish_misfit!r}")
        self.model, self.data = model, data
        self.second_order = "M" in model.maps
        if self.second_order:
            substitution = "gamma"
        self.substitution = substitution
        self.w = np.asarray(data.w, dtype=float)
        lam = self._weights(weights)
        self.options = {"substitution": substitution, "weights": "uniform" if weights is None else "given",
                        "lmis": lmis, "backend": backend, "max_iter": max_iter, "tol": tol, "gamma0": gamma0,
                        "presolve": presolve, "heuristic": heuristic}
        self._solve_opts = {"backend": backend, "max_iter": int(max_iter), "tol": float(tol),
                            "heuristic": heuristic}
        if admm is None and backend == "admm" and self.second_order:
            admm = scr.ADMMOptions(eps_rel=1e-2)  # measured, see the module docstring
        if admm is not None:
            self._solve_opts["admm"] = admm
        self._rng_seed = seed
        self.gamma0 = gamma0
        self.polish_misfit = polish_misfit
        self.problem = self._build(lam, lmis)
        self.compiled = scr.compile(self.problem, presolve=presolve)  # presolved once for every start

    # -- problem construction ---------------------------------------------------------------
    def _families(self) -> dict[str, str]:
        """Constraint families of this formulation: key (for ``weights``) → label (for plots)."""
        if self.second_order:
            return dict(_FAMILIES_SECOND_ORDER)
        return {k: v for k, v in _FAMILIES_STATE_SPACE.items()
                if self.substitution == "both" or k.startswith(self.substitution)}

    def _weights(self, weights: Any) -> dict[str, np.ndarray]:
        """Per family, the weight of each frequency's relaxation (λᵢ, γᵢ, δᵢ, ρᵢ of Algorithm 3.1)."""
        s = self.w.size
        fams = self._families()

        def vector(value: Any, what: str) -> np.ndarray:
            v = np.broadcast_to(np.asarray(value, dtype=float), (s,)) if np.ndim(value) == 0 else \
                np.asarray(value, dtype=float).reshape(-1)
            if v.shape != (s,) or np.any(~np.isfinite(v)) or np.any(v <= 0):
                raise ModelError(f"{what} must be a positive number or {s} positive finite numbers "
                                 f"(one per frequency); got {np.asarray(value).shape} values")
            return np.array(v, dtype=float)

        if weights is None:
            return {k: np.ones(s) for k in fams}
        if isinstance(weights, dict):
            unknown = sorted(set(weights) - set(fams))
            if unknown:
                raise ModelError(f"weights for unknown constraint famil{'y' if len(unknown) == 1 else 'ies'} "
                                 f"{', '.join(unknown)}; this formulation has {', '.join(fams)}")
            return {k: vector(weights.get(k, 1.0), f"weights[{k!r}]") for k in fams}
        lam = vector(weights, "weights")
        return {k: lam for k in fams}

    def _build(self, lam: dict[str, np.ndarray], lmis: bool) -> scr.BilinearProblem:
        model, H = self.model, np.asarray(self.data.H, dtype=complex)
        maps = model.maps
        l = model.n_parameters
        p, m = model.n_outputs, model.n_inputs
        theta = scr.Variable("theta", (l,))
        variables: list[scr.Variable] = [theta]
        terms: list[scr.Bilinear] = []
        lmi_list: list[Any] = []
        labels = self._families()
        self.families: dict[str, list[int]] = {}

        def add(family: str, i: int, **maps_: Any) -> None:
            """The bilinear term A P B = C of frequency i in a constraint family, with its weight."""
            self.families.setdefault(labels[family], []).append(len(terms))
            terms.append(scr.Bilinear(**maps_, weight=float(lam[family][i]), name=f"{family}[{i}]"))

        def aff(amap: Any, sign: float = 1.0) -> scr.Affine:
            return scr.Affine(sign * amap.X0, {theta: sign * _theta_coef(amap)})

        if self.second_order:
            n = model.n_dof
            MVK0 = np.hstack([maps["M"].X0, maps["V"].X0, maps["K"].X0])
            MVKc = np.concatenate([_theta_coef(maps["M"]), _theta_coef(maps["V"]), _theta_coef(maps["K"])], axis=1)
            A_mvk = scr.Affine(MVK0, {theta: MVKc})
            f = {"position": np.ones(self.w.size, dtype=complex), "velocity": 1j * self.w,
                 "acceleration": -(self.w**2) + 0j}[model.output]
            self.gamma_vars = []
            for i, wi in enumerate(self.w):
                G = scr.Variable(f"Gamma{i}", (n, m), complex=True)
                variables.append(G)
                self.gamma_vars.append(G)
                Pi = np.vstack([-(wi**2) * np.eye(n), 1j * wi * np.eye(n), np.eye(n)])
                Gi = scr.Affine(np.zeros((n, m)), {G: _identity((n, m))})
                add("dynamics", i, A=A_mvk, P=Pi, B=Gi, C=aff(maps["B"]))
                add("output", i, A=aff(maps["C"]), P=f[i] * np.eye(n), B=Gi, C=scr.Affine(H[i]))  # Hᵢ = fᵢ C Γᵢ
            if lmis:
                lmi_list.extend(_mvk_lmis(maps, theta, self.options))
        else:
            n = model.n_states
            eye = np.eye(n)
            self.gamma_vars, self.psi_vars = [], []
            for i, wi in enumerate(self.w):
                Hi_minus_D = scr.Affine(H[i] - maps["D"].X0, {theta: -_theta_coef(maps["D"])})
                if self.substitution in ("gamma", "both"):
                    G = scr.Variable(f"Gamma{i}", (n, m), complex=True)
                    variables.append(G)
                    self.gamma_vars.append(G)
                    Gi = scr.Affine(np.zeros((n, m)), {G: _identity((n, m))})
                    rhs = scr.Affine(-maps["B"].X0, {G: 1j * wi * _identity((n, m)), theta: -_theta_coef(maps["B"])})
                    add("gamma_dynamics", i, A=aff(maps["A"]), P=eye, B=Gi, C=rhs)
                    add("gamma_output", i, A=aff(maps["C"]), P=eye, B=Gi, C=Hi_minus_D)
                if self.substitution in ("psi", "both"):
                    S = scr.Variable(f"Psi{i}", (p, n), complex=True)
                    variables.append(S)
                    self.psi_vars.append(S)
                    Si = scr.Affine(np.zeros((p, n)), {S: _identity((p, n))})
                    rhs = scr.Affine(-maps["C"].X0, {S: 1j * wi * _identity((p, n)), theta: -_theta_coef(maps["C"])})
                    add("psi_dynamics", i, A=Si, P=eye, B=aff(maps["A"]), C=rhs)
                    add("psi_output", i, A=Si, P=eye, B=aff(maps["B"]), C=Hi_minus_D)
        # positivity declared on parameters: θk ≥ 0 as 1×1 LMIs
        for k, pos in enumerate(model.positive):
            if pos:
                coef = np.zeros((1, 1, l))
                coef[0, 0, k] = 1.0
                lmi_list.append(scr.Affine(np.zeros((1, 1)), {theta: coef}))
        self.theta_var = theta
        return scr.BilinearProblem(variables=variables, bilinear=terms, lmis=lmi_list)

    # -- one start ---------------------------------------------------------------------------
    def _aux_start(self, x0: np.ndarray) -> dict[str, Any]:
        model = self.model
        start: dict[str, Any] = {"theta": x0}
        mode = self.gamma0
        gam = psi = None
        if mode == "model":
            try:
                if self.second_order:
                    mats = model.matrices(x0)
                    M, V, K, B = (mats[k] for k in "MVKB")
                    Z = -(self.w**2)[:, None, None] * M + 1j * self.w[:, None, None] * V + K
                    gam = np.linalg.solve(Z, np.broadcast_to(B.astype(complex), (self.w.size, *B.shape)))
                else:
                    A, B, C, _ = model.state_space(x0)
                    Z = 1j * self.w[:, None, None] * np.eye(A.shape[0]) - A
                    gam = np.linalg.solve(Z, np.broadcast_to(B.astype(complex), (self.w.size, *B.shape)))
                    psi = np.swapaxes(np.linalg.solve(np.swapaxes(Z, 1, 2),
                                                      np.broadcast_to(C.T.astype(complex), (self.w.size, *C.T.shape))),
                                      1, 2)
                if not np.all(np.isfinite(gam)) or (psi is not None and not np.all(np.isfinite(psi))):
                    gam = psi = None
            except (np.linalg.LinAlgError, ModelError):
                gam = psi = None
            if gam is None:
                mode = "random"
        rng = np.random.default_rng([self._rng_seed, *np.abs(np.round(x0 * 1e6)).astype(np.int64).tolist()[:4]])
        for i, G in enumerate(self.gamma_vars):
            if mode == "model":
                start[G.name] = gam[i]
            elif mode == "random":
                start[G.name] = rng.standard_normal(G.shape) + 1j * rng.standard_normal(G.shape)
        for i, S in enumerate(getattr(self, "psi_vars", [])):
            if mode == "model" and psi is not None:
                start[S.name] = psi[i]
            elif mode == "random":
                start[S.name] = rng.standard_normal(S.shape) + 1j * rng.standard_normal(S.shape)
        return start

    def solve(self, x0: np.ndarray, callback: Any = None) -> scr.SCRSolution:
        """The raw engine solution from the start ``x0`` (parameter vector); ``callback`` as :func:`symid.scr.solve`."""
        return scr.solve(self.compiled, self._aux_start(np.asarray(x0, dtype=float)), callback=callback,
                         **self._solve_opts)

    def family_residuals(self, sol: scr.SCRSolution) -> dict[str, list[float]]:
        """Per iteration, the summed residual of each constraint family (thesis Figure 3-2's f_q)."""
        return {fam: [float(np.sum(np.asarray(h.residuals)[idx])) for h in sol.history]
                for fam, idx in self.families.items()}

    def _history(self, sol: scr.SCRSolution) -> tuple[dict[str, Any], ...]:
        """Per iteration: residual, objective, relaxation, time, θ and the family residuals."""
        fams = self.family_residuals(sol)
        return tuple({"residual": h.residual, "objective": h.objective, "relaxation": h.relaxation, "time": h.time,
                      "theta": np.asarray(it["theta"], dtype=float).reshape(-1).tolist(),
                      "families": {f: v[k] for f, v in fams.items()}}
                     for k, (h, it) in enumerate(zip(sol.history, sol.iterates, strict=True)))

    def _outcome(self, x0: np.ndarray, callback: Any = None) -> tuple[StartOutcome, str]:
        """SCR from ``x0`` as a start outcome, and the engine's status."""
        t0 = time.perf_counter()
        try:
            sol = self.solve(x0, callback)
        except (np.linalg.LinAlgError, ArithmeticError) as exc:  # a numerical breakdown inside the engine
            return StartOutcome(start=x0, theta=np.full_like(x0, np.nan), cost=float("inf"), converged=False,
                                iterations=0, wall_time=time.perf_counter() - t0,
                                message=f"SCR failed: {type(exc).__name__}: {exc}"), "failed"
        elapsed = time.perf_counter() - t0
        theta = np.asarray(sol.x["theta"], dtype=float).reshape(-1)
        cost = relative_misfit(self.model, self.data, theta)
        return StartOutcome(start=x0, theta=theta, cost=cost, converged=bool(sol.success and np.isfinite(cost)),
                            iterations=sol.iterations, wall_time=elapsed, message=sol.message,
                            history=self._history(sol)), sol.status

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start ``x0``; never raises on solver failure."""
        return self._outcome(np.asarray(x0, dtype=float))[0]

    def run_polished(self, x0: np.ndarray, polisher: Any) -> StartOutcome:
        """``"scr+polish"`` from the start ``x0``: SCR hands over to ``polisher`` once in a good basin.

        After SCR iterations 1, 2, 4, 8, … (while SCR has not converged) a trial
        ``polisher.run`` starts from the current SCR estimate; the first trial whose
        relative misfit is ≤ ``polish_misfit`` ends the start. Without such a trial, SCR
        runs to its own end and :func:`symid.polish.polish_outcome` refines its estimate.
        Time and iterations are those of SCR plus every polish, trials included;
        ``history`` is SCR's.

        Measured on the 2-DOF mass-damper (``benchmarks/frf.py``): the trial after the
        first SCR iteration is accepted from most starts, so SCR's tail, where its time
        goes (scr-lessons 5), is skipped.
        """
        x0 = np.asarray(x0, dtype=float)
        t0 = time.perf_counter()
        trials: list[tuple[int, StartOutcome]] = []
        threshold = self.polish_misfit

        def trial(k: int, x: dict[str, Any]) -> bool:
            if threshold is None or k & (k - 1):  # powers of two only: trials cost at most ~log2(k) polishes
                return False
            out = polisher.run(np.asarray(x["theta"], dtype=float).reshape(-1))
            trials.append((k, out))
            return bool(np.isfinite(out.cost) and out.cost <= threshold)

        base, status = self._outcome(x0, trial)
        name = getattr(polisher, "method", type(polisher).__name__)
        spent = sum(o.iterations for _, o in trials)
        if status == "stopped":
            k, pol = trials[-1]
            return StartOutcome(start=x0, theta=pol.theta, cost=pol.cost, converged=bool(pol.converged),
                                iterations=base.iterations + spent, wall_time=time.perf_counter() - t0,
                                message=f"SCR handed over to {name} after {k} iteration{'s' * (k > 1)} "
                                        f"({len(trials)} trial polish{'es' * (len(trials) > 1)}): misfit "
                                        f"{pol.cost:.3e} ≤ {threshold:g}; {name}: {pol.message}",
                                history=base.history)
        final = polish_outcome(polisher, base)
        note = f"; {len(trials)} trial polishes above misfit {threshold:g}" if trials else ""
        return dataclasses.replace(final, iterations=final.iterations + spent, wall_time=time.perf_counter() - t0,
                                   message=final.message + note)
