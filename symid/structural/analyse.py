"""``identifiability(model)``: the full report, and the cheap local check used before estimation."""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping

import sympy as sp

from symid.errors import IdentifiabilityWarning, ModelError
from symid.structural.arguments import checked_arguments, checked_known, checked_seed
from symid.structural.combinations import monomial_candidates, parameters_to_fix, select_combinations
from symid.structural.deadline import run_with_deadline
from symid.structural.local import local_analysis
from symid.structural.numeric import numeric_local_check
from symid.structural.report import IdentifiabilityReport, NecessaryCondition
from symid.structural.steps import limit_reason, raise_on_error, run_global
from symid.structural.summary import free_parameters, model_kind

_EXACT_LIMIT = 400

__all__ = ["DEFAULT_TIMEOUT", "check_local", "identifiability", "warn_if_not_identifiable"]

DEFAULT_TIMEOUT = 30.0
"""Default wall-time budget (s) of :func:`identifiability`."""


def _describe(model) -> str:
    kind = type(model).__name__
    name = f" {model.name!r}" if getattr(model, "name", None) else ""
    return f"{kind}{name} ({model._shape_text()})"


def _necessary(model, n_free: int, known: Mapping[str, object]) -> NecessaryCondition:
    n, p, m = model.n_states, model.n_outputs, model.n_inputs
    bound = n * (p + m)
    if model_kind(model) == "state-space":
        free = {q.name for q in free_parameters(model, known)}
        if any(model.parameters[i].name in free for i in model.maps["D"].depends_on):
            bound += p * m
    elif model.output == "acceleration":
        bound += p * m
    return NecessaryCondition(n_free, n, m, p, bound, n_free <= bound)


def _positive_flags(model, positive: bool | None, known) -> list[bool]:
    free = free_parameters(model, known)
    if positive is None:
        return [bool(q.is_positive) for q in free]
    return [bool(positive)] * len(free)


def _complexity(expr: sp.Expr) -> tuple[int, int]:
    terms = len(sp.Add.make_args(sp.expand(sp.numer(sp.together(expr)))))
    return terms, sp.count_ops(expr)


def identifiability(model, *, known: Mapping[str, float] | None = None, positive: bool | None = None,
                    timeout: float | None = DEFAULT_TIMEOUT, exact_count: bool = False,
                    seed: int = 0) -> IdentifiabilityReport:
    """Structural identifiability of a model's parameters from its input-output map.

    Local identifiability comes from the exact rank of the Jacobian of an exhaustive
    summary (the transfer matrix at 2N + 1 + r rational frequencies, equivalent to the
    Markov parameters; see :mod:`symid.structural.local`) at two random rational points
    (cheap, always computed). Global
    identifiability comes from solving summary(θ) = summary(θ*) exactly at a random
    rational θ* with a Gröbner basis, where the summary is the normalised
    transfer-function coefficients (Markov parameters for a non-minimal realisation).
    One admissible solution → global; k > 1 → local (k reported); infinitely many →
    not identifiable. For parameters that are not identifiable the report lists
    identifiable combinations and a reparameterisation.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
        Parameters may appear in any matrix; any output kind; at least one parameter.
    known : dict of str to float, optional
        Parameter values taken as known (substituted before anything else), by name or
        symbol: finite real numbers (int, float, ``Fraction``, numpy or sympy numbers;
        floats through their shortest decimal, ``Fraction`` exactly). At least one
        parameter must remain free.
    positive : bool, optional
        Discard solutions with a non-positive value of a positive parameter. ``None``
        (default) uses the declarations (``si.parameters(..., positive=True)``);
        ``True`` treats every parameter as positive; ``False`` ignores positivity.
        The report says when positivity changed a verdict.
    timeout : float or None, optional
        Wall-time budget in seconds of the whole analysis, > 0 (default 30 s; ``None``
        or ``inf``: no limit, everything in this process). Each bounded step runs in a
        child process that is killed when the budget is spent (:mod:`~.deadline`), so
        the call returns within about ``timeout`` plus the time to stop a process
        (measured: under 0.1 s on the zoo models). The exact local step comes first (if
        even it does not finish, the local verdicts come from a floating-point rank,
        flagged as a screen). For a locally identifiable model the Gröbner step and a
        numerical search for other solutions of summary(θ) = summary(θ*) (about 0.5 s)
        then run side by side; each solution found is certified by the Krawczyk interval
        test when the summary system is square (as many equations as unknowns).
        Certified solutions that move every parameter prove the model locally but not
        globally identifiable: the report stops there, with ``n_solutions_at_least`` in
        place of the exact count. Otherwise the Gröbner step has the rest of the budget;
        if it does not finish, the global verdict is marked undetermined with the
        reason (the timeout; or a documented limit: more than 400 solutions, out of
        memory, a worker process that died), and numerical witnesses, if any, are
        reported as evidence. For a non-identifiable model, the combinations are then
        computed (small work) and checked within what is left of the budget.
    exact_count : bool, optional
        Keep the Gröbner step running for the exact solution count k even when
        certified witnesses settle the verdicts sooner. Default False.
    seed : int, optional
        Seed of the random rational points, an integer in [0, 2⁶³ − 1] (default 0). The
        same model and seed give the same report, except for what wall time decides
        (whether the Gröbner step finishes within ``timeout``, how many witnesses the
        0.5 s search finds); the verdicts are generic, so the seed only matters on a
        measure-zero set. ``None`` is refused rather than read as "a fresh random seed",
        so that a report can always be reproduced.

    Raises
    ------
    ModelError
        A model or ``known`` that cannot be analysed: not a model, no parameter at all,
        ``known`` not a dict, an unknown or repeated name, a value that is not a finite
        real number, every parameter known; or a model found degenerate during the
        analysis (det M(θ) ≡ 0).
    OptionError
        A bad ``timeout``, ``positive``, ``exact_count`` or ``seed``.
    SolverError
        An analysis step failed unexpectedly (a bug): never reported as a weaker verdict.

    Returns
    -------
    IdentifiabilityReport

    Examples
    --------
    >>> import symid as si
    >>> a, b, c = si.parameters("a b c", positive=True)
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]])
    >>> rep = si.identifiability(model)
    >>> rep.verdict, rep.verdicts
    ('none', {'a': 'global', 'b': 'none', 'c': 'none'})
    >>> [c["expression"] for c in rep.combinations]
    ['b*c']
    >>> si.identifiability(model, known={"b": 2}).verdict
    'global'
    """
    t0 = time.perf_counter()
    args = checked_arguments(model, known=known, timeout=timeout, positive=positive, exact_count=exact_count,
                             seed=seed)
    timeout, seed, known_exact = args.timeout, args.seed, args.known
    free = free_parameters(model, known_exact)
    names = tuple(q.name for q in free)
    pos = _positive_flags(model, args.positive, known_exact)
    necessary = _necessary(model, len(free), known_exact)
    notes: list[str] = []

    def left() -> float | None:
        return None if timeout is None else max(timeout - (time.perf_counter() - t0), 0.0)

    status_local, local = run_with_deadline(local_analysis, {"model": model, "known": known_exact, "seed": seed},
                                            left())
    t_local = time.perf_counter() - t0
    if status_local == "timeout":
        return _numeric_report(model, names, args, necessary, t0,
                               f"the exact local step exceeded the timeout ({timeout:g} s)")
    stopped = limit_reason("exact local step", status_local, local)
    if stopped is not None:
        return _numeric_report(model, names, args, necessary, t0, stopped)
    raise_on_error("local (Jacobian rank)", status_local, local)
    monos = monomial_candidates(local)
    full_rank = local.rank == len(free)

    # One budget: the Gröbner step and, for a locally identifiable model, the witness
    # search side by side in two child processes (symid/structural/steps.py).
    out = run_global(model, known_exact, names=names, positive=pos, seed=seed, extra_candidates=monos,
                     full_rank=full_rank, exact_count=args.exact_count, left=left)
    glob = out.result
    notes.extend(out.notes)
    determined = glob is not None
    witnesses, certified, theta_star = out.witnesses, out.certified, out.theta_star
    proven_by_witnesses = out.proven_by_witnesses and not determined
    if determined:
        global_status = "determined"
    elif proven_by_witnesses:
        why = (f"Gröbner basis stopped after {out.seconds:.2g} s; exact_count=True keeps it running until the "
               "timeout" if not args.exact_count else
               f"Gröbner basis did not finish within the timeout of {timeout:g} s")
        if out.limit is not None:
            why = out.limit
        global_status = (f"NOT globally identifiable, proven by {sum(certified)} certified solution(s) θ ≠ θ* of "
                         f"summary(θ) = summary(θ*); exact count not computed ({why})")
    elif out.limit is not None:
        global_status = f"undetermined ({out.limit})"
    else:
        global_status = f"undetermined (timeout after {timeout:g} s)"
    if not determined and not proven_by_witnesses and witnesses:
        global_status += (f"; {len(witnesses)} other admissible solution(s) of summary(θ) = summary(θ*) "
                          "found numerically: NOT globally identifiable")
    if witnesses and not determined:
        n_cert = sum(certified)
        notes.append(f"the {len(witnesses)} solution(s) θ ≠ θ* in `witnesses` were found by Gauss–Newton from random "
                     "starts and refined by Newton's method at 60 digits (residual < 1e-40); "
                     f"{n_cert} of them certified by the Krawczyk test in interval arithmetic (an exact real "
                     "admissible solution within relative 1e-20, distinct from θ* and from each other)")
    t_global = out.seconds

    loc = dict(zip(names, local.identifiable, strict=True))
    verdicts: dict[str, str] = {}
    n_sol = n_real = n_complex = None
    positivity_changed = False
    solutions: tuple = ()
    if not determined:
        for nm in names:
            verdicts[nm] = "local" if loc[nm] else "none"
        verdict = "local" if full_rank else "none"
    else:
        notes.extend(glob.notes)
        n_sol, n_real, n_complex = glob.n_admissible, glob.n_real, glob.n_complex
        solutions = glob.solutions
        for nm in names:
            if not loc[nm]:
                verdicts[nm] = "none"
            else:
                verdicts[nm] = "global" if glob.global_admissible.get(nm, False) else "local"
        if not full_rank:
            verdict = "none"
        elif not glob.zero_dimensional:
            verdict = "local"
            notes.append("the Jacobian has full rank but the solution set has a positive-dimensional part "
                         "(non-generic points)")
        else:
            verdict = "global" if n_sol == 1 else "local"
        if glob.zero_dimensional and full_rank:
            real_verdict = "global" if n_real == 1 else "local"
            real_params = {nm: ("global" if glob.global_real[nm] else "local") for nm in names if loc[nm]}
            adm_params = {nm: verdicts[nm] for nm in names if loc[nm]}
            if real_verdict != verdict or real_params != adm_params:
                positivity_changed = True
                pos_names = [nm for nm, f in zip(names, pos, strict=True) if f]
                changed = [nm for nm in real_params if real_params[nm] != adm_params[nm]]
                what = f"model verdict {real_verdict} → {verdict}" if real_verdict != verdict else \
                    f"verdict of {', '.join(changed)} local → global"
                notes.append(f"positivity ({', '.join(pos_names)} > 0) discarded {n_real - n_sol} of {n_real} real "
                             f"solutions: {what}")
            elif n_real is not None and n_sol is not None and n_real > n_sol:
                notes.append(f"positivity discarded {n_real - n_sol} of {n_real} real solutions (verdict unchanged)")
            if n_complex and n_real is not None and n_complex > n_real:
                cplx_verdict = "global" if n_complex == 1 else "local"
                msg = f"{n_complex - n_real} of {n_complex} complex solutions are not real and were discarded"
                if cplx_verdict != real_verdict:
                    msg += f" (over ℂ the verdict would be {cplx_verdict})"
                notes.append(msg)
            if verdict == "local":
                notes.append("counts of real and positive solutions are at the random point θ*; elsewhere they "
                             f"can differ (the complex count, {n_complex}, is generic)")

    # -- combinations and reparameterisation -------------------------------------
    combos, reparam, fix = [], {}, ()
    if local.rank < len(free):
        candidates = [(e, "scaling", (glob.membership[i] if determined else None)) for i, e in enumerate(monos)]
        if determined:
            gb = sorted(glob.candidates, key=_complexity)
            candidates += [(e, "groebner", True) for e in gb]
            sm = sorted(glob.summary_expressions, key=_complexity)
            candidates += [(e, "summary", True) for e in sm]
        chosen = select_combinations(local, candidates)
        combos = [{"expression": sp.sstr(c.expression), "source": c.source, "global": c.is_global} for c in chosen]
        reparam = {f"phi{i + 1}": c["expression"] for i, c in enumerate(combos)}
        fix_syms = parameters_to_fix(local)
        fix = tuple(q.name for q in fix_syms)
        if len(local.identifiable) - sum(local.identifiable) > 0 and \
                sum(local.identifiable) + len(combos) < local.rank:
            notes.append("the combinations found do not reach the Jacobian rank "
                         f"({sum(local.identifiable) + len(combos)} of {local.rank}); the list is incomplete")
        if fix:
            notes.append(_check_fix(model, known_exact, fix, seed, left()))
    if not necessary.satisfied:
        notes.append("the counting condition fails: the parameters cannot all be identifiable")
    total = time.perf_counter() - t0
    timing = {"local": round(t_local, 4), "global": round(t_global, 4), "total": round(total, 4)}
    if determined:
        theta_star = {k: str(v) for k, v in glob.theta_star.items()}
    return IdentifiabilityReport(
        model=_describe(model), parameters=names, known=args.known_values, verdict=verdict, verdicts=verdicts,
        locally_identifiable=loc, global_determined=determined, global_status=global_status,
        n_solutions=n_sol, n_solutions_real=n_real, n_solutions_complex=n_complex,
        jacobian_ranks=tuple(local.ranks),
        summary_kind=glob.summary_kind if determined else None,
        n_summary=len(glob.summary_labels) if determined else None,
        necessary_condition=necessary, combinations=tuple(combos), reparameterisation=reparam, fix=fix,
        positivity_changed=positivity_changed, notes=tuple(notes), theta_star=theta_star,
        solutions=tuple(solutions), witnesses=witnesses, witnesses_certified=tuple(certified),
        n_solutions_at_least=(1 + sum(certified)) if proven_by_witnesses else None,
        verdicts_proven=determined or proven_by_witnesses, timing=timing)


def _check_fix(model, known_exact, fix: tuple[str, ...], seed: int, budget: float | None) -> str:
    """A note: with the parameters of ``fix`` set to 1, is every other parameter locally identifiable?"""
    what = ", ".join(f"{q} = 1" for q in fix)
    if budget is not None and budget <= 0:
        return f"with {what} known, the other parameters were not checked (no time left in the budget)"
    status, check = run_with_deadline(local_analysis, {"model": model, "known": {**known_exact, **dict.fromkeys(fix,
                                      sp.Integer(1))}, "seed": seed + 1}, budget)
    if status == "timeout":
        return f"with {what} known, the other parameters were not checked (no time left in the budget)"
    stopped = limit_reason("check of the reparameterisation", status, check)
    if stopped is not None:
        return f"with {what} known, the other parameters were not checked ({stopped})"
    raise_on_error("local check of the reparameterisation", status, check)
    if all(check.identifiable):
        return f"with {what} known, every other parameter is locally identifiable (checked)"
    bad = [q.name for q, ok in zip(check.parameters, check.identifiable, strict=True) if not ok]
    return f"with {what} known, {', '.join(bad)} remain(s) not locally identifiable (checked)"


def _numeric_report(model, names, args, necessary, t0, why: str) -> IdentifiabilityReport:
    """Report from the floating-point Jacobian rank when the exact local step did not finish (``why``)."""
    num = numeric_local_check(model, known=args.known_values, seed=args.seed)
    bad = set(num.not_identifiable)
    verdicts = {nm: ("none" if nm in bad else "local") for nm in names}
    notes = (f"{why}: local verdicts come from the floating-point rank of the frequency-response Jacobian "
             f"(rank {num.rank} of {num.n_parameters}), a screen rather than a proof",)
    if not necessary.satisfied:
        notes += ("the counting condition fails: the parameters cannot all be identifiable",)
    total = time.perf_counter() - t0
    return IdentifiabilityReport(
        model=_describe(model), parameters=names, known=args.known_values, verdict="local" if not bad else "none",
        verdicts=verdicts, locally_identifiable={nm: nm not in bad for nm in names}, global_determined=False,
        global_status=f"undetermined ({why})", n_solutions=None, n_solutions_real=None, n_solutions_complex=None,
        jacobian_ranks=(num.rank,), summary_kind=None, n_summary=None, necessary_condition=necessary,
        combinations=(), reparameterisation={}, fix=(), positivity_changed=False, notes=notes, theta_star={},
        solutions=(), timing={"local": round(total, 4), "global": 0.0, "total": round(total, 4)})


def check_local(model, known: Mapping[str, float] | None = None, *, seed: int = 0) -> tuple[str, ...]:
    """Names of the parameters that are not locally identifiable (cheap; no Gröbner basis).

    Exact (rational Jacobian rank) for models with at most ``_EXACT_LIMIT`` = 400
    parameters × states; above that the floating-point rank of
    :func:`symid.structural.numeric.numeric_local_check` (the 108-parameter truss takes
    about 10 s exactly and a fraction of a second in floating point). No deadline.

    Raises
    ------
    ModelError
        Not a model, or a bad ``known`` (as for :func:`identifiability`; every
        parameter known is allowed here and gives ``()``).
    OptionError
        A bad ``seed``.

    Examples
    --------
    >>> import symid as si
    >>> a, b, c = si.parameters("a b c")
    >>> from symid.structural import check_local
    >>> check_local(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]]))
    ('b', 'c')
    """
    known_exact, known_values = checked_known(model, known, require_free=False)
    seed = checked_seed(seed)
    if len(known_exact) == model.n_parameters:
        return ()
    if model.n_parameters * model.n_states > _EXACT_LIMIT:
        return numeric_local_check(model, known=known_values, seed=seed).not_identifiable
    local = local_analysis(model, known_exact, seed=seed)
    return tuple(q.name for q, ok in zip(local.parameters, local.identifiable, strict=True) if not ok)


def warn_if_not_identifiable(model, known: Mapping[str, float] | None = None, *, stacklevel: int = 2
                             ) -> tuple[str, ...]:
    """Emit an :class:`~symid.IdentifiabilityWarning` naming the parameters that are not locally identifiable.

    Called by estimators before they start. Returns the names (empty when all are
    locally identifiable). A model the local test cannot handle is let through silently.

    Examples
    --------
    >>> import warnings
    >>> import symid as si
    >>> from symid.structural import warn_if_not_identifiable
    >>> a, b, c = si.parameters("a b c")
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_if_not_identifiable(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]]))
    ('b', 'c')
    >>> w[0].category.__name__
    'IdentifiabilityWarning'
    """
    try:
        bad = check_local(model, known)
    except ModelError:
        return ()
    if bad:
        warnings.warn(
            f"parameter(s) {', '.join(bad)} are not locally identifiable from the input-output map: infinitely "
            "many values fit the data equally well. Fix some of them (known values) or reparameterise; "
            "si.identifiability(model) lists the identifiable combinations.",
            IdentifiabilityWarning, stacklevel=stacklevel + 1)
    return bad
