"""``identifiability(model)``: the full report, and the cheap local check used before estimation."""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from collections.abc import Mapping
from fractions import Fraction

import sympy as sp
from sympy import QQ

from symid.errors import IdentifiabilityWarning, ModelError
from symid.structural.arguments import checked_arguments, checked_known, checked_seed
from symid.structural.combinations import (
    _rank,
    linear_expression,
    linear_space,
    monomial_candidates,
    parameters_to_fix,
    poly_gradients,
    rref_rows,
    select_combinations,
)
from symid.structural.deadline import run_with_deadline, start
from symid.structural.local import local_analysis
from symid.structural.numeric import numeric_local_check
from symid.structural.report import IdentifiabilityReport, NecessaryCondition
from symid.structural.steps import limit_reason, raise_on_error, run_global
from symid.structural.summary import exhaustive_summary, free_parameters, model_kind
from symid.structural.witness import METHOD as witness_method

_EXACT_LIMIT = 400

__all__ = ["DEFAULT_TIMEOUT", "check_local", "identifiability", "warn_if_not_identifiable"]

LOCAL = "local"
UNDETERMINED = "local, global undetermined"


def _verdicts_from_groebner(glob, names, loc, full_rank: bool, *, admissible: bool) -> tuple[str, dict[str, str]]:
    """Model and per-parameter verdicts from the (generic, confirmed) global step.

    "global" needs a single value over every *complex* solution (a generic property,
    confirmed at θ**); "local" needs two admissible (or, ``admissible=False``, real)
    solutions at θ* that differ (proven: the solutions are simple, so they persist on a
    neighbourhood of θ*); anything between is "local, global undetermined".
    """
    single = glob.global_admissible if admissible else glob.global_real
    count = glob.n_admissible if admissible else glob.n_real
    # the solutions compared: all of them (finitely many), or those of the generic slice of a positive-dimensional
    # set (symid.structural.slicing: admissible points of the set, so two that differ prove "local" too)
    finite = (glob.zero_dimensional and full_rank) or bool(glob.slice_values)
    verdicts = {}
    for nm in names:
        if not loc[nm]:
            verdicts[nm] = "none"
        elif glob.global_complex.get(nm, False):
            verdicts[nm] = "global"
        elif finite and (not single.get(nm, True) or nm in glob.local_elsewhere):
            verdicts[nm] = LOCAL
        else:
            verdicts[nm] = UNDETERMINED
    if not full_rank:
        verdict = "none"
    elif not glob.zero_dimensional:
        verdict = UNDETERMINED
    elif glob.n_complex == 1:
        verdict = "global"
    elif (count is not None and count >= 2) or glob.local_elsewhere:
        verdict = LOCAL
    else:
        verdict = UNDETERMINED
    return verdict, verdicts

MAX_COMBINATION_TERMS = 300
"""Summary entries with more terms (numerator and denominator) are not offered as combinations."""

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


def identifiability(model, *, known: Mapping[str, float] | None = None, positive: bool | None = None,
                    timeout: float | None = DEFAULT_TIMEOUT, exact_count: bool = False,
                    seed: int = 0, engine: str = "auto", at: Mapping[str, float] | None = None
                    ) -> IdentifiabilityReport:
    """Structural identifiability of a model's parameters from its input-output map.

    Local identifiability comes from the exact rank of the Jacobian of an exhaustive
    summary (the transfer matrix at 2N + 1 + r rational frequencies, equivalent to the
    Markov parameters; see :mod:`symid.structural.local`) at two random rational points
    (cheap, always computed). Global identifiability comes from solving
    summary(θ) = summary(θ*) exactly with a Gröbner basis, where the summary is the
    normalised transfer-function coefficients (Markov parameters for a non-minimal
    realisation), at a random rational θ* that is checked to be generic: drawn from a
    wide set (p/q, p ≤ 10⁵, q ≤ 10³), redrawn unless the Jacobian has its generic rank
    at θ* itself and summary(θ) = summary(θ*) has no multiple solution (where solutions
    merge, a count would be too small). Every global claim is confirmed at a second
    independent generic point θ**.

    The verdicts (model and per parameter; :data:`~symid.structural.report.VERDICTS`):

    * ``"global"``: a single complex solution (model), or a single value over every
      complex solution (parameter), at θ* and at θ**;
    * ``"local"``: locally identifiable and *proven* not globally: two admissible
      (real, positive where declared) solutions at θ* that differ (in that parameter),
      from the Gröbner basis or certified by the Krawczyk test; both are simple
      solutions, so they persist for every θ* nearby;
    * ``"local, global undetermined"``: locally identifiable, the global question open
      (the Gröbner step did not finish, or only positivity or realness at θ* separates
      θ* from the other complex solutions: a count of positive solutions holds at that
      θ* only, so it never makes a verdict "global");
    * ``"none"``: not locally identifiable (infinitely many solutions); the report
      then lists identifiable combinations and a reparameterisation.

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
        numerical search for other solutions of summary(θ) = summary(θ*) (a fixed
        number of curve steps and starts) then run side by side; each solution found is
        certified by the Krawczyk interval test when the summary system is square (as
        many equations as unknowns), and the parameters the certified solutions do not
        move are tried for a checked rational formula in the summary entries
        (:mod:`~symid.structural.rational_formulas`: globally identifiable).
        Certified solutions that move every parameter (but those a formula proves
        global) settle the verdicts: the report stops there, with ``n_solutions_at_least`` in
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
        Seed of the random rational points, an integer in [0, 2⁶³ − 1] (default 0).
        The report is a deterministic function of the model, the options and the seed:
        the same on any machine, except ``timing``. Wall time decides only how complete
        it is, never what it asserts: whether the Gröbner step finishes within
        ``timeout`` (else the global verdicts read ``"local, global undetermined"``,
        or ``"local"`` where certified witnesses prove it, with a lower bound on the
        count), and whether the exact count arrives before certified witnesses settle
        the verdicts. The witness search runs a fixed number of starts (not a time
        limit), so the witnesses and the lower bound do not depend on the machine's
        speed (up to floating-point rounding of the Gauss–Newton starts, which can
        only change which witnesses are found, each of them certified exactly). ``None``
        is refused rather than read as "a fresh random seed", so that a report can
        always be reproduced.
    engine : {"auto", "sympy", "msolve"}, optional
        What solves summary(θ) = summary(θ*) for a model whose Jacobian has full rank
        (finitely many solutions): ``"msolve"`` (F4 and a rational parametrization, much
        faster on 9–18 parameters; install with ``pip install "symid[msolve]"``, or set
        ``$SYMID_MSOLVE`` to the program; ``SYMID_MSOLVE=off`` turns it off), ``"sympy"``
        (Buchberger over ℚ, pure Python), or ``"auto"`` (default: msolve when found, else
        sympy). A model that is not locally identifiable is solved on a generic slice
        of its solution set (:mod:`~symid.structural.slicing`), by the same engine. A
        mass-spring-damper chain driven and measured at one mass needs neither: its
        continued-fraction inversion (:mod:`~symid.structural.ladder` at an end mass,
        :mod:`~symid.structural.ladder_interior` at an interior one) proves every
        parameter global in well under a second, whatever the engine; nor does one driven
        next to its free end and measured there (:mod:`~symid.structural.ladder_adjacent`,
        at most 0.3 s a point up to 6 masses, 1.2–1.5 s at 8).
        The report is the same either way (``engine`` in it says which ran; the floats of
        ``solutions`` agree to rounding). sympy's count over ℚ is exact; msolve's over ℚ
        is multi-modular with a probabilistic stopping criterion (Monte Carlo, as the
        confirmation modulo a random prime at θ** is for both); see
        :mod:`symid.structural.msolve`.
    at : dict of str to float, optional
        Your own values of the free parameters (nominal values, an estimate): the report
        then also lists every other admissible set of values with the same response *at
        these values* (``rep.solutions_at``; the global step run at them, with its own
        ``timeout``), for a model that is locally but not proven globally identifiable
        (a globally identifiable one has none at generic values; a model that is not
        locally identifiable has infinitely many, and ``fix`` says what to make known).
        The structural verdicts stay those of the random points.

    Raises
    ------
    ModelError
        A model, ``known`` or ``at`` that cannot be analysed: not a model, no parameter
        at all, ``known`` not a dict, an unknown or repeated name, a value that is not a
        finite real number, every parameter known, ``at`` missing a free parameter or
        negative for a positive one; or a model found degenerate during the analysis
        (det M(θ) ≡ 0).
    OptionError
        A bad ``timeout``, ``positive``, ``exact_count``, ``seed`` or ``engine`` (or
        ``engine="msolve"`` with no msolve program found).
    SolverError
        An analysis step failed unexpectedly (a bug), or msolve failed or wrote a
        malformed answer (:class:`~symid.structural.msolve.MsolveError`): never reported
        as a weaker verdict.

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
    >>> th = si.parameters("th")
    >>> si.identifiability(si.StateSpaceModel(A=[[-1]], B=[[th]], C=[[th]])).verdicts  # θ and −θ
    {'th': 'local'}
    >>> [c["expression"] for c in rep.combinations]
    ['b*c']
    >>> si.identifiability(model, known={"b": 2}).verdict
    'global'
    """
    point = None if at is None else _checked_point(model, known, at)
    rep = _identifiability(model, known=known, positive=positive, timeout=timeout, exact_count=exact_count,
                           seed=seed, engine=engine)
    return rep if point is None else _with_point(model, rep, point, timeout)


_AT_SKIPPED = {
    "global": "none: the model is globally identifiable (no other values give the response at generic values)",
    "none": "infinitely many: the model is not locally identifiable (make the parameters of `fix` known)",
}


def _checked_point(model, known: Mapping[str, float] | None, at: Mapping[str, float]) -> dict[str, float]:
    """``at`` as {free name: float}, checked (a ModelError names what is wrong)."""
    if not isinstance(at, Mapping):
        raise ModelError(f"at must be a dict of parameter values by name; got {type(at).__name__}")
    given_known = {getattr(k, "name", k) for k in (known or {})}
    free = [n for n in model.parameter_names if n not in given_known]
    names = {getattr(k, "name", k): v for k, v in at.items()}
    unknown = [n for n in names if n not in model.parameter_names]
    if unknown:
        raise ModelError(f"at names {', '.join(map(repr, unknown))}, not a parameter of the model "
                         f"({', '.join(model.parameter_names)})")
    missing = [n for n in free if n not in names]
    if missing:
        raise ModelError(f"at must give every free parameter; {', '.join(missing)} missing")
    out = {}
    positive = dict(zip(model.parameter_names, model.positive, strict=True))
    for n in free:
        try:
            v = float(names[n])
        except (TypeError, ValueError):
            raise ModelError(f"at[{n!r}] must be a real number; got {names[n]!r}") from None
        if not math.isfinite(v) or (positive[n] and v <= 0):
            raise ModelError(f"at[{n!r}] = {v!r}: a finite number{', > 0 (declared positive)' if positive[n] else ''}"
                             " is needed")
        out[n] = v
    return out


def _with_point(model, rep: IdentifiabilityReport, point: dict[str, float], timeout) -> IdentifiabilityReport:
    """The report with the other admissible solutions at the user's values (``at=``)."""
    if rep.verdict in _AT_SKIPPED:
        return dataclasses.replace(rep, at=point, at_status=_AT_SKIPPED[rep.verdict])
    reduced = model.with_known(rep.known) if rep.known else model
    t0 = time.perf_counter()
    others = solutions_at(reduced, [point[n] for n in reduced.parameter_names], timeout=timeout)
    spent = time.perf_counter() - t0
    if others is None:
        status = (f"not decided (the global step at these values did not finish within {timeout:g} s, or they are "
                  f"special: two solutions merging, a pole cancelling a zero)" if timeout is not None else
                  "not decided (these values are special: two solutions merging, a pole cancelling a zero)")
    elif not others:
        status = "none: no other admissible values give the response at these values"
    else:
        status = f"{len(others)} other admissible set(s) of values give the response at these values"
    return dataclasses.replace(rep, at=point, at_status=status,
                               solutions_at=None if others is None else tuple(others),
                               timing={**rep.timing, "at": spent})


def _identifiability(model, *, known, positive, timeout, exact_count, seed, engine) -> IdentifiabilityReport:
    """:func:`identifiability` without ``at``."""
    t0 = time.perf_counter()
    args = checked_arguments(model, known=known, timeout=timeout, positive=positive, exact_count=exact_count,
                             seed=seed, engine=engine)
    timeout, seed, known_exact = args.timeout, args.seed, args.known
    free = free_parameters(model, known_exact)
    names = tuple(q.name for q in free)
    pos = _positive_flags(model, args.positive, known_exact)
    necessary = _necessary(model, len(free), known_exact)
    notes: list[str] = []
    if getattr(model, "initial_state_kind", "zero") in ("known", "affine"):
        notes.append(_X0_IGNORED)

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
    # a model that is not locally identifiable: its summary entries (identifiable functions, the
    # last source of combinations) are computed beside the Gröbner step, on the core the witness
    # search would use, so that the combinations never depend on the basis finishing
    summary_job = None
    if not full_rank and timeout is not None:
        summary_job = start(_summary_candidates, {"model": model, "known": known_exact, "local": local,
                                                  "limit": 4 * len(free)})
    try:
        return _finish(model, args, local, monos, full_rank, free, names, pos, necessary, notes, t0, t_local, left,
                       summary_job)
    finally:
        if summary_job is not None:
            summary_job.stop()


def _finish(model, args, local, monos, full_rank, free, names, pos, necessary, notes, t0, t_local, left,
            summary_job) -> IdentifiabilityReport:
    """The global step, the verdicts, the combinations and the report (see :func:`identifiability`)."""
    timeout, seed, known_exact = args.timeout, args.seed, args.known
    fix = () if full_rank else tuple(q.name for q in parameters_to_fix(local))
    if local.rank == 0:  # nothing to fix so that the rest becomes identifiable: there is no rest
        fix = ()
        notes.append("the response does not depend on any parameter: nothing about them can be learned from it"
                     + (" (the output does not depend on the input at all: H ≡ 0; check which coordinates B and C "
                        "act on)" if all(local.silent) and _zero_response(model, known_exact) else ""))
    # locally identifiable linear functions: with the identifiable parameters they span every one; the global
    # step says which of their combinations are globally identifiable
    linear = [] if full_rank else linear_space(local, model, known_exact, seed=seed)
    forms = [*({nm: 1} for nm, ok in zip(names, local.identifiable, strict=True) if ok),
             *({nm: Fraction(int(v.numerator), int(v.denominator)) for nm, v in zip(names, vec, strict=True) if v}
               for vec in linear)]
    out = run_global(model, known_exact, names=names, positive=pos, seed=seed, extra_candidates=monos,
                     full_rank=full_rank, exact_count=args.exact_count, left=left, rank=local.rank,
                     msolve=args.msolve, fix=fix, linear_forms=forms,
                     identifiable=[nm for nm, ok in zip(names, local.identifiable, strict=True) if ok])
    glob = out.result
    notes.extend(out.notes)
    determined = glob is not None
    witnesses, certified, theta_star = out.witnesses, out.certified, out.theta_star
    n_cert = sum(certified)
    if determined:
        global_status = "determined"
    else:
        if out.limit is not None:
            why = out.limit
        elif out.proven_by_witnesses and not args.exact_count:
            why = "the Gröbner basis was stopped once certified solutions settled the verdicts; exact_count=True " \
                  "keeps it running until the timeout"
        elif n_cert:
            why = f"the Gröbner basis did not finish within the timeout of {timeout:g} s"
        else:
            why = f"timeout after {timeout:g} s"
        if n_cert:
            global_status = (f"NOT globally identifiable, proven by {n_cert} certified solution(s) θ ≠ θ* of "
                             f"summary(θ) = summary(θ*); exact count not computed ({why})")
        else:
            global_status = f"undetermined ({why})"
            if witnesses:
                global_status += (f"; {len(witnesses)} other admissible solution(s) of summary(θ) = summary(θ*) "
                                  "found numerically (not certified): evidence that the model is NOT globally "
                                  "identifiable")
    if witnesses and not determined:
        notes.append(f"the {len(witnesses)} solution(s) θ ≠ θ* in `witnesses` were {witness_method}; "
                     f"{n_cert} of them certified by the Krawczyk test (an exact real admissible solution within "
                     "relative 1e-6 or less, distinct from θ* and from each other, simple, so it persists for every "
                     "θ near θ*)")
    if out.formulas and not determined:
        notes.append("globally identifiable by a rational formula in the summary entries c[…], checked exactly as a "
                     f"polynomial identity: {'; '.join(out.formulas.values())} (symid.structural.rational_formulas)")
    t_global = out.seconds

    loc = dict(zip(names, local.identifiable, strict=True))
    verdicts: dict[str, str] = {}
    n_sol = n_real = n_complex = None
    positivity_changed = False
    solutions: tuple = ()
    if not determined:
        star_f = {k: float(sp.Rational(v)) for k, v in theta_star.items()}
        moved = {nm for w, ok in zip(witnesses, certified, strict=True) if ok for nm in names
                 if abs(w[nm] - star_f[nm]) > 1e-6 * max(1.0, abs(star_f[nm]))}
        for nm in names:
            verdicts[nm] = "none" if not loc[nm] else (
                "global" if nm in out.formulas else (LOCAL if nm in moved else UNDETERMINED))
        verdict = "none" if not full_rank else (LOCAL if n_cert else UNDETERMINED)
        if full_rank and all(v == "global" for v in verdicts.values()):
            verdict = "global"  # every parameter a checked rational formula in the summary: one solution
        count = (f"at least {1 + n_cert} admissible solutions at θ* (certified lower bound: θ* and {n_cert} "
                 f"solution(s) certified by the Krawczyk test; exact count not computed: {why})") if n_cert else \
            f"not computed ({why})"
    else:
        notes.extend(glob.notes)
        n_sol, n_real, n_complex = glob.n_admissible, glob.n_real, glob.n_complex
        solutions = glob.solutions
        verdict, verdicts = _verdicts_from_groebner(glob, names, loc, full_rank, admissible=True)
        if not full_rank:
            count = "infinitely many (the Jacobian is rank deficient: a positive-dimensional solution set)"
        elif not glob.zero_dimensional:
            count = "infinitely many at θ* (a positive-dimensional part at θ* although the Jacobian has full rank)"
            notes.append("the Jacobian has full rank but the solution set has a positive-dimensional part "
                         "(non-generic points)")
        else:
            count = (f"exact: {n_complex} complex solution(s) (generic: the same at every generic θ*); at this θ*, "
                     f"{n_real} real and {n_sol} admissible (real and positive where declared: these two "
                     "counts depend on θ*)")
        if glob.zero_dimensional and full_rank:
            real_verdict, real_params = _verdicts_from_groebner(glob, names, loc, full_rank, admissible=False)
            if real_verdict != verdict or real_params != verdicts:
                positivity_changed = True
                pos_names = [nm for nm, f in zip(names, pos, strict=True) if f]
                changed = [nm for nm in names if real_params[nm] != verdicts[nm]]
                what = f"model verdict {real_verdict} → {verdict}" if real_verdict != verdict else \
                    f"verdict of {', '.join(changed)} {real_params[changed[0]]} → {verdicts[changed[0]]}"
                notes.append(f"positivity ({', '.join(pos_names)} > 0) discarded {n_real - n_sol} of {n_real} real "
                             f"solutions at θ*: {what}")
            elif n_real is not None and n_sol is not None and n_real > n_sol:
                notes.append(f"positivity discarded {n_real - n_sol} of {n_real} real solutions at θ* (verdict "
                             "unchanged)")
            if n_complex and n_real is not None and n_complex > n_real:
                notes.append(f"{n_complex - n_real} of {n_complex} complex solutions are not real at θ* and were "
                             "discarded")
            open_ = [nm for nm in names if verdicts[nm] == UNDETERMINED]
            if n_complex is not None and n_complex > 1 and n_sol == 1 and open_:
                notes.append(f"only θ* itself is admissible at θ*, but summary(θ) = summary(θ*) has {n_complex} "
                             "complex solutions: whether the others become admissible elsewhere depends on θ*, so "
                             "the global verdict is undetermined (not 'global': that would hold at this θ* only)")
            elif n_complex is not None and n_complex > 1 and n_sol == 1:
                notes.append(f"only θ* itself is admissible at θ* of the {n_complex} complex solutions, but at "
                             "another random point two admissible solutions differ (above): not global")
            if open_:
                global_status = (f"determined (the exact step finished: {n_complex} complex solutions); the "
                                 f"verdicts of {', '.join(open_)} stay undetermined: no point tried had two "
                                 "admissible solutions that differ in them, and a count of admissible solutions at "
                                 "one θ* is not structural")
            if n_complex is not None and n_complex > 1:
                notes.append("counts of real and admissible solutions are at the random point θ*; elsewhere they "
                             f"can differ (the complex count, {n_complex}, is generic)")
        if glob.confirmed and glob.theta_confirm:
            notes.append("global verdicts confirmed at a second independent random point θ** (same result)")

    # -- combinations and reparameterisation -------------------------------------
    combos, reparam = [], {}
    if local.rank < len(free):
        # the scaling monomials (global when single-valued on the slice: symid.structural.slicing), then the
        # summary entries, identifiable functions by definition (computed in a child beside the global step)
        member = glob.membership if determined and len(glob.membership) == len(monos) else (None,) * len(monos)
        candidates = [(e, "scaling", member[i]) for i, e in enumerate(monos)]
        candidates += _linear_candidates(free, linear, forms, glob.linear_global if determined else None)
        if determined and glob.partial:
            notes.append("the global flags of the combinations are not decided: only some solutions of the slice "
                         "were computed (exact ones, from symmetries of the summary), enough for every verdict")
        s_kwargs = {"model": model, "known": known_exact, "local": local, "limit": 4 * len(free)}
        status_s, found_s = run_with_deadline(_summary_candidates, s_kwargs, left()) \
            if summary_job is None else summary_job.wait(left())
        stopped = limit_reason("combinations step", status_s, found_s)
        if status_s == "ok":
            found_s, skipped = found_s
            candidates += found_s
            if skipped:
                notes.append(f"{skipped} summary entr{'y' if skipped == 1 else 'ies'} with more than "
                             f"{MAX_COMBINATION_TERMS} terms not offered as combinations (too long to read)")
        elif stopped is not None:
            notes.append(f"no combinations from the summary entries: {stopped}")
        elif status_s == "timeout":
            notes.append("the summary entries were not computed within the budget: no combinations from them")
        else:
            raise_on_error("combinations", status_s, found_s)
        chosen = select_combinations(local, candidates)
        combos = [{"expression": sp.sstr(c.expression), "source": c.source, "global": c.is_global} for c in chosen]
        reparam = {f"phi{i + 1}": c["expression"] for i, c in enumerate(combos)}
        if len(local.identifiable) - sum(local.identifiable) > 0 and \
                sum(local.identifiable) + len(combos) < local.rank:
            notes.append("the combinations found do not reach the Jacobian rank "
                         f"({sum(local.identifiable) + len(combos)} of {local.rank}); the list is incomplete")
        if fix:
            notes.append(_check_fix(model, known_exact, fix, seed, left()))
    silent = [nm for nm, q in zip(names, local.silent, strict=True) if q]
    if silent:
        notes.append(f"the response does not depend on {', '.join(silent)} at all (their column of the Jacobian is "
                     f"zero at every test point): no data of this kind tell anything about "
                     f"{'it' if len(silent) == 1 else 'them'}; drop {'it' if len(silent) == 1 else 'them'} from the "
                     "model or give a known value")
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
        n_solutions_at_least=(1 + n_cert) if (n_cert and not determined) else None,
        verdicts_proven=verdict != UNDETERMINED and UNDETERMINED not in verdicts.values(), timing=timing,
        theta_confirm=dict(glob.theta_confirm) if determined else {}, solution_count=count,
        engine=glob.engine if determined else "")


def _linear_candidates(free, linear, forms, lam) -> list[tuple]:
    """Linear combinations, the globally identifiable ones first (a basis of the combinations of ``forms`` with
    coefficients ``lam``, in reduced row echelon form), then the basis ``linear`` of the locally identifiable ones
    (global when in that span; unknown when ``lam`` is None: the global step did not finish)."""
    n = len(free)
    index = {q.name: i for i, q in enumerate(free)}

    def vec(form) -> list:
        out = [QQ(0)] * n
        for nm, a in form.items():
            out[index[nm]] = QQ(Fraction(a).numerator, Fraction(a).denominator)
        return out

    out = []
    glob_rows = []
    if lam is not None:
        combos = []
        for coeffs in lam:
            acc = [QQ(0)] * n
            for c, form in zip(coeffs, forms, strict=True):
                if c:
                    acc = [x + QQ(c.numerator, c.denominator) * y for x, y in zip(acc, vec(form), strict=True)]
            combos.append(acc)
        glob_rows = rref_rows(combos, n)
        out += [(linear_expression(row, free), "linear", True) for row in glob_rows]
    for row in linear:
        is_global = None if lam is None else _rank([*glob_rows, row]) == len(glob_rows)
        out.append((linear_expression(row, free), "linear", is_global))
    return out


def _factored(poly) -> sp.Expr:
    """A polynomial as an expression with the monomial common to all its terms pulled out (cheap, on the terms)."""
    terms = list(poly.terms())
    common = [min(m[i] for m, _ in terms) for i in range(poly.ring.ngens)] if terms else []
    if not any(common):
        return poly.as_expr()
    rest = poly.ring({tuple(e - g for e, g in zip(m, common, strict=True)): c for m, c in terms})
    return sp.Mul(*[q**e for q, e in zip(poly.ring.symbols, common, strict=True) if e]) * rest.as_expr()


def _summary_candidates(model, known, local, limit: int) -> list[tuple]:
    """The ``limit`` simplest summary entries (fewest terms) as combination candidates, with their gradients,
    and how many were skipped for having more than :data:`MAX_COMBINATION_TERMS` terms.

    Run in a child process beside the global step of a model that is not locally
    identifiable: the summary entries are identifiable functions (global by definition),
    so the combinations do not depend on the global step finishing.
    """
    summ = exhaustive_summary(model, known)
    order = sorted(range(len(summ)), key=lambda i: (len(summ.numerators[i]) + len(summ.denominators[i]), i))
    out, skipped = [], 0
    for i in order[:limit]:
        num, den = summ.numerators[i], summ.denominators[i]
        if len(num) + len(den) > MAX_COMBINATION_TERMS:
            skipped += 1
            continue
        out.append((_factored(num) / _factored(den), "summary", True, poly_gradients(num, den, local.points)))
    return out, skipped


def _zero_response(model, known_exact) -> bool:
    """Whether the model's transfer function is identically zero: its exhaustive summary has no entry."""
    return len(exhaustive_summary(model, known_exact).labels) == 0


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


_X0_IGNORED = ("this analysis is of the input-output map from a zero initial state: the model's nonzero initial state "
               "x0 is not used, and records of its free response (a dose given as x0) can determine parameters "
               "that this report calls not identifiable")


GLOBAL_CHECK_BUDGET = 3.0
"""Seconds :func:`several_solutions` gives :func:`identifiability` (the small models where a flip-flop hides, such
as first-order absorption and elimination, take 0.1 to 0.5 s; a new user's 5th-order LC ladder, whose mirror image
fits as well, 0.9 to 1.5 s idle, and more on a busy machine, where a budget of 1 s let the mirror pass unsaid in 3
of 4 runs). Larger ones end undetermined, and :func:`global_check` says so."""


def several_solutions(model, *, timeout: float | None = GLOBAL_CHECK_BUDGET) -> str | None:
    """One sentence when :func:`identifiability` proves, within ``timeout`` seconds (``None``: no limit), that other
    admissible parameter values give the model's response (locally, not globally identifiable), else ``None``.

    :func:`symid.identify` calls it after a fit: the estimate is then one of several that the data
    cannot tell apart, and which one depends on the start (a new user's oral-dose model, ka and
    ke interchangeable, came back with them swapped from 19 of 20 records, a success every time
    and nothing said). Cached per model structure and ``timeout`` within the process; a check
    that runs out of time returns ``None`` here, and :func:`global_check` says it was not decided.
    ``None`` for a model with a
    nonzero initial state: the analysis is of the input-output map from rest, and a free
    response can tell apart solutions that map cannot.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.analyse import several_solutions
    >>> ka, ke, q = si.parameters("ka ke q", positive=True)
    >>> oral = si.StateSpaceModel(A=[[-ka, 0], [ka, -ke]], B=[[1], [0]], C=[[0, q]])
    >>> print(several_solutions(oral, timeout=None))  # doctest: +ELLIPSIS
    the model is locally but not globally identifiable: at a random parameter point, 2 admissible ...
    """
    return global_check(model, timeout=timeout)[0]


def global_check(model, *, timeout: float | None = GLOBAL_CHECK_BUDGET) -> tuple[str | None, bool]:
    """:func:`several_solutions`'s sentence (or ``None``) and whether the question was decided within ``timeout``:
    ``(None, False)`` when the analysis did not settle whether other admissible parameter values give the model's
    response (what :func:`symid.identify` then says, rather than nothing: the answer must not depend on the
    machine's load). Cached per model structure and ``timeout`` within the process.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.analyse import global_check
    >>> k, g = si.parameters("k g", positive=True)
    >>> global_check(si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]]), timeout=None)
    (None, True)
    """
    if getattr(model, "initial_state_kind", "zero") in ("known", "affine"):
        return None, True  # nothing asked: the map from rest is not what such records determine
    try:
        key = (timeout, type(model).__name__, getattr(model, "output", None), tuple(model.parameter_names),
               tuple(model.positive), getattr(model, "initial_state_kind", "zero"),
               tuple((k, sp.srepr(v)) for k, v in sorted(model.symbolic.items())))
    except (AttributeError, TypeError):
        return None, False
    if key not in _SEVERAL:
        if len(_SEVERAL) >= 64:  # the oldest goes
            _SEVERAL.pop(next(iter(_SEVERAL)))
        _SEVERAL[key] = _several_solutions(model, timeout)
    return _SEVERAL[key]


_SEVERAL: dict[tuple, tuple[str | None, bool]] = {}
""":func:`global_check`'s answers by model structure (a cache: the answer depends on the structure only)."""


def _several_solutions(model, timeout: float | None) -> tuple[str | None, bool]:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rep = identifiability(model, timeout=timeout)
    except Exception:  # a check after the fit never costs the user the fit: it says it was not decided instead
        return None, False
    count, bound = rep.n_solutions, rep.n_solutions_at_least
    if rep.verdict != "local" or not ((count or 0) >= 2 or (bound or 0) >= 2):
        return None, bool(rep.verdicts_proven)
    star = {n: float(Fraction(str(v))) for n, v in rep.theta_star.items()}
    sols = [*rep.solutions] if rep.solutions else [star, *rep.witnesses]
    differ = [n for n in rep.parameters
              if len({float(f"{float(sol[n]):.6g}") for sol in sols if n in sol}) > 1]
    how = f"{count}" if count is not None else f"at least {bound}"
    listed = "solutions lists them" if rep.solutions else "witnesses lists those found"
    return (f"the model is locally but not globally identifiable: at a random parameter point, {how} admissible "
            f"parameter values give the same response" + (f" ({', '.join(differ)} differ between them)" if differ
                                                         else "")
            + "; the estimate is one of them, which one depends on the start, and no data of this kind tell them "
            f"apart (si.identifiability(model).{listed}): fix what is known, or compare starts (starts=, "
            ".alternatives())"), True


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
    if bad and getattr(model, "initial_state_kind", "zero") in ("known", "affine"):
        warnings.warn(
            f"parameter(s) {', '.join(bad)} are not locally identifiable from the input-output map from a zero "
            "initial state, the only map this check analyses; this model's nonzero initial state x0 may determine "
            "them from its free response (a dose given as x0), so check the estimate's standard errors "
            "(identifiability_check=False skips this check).",
            IdentifiabilityWarning, stacklevel=stacklevel + 1)
    elif bad:
        warnings.warn(
            f"parameter(s) {', '.join(bad)} are not locally identifiable from the input-output map: infinitely "
            "many values fit the data equally well. Fix some of them (known values) or reparameterise; "
            "si.identifiability(model) lists the identifiable combinations.",
            IdentifiabilityWarning, stacklevel=stacklevel + 1)
    return bad


def _solutions_at(model, point: list) -> list[dict[str, float]]:
    """The admissible real solutions of summary(θ) = summary(point) (a run of the global step at that point)."""
    from symid.structural.global_ import global_analysis, star_and_summary
    from symid.structural.msolve import msolve_binary
    from symid.structural.summary import KIND_TF, analysed_output, is_minimal_at, model_matrices

    params, _, _, summ, rng = star_and_summary(model, seed=0)
    star = [sp.Rational(v.numerator, v.denominator) for v in point]
    kind = model_kind(model)
    if summ.kind == KIND_TF and not (is_minimal_at(model_matrices(model, None), kind, analysed_output(model),
                                                   params, star) or summ.exhaustive_at(star)):
        raise ModelError("the transfer function is not an exhaustive summary at this point")
    binary = msolve_binary()
    res = global_analysis(model, positive=list(model.positive), prepared=(params, star, True, summ, rng),
                          msolve=binary, expressions=False)
    return [dict(s) for s in res.solutions]


def solutions_at(model, theta, *, timeout: float | None = GLOBAL_CHECK_BUDGET) -> list[dict[str, float]] | None:
    """The other admissible parameter values with the response of the model at ``theta`` (a dict per solution),
    from the global step run at ``theta`` itself (rounded to 12 digits, as a rational point); ``None`` when it does
    not finish within ``timeout`` seconds or fails (nothing is claimed then), ``[]`` when there are none.

    :func:`symid.identify` calls it for an estimate of a model :func:`several_solutions` calls not unique: the
    user sees the values the data cannot tell from the estimate. A point where the transfer function is not an
    exhaustive summary (a pole-zero cancellation at ``theta``) or has a multiple solution gives ``None``.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.analyse import solutions_at
    >>> ka, ke, q = si.parameters("ka ke q", positive=True)
    >>> oral = si.StateSpaceModel(A=[[-ka, 0], [ka, -ke]], B=[[1], [0]], C=[[0, q]])
    >>> [{k: round(v, 6) for k, v in s.items()} for s in solutions_at(oral, [1.2, 0.15, 0.025], timeout=None)]
    [{'ka': 0.15, 'ke': 1.2, 'q': 0.2}]
    """
    try:
        names = list(model.parameter_names)
        values = [float(v) for v in theta]
        if len(values) != len(names) or not all(map(math.isfinite, values)):
            return None
        point = [Fraction(float(f"{v:.12g}")) for v in values]
        status, found = run_with_deadline(_solutions_at, {"model": model, "point": point}, timeout)
    except Exception:  # a check after the fit never costs the user the fit
        return None
    if status != "ok":
        return None
    return [s for s in found if any(abs(s[n] - v) > 1e-8 * max(abs(v), 1e-300) for n, v in zip(names, values,
                                                                                                  strict=True))]
