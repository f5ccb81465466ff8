"""The bounded steps of :func:`~symid.structural.identifiability`, each in a child process under one budget.

The exact local step runs first; for a locally identifiable model, the Gröbner step
and the numerical witness search then run side by side in two child processes
(:mod:`~symid.structural.deadline`), started once each (the witness search after a
head start of ``HEAD_START`` s, and only if the basis is not ready by then). Certified witnesses that move
every parameter settle the verdicts and the Gröbner child is stopped (unless
``exact_count``); otherwise the Gröbner child has the rest of the budget. Once the
witness search has ended (or when it is not run), the Gröbner child is told that a core
is spare and starts the confirmation at θ** beside the step at θ*
(:func:`~symid.structural.global_.generic_global`'s ``spare_core``).

How an outcome is read (issue 12, item 5: an internal failure is never turned into a
weaker verdict):

* a result: used;
* the deadline: "undetermined (timeout ...)";
* a documented limit: "undetermined (reason)" — the exact step's
  :class:`~symid.structural.global_.ExactStepLimit` (too many solutions), a
  ``MemoryError``, or a child that died without a result (a crash, the out-of-memory
  killer, killed by hand), with the exit code or signal named;
* a model problem found inside a step (``ModelError`` and its subclasses): raised as a
  :class:`~symid.errors.ModelError`;
* any other exception (a bug): raised as a :class:`~symid.errors.SolverError` naming
  the step, with the child's traceback.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import sympy as sp

from symid.errors import ModelError, SolverError
from symid.structural.deadline import Running, run_with_deadline, start, wait_any
from symid.structural.global_ import GlobalResult, generic_global, star_and_summary
from symid.structural.rational_formulas import rational_formulas
from symid.structural.slicing import sliced_global
from symid.structural.witness import WitnessResult, find_witnesses

__all__ = ["GlobalOutcome", "limit_reason", "raise_on_error", "run_global"]

HEAD_START = 0.05
"""Seconds the Gröbner step runs alone before the witness search starts (a fork costs ~7 ms here; most zoo
models' bases take less than this)."""

_MODEL_ERRORS = ("ModelError", "NonAffineError", "PoleError", "DataError")
_LIMITS = ("ExactStepLimit", "SummaryTooLarge", "MemoryError")


def _global_step(model, known, positive, seed, extra_candidates, expressions, rank, msolve=None, fix=(),
                 linear_forms=(), identifiable=None, spare_core=None):
    """A generic θ*, the summary and the Gröbner step (confirmed at θ**), in one child process.

    ``fix``: for a model that is not locally identifiable, the parameters that cut its solution set
    (:mod:`~symid.structural.slicing`), and ``linear_forms`` the linear functions whose single-valued
    combinations are asked. ``spare_core``: an event the parent sets when the witness search no longer
    needs its core (:func:`~symid.structural.global_.generic_global` then confirms at θ** beside θ*).
    """
    if fix:
        return sliced_global(model, known, fix=fix, positive=positive, seed=seed, extra_candidates=extra_candidates,
                             msolve=msolve, linear_forms=linear_forms, identifiable=identifiable)
    return generic_global(model, known, positive=positive, seed=seed, rank=rank, extra_candidates=extra_candidates,
                          expressions=expressions, msolve=msolve, spare_core=spare_core)


class SpareFlag:
    """A flag the parent sets once a core is free, read by its child processes: ``set``, ``is_set``, ``wait``.

    One byte of shared memory, with no lock on purpose. A ``multiprocessing.Event`` waited
    on in a child that exits or is killed mid-wait leaves its condition counting a sleeper
    that never wakes, and the parent's next ``set()`` then blocks forever (seen: a report
    that hung when its global step ended within the head start while the child's
    confirmation thread was still polling the event).
    """

    def __init__(self, ctx: Any):
        self._value = ctx.RawValue("b", 0)

    def set(self) -> None:
        self._value.value = 1

    def is_set(self) -> bool:
        return bool(self._value.value)

    def wait(self, timeout: float | None = None) -> bool:
        """Whether the flag is set, after waiting up to ``timeout`` s for it (None: as long as it takes)."""
        end = None if timeout is None else time.monotonic() + timeout
        while not self._value.value:
            rest = None if end is None else end - time.monotonic()
            if rest is not None and rest <= 0:
                return False
            time.sleep(0.02 if rest is None else min(0.02, rest))  # as often as a polling Event.wait(0.02) woke
        return True


def _spare_core_event() -> SpareFlag | None:
    """A flag shared with child processes, or None on a machine with one usable core (nothing to spare)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        cores = os.cpu_count() or 1
    if cores < 2:
        return None
    return SpareFlag(mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn"))


def _witness_step(model, known, positive, seed, rank):
    """θ* (the Gröbner step's first draw), the summary, the numerical witness search and, for the parameters the
    certified witnesses do not move, checked rational formulas (:mod:`~symid.structural.rational_formulas`), in
    one child process: (witnesses, {parameter: formula text})."""
    prepared = star_and_summary(model, known, seed=seed, rank=rank)
    wit = find_witnesses(model, known, positive=positive, seed=seed, prepared=prepared)
    params, star, _, summ, _ = prepared
    moved = _moved(wit, [q.name for q in params])
    rest = [q.name for q in params if q.name not in moved]
    formulas = rational_formulas(summ, rest, seed=seed, at=star) if rest else {}
    return wit, {name: f.text(summ.labels) for name, f in formulas.items()}


def _moved(wit: WitnessResult, names: Sequence[str]) -> set[str]:
    """The parameters in which some certified witness differs from θ*."""
    star_f = {k: float(sp.Rational(v)) for k, v in wit.theta_star.items()}
    return {nm for w, ok in zip(wit.witnesses, wit.certified, strict=True) if ok
            for nm in names if abs(w[nm] - star_f[nm]) > 1e-6 * max(1.0, abs(star_f[nm]))}


def limit_reason(step: str, status: str, value: object) -> str | None:
    """Why ``step`` stopped at a documented limit (a dead child, out of memory, too many solutions); else None.

    Examples
    --------
    >>> from symid.structural.steps import limit_reason
    >>> limit_reason("Gröbner step", "died", "its process was killed by SIGKILL")
    'the Gröbner step stopped without a result: its process was killed by SIGKILL'
    >>> limit_reason("Gröbner step", "error", ("TypeError", "a bug", "")) is None
    True
    """
    if status == "died":
        return f"the {step} stopped without a result: {value}"
    if status == "error" and value[0] == "MemoryError":
        return f"the {step} ran out of memory (MemoryError{': ' + value[1] if value[1] else ''})"
    if status == "error" and value[0] in _LIMITS:
        return str(value[1])
    return None


def raise_on_error(step: str, status: str, value: object) -> None:
    """Raise the failure of ``step`` (status ``"error"``): a model problem as ModelError, anything else as SolverError.

    Examples
    --------
    >>> from symid.structural.steps import raise_on_error
    >>> raise_on_error("global", "error", ("KeyError", "'x'", ""))
    Traceback (most recent call last):
    ...
    symid.errors.SolverError: the global step of the identifiability analysis failed: KeyError: 'x'
    """
    if status != "error":
        return
    name, message, tb = value
    if name in _MODEL_ERRORS:
        raise ModelError(message)
    raise SolverError(f"the {step} step of the identifiability analysis failed: {name}: {message}"
                      + (f"\n{tb}" if tb else ""))


@dataclass
class GlobalOutcome:
    """What the Gröbner step and the witness search gave within the budget.

    Attributes
    ----------
    result : GlobalResult or None
        The exact global result, when the Gröbner step finished.
    limit : str or None
        The documented limit that stopped the Gröbner step, if any.
    witnesses : tuple of dict
        Solutions θ ≠ θ* found by the witness search (when it finished first).
    certified : tuple of bool
        Per witness, certified by the Krawczyk test.
    theta_star : dict of str to str
        θ* of the witness search (the same as the Gröbner step's).
    proven_by_witnesses : bool
        Every parameter is settled: moved by a certified witness (not globally identifiable)
        or given by a checked formula (globally identifiable, ``formulas``).
    formulas : dict of str to str
        Parameters the witnesses do not move that a checked rational formula in the
        summary entries proves globally identifiable, with the formula.
    seconds : float
        Wall time of the step.
    notes : list of str
    """

    result: GlobalResult | None = None
    limit: str | None = None
    witnesses: tuple = ()
    certified: tuple = ()
    theta_star: dict = field(default_factory=dict)
    proven_by_witnesses: bool = False
    formulas: dict = field(default_factory=dict)
    seconds: float = 0.0
    notes: list = field(default_factory=list)


def _read_witnesses(out: GlobalOutcome, value: tuple, names: Sequence[str]) -> None:
    wit, formulas = value
    moved = _moved(wit, names)
    out.theta_star, out.witnesses, out.certified = wit.theta_star, wit.witnesses, wit.certified
    out.formulas = dict(formulas)
    out.proven_by_witnesses = bool(moved) and (moved | set(formulas)) == set(names)
    if wit.witnesses and not any(wit.certified):
        why = ("the Krawczyk test failed for each" if wit.square else
               "the Krawczyk test needs as many summary equations as unknowns; this system has more")
        out.notes.append(f"the witnesses are not certified ({why}): they are numerical evidence, not a proof")
    elif not wit.witnesses:
        out.notes.append(f"no second solution found numerically (curves and {wit.n_starts} starts); this proves "
                         "nothing about the global verdict")


def run_global(model, known: Mapping[str, sp.Rational], *, names: Sequence[str], positive: Sequence[bool],
               seed: int, extra_candidates: Sequence[sp.Expr], full_rank: bool, exact_count: bool,
               left: Callable[[], float | None], rank: int | None = None, msolve: str | None = None,
               fix: Sequence[str] = (), linear_forms: Sequence[Mapping[str, object]] = (),
               identifiable: Sequence[str] | None = None) -> GlobalOutcome:
    """Run the Gröbner step (and, for a full-rank Jacobian, the witness search beside it) within ``left()`` s.

    ``left()`` gives the seconds left of the budget (``None``: no limit, and the
    Gröbner step runs in this process without a witness search). ``msolve``: the msolve
    program for the exact step (:func:`~symid.structural.global_.generic_global`).
    ``fix``: for a rank-deficient Jacobian, the parameters whose random values cut the
    solution set to finitely many points (:mod:`~symid.structural.slicing`);
    ``linear_forms``: linear functions of θ whose single-valued combinations are asked;
    ``identifiable``: the locally identifiable parameters.
    """
    t1 = time.perf_counter()
    out = GlobalOutcome()
    g_kwargs = {"model": model, "known": known, "positive": list(positive), "seed": seed,
                "extra_candidates": list(extra_candidates), "expressions": not full_rank, "rank": rank,
                "msolve": msolve, "fix": tuple(fix), "linear_forms": list(linear_forms),
                "identifiable": None if identifiable is None else list(identifiable)}
    if left() is None:  # no deadline: the exact answer, in this process
        status, value = run_with_deadline(_global_step, g_kwargs, None)
    else:
        status, value = _side_by_side(model, known, names, positive, seed, g_kwargs, full_rank, exact_count,
                                      left, out, rank)
    out.limit = limit_reason("Gröbner step", status, value)
    if out.limit is None:
        raise_on_error("global (Gröbner basis)", status, value)
    if status == "ok":
        if not isinstance(value, GlobalResult):  # pragma: no cover - defensive
            raise SolverError(f"the global step returned {type(value).__name__}, not a result")
        out.result = value
    out.seconds = time.perf_counter() - t1
    return out


def _side_by_side(model, known, names, positive, seed, g_kwargs, full_rank, exact_count, left,
                  out: GlobalOutcome, rank) -> tuple[str, object]:
    gjob: Running | None = None
    wjob: Running | None = None
    status, value = "timeout", None
    spare = _spare_core_event()  # set once the witness search is not (or no longer) running
    try:
        gjob = start(_global_step, {**g_kwargs, "spare_core": spare})
        if full_rank and gjob.wait(min(HEAD_START, left()))[0] == "timeout":  # a fast basis needs no witnesses
            wjob = start(_witness_step, {"model": model, "known": known, "positive": list(positive), "seed": seed,
                                         "rank": rank})
        elif spare is not None:
            spare.set()
        while True:
            wait_any([j for j in (gjob, wjob) if j is not None], left())
            status, value = gjob.wait(0)
            if status != "timeout":
                break
            if wjob is not None:
                wstatus, wit = wjob.wait(0)
                if wstatus != "timeout":
                    wjob = None
                    if spare is not None:
                        spare.set()
                    why = limit_reason("numerical search for a second solution", wstatus, wit)
                    if why is not None:
                        out.notes.append(why)
                    else:
                        raise_on_error("witness search", wstatus, wit)
                        _read_witnesses(out, wit, names)
                        if out.proven_by_witnesses and not exact_count:
                            break
            if left() <= 0:
                break
        if wjob is not None and status == "timeout":
            out.notes.append("the numerical search for a second solution did not finish within the timeout")
    finally:
        for job in (gjob, wjob):
            if job is not None:
                job.stop()
    return status, value
