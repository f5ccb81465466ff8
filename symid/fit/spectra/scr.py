"""SCR on power spectra: thesis Algorithm 5.1, X(θ, ωᵢ) Pᵢ X(θ, ωᵢ)ᴴ = Qᵢ with M, V, K ⪰ 0.

Each frequency is one bilinear term A(θ) P B(θ) = C of (2-1) with A = X(θ, ωᵢ),
P = Pᵢ, B = X(θ, ωᵢ)ᴴ, C = Qᵢ (see :mod:`symid.fit.spectra.equations`); the SCR matrix
(2-6) with Q = Yᵢ, R = Yᵢᴴ is the matrix of Algorithm 5.1. Two exact reformulations
keep the sub-problems small and unit-free without changing a single iterate:

* **rank compression.** With Pᵢ = Uᵢ Sᵢ Uᵢᴴ (Uᵢ the eigenvectors of the eigenvalues above
  ``rank_tol`` times the largest), the term A = X Uᵢ, P = Sᵢ, B = Uᵢᴴ Xᴴ, started at
  Q = YᵢUᵢ, R = UᵢᴴYᵢᴴ, has an SCR matrix M_c with M = diag(I, Uᵢ) M_c diag(I, Uᵢᴴ);
  multiplying by matrices with orthonormal columns keeps the nuclear norm, so both
  sub-problems are the same. With one input and exact spectra Pᵢ has rank 1, and each
  block shrinks from 2n × 2n to (n + 1) × (n + 1).
* **one global scale.** All Pᵢ and Qᵢ are divided by max ‖Qᵢ‖₂: every nuclear norm is
  scaled by the same number, so the iterates do not change, but the stopping tolerance
  no longer depends on the units of the spectra.

* **θ by a scale** (``scale=``). The engine works on φ = θ / scale, which changes no
  sub-problem's solution, only the numbers the solver sees; in the units of the scale the
  estimate follows the units of θ and ω (tests/test_units_invariance_spectra_scr.py: from
  the start's own Yᵢ, a mass in units of 1e-6 kg gave an estimate 6e-7 off without it,
  the frequency axis × 1e-6 one 100 % off after 40 iterations, × 1e6 a solver error; with
  it 7e-16). With a scale the terms are also written X̃ P̃ X̃ᴴ = Qᵢ/max‖Qᵢ‖ with
  P̃ = Pᵢ/max‖Pᵢ‖ and X̃ = X·√(max‖Pᵢ‖/max‖Qᵢ‖), the same equations, so that outputs in
  other units (Φyy × β², M, V, K / β) give the same numbers too: the relaxation matrix
  [[Q + XPRᴴ + …, (X + R)P], [P(Xᴴ + Rᴴ), P]] is not homogeneous under X → X/β, P → β²P,
  and without it Φyy × 1e6 ended 2e-5 off ('stationary' after 10 iterations instead of
  'converged' after 6) and × 1e12 in a solver error at iteration 0. Without a scale, P is
  divided by max‖Qᵢ‖ as Q is, the thesis's own relaxation (the default, measured on its
  example). It is not the default: with each start's |θ₀| as the scale, ``msd3_psd``
  (§5-6, Clarabel, seed 0) reached the truth from 4 of 5 starts instead of 5 (one stopped
  at its residual tolerance 1e-8 with an entry 2.9e-4 off; the others 1.3e-6–2.2e-8
  against 6.8e-8), and on the 2-DOF with ADMM from 3 of 20 N(0, 1) starts instead of 8.

* **physical units** (``unit_scale``, default on). The relaxation above and the random
  start of the Yᵢ (σ = 10, "high valued" next to entries of order one) are the thesis's,
  in the thesis's units; a model in SI units (a building: masses of 2e4 kg, stiffnesses
  of 3e7 N/m) is another problem to them. Without ``scale``, the typical values read off
  the spectra (:func:`symid.fit.spectra.scale.typical_scale`) become the scale when one of
  them lies outside ``UNIT_RANGE`` = 1e-2 … 1e2, and not otherwise (the thesis's
  ``msd3_psd``, typical values 0.03–1, reached the truth from 5 of 5 starts as it is and
  from 0 of 5 with them as the scale; ``benchmarks/psd.py --variants
  scr-admm,scr-admm-typical --out benchmarks/results/psd_typical_scale.json``). Measured on shear buildings in SI units
  (``benchmarks/psd_units.py``; numbers in the README).

Unlike the frequency-response formulations, the engine's per-term equilibration is off
by default (``normalize=False``): it changes the relaxation, and on the thesis example
(§5-6) the equilibrated iteration stalls where the thesis's plain one converges.

Initialisation (``aux_init``):

* ``"random"`` (default): §5-6, every Yᵢ a "high valued random definite matrix",
  Yᵢ = σ_Y·ZᵢZᵢᵀ with Zᵢ an n×n matrix of N(0, σ²) entries, σ = ``aux_std`` = 10 (the
  thesis's variance 10²) and σ_Y = ``aux_sign``. The thesis prints Yᵢ = +ZᵢZᵢᴴ; measured
  on its example (``benchmarks/psd.py``), that start falls into the same local minimum
  (max-entry error ≈ 20–45) from every draw, while Yᵢ = −ZᵢZᵢᵀ reaches the truth.
  Yᵢ = −X(θ, ωᵢ) in Algorithm 5.1, and at the low frequencies, where the spectra carry
  their energy, −X ≈ −K is negative definite: we read the printed sign as a slip and
  default to ``aux_sign=-1`` (``+1`` reproduces the printed recipe). The engine
  starts its Q, R at −A(x0), so the first iteration is run on the same problem with one
  extra scalar variable t, A = X(θ)Uᵢ + t Eᵢ with Eᵢ = (−Yᵢ − X(θ₀))Uᵢ, t₀ = 1 and the
  equality t = 0: it starts at Q = YᵢUᵢ and, t being 0 after one step, its iterate is
  exactly the first iterate of Algorithm 5.1. The iterations then continue on the
  problem without t. The draws are seeded by ``seed`` and the start θ₀, which itself
  plays no other role.
* ``"model"``: Yᵢ = −X(θ₀, ωᵢ), the engine's default start from θ₀.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symid import scr
from symid.errors import OptionError
from symid.fit.base import ScrEstimator, mvk_lmis, positivity_lmis
from symid.fit.options import check_bool, check_choice, check_float, check_scale, check_seed
from symid.fit.result import StartOutcome
from symid.fit.spectra.equations import SpectraEstimator, spectral_equations

__all__ = ["MANY_LINES", "UNIT_RANGE", "ScrPSD", "physical_units_scale"]

_AUX_INITS = ("random", "model")


MANY_LINES = 250
"""Frequencies above which SCR with Clarabel (``backend="cvxpy"``) is said to be slow (one conic block per line)."""
UNIT_RANGE = (1e-2, 1e2)
"""Typical values within this range leave θ as it is (units of order one, as the thesis's); one outside makes them the
scale (module notes, ``unit_scale``)."""


def physical_units_scale(model: Any, data: Any, typical: np.ndarray | None = None) -> np.ndarray | None:
    """The spectra's typical values when one lies outside :data:`UNIT_RANGE` (a model in physical units), else None;
    ``typical``: those values when the caller has them already.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.spectra.scr import physical_units_scale
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> w = np.logspace(-0.5, 0.5, 12)
    >>> physical_units_scale(model, si.simulate_spectra(model, [1.0, 0.2, 1.0], w, 1.0)) is None
    True
    >>> big = physical_units_scale(model, si.simulate_spectra(model, [2e4, 4e4, 3e7], 40 * w, 1e6))
    >>> bool(np.all(np.abs(np.log10(big / [2e4, 4e4, 3e7])) < 1))   # each within a factor 10
    True
    """
    from symid.fit.spectra.scale import typical_scale

    typical = typical_scale(model, data) if typical is None else typical
    if typical is None or np.all((typical >= UNIT_RANGE[0]) & (typical <= UNIT_RANGE[1])):
        return None
    return typical


class ScrPSD(ScrEstimator, SpectraEstimator):
    """Algorithm 5.1 (SCR with M, V, K ⪰ 0) on output and input spectra, built once, run per start.

    Parameters
    ----------
    model : SecondOrderModel
        C known, square and invertible (a full set of sensors), B known.
    data : SpectralData
    lmis : bool, optional
        M(θ), V(θ), K(θ) ⪰ 0 as LMIs when they are parameterised and symmetric (default
        True; §5-7 shows they are decisive).
    positivity : bool, optional
        θₖ ≥ 0 for parameters declared ``positive=True`` (default True).
    backend : {"cvxpy", "admm"}
        Engine back end (default ``"cvxpy"``: Clarabel, exact sub-problems).
    max_iter : int
        SCR iterations per start (default 40; §5-6 converges within 7 from a good draw).
    tol : float
        Stopping tolerance on the largest residual ‖X Pᵢ Xᴴ − Qᵢ‖_F of the scaled terms
        (default 1e-8).
    aux_init : {"random", "model"}
        Initial Yᵢ (see the module notes).
    aux_std : float
        Standard deviation σ of the entries of Zᵢ for ``aux_init="random"`` (default 10).
    aux_sign : {-1, 1}
        Sign of Yᵢ = ±ZᵢZᵢᵀ for ``aux_init="random"`` (default −1, see the module notes).
    seed : int
        Seed of the Zᵢ draws (combined with the start θ₀).
    rank_tol : float
        Relative eigenvalue threshold of the exact rank compression of Pᵢ (default 1e-10;
        0 keeps every eigenvalue).
    normalize : bool
        Let the engine equilibrate each term (default False, see the module notes).
    admm : symid.engine.scr.ADMMOptions, optional
        Options of the ADMM back end.
    time_limit : float, optional
        Wall-time budget of one start in seconds, the first step from the random Yᵢ
        included (status ``"time_limit"``; the iteration under way is cut short, see
        :func:`symid.engine.scr.solve`). Default 600, a safety (the thesis's ``msd3_psd``
        takes 75 s a start with Clarabel; a new user's 779 lines ran 11 minutes without an
        end); ``None`` for none.
    callback : callable, optional
        Called after every SCR iteration with a :class:`symid.engine.scr.ScrProgress`
        (iteration, residual, data misfit, elapsed seconds, θ); a true return value stops
        the start (status ``"stopped"``).
    verbose : bool
        Print one line per SCR iteration (iteration, residual, misfit, elapsed). Default False.
    scale : array_like, optional
        Typical magnitude of each parameter; the engine works on θ / scale (module notes).
        Default: θ as it is, unless ``unit_scale`` finds the model in physical units.
    unit_scale : bool, optional
        Without ``scale``, take the typical values read off the spectra
        (:func:`symid.fit.spectra.scale.typical_scale`) as the scale when one lies outside
        ``UNIT_RANGE`` (a model in physical units, module notes); default True.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.spectra.scr import ScrPSD
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], np.linspace(0.5, 3, 8), Phi_uu=1.0)
    >>> out = ScrPSD(model, spec, aux_init="model").run(np.array([2.0, 1.0, 2.0]))
    >>> np.round(out.theta, 4)
    array([1. , 0.5, 4. ])
    """

    def __init__(self, model: Any, data: Any, *, lmis: bool = True, positivity: bool = True,
                 backend: str = "cvxpy", max_iter: int = 40, tol: float = 1e-8, aux_init: str = "random",
                 aux_std: float = 10.0, aux_sign: int = -1, seed: int = 0, rank_tol: float = 1e-10,
                 normalize: bool = False, admm: Any = None, time_limit: float | None = 600.0, callback: Any = None,
                 verbose: bool = False, scale: Any = None, unit_scale: bool = True):
        self.aux_init = check_choice("aux_init", aux_init, _AUX_INITS)
        self.aux_std = check_float("aux_std", aux_std, low=0, strict_low=True)
        if aux_sign not in (-1, 1) or isinstance(aux_sign, bool):
            raise OptionError(f"aux_sign must be -1 or 1; got {aux_sign!r}")
        rank_tol = check_float("rank_tol", rank_tol, low=0, high=1 - 1e-16)
        lmis, positivity = check_bool("lmis", lmis), check_bool("positivity", positivity)
        self.aux_sign, self.seed = int(aux_sign), check_seed("seed", seed)
        solve_opts = self._engine_options(backend=backend, max_iter=max_iter, tol=tol, admm=admm,
                                          time_limit=time_limit)
        self._progress_options(callback, verbose)
        self.model, self.data = model, data
        self.eq = spectral_equations(model, data)
        lines = int(np.asarray(data.w).size)
        if solve_opts["backend"] == "cvxpy" and lines > MANY_LINES:
            import warnings

            from symid.errors import DataWarning

            warnings.warn(f"{lines} frequencies with backend='cvxpy' (Clarabel): every SCR iteration is one conic "
                          f"problem of {lines} blocks, minutes each at this size (the thesis's 170 took 5 s an "
                          f"iteration); backend='admm' (11 times faster there) or fewer lines "
                          f"(si.estimate_spectra(..., n_frequencies=100))", DataWarning, stacklevel=4)
        scale_from = "given" if scale is not None else None
        self.data_typical = None  # the spectra's typical values when computed here (identify's draws reuse them)
        if scale is None and check_bool("unit_scale", unit_scale):
            from symid.fit.spectra.scale import typical_scale

            self.data_typical = typical_scale(model, data)
            scale = physical_units_scale(model, data, typical=self.data_typical)
            scale_from = None if scale is None else "the spectra's typical values (a model in physical units)"
        self.options: dict[str, Any] = {"lmis": lmis, "positivity": positivity, "backend": backend,
                                        "max_iter": max_iter, "tol": tol, "aux_init": aux_init, "aux_std": aux_std,
                                        "aux_sign": aux_sign, "seed": seed, "rank_tol": rank_tol,
                                        "normalize": normalize, "time_limit": solve_opts["time_limit"],
                                        "callback": None if callback is None else "given", "verbose": self._verbose,
                                        "scale": None if scale is None else check_scale("scale", scale,
                                                                                        model.n_parameters).tolist(),
                                        "unit_scale": bool(unit_scale), "scale_from": scale_from}
        self._normalize = check_bool("normalize", normalize)
        self.scale = float(np.max(np.linalg.norm(self.eq.Q, ord=2, axis=(1, 2)))) or 1.0
        # with a scale: P / max‖Pᵢ‖ and X·√(max‖Pᵢ‖ / max‖Qᵢ‖), the same terms in any output unit (module notes)
        p_size = float(np.max(np.linalg.norm(self.eq.P, ord=2, axis=(1, 2)))) or self.scale
        self._p_size = p_size if scale is not None else self.scale
        self._gain = float(np.sqrt(self._p_size / self.scale))
        self._U, self._S = self._compress(rank_tol)
        self.options["ranks"] = sorted({u.shape[1] for u in self._U})
        self.theta_var = scr.Variable("theta", (model.n_parameters,))
        self.theta_scale = np.ones(model.n_parameters) if scale is None else np.asarray(self.options["scale"])
        self._constraints = self._lmis(lmis, positivity)
        self._setup_engine(self._build(None), solve_opts, normalize=self._normalize)

    def polisher(self) -> Any:
        """IPOPT on (5-13) (:class:`~symid.fit.spectra.ipopt.IpoptPSD`), with the same positivity and time limit
        (a polish is bounded as a start is)."""
        from symid.fit.spectra.ipopt import IpoptPSD

        return IpoptPSD(self.model, self.data, positivity=self.options["positivity"],
                        time_limit=self.options["time_limit"])

    # -- problem construction ---------------------------------------------------------------
    def _compress(self, rank_tol: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
        lam, V = np.linalg.eigh(self.eq.P / self._p_size)
        U, S = [], []
        for i in range(lam.shape[0]):
            big = np.abs(lam[i]).max()
            keep = np.abs(lam[i]) > rank_tol * big if big > 0 else np.ones(lam.shape[1], dtype=bool)
            if not keep.any():
                keep[np.argmax(np.abs(lam[i]))] = True
            U.append(V[i][:, keep])
            S.append(np.diag(lam[i][keep]))
        return U, S

    def _lmis(self, lmis: bool, positivity: bool) -> list[scr.Affine]:
        theta = self.theta_var
        out = mvk_lmis(self.model.maps, theta, self.options, scale=self.theta_scale) if lmis else []
        if positivity:
            out.extend(positivity_lmis(self.model, theta))
        return out

    def _build(self, shift: list[np.ndarray] | None) -> scr.BilinearProblem:
        """The problem of Algorithm 5.1; with ``shift`` (one Eᵢ per frequency) the first-step problem."""
        eq, theta = self.eq, self.theta_var
        t = scr.Variable("t") if shift is not None else None
        terms = []
        for i in range(eq.w.size):
            U = self._U[i]
            A0 = self._gain * eq.X0[i] @ U
            Ac = self._gain * np.einsum("abk,bc->ack", eq.Xc[i], U) * self.theta_scale  # coefficients of φ = θ / scale
            coef_a: dict[Any, np.ndarray] = {theta: Ac}
            coef_b: dict[Any, np.ndarray] = {theta: np.conj(np.transpose(Ac, (1, 0, 2)))}
            if t is not None:
                coef_a[t] = self._gain * shift[i]
                coef_b[t] = self._gain * shift[i].conj().T
            terms.append(scr.Bilinear(A=scr.Affine(A0, coef_a), P=self._S[i], B=scr.Affine(A0.conj().T, coef_b),
                                      C=eq.Q[i] / self.scale, name=f"spectrum[{i}]"))
        variables = [theta] if t is None else [theta, t]
        equalities = [] if t is None else [scr.Affine([[0.0]], {t: [[1.0]]})]
        return scr.BilinearProblem(variables=variables, bilinear=terms, lmis=self._constraints,
                                   equalities=equalities)

    def initial_Y(self, x0: np.ndarray) -> np.ndarray:
        """The §5-6 draws Yᵢ = ±ZᵢZᵢᵀ, Zᵢ with N(0, ``aux_std``²) entries, for the start ``x0``."""
        x0 = np.ascontiguousarray(x0, dtype=float)
        rng = np.random.default_rng([self.seed, *np.frombuffer(x0.tobytes(), dtype=np.uint32).tolist()])
        n = self.model.n_dof
        Z = self.aux_std * rng.standard_normal((self.eq.w.size, n, n))
        return self.aux_sign * (Z @ np.swapaxes(Z, 1, 2))

    # -- one start ---------------------------------------------------------------------------
    def solve(self, x0: np.ndarray, monitor: Any = None) -> tuple[scr.SCRSolution | None, scr.SCRSolution]:
        """The raw engine solutions from ``x0``: (first step from the random Yᵢ or None, the iteration);
        ``monitor`` as :func:`symid.engine.scr.solve` (the iteration only). Their θ is θ / :attr:`theta_scale`."""
        x0 = np.asarray(x0, dtype=float)
        t0 = time.perf_counter()
        first = None
        start = x0 / self.theta_scale
        if self.aux_init == "random":
            Y = self.initial_Y(x0)
            shift = [(-Y[i] - self.eq.X(x0)[i]) @ self._U[i] for i in range(Y.shape[0])]
            opts = {**self._solve_opts, "max_iter": 1}
            first = scr.solve(self._build(shift), {"theta": start, "t": 1.0}, presolve=False,
                              normalize=self._normalize, **opts)
            if first.status == "solver_error":
                return first, first
            start = np.asarray(first.x["theta"], dtype=float)
        opts = dict(self._solve_opts)
        if opts.get("time_limit") is not None:  # one budget for the first step and the iteration
            opts["time_limit"] = max(opts["time_limit"] - (time.perf_counter() - t0), 1e-3)
        return first, scr.solve(self.compiled, {"theta": start}, monitor=monitor, **opts)

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start ``x0``; never raises on solver failure."""
        x0 = np.asarray(x0, dtype=float)
        t0 = time.perf_counter()

        def theta_of(x: Any) -> np.ndarray:
            return np.asarray(x["theta"], dtype=float).reshape(-1) * self.theta_scale

        monitor = self.engine_monitor(theta_of, t0)
        first, sol = self.solve(x0, monitor)
        theta = theta_of(sol.x)
        hist = self.engine_history(first) if first is not None and first is not sol else ()
        hist = hist + self.engine_history(sol, offset=len(hist))
        message = sol.message
        limit = self._solve_opts.get("time_limit")
        if limit is not None and "time_limit" in (sol.status, getattr(first, "status", None)):
            message = (f"time limit of {limit:g} s reached after {len(hist)} iterations (the first step from random "
                       f"Yᵢ included); the last iterate is kept")
        elif first is not None:
            message = (f"first step from random Yᵢ (§5-6), then {message}" if first is not sol else
                       f"first step from random Yᵢ (§5-6) failed: {first.message}")
        if self.aux_init == "random":
            # a new user's start and none gave every digit the same, and nothing said why
            message += "; the start only seeds the random Yᵢ (aux_init='model' starts from it)"
        return self.solved_outcome(x0, theta, sol, t0, message=message, history=hist)
