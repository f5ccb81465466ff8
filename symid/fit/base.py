"""The estimator interface every method implements, and the parts SCR estimators share.

An :class:`Estimator` is one method on one model and data set. It is built once —
every option is validated then, so nothing bad starts running — and run once per
start: ``run(x0) -> StartOutcome``. Each data kind (:mod:`symid.fit.frf`,
:mod:`symid.fit.spectra`, :mod:`symid.fit.similarity`) supplies the data misfit
(``misfit``, ``residuals``, ``n_data``) in a small base class of its own; each method
supplies ``run``. What a method may be refined by is declared (:meth:`Estimator.polisher`),
never probed for.

Naming rules followed by every estimator's options (one vocabulary across data kinds):

=================  ===========================================================================
``positivity``     keep the parameters declared ``positive=True`` ≥ 0 (default True)
``max_iter``       the solver's iteration limit
``tol``            the solver's stopping tolerance
``seed``           seed of the random starts of auxiliary unknowns (Γ, T, S, Y …)
``aux_init``       how the auxiliary unknowns start: ``"random"``, ``"model"`` (computed from
                   the model at the start θ), ``"zero"``, ``"identity"`` (where they apply)
``weights``        SCR: weights of the nuclear-norm relaxations (λ of the thesis)
``backend``        SCR: ``"admm"`` or ``"cvxpy"`` (Clarabel)
``scale``          typical magnitude of each parameter (the unknowns are θ / scale)
``time_limit``     wall-time budget of one start in seconds (default: none)
=================  ===========================================================================
"""

from __future__ import annotations

import abc
import inspect
import time
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from symid.errors import OptionError, SymidError
from symid.fit.options import (
    check_bool,
    check_callback,
    check_choice,
    check_float,
    check_int,
    check_known_names,
    check_time_limit,
)
from symid.fit.result import ScrIteration, StartOutcome
from symid.fit.success import fit_test, physical_check

__all__ = [
    "Estimator",
    "ScrEstimator",
    "identity_coef",
    "mvk_lmis",
    "positivity_lmis",
    "project_positive",
    "symmetric_map",
    "theta_coef",
]


class Estimator(abc.ABC):
    """One estimation method for one model and data set: built once, run per start.

    Subclasses set ``method`` and implement :meth:`run`; a data kind's base class
    implements :meth:`misfit`, :meth:`residuals`, :meth:`n_data` and sets ``cost_kind``.
    Options are keyword-only arguments of ``__init__``, validated there (an
    :class:`~symid.errors.OptionError` names a bad one); :meth:`create` also refuses
    names ``__init__`` does not take, listing the valid ones.

    Attributes
    ----------
    method : str
        The method name of :func:`symid.identify` (``"scr"``, ``"ipopt"``, ...).
    cost_kind : str
        What the data misfit ``cost`` measures.
    model, data
        What the estimator was built on.
    options : dict
        The options it runs with (after validation and defaults).
    noise_floor : float or None
        The relative misfit noise alone leaves, when known (see :mod:`symid.fit.success`).
    """

    method: ClassVar[str] = ""
    cost_kind: ClassVar[str] = ""

    model: Any
    data: Any
    options: dict[str, Any]
    noise_floor: float | None = None

    @classmethod
    def option_names(cls) -> tuple[str, ...]:
        """The keyword options this estimator takes (from its ``__init__`` signature)."""
        sig = inspect.signature(cls.__init__)
        return tuple(p.name for p in sig.parameters.values() if p.kind is inspect.Parameter.KEYWORD_ONLY)

    @classmethod
    def create(cls, model: Any, data: Any, options: Mapping[str, Any], *, noise_floor: float | None = None,
               owner: str | None = None) -> Estimator:
        """Build the estimator after refusing unknown option names (an :class:`OptionError` lists the valid ones)."""
        check_known_names(owner or f"method {cls.method!r} ({cls.__name__})", options, cls.option_names())
        est = cls(model, data, **options)
        est.noise_floor = None if noise_floor is None else check_float("noise_floor", noise_floor, low=0)
        return est

    # -- the data kind's part ---------------------------------------------------------------
    @abc.abstractmethod
    def misfit(self, theta: np.ndarray) -> float:
        """The data misfit (``cost``) of the model at θ; ``inf`` where it cannot be evaluated."""

    def residuals(self, theta: np.ndarray) -> np.ndarray | None:
        """Residuals ordered by frequency (or time) in the misfit's own weighting, for the whiteness test, or
        ``None`` (no such test)."""
        return None

    def n_data(self) -> int:
        """Number of real data values the misfit sums over."""
        return 0

    def local_gain(self, theta: np.ndarray) -> float | None:
        """‖P_J r‖² / ‖r‖²: the fraction of the misfit one Gauss–Newton step from θ predicts to remove, for data kinds
        without a black box (:mod:`symid.fit.success`), from the residual r (cost ∝ ‖r‖²) and its Jacobian J of the
        estimator's ``jacobian`` (columns of parameters at their bound 0 left out, directions below 1e-8 of the
        largest singular value ignored); ``None`` when the estimator has no ``jacobian`` or it cannot be evaluated."""
        jacobian = getattr(self, "jacobian", None)
        if jacobian is None:
            return None
        th = np.asarray(theta, dtype=float).reshape(-1)
        try:
            r, J = jacobian(th)
        except (SymidError, ValueError, ArithmeticError, np.linalg.LinAlgError):  # a pole on a line, singular M
            return None
        r, J = np.asarray(r, dtype=float).reshape(-1), np.asarray(J, dtype=float)
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(J))) or not np.any(r):
            return None
        pos = np.asarray(self.model.positive, dtype=bool)
        at_bound = pos & (th <= 1e-9 * float(np.max(np.abs(th), initial=0.0)))
        free = np.concatenate([~at_bound, np.ones(J.shape[1] - th.size, dtype=bool)])  # nuisance unknowns: free
        J = J[:, free]
        if J.shape[1] == 0:
            return None
        norms = np.linalg.norm(J, axis=0)
        J = J / np.where(norms > 0, norms, 1.0)
        U, S, _ = np.linalg.svd(J, full_matrices=False)
        if S.size == 0 or S[0] == 0:
            return None
        U = U[:, S > 1e-8 * S[0]]
        return float(np.sum((U.T @ r) ** 2) / np.sum(r**2))

    def black_box(self) -> tuple[float, int] | None:
        """``(misfit, b)`` of a black box of the model's order fitted to the data, in the same misfit, with its
        number of real parameters b; ``None`` (default) when the data kind has none. The success rule refuses a
        fit that is not exact when this black box fits better than noise explains (:mod:`symid.fit.success`)."""
        return None

    # -- the method's part ------------------------------------------------------------------
    @abc.abstractmethod
    def run(self, x0: np.ndarray) -> StartOutcome:
        """Estimate from the start ``x0`` (a parameter vector); never raises on solver failure."""

    def polisher(self) -> Estimator | None:
        """The local refinement ``polish=True`` / ``"scr+polish"`` uses after this method, or ``None``."""
        return None

    def check_start(self, x0: np.ndarray) -> None:
        """Refuse a user's start this method cannot take (an :class:`OptionError` saying why), before any
        start runs; e.g. one outside the method's ``bounds``. Default: every start is taken."""
        return None

    def run_polished(self, x0: np.ndarray, polisher: Estimator) -> StartOutcome:
        """This method from ``x0``, then ``polisher`` from its estimate (kept when it lowers the misfit)."""
        from symid.fit.polish import polish_outcome

        return polish_outcome(polisher, self.run(x0))

    def _progress_options(self, callback: Any, verbose: Any) -> None:
        """Validate and keep ``callback`` (a function of one :class:`symid.engine.scr.ScrProgress`) and
        ``verbose`` (print one line per iteration), for :meth:`progress_reporter`."""
        self._callback = check_callback("callback", callback, "ScrProgress")
        self._verbose = check_bool("verbose", verbose)

    def progress_reporter(self, t0: float, label: str | None = None) -> Callable[[int, float, Any], bool] | None:
        """``report(k, residual, θ)`` after iteration k: a :class:`symid.engine.scr.ScrProgress` (θ's data
        misfit, seconds since ``t0``) to ``callback`` and, with ``verbose``, a printed line headed by
        ``label`` (default: the method); it returns True when the callback asks to stop. ``None`` when
        neither is asked for (nothing is computed then)."""
        from symid.engine.scr.result import ScrProgress, print_progress

        callback, verbose = getattr(self, "_callback", None), getattr(self, "_verbose", False)
        if callback is None and not verbose:
            return None
        label = self.method if label is None else label

        def report(k: int, residual: float, theta: Any) -> bool:
            theta = np.asarray(theta, dtype=float).reshape(-1)
            info = ScrProgress(int(k), float(residual), self.misfit(theta), time.perf_counter() - t0, theta)
            if verbose:
                print_progress(info, label)
            return bool(callback(info)) if callback is not None else False

        return report

    def outcome(self, x0: np.ndarray, theta: np.ndarray, *, finished: bool, status: str, message: str,
                iterations: int, wall_time: float, history: tuple[ScrIteration, ...] = ()) -> StartOutcome:
        """A :class:`StartOutcome` with its cost and the success rule applied (:mod:`symid.fit.success`:
        :func:`~symid.fit.success.fit_test` and :func:`~symid.fit.success.physical_check`); ``finished``
        (the solver reached its own stopping rule) is reported beside ``success``, not folded into it."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        finite = bool(np.all(np.isfinite(theta)))
        cost = self.misfit(theta) if finite else float("inf")
        res = self.residuals(theta) if finite and np.isfinite(cost) else None
        independent = getattr(self, "residual_independent", None)
        test = fit_test(cost, n_data=self.n_data(), n_parameters=int(theta.size), residuals=res,
                        noise_floor=self.noise_floor, black_box=self.black_box,
                        local_gain=lambda: self.local_gain(theta),
                        independent=None if independent is None else (lambda: independent(theta)))
        fits, fit_text = test.fits, test.text
        unphysical = physical_check(self.model, theta)  # never a success against the model's declarations
        if unphysical is not None:
            fits, fit_text = False, f"{fit_text}; not physical: {unphysical}"
        if not finite:
            message = f"{message}; the estimate is not finite"
        return StartOutcome(start=np.asarray(x0, dtype=float), theta=theta, cost=cost,
                            success=bool(fits), finished=bool(finished), status=status,
                            iterations=int(iterations), wall_time=float(wall_time), message=message,
                            fit=fit_text, history=history)


# -- SCR ---------------------------------------------------------------------------------------

def project_positive(model: Any, theta: Any) -> tuple[np.ndarray, str]:
    """θ with every declared-positive parameter below 0 set to 0, and a note naming them (``""``: none).

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.base import project_positive
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> theta, note = project_positive(model, [2.0, -0.003, 3.0])
    >>> theta.tolist(), note
    ([2.0, 0.0, 3.0], 'projected onto the bound 0 of parameters declared positive: c (was -0.003)')
    """
    theta = np.array(theta, dtype=float).reshape(-1)
    below = np.asarray(model.positive, dtype=bool) & (theta < 0)
    if not below.any():
        return theta, ""
    names = [f"{n} (was {v:.3g})" for n, v, b in zip(model.parameter_names, theta, below, strict=True) if b]
    theta[below] = 0.0
    return theta, f"projected onto the bound 0 of parameters declared positive: {', '.join(names)}"


_BACKENDS = ("admm", "cvxpy")
_HEURISTICS = ("nuclear", "truncated")


def theta_coef(amap: Any) -> np.ndarray:
    """Coefficient array (r, c, l) of an affine model map, as :class:`symid.engine.scr.Affine` wants it."""
    return np.moveaxis(amap.Xi, 0, -1)


def identity_coef(shape: tuple[int, int]) -> np.ndarray:
    """Coefficients (r, c, r, c) of the identity map of an (r, c) matrix variable."""
    r, c = shape
    return np.eye(r * c).reshape(r, c, r, c)


def symmetric_map(amap: Any) -> bool:
    """Whether X(θ) is symmetric for every θ."""
    return bool(np.allclose(amap.X0, amap.X0.T) and np.allclose(amap.Xi, np.swapaxes(amap.Xi, 1, 2)))


def positivity_lmis(model: Any, theta: Any, which: Callable[[int], bool] | None = None) -> list[Any]:
    """θₖ ≥ 0 as 1×1 LMIs for the parameters declared positive (and selected by ``which``)."""
    from symid import scr

    out = []
    l = model.n_parameters
    for k, pos in enumerate(model.positive):
        if pos and (which is None or which(k)):
            coef = np.zeros((1, 1, l))
            coef[0, 0, k] = 1.0
            out.append(scr.Affine(np.zeros((1, 1)), {theta: coef}))
    return out


def mvk_lmis(maps: Any, theta: Any, options: dict[str, Any], names: str = "MVK", scale: Any = None) -> list[Any]:
    """M, V, K ⪰ 0 as LMIs in θ for each non-constant symmetric map; a non-symmetric one is
    skipped and recorded in ``options`` (``lmi_M`` … ``"skipped: not symmetric"``). With
    ``scale``, the variable is φ = θ / scale."""
    from symid import scr

    out = []
    for name in names:
        if maps[name].is_constant:
            continue
        if not symmetric_map(maps[name]):
            options[f"lmi_{name}"] = "skipped: not symmetric"
            continue
        coef = theta_coef(maps[name]) if scale is None else theta_coef(maps[name]) * scale
        out.append(scr.Affine(maps[name].X0, {theta: coef}))
    return out


class ScrEstimator(Estimator):
    """What every SCR estimator shares: engine options, the compiled problem, finish rule, history.

    A subclass builds its :class:`symid.engine.scr.BilinearProblem` and calls
    :meth:`_setup_engine` with it; :meth:`engine_solve` then runs the engine from a start.
    """

    method: ClassVar[str] = "scr"

    def _engine_options(self, *, backend: Any, max_iter: Any, tol: Any, heuristic: Any = "nuclear",
                        truncate_after: Any = 0, admm: Any = None, time_limit: Any = None) -> dict[str, Any]:
        """Validated options of :func:`symid.engine.scr.solve`."""
        from symid import scr

        opts = {"backend": check_choice("backend", backend, _BACKENDS),
                "time_limit": check_time_limit("time_limit", time_limit),
                "max_iter": check_int("max_iter", max_iter, low=1, high=10**7),
                "tol": check_float("tol", tol, low=0, strict_low=True),
                "heuristic": check_choice("heuristic", heuristic, _HEURISTICS),
                "truncate_after": check_int("truncate_after", truncate_after, low=0)}
        if admm is not None:
            if not isinstance(admm, scr.ADMMOptions):
                raise OptionError(f"admm must be a symid.engine.scr.ADMMOptions; got {type(admm).__name__}")
            opts["admm"] = admm
        return opts

    def engine_monitor(self, theta_of: Callable[[Mapping[str, Any]], Any], t0: float) -> Any:
        """The engine's ``monitor`` reporting each iteration to ``callback``/``verbose`` as a
        :class:`symid.engine.scr.ScrProgress` (θ from the iterate by ``theta_of``, its data misfit,
        seconds since ``t0``); ``None`` when neither is asked for (nothing is computed then)."""
        report = self.progress_reporter(t0)
        if report is None:
            return None

        def monitor(k: int, x: Mapping[str, Any], it: Any, elapsed: float) -> bool:
            return report(k, float(it.residual), theta_of(x))

        return monitor

    def _setup_engine(self, problem: Any, solve_options: dict[str, Any], *, presolve: bool = True,
                      normalize: bool = True, equalities: str = "exact") -> None:
        from symid import scr

        self.problem = problem
        self.compiled = scr.compile(problem, presolve=check_bool("presolve", presolve),
                                    normalize=check_bool("normalize", normalize), equalities=equalities)
        self._solve_opts = solve_options

    def engine_solve(self, start: Mapping[str, Any], callback: Any = None, compiled: Any = None,
                     monitor: Any = None) -> Any:
        """The engine's :class:`symid.engine.scr.SCRSolution` from ``start`` (by variable name)."""
        from symid import scr

        return scr.solve(self.compiled if compiled is None else compiled, start, callback=callback,
                         monitor=monitor, **self._solve_opts)

    @staticmethod
    def engine_finished(sol: Any) -> bool:
        """SCR finished: it converged, or it stopped moving (stationary, e.g. on noisy data)."""
        return sol.status == "converged" or bool(sol.info.get("stationary", False))

    @staticmethod
    def engine_history(sol: Any, *, theta_of: Callable[[dict], Any] | None = None,
                       families: Mapping[str, list[int]] | None = None, offset: int = 0
                       ) -> tuple[ScrIteration, ...]:
        """Typed per-iteration records of an engine solution."""
        out = []
        for k, h in enumerate(sol.history):
            th = None
            if theta_of is not None and k < len(sol.iterates):
                th = np.asarray(theta_of(sol.iterates[k]), dtype=float).reshape(-1)
            fam = None
            if families:
                res = np.asarray(h.residuals)
                fam = {name: float(np.sum(res[idx])) for name, idx in families.items()}
            out.append(ScrIteration(iteration=offset + k + 1, residual=float(h.residual),
                                    objective=float(h.objective), relaxation=float(h.relaxation),
                                    time=float(h.time), theta=th, families=fam))
        return tuple(out)

    def solved_outcome(self, x0: np.ndarray, theta: np.ndarray, sol: Any, t0: float, *, message: str | None = None,
                       history: tuple[ScrIteration, ...] | None = None) -> StartOutcome:
        """The outcome of one SCR start whose engine solution is ``sol`` (started at ``t0``).

        When ``history`` holds the iterates' θ and one of them fits the data better than the
        last (a relative misfit below 0.999 of it), that one is the estimate, and the message
        says so: the engine's last iterate minimises its relaxation, not the data misfit, and
        a run that does not converge can end far above where it passed (found on a quarter car
        at 1 % noise: best iterate 5.0 at iteration 3, last 25.5 after 500). The engine's own
        status is kept.

        A declared-positive parameter that comes out negative is projected onto the engine's
        own constraint θ ≥ 0 (which ADMM meets only to its tolerance: −0.0033 for a mass of
        order 300, 1e-5 of its size, was reported as the estimate, not physical), and the
        message names it with the value it had; the misfit and the success rule are those of
        the projected estimate.
        """
        text = sol.message if message is None else message
        if history is not None:
            theta = np.asarray(theta, dtype=float).reshape(-1)
            last = self.misfit(theta) if np.all(np.isfinite(theta)) else float("inf")
            best_k, best = -1, last
            for k, it in enumerate(history):
                if it.theta is None or it.theta.shape != theta.shape or not np.all(np.isfinite(it.theta)):
                    continue
                cost = self.misfit(it.theta)
                if cost < 0.999 * best:
                    best_k, best = k, cost
            if best_k >= 0:
                theta = history[best_k].theta
                text = (f"{text}; the estimate is iteration {history[best_k].iteration}'s, whose misfit {best:.3e} is "
                        f"below the last iterate's {last:.3e}")
        theta, projected = project_positive(self.model, theta)
        if projected:
            text = f"{text}; {projected}"
        return self.outcome(x0, theta, finished=self.engine_finished(sol), status=sol.status, message=text,
                            iterations=sol.iterations if history is None else len(history),
                            wall_time=time.perf_counter() - t0,
                            history=self.engine_history(sol) if history is None else history)
