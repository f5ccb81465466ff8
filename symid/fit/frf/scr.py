"""SCR formulations for frequency responses: thesis Algorithm 3.1 (state space) and (4-8) (second order).

State space, for every frequency ωᵢ (thesis (3-15)):

- Γ substitution (3-10): A(θ) Γᵢ = jωᵢ Γᵢ − B(θ) and Hᵢ − D(θ) = C(θ) Γᵢ;
- Ψ substitution (3-12): Ψᵢ A(θ) = jωᵢ Ψᵢ − C(θ) and Hᵢ − D(θ) = Ψᵢ B(θ).

Second order (4-8): [M(θ) V(θ) K(θ)] Pᵢ Γᵢ = B(θ) with Pᵢ = [−ωᵢ² I; jωᵢ I; I] (the thesis
prints −jωᵢ in (4-7)/(4-8); the sign must be + for Z = −ω²M + jωV + K of (4-5)), and
Hᵢ = fᵢ C(θ) Γᵢ with fᵢ = 1, jωᵢ or −ωᵢ² for position, velocity or acceleration output
(4-9); M, V, K ⪰ 0 as LMIs when they are symmetric.

Every equation is posed as a bilinear term; the engine's presolve turns the rows that
hold no product of unknowns into linear equalities and eliminates what they determine,
so only what is truly bilinear is relaxed.

Choices, measured (``examples/belt_drive_scr.py``, ``examples/mass_damper_2dof_scr.py``,
``benchmarks/frf.py``):

- Γ alone by default. On the belt drive from zero, every equation relaxed, Γ reaches
  ‖θ − θ*‖₂ ≤ 1e-6 (ADMM: iteration 131; Clarabel: 84); Γ and Ψ with unit weights
  stall (ADMM 2e-2, Clarabel 0.26 after 1000 / 300 iterations); with the Ψ families
  weighed δ = ρ = 0.01 they converge (1e-6 at iteration 95).
- Unit weights λᵢ = γᵢ = 1 otherwise, as the thesis; the engine equilibrates every block
  (rows by A P and C, columns by P B and C, P), which is the block scaling. With rows
  equilibrated by A alone, the stacked Pᵢ of (4-8) left A P ~ 1/ωᵢ² beside P B on
  problems in physical units (ω ~ 10²), and the first sub-problem from a start within
  a factor 3 of the truth of a 2-mass chain drove θ to ~0.03 θ* (Clarabel).
- Γᵢ started from the model at the start θ₀ (``aux_init="model"``), seeded N(0, 1)
  draws where Z(θ₀) is singular. A start at a solution is then a fixed point: from the
  truth of 20 generated problems (``benchmarks/population_models.py``: chains, chains
  with two sensors, gains, state-space networks, compartment models; n = 2, 3; physical
  values; ``scale=`` the typical values) SCR stays there 20 times, against 6 with random
  Γᵢ, which walk away (issue 14). From 40 informed and 40 uninformed starts of the same
  problems both succeed equally rarely (6 and 6 informed; 4 and 5 uninformed, 15 s per
  start); on the 2-DOF, 3 seeds × 20 N(0, 1) starts, 55 against 58 of 60
  (``benchmarks/scr_robust.py``, sections ``population_aux_init``, ``thesis_aux_init``).
- Noisy data: the output equations Hᵢ = fᵢCΓᵢ, split off by the presolve, are kept in
  the least-squares sense (:mod:`symid.engine.scr.presolve`, step 3): when they and
  the known rows fix every unknown (the belt drive), SCR returns the least-squares
  estimate of its equations, each real equation's error weighed by the size of its
  terms, independent of units (it is not the least-squares fit of H: on the belt
  drive's 10 lines with noise 1e-4 its misfit is 3.7 times the truth's and more than
  ten times a vector fit's, so the success rule does not call it a fit; ``"scr+polish"``
  does fit); otherwise SCR stops once its iterate no longer moves
  (status ``"stationary"``) and the fit test judges the estimate. On the 2-DOF with 1 %
  noise, 5 records × 5 starts: SCR alone fits 24 of 25 times, at a median 1.5 (at most
  2.3) of IPOPT's standard errors from IPOPT's estimate — SCR's fixed point minimises
  its equations, not the output misfit — and ``"scr+polish"`` returns IPOPT's estimate
  (relative difference ≤ 3e-10) 25 of 25 times in a median 0.13 s
  (``benchmarks/scr_robust.py``, section ``noise``).
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
  trial polish from the current SCR estimate fits the data (a success by the fit rule,
  so noisy data qualify, or misfit ≤ 1e-8); on the 2-DOF that is after the first SCR
  iteration from most starts (``benchmarks/frf.py``). A trial runs at most
  ``trial_max_iter`` = 100 IPOPT iterations: on the 2-DOF (20 starts each on the exact
  data and two 1 %-noise records) the 59 accepted trials took at most 40 (median 20),
  while 5 of the 55 rejected ones ran 1010–3000 (issue 14: one start of a 3-mass chain
  took 282 s that way).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from symid import scr
from symid.errors import ModelError, OptionError
from symid.fit.base import ScrEstimator, identity_coef, mvk_lmis, positivity_lmis, theta_coef
from symid.fit.frf.misfit import VARIANCE_OPTION_DOC, FrfEstimator, NoiseWeighted
from symid.fit.options import check_bool, check_choice, check_float, check_int, check_scale, check_seed
from symid.fit.polish import polish_outcome
from symid.fit.result import StartOutcome
from symid.model.secondorder import MIXED, output_factor

__all__ = ["ScrFRF"]

# constraint families: key of ``weights`` → label in plots (thesis Algorithm 3.1 weights λ, γ, δ, ρ)
_FAMILIES_STATE_SPACE = {"gamma_dynamics": "f1: A Γ = jωΓ − B  (λ)", "gamma_output": "f2: H − D = C Γ  (γ)",
                         "psi_dynamics": "f3: Ψ A = jωΨ − C  (δ)", "psi_output": "f4: H − D = Ψ B  (ρ)"}
_FAMILIES_SECOND_ORDER = {"dynamics": "[M V K] P Γ = B", "output": "H = f C Γ"}
_AUX_INITS = ("random", "model", "zero")
_BUILT_KEPT = 4  # problems kept for the automatic scales of the last starts


class ScrFRF(NoiseWeighted, ScrEstimator, FrfEstimator):
    """Sequential convex relaxation on a frequency response, built once, run per start.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData
    substitution : {"gamma", "psi", "both"}, optional
        State-space models: which substitution of thesis (3-10)/(3-12) to use
        (default ``"gamma"``; the thesis uses both, but with C known Ψ only slows
        convergence, see the module notes). Second-order models always use Γ.
    weights : array_like or dict, optional
        Weights of the nuclear-norm relaxations (Algorithm 3.1's λᵢ, γᵢ, δᵢ, ρᵢ). An
        array of one positive number per frequency weighs every constraint family at
        that frequency alike (3-15); a dict weighs families apart, by key
        ``"gamma_dynamics"`` (λ), ``"gamma_output"`` (γ), ``"psi_dynamics"`` (δ),
        ``"psi_output"`` (ρ) for a state-space model and ``"dynamics"``, ``"output"``
        for a second-order one, each a number or one number per frequency (missing
        families weigh 1). Default: 1 everywhere, as the thesis's examples. The engine
        first equilibrates every term (:mod:`symid.engine.scr.presolve`), so a weight means the
        same whatever the units of H. With a noise variance (``variance``) every family's
        weight at ωᵢ is further multiplied by the noise weight of that line (below).
    {variance}
        SCR weighs the relaxation of every equation at ωᵢ (λᵢ, γᵢ, δᵢ, ρᵢ) by
        qᵢ ∝ gᵢ / σ̄ᵢ (mean 1), σ̄²ᵢ the mean variance of the entries of Hᵢ and gᵢ the size
        by which SCR divides Γᵢ (``scale``; hᵢ for Ψᵢ): σ̄ᵢ / gᵢ is the noise Hᵢ puts on
        the unknowns SCR works on, and the nuclear norm grows like the equation error,
        not its square. Noise of the same relative size on every line (σ̄ᵢ ∝ gᵢ) gives
        about the unweighted SCR. Measured on the 2-DOF from a start within a factor 2.5
        (``benchmarks/frf_weighting.py``, 20 records each): the mean squared parameter
        error of SCR alone is 0.012, 0.058 and 0.15 of the unweighted SCR's with noise
        0.1 % / 3 % of |H| on the lower / upper half of the band, rising geometrically
        between them, or of constant size; qᵢ ∝ 1 / σ̄ᵢ gave 0.030, 0.30 and 1.0 (8 records).
        The misfit SCR reports, its success rule (judged against the declared noise) and
        the IPOPT polish of ``"scr+polish"`` use the same variance. Equations the presolve
        solves as linear least squares (the output equations when they and the known
        rows fix every unknown, e.g. the belt drive) keep their weights by the size of
        their terms: there the noise enters through the polish only.
    lmis : bool, optional
        Second-order models: M, V, K ⪰ 0 (default True; thesis §5-7 shows they are decisive).
    positivity : bool, optional
        Parameters declared positive are constrained ≥ 0 (1×1 LMIs; default True).
    backend : {"admm", "cvxpy"}
        Engine back end (default ``"admm"``: numpy ADMM, LMIs by projection, tens of
        milliseconds per SCR iteration here; ``"cvxpy"``, Clarabel, solves each
        sub-problem exactly and needs fewer iterations but costs about a second per
        iteration on the 2-DOF problem, see ``benchmarks/frf.py``).
    max_iter : int
        SCR iterations per start (default 500).
    tol : float
        Stop when the largest normalised bilinear residual is ≤ ``tol`` and the step is
        small (default 1e-6: the ADMM back end is inexact near 1e-7; use
        ``polish`` in :func:`symid.identify` / ``"scr+polish"`` in :func:`symid.compare`
        for full precision).
    aux_init : {"model", "random", "zero"}
        Initial Γᵢ (and Ψᵢ): computed from the model at the start θ (default
        ``"model"``: Γᵢ = Z(θ₀, ωᵢ)⁻¹ B(θ₀), so a start at a solution is a fixed point and
        SCR stays there), falling back to seeded N(0, 1) draws when the model cannot be
        evaluated at the start (a singular Z(θ₀), e.g. θ₀ = 0 for a second-order model);
        ``"random"``: the seeded draws always; ``"zero"``: thesis ch. 3, "all matrices
        initialised as zero". See the module notes for what was measured.
    seed : int
        Seed of the random Γᵢ, combined with the start θ (so a start gives the same run
        every time).
    presolve : bool
        Let the engine turn the rows that hold no product of unknowns into linear
        equalities and eliminate what they fix (default True; ``False`` relaxes every
        equation, as the thesis posed (3-15)).
    heuristic : {"nuclear", "truncated"}
        Rank surrogate of the engine (:func:`symid.engine.scr.solve`).
    admm : symid.engine.scr.ADMMOptions, optional
        Options of the ADMM back end. Default: the engine's, except ``eps_rel=1e-2`` for
        second-order models (sub-problems solved to 1% while the bilinear residual is
        large, to the residual's level once it is smaller, through the engine's
        ``tighten``; see the module docstring).
    scale : array_like, optional
        Typical magnitude of each parameter (one number or one per parameter). SCR then
        works on φ = θ / scale, and each Γᵢ (Ψᵢ) on Γᵢ / gᵢ with gᵢ the size of Γᵢ of the
        model at θ = scale, so that every unknown is of order one whatever the units.
        Default: the same from each start θ₀ (scale |θ₀ₖ|, 1 where θ₀ₖ = 0; gᵢ the size of
        Γᵢ at θ = |θ₀|; the problem is rebuilt per start, ~0.3–0.6 s for a 100-frequency chain),
        so that the estimate moves with the units of θ, ω and H exactly as the physics
        says (``tests/test_scr_robust.py``). ``scale=1`` works on θ as it is.
    time_limit : float, optional
        Wall-time budget of one start in seconds (status ``"time_limit"``): the SCR
        iteration under way is cut short when it is spent (:func:`symid.engine.scr.solve`),
        and ``"scr+polish"`` runs no trial polish after it. Default: none.
    polish_misfit : float or None
        ``"scr+polish"`` (:meth:`run_polished`): after SCR iterations 1, 2, 4, 8, … a
        trial polish runs from the current SCR estimate, and SCR stops as soon as one
        fits the data: a success by the rule every method is held to
        (:mod:`symid.fit.success`; noisy data qualify by their white residual) or a
        relative data misfit ≤ ``polish_misfit`` (default 1e-8, the misfit criterion of
        :func:`symid.compare`); otherwise SCR runs to its own end and is polished then.
        ``None``: no trial, polish the final SCR estimate only.
    trial_max_iter : int
        IPOPT iterations of one trial polish (default 100): a trial from outside the
        basin stops there instead of running IPOPT to its own limit (3000).
    callback : callable, optional
        Called after every SCR iteration with a :class:`symid.engine.scr.ScrProgress`
        (iteration, bilinear residual, data misfit, elapsed seconds, θ); a true return
        value stops the start (status ``"stopped"``).
    verbose : bool
        Print one line per SCR iteration (iteration, residual, misfit, elapsed). Default False.
    """

    def __init__(self, model: Any, data: Any, *, substitution: str = "gamma", weights: Any = None,
                 lmis: bool = True, positivity: bool = True, backend: str = "admm", max_iter: int = 500,
                 tol: float = 1e-6, aux_init: str = "model", seed: int = 0, presolve: bool = True,
                 heuristic: str = "nuclear", admm: Any = None, scale: Any = None, time_limit: float | None = None,
                 polish_misfit: float | None = 1e-8, trial_max_iter: int = 100, callback: Any = None,
                 verbose: bool = False, variance: Any = "data"):
        substitution = check_choice("substitution", substitution, ("gamma", "psi", "both"))
        self.aux_init = check_choice("aux_init", aux_init, _AUX_INITS)
        lmis, positivity = check_bool("lmis", lmis), check_bool("positivity", positivity)
        if polish_misfit is not None:
            polish_misfit = check_float("polish_misfit", polish_misfit, low=0, strict_low=True)
        self._rng_seed = check_seed("seed", seed)
        self._progress_options(callback, verbose)
        self.model, self.data = model, data
        self.second_order = "M" in model.maps
        if self.second_order:
            substitution = "gamma"
        self.substitution = substitution
        self.w = np.asarray(data.w, dtype=float)
        l = model.n_parameters
        self._auto = scale is None
        given = not self._auto
        self.scale = check_scale("scale", scale, l) if given else np.ones(l)
        self._aux_scale, self._psi_scale = self._aux_scales(self.scale if given else None)
        variance_label = self.set_variance(variance)
        self._variance = variance
        lam = self._weights(weights)  # the noise weights join them in _build, with the sizes of Γᵢ, Ψᵢ
        solve_opts = self._engine_options(backend=backend, max_iter=max_iter, tol=tol, heuristic=heuristic,
                                          admm=admm, time_limit=time_limit)
        if admm is None and backend == "admm" and self.second_order:
            solve_opts["admm"] = scr.ADMMOptions(eps_rel=1e-2)  # measured, see the module docstring
        self.options = {"substitution": substitution, "weights": "uniform" if weights is None else "given",
                        "lmis": lmis, "positivity": positivity, "backend": backend, "max_iter": max_iter,
                        "tol": tol, "aux_init": aux_init, "seed": seed, "presolve": presolve,
                        "heuristic": heuristic, "scale": self.scale.tolist() if given else scale,
                        "time_limit": solve_opts["time_limit"], "callback": None if callback is None else "given",
                        "verbose": self._verbose, "variance": variance_label}
        self.polish_misfit = polish_misfit
        self.trial_max_iter = check_int("trial_max_iter", trial_max_iter, low=1, high=10**7)
        self.options["trial_max_iter"] = self.trial_max_iter
        # measured data never satisfy the equalities the presolve splits off exactly: least squares
        self._build_args, self._presolve = (lam, lmis, positivity), presolve
        self._setup_engine(self._build(lam, lmis, positivity), solve_opts, presolve=presolve,
                           equalities="least_squares")
        self._built: dict[bytes, tuple] = {}
        self._current: bytes | None = None

    def polisher(self) -> Any:
        """IPOPT on the same frequency response (:class:`~symid.fit.frf.ipopt.IpoptFRF`), with the same
        positivity, scale, noise variance and time limit (its ``run`` takes per-run ``max_iter``/``time_limit``
        caps)."""
        from symid.fit.frf.ipopt import IpoptFRF

        scale = None if self._auto else self.options["scale"]  # IPOPT scales itself from its start
        return IpoptFRF(self.model, self.data, positivity=self.options["positivity"], scale=scale,
                        time_limit=self.options["time_limit"], variance=self._variance)

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
            try:
                np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise OptionError(f"{what} must be a positive number or {s} positive numbers (one per frequency); "
                                  f"got {value!r}") from None
            v = np.broadcast_to(np.asarray(value, dtype=float), (s,)) if np.ndim(value) == 0 else \
                np.asarray(value, dtype=float).reshape(-1)
            if v.shape != (s,) or np.any(~np.isfinite(v)) or np.any(v <= 0):
                raise OptionError(f"{what} must be a positive number or {s} positive finite numbers "
                                 f"(one per frequency); got {np.asarray(value).shape} values")
            return np.array(v, dtype=float)

        if weights is None:
            return {k: np.ones(s) for k in fams}
        if isinstance(weights, dict):
            unknown = sorted(set(weights) - set(fams))
            if unknown:
                raise OptionError(f"weights for unknown constraint famil{'y' if len(unknown) == 1 else 'ies'} "
                                 f"{', '.join(unknown)}; this formulation has {', '.join(fams)}")
            return {k: vector(weights.get(k, 1.0), f"weights[{k!r}]") for k in fams}
        lam = vector(weights, "weights")
        return {k: lam for k in fams}

    def _noise_weighted(self, lam: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The relaxation weights times the noise weight of every line, gᵢ / σ̄ᵢ for the Γ families and hᵢ / σ̄ᵢ
        for the Ψ ones (scaled to mean 1; class text); unchanged without a variance."""
        var = self.variance_shape
        if var is None:
            return lam
        sbar = np.sqrt(np.mean(var.reshape(self.w.size, -1), axis=1))
        out = {}
        for key, v in lam.items():
            q = (self._psi_scale if key.startswith("psi") else self._aux_scale) / sbar
            out[key] = v * (q / np.mean(q))
        return out

    def _build(self, lam: dict[str, np.ndarray], lmis: bool, positivity: bool) -> scr.BilinearProblem:
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
        lam = self._noise_weighted(lam)

        def add(family: str, i: int, **maps_: Any) -> None:
            """The bilinear term A P B = C of frequency i in a constraint family, with its weight."""
            self.families.setdefault(labels[family], []).append(len(terms))
            terms.append(scr.Bilinear(**maps_, weight=float(lam[family][i]), name=f"{family}[{i}]"))

        sc = self.scale
        g = self._aux_scale

        def tc(amap: Any) -> np.ndarray:  # coefficients of φ = θ / scale
            return theta_coef(amap) * sc

        def aff(amap: Any, sign: float = 1.0) -> scr.Affine:
            return scr.Affine(sign * amap.X0, {theta: sign * tc(amap)})

        if self.second_order:
            n = model.n_dof
            MVK0 = np.hstack([maps["M"].X0, maps["V"].X0, maps["K"].X0])
            MVKc = np.concatenate([tc(maps["M"]), tc(maps["V"]), tc(maps["K"])], axis=1)
            A_mvk = scr.Affine(MVK0, {theta: MVKc})
            f = output_factor(model, self.w)  # (s, p): each output row times (jω)ᵈ
            C0, Cc = maps["C"].X0, tc(maps["C"])
            self.gamma_vars = []
            for i, wi in enumerate(self.w):
                G = scr.Variable(f"Gamma{i}", (n, m), complex=True)
                variables.append(G)
                self.gamma_vars.append(G)
                Pi = np.vstack([-(wi**2) * np.eye(n), 1j * wi * np.eye(n), np.eye(n)])
                Gi = scr.Affine(np.zeros((n, m)), {G: g[i] * identity_coef((n, m))})
                add("dynamics", i, A=A_mvk, P=Pi, B=Gi, C=aff(maps["B"]))
                if model.output != MIXED:  # Hᵢ = fᵢ C Γᵢ
                    add("output", i, A=aff(maps["C"]), P=f[i, 0] * np.eye(n), B=Gi, C=scr.Affine(H[i]))
                else:  # Hᵢ = diag(fᵢ) C(θ) Γᵢ, the rows' factors in the map of C
                    Cf = scr.Affine(f[i][:, None] * C0, {theta: f[i][:, None, None] * Cc})
                    add("output", i, A=Cf, P=np.eye(n), B=Gi, C=scr.Affine(H[i]))
            if lmis:
                lmi_list.extend(mvk_lmis(maps, theta, self.options, scale=sc))
        else:
            n = model.n_states
            eye = np.eye(n)
            self.gamma_vars, self.psi_vars = [], []
            for i, wi in enumerate(self.w):
                Hi_minus_D = scr.Affine(H[i] - maps["D"].X0, {theta: -tc(maps["D"])})
                if self.substitution in ("gamma", "both"):
                    G = scr.Variable(f"Gamma{i}", (n, m), complex=True)
                    variables.append(G)
                    self.gamma_vars.append(G)
                    Gi = scr.Affine(np.zeros((n, m)), {G: g[i] * identity_coef((n, m))})
                    rhs = scr.Affine(-maps["B"].X0, {G: 1j * wi * g[i] * identity_coef((n, m)), theta: -tc(maps["B"])})
                    add("gamma_dynamics", i, A=aff(maps["A"]), P=eye, B=Gi, C=rhs)
                    add("gamma_output", i, A=aff(maps["C"]), P=eye, B=Gi, C=Hi_minus_D)
                if self.substitution in ("psi", "both"):
                    S = scr.Variable(f"Psi{i}", (p, n), complex=True)
                    variables.append(S)
                    self.psi_vars.append(S)
                    h = self._psi_scale[i]
                    Si = scr.Affine(np.zeros((p, n)), {S: h * identity_coef((p, n))})
                    rhs = scr.Affine(-maps["C"].X0, {S: 1j * wi * h * identity_coef((p, n)), theta: -tc(maps["C"])})
                    add("psi_dynamics", i, A=Si, P=eye, B=aff(maps["A"]), C=rhs)
                    add("psi_output", i, A=Si, P=eye, B=aff(maps["B"]), C=Hi_minus_D)
        if positivity:  # θk ≥ 0 for the parameters declared positive
            lmi_list.extend(positivity_lmis(model, theta))
        self.theta_var = theta
        return scr.BilinearProblem(variables=variables, bilinear=terms, lmis=lmi_list)

    def _aux_scales(self, reference: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """gᵢ, hᵢ: the size (largest entry) of Γᵢ and Ψᵢ of the model at θ = ``reference``, or 1 (none given,
        or the model cannot be evaluated there)."""
        ones = np.ones(self.w.size)
        aux = None if reference is None else self._model_aux(reference)
        if aux is None:
            return ones, ones

        def size(x: np.ndarray) -> np.ndarray:
            top = np.abs(x).reshape(self.w.size, -1).max(axis=1)
            return np.where((top > 0) & np.isfinite(top), top, 1.0)

        gam, psi = aux
        return size(gam), (ones if psi is None else size(psi))

    def _model_gamma(self, theta: np.ndarray) -> np.ndarray | None:
        """Γᵢ of the model at θ for every frequency (``None`` where it cannot be evaluated)."""
        aux = self._model_aux(theta)
        return None if aux is None else aux[0]

    def _model_aux(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray | None] | None:
        """Γᵢ = Z(θ, ωᵢ)⁻¹B(θ) and (state space) Ψᵢ = C(θ)(jωᵢI − A(θ))⁻¹ for every frequency, or ``None``
        where the model cannot be evaluated (a singular Z, non-finite values)."""
        psi = None
        try:
            if self.second_order:
                mats = self.model.matrices(theta)
                M, V, K, B = (mats[k] for k in "MVKB")
                Z = -(self.w**2)[:, None, None] * M + 1j * self.w[:, None, None] * V + K
            else:
                A, B, C, _ = self.model.state_space(theta)
                Z = 1j * self.w[:, None, None] * np.eye(A.shape[0]) - A
                Ct = np.broadcast_to(C.T.astype(complex), (self.w.size, *C.T.shape))
                psi = np.swapaxes(np.linalg.solve(np.swapaxes(Z, 1, 2), Ct), 1, 2)
            gam = np.linalg.solve(Z, np.broadcast_to(B.astype(complex), (self.w.size, *B.shape)))
        except (np.linalg.LinAlgError, ModelError):
            return None
        if not np.all(np.isfinite(gam)) or (psi is not None and not np.all(np.isfinite(psi))):
            return None
        return gam, psi

    # -- one start ---------------------------------------------------------------------------
    @staticmethod
    def start_scale(x0: np.ndarray) -> np.ndarray:
        """The automatic scale of a start: |θ₀ₖ| where it is finite and nonzero, else 1 (no unit to read)."""
        mag = np.abs(np.asarray(x0, dtype=float))
        return np.where(np.isfinite(mag) & (mag > 0), mag, 1.0)

    def _use_scale(self, x0: np.ndarray) -> None:
        """Without ``scale=``: the problem for the start's own scale (θ / |θ₀|, Γᵢ and Ψᵢ by their size at θ₀),
        built once per distinct scale (the last few are kept)."""
        sc = self.start_scale(x0)
        key = sc.tobytes()
        if key == self._current:
            return
        built = self._built.pop(key, None)
        if built is None:
            self.scale = sc
            # Γᵢ, Ψᵢ sized at θ = |θ₀| as for a given scale: at a start with negative entries (thesis N(0, 1)
            # draws) the model's resonances sit elsewhere (measured, 2-DOF, 10 thesis starts: 8 succeed sized
            # at |θ₀|, 6 sized at θ₀)
            self._aux_scale, self._psi_scale = self._aux_scales(sc)
            problem = self._build(*self._build_args)
            self._setup_engine(problem, self._solve_opts, presolve=self._presolve, equalities="least_squares")
            built = (sc, self._aux_scale, self._psi_scale, self.problem, self.compiled, self.families,
                     self.gamma_vars, getattr(self, "psi_vars", []), self.theta_var)
        (self.scale, self._aux_scale, self._psi_scale, self.problem, self.compiled, self.families,
         self.gamma_vars, self.psi_vars, self.theta_var) = built
        self._built[key] = built
        while len(self._built) > _BUILT_KEPT:
            self._built.pop(next(iter(self._built)))
        self._current = key

    def _aux_start(self, x0: np.ndarray) -> dict[str, Any]:
        start: dict[str, Any] = {"theta": x0 / self.scale}
        mode = self.aux_init
        aux = self._model_aux(x0) if mode == "model" else None
        if mode == "model" and aux is None:
            mode = "random"  # the model cannot be evaluated at the start: seeded draws
        gam, psi = aux if aux is not None else (None, None)
        # seeded by the start too, in the units SCR works in (θ₀ / scale: the same draws whatever the units),
        # its first 4 entries to 1e-6, capped so that huge values cannot overflow
        key = np.minimum(np.abs(np.round(start["theta"][:4] * 1e6)), 2.0**62).astype(np.int64).tolist()
        rng = np.random.default_rng([self._rng_seed, *key])
        for i, G in enumerate(self.gamma_vars):
            if mode == "model":
                start[G.name] = gam[i] / self._aux_scale[i]
            elif mode == "random":
                start[G.name] = rng.standard_normal(G.shape) + 1j * rng.standard_normal(G.shape)
        for i, S in enumerate(getattr(self, "psi_vars", [])):
            if mode == "model" and psi is not None:
                start[S.name] = psi[i] / self._psi_scale[i]
            elif mode == "random":
                start[S.name] = rng.standard_normal(S.shape) + 1j * rng.standard_normal(S.shape)
        return start

    def solve(self, x0: np.ndarray, callback: Any = None, monitor: Any = None) -> scr.SCRSolution:
        """The raw engine solution from the start ``x0`` (θ in ``sol.x["theta"]`` is θ / :attr:`scale`);
        ``callback``, ``monitor`` as :func:`symid.engine.scr.solve`."""
        x0 = np.asarray(x0, dtype=float)
        if self._auto:
            self._use_scale(x0)
        return self.engine_solve(self._aux_start(x0), callback=callback, monitor=monitor)

    def family_residuals(self, sol: scr.SCRSolution) -> dict[str, list[float]]:
        """Per iteration, the summed residual of each constraint family (thesis Figure 3-2's f_q)."""
        return {fam: [float(np.sum(np.asarray(h.residuals)[idx])) for h in sol.history]
                for fam, idx in self.families.items()}

    def _outcome(self, x0: np.ndarray, callback: Any = None) -> tuple[StartOutcome, str]:
        """SCR from ``x0`` as a start outcome, and the engine's status."""
        t0 = time.perf_counter()
        monitor = self.engine_monitor(lambda x: np.asarray(x["theta"], dtype=float).reshape(-1) * self.scale, t0)
        try:
            sol = self.solve(x0, callback, monitor)
        except (np.linalg.LinAlgError, ArithmeticError) as exc:  # a numerical breakdown inside the engine
            return self.outcome(x0, np.full_like(x0, np.nan), finished=False, status="failed",
                                message=f"SCR failed: {type(exc).__name__}: {exc}", iterations=0,
                                wall_time=time.perf_counter() - t0), "failed"
        theta = np.asarray(sol.x["theta"], dtype=float).reshape(-1) * self.scale
        hist = self.engine_history(sol, theta_of=lambda it: np.asarray(it["theta"]).reshape(-1) * self.scale,
                                   families=self.families)
        return self.solved_outcome(x0, theta, sol, t0, history=hist), sol.status

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start ``x0``; never raises on solver failure."""
        return self._outcome(np.asarray(x0, dtype=float))[0]

    def run_polished(self, x0: np.ndarray, polisher: Any) -> StartOutcome:
        """``"scr+polish"`` from the start ``x0``: SCR hands over to ``polisher`` once in a good basin.

        After SCR iterations 1, 2, 4, 8, … (while SCR has not converged) a trial polish
        (``polisher.run`` capped at ``trial_max_iter`` iterations and at the time left of
        the start's ``time_limit``; ``polisher`` is IPOPT, :meth:`polisher`) starts from
        the current SCR estimate; the first trial that fits the data — a success by the
        rule every method is held to (:mod:`symid.fit.success`: exact fit, noise floor or
        white residual), or a misfit ≤ ``polish_misfit`` — ends the start (a trial that
        fits but hit its cap is finished by ``polisher``). Without such a trial, SCR runs
        to its own end and :func:`symid.fit.polish.polish_outcome` refines its estimate.
        Every polish gets the time the start has left. Time and iterations are those of
        SCR plus every polish, trials included; ``history`` is SCR's.

        Measured on the 2-DOF mass-damper (``benchmarks/frf.py``): the trial after the
        first SCR iteration is accepted from most starts, so SCR's slow tail is skipped.
        """
        x0 = np.asarray(x0, dtype=float)
        t0 = time.perf_counter()
        trials: list[tuple[int, StartOutcome]] = []
        threshold = self.polish_misfit
        budget = self.options["time_limit"]
        accepted: list[bool] = []

        def left() -> float | None:
            return None if budget is None else max(budget - (time.perf_counter() - t0), 1e-3)

        def fits(out: StartOutcome) -> bool:
            return bool(out.success or (threshold is not None and np.isfinite(out.cost) and out.cost <= threshold))

        def trial(k: int, x: dict[str, Any]) -> bool:
            if threshold is None or k & (k - 1):  # powers of two only: at most ~log2(k) trials
                return False
            if budget is not None and time.perf_counter() - t0 >= budget:
                return False  # the start's time is spent: SCR stops at its own check
            out = polisher.run(np.asarray(x["theta"], dtype=float).reshape(-1) * self.scale,
                               max_iter=self.trial_max_iter, time_limit=left())
            trials.append((k, out))
            if fits(out):
                accepted.append(True)
            return bool(accepted)

        class _Rest:  # the polisher with the time the start has left
            method = polisher.method

            @staticmethod
            def run(theta: np.ndarray) -> StartOutcome:
                return polisher.run(theta, time_limit=left())

        base, _ = self._outcome(x0, trial)
        name = polisher.method
        spent = sum(o.iterations for _, o in trials)
        if accepted:
            k, pol = trials[-1]
            how = "fits the data" if pol.success else f"misfit {pol.cost:.3e} ≤ {threshold:g}"
            if not pol.finished:  # fits, but the trial hit its cap: let the polisher finish it
                pol = polish_outcome(_Rest, pol)
            return dataclasses.replace(
                pol, start=x0, iterations=base.iterations + spent + (pol.iterations - trials[-1][1].iterations),
                wall_time=time.perf_counter() - t0,
                message=f"SCR handed over to {name} after {k} iteration{'s' * (k > 1)} ({len(trials)} trial "
                        f"polish{'es' * (len(trials) > 1)}, the last {how}); {name}: {pol.message}",
                history=base.history)
        final = polish_outcome(_Rest, base)
        note = (f"; {len(trials)} trial polish{'es' * (len(trials) > 1)} (≤ {self.trial_max_iter} iterations "
                f"each) did not fit") if trials else ""
        return dataclasses.replace(final, iterations=final.iterations + spent, wall_time=time.perf_counter() - t0,
                                   message=final.message + note)


ScrFRF.__doc__ = (ScrFRF.__doc__ or "").replace("{variance}", VARIANCE_OPTION_DOC)
