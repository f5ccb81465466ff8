"""The identifiability report: per-parameter verdicts, solution count, combinations, timing."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from fractions import Fraction
from typing import Any

__all__ = ["VERDICTS", "IdentifiabilityReport", "NecessaryCondition"]

_VERDICT_TEXT = {
    "global": "GLOBALLY IDENTIFIABLE",
    "local": "LOCALLY, NOT GLOBALLY IDENTIFIABLE (finitely many solutions)",
    "local, global undetermined": "LOCALLY IDENTIFIABLE (global verdict undetermined)",
    "none": "NOT IDENTIFIABLE",
}

VERDICTS = ("global", "local", "local, global undetermined", "none")
"""The values of ``verdict`` and ``verdicts[name]``."""


@dataclass(frozen=True)
class NecessaryCondition:
    """The counting condition of thesis §1-2: at most n(p + m) free parameters.

    The thesis states "fewer than n(p + m)"; the e-nose model (6-19) has exactly
    n(p + m) = 6 parameters and is identifiable, so the bound that holds is
    ``n_parameters ≤ n(p + m)`` (plus p·m when D carries parameters): an order-n
    input-output map has n(p + m) (+ p·m) free coordinates.
    """

    n_parameters: int
    n_states: int
    n_inputs: int
    n_outputs: int
    bound: int
    satisfied: bool

    def __str__(self) -> str:
        sign = "≤" if self.satisfied else ">"
        mark = "satisfied" if self.satisfied else "VIOLATED: cannot be identifiable"
        if self.satisfied and self.n_parameters == self.bound:
            mark = "satisfied with equality (the thesis's strict '<' is too strong: see (6-19))"
        n, p, m = self.n_states, self.n_outputs, self.n_inputs
        if self.bound == n * (p + m):
            count = f"n(p+m) = {n}·({p}+{m})"
        else:  # D carries parameters: p·m more coordinates
            count = f"n(p+m) + pm = {n}·({p}+{m}) + {p}·{m}"
        return f"{self.n_parameters} free parameters {sign} {count} = {self.bound}: {mark}"


_APART_SHOWN = 3  # other solutions compared with θ*'s in the summary (every one is in rep.solutions)


@dataclass(frozen=True)
class IdentifiabilityReport:
    """Structural identifiability of a model's parameters from its input-output map.

    Attributes
    ----------
    model : str
        Short description of the model.
    parameters : tuple of str
        The free (unknown) parameters examined, in θ order.
    known : dict of str to float
        Parameters fixed by ``known=``.
    verdict : str
        Model verdict, one of :data:`VERDICTS`: ``"global"`` (one solution of
        summary(θ) = summary(θ*) over ℂ, at a generic θ* and confirmed at a second
        point), ``"local"`` (locally identifiable and *proven* not globally: two
        admissible solutions at θ*, from the Gröbner step or certified witnesses),
        ``"local, global undetermined"`` (locally identifiable; the global question is
        open: the Gröbner step did not finish, or only positivity or realness at θ*
        separates θ* from the other complex solutions) or ``"none"`` (not locally
        identifiable).
    verdicts : dict of str to str
        Per free parameter, the same four values: ``"global"`` when the parameter
        takes a single value over every complex solution (at θ* and θ**), ``"local"``
        when it takes two values over admissible solutions at θ* (Gröbner step or a
        certified witness), ``"local, global undetermined"`` when locally identifiable
        and neither is shown, ``"none"`` when not locally identifiable.
    locally_identifiable : dict of str to bool
        Per free parameter, from the Jacobian's null space.
    global_determined : bool
        Whether the global (Gröbner) step finished.
    global_status : str
        ``"determined"``; ``"determined (...); the verdicts of … stay undetermined: ..."``
        when the exact step finished but only θ* is admissible at θ* among several complex
        solutions and no other point showed two admissible ones that differ;
        ``"NOT globally identifiable, proven by k certified
        solution(s) ..."`` when certified witnesses settled the verdicts before the
        Gröbner step finished; or ``"undetermined (...)"`` with the reason (timeout,
        error).
    n_solutions : int or None
        Admissible solutions of summary(θ) = summary(θ*) (real, positive where declared)
        *at this θ**: not a structural number (it can differ at another θ*); None when
        infinitely many or undetermined.
    n_solutions_real : int or None
        Distinct real solutions at this θ* (also depends on θ*).
    n_solutions_complex : int or None
        Distinct complex solutions: the generic (structural) count.
    jacobian_ranks : tuple of int
        Exact Jacobian rank at each random rational point (out of ``len(parameters)``).
    summary_kind : str or None
        The exhaustive summary used by the global step.
    n_summary : int or None
        Number of non-constant summary entries.
    necessary_condition : NecessaryCondition
    combinations : tuple of dict
        Identifiable combinations (``expression``, ``source``, ``global``), for a model
        with non-identifiable parameters.
    reparameterisation : dict of str to str
        Suggested new parameters (``phi1 = b*c``, ...).
    fix : tuple of str
        Parameters whose values, once known, make the others locally identifiable.
    positivity_changed : bool
        Discarding non-positive solutions changed a verdict.
    notes : tuple of str
        Everything worth knowing (positivity, realness, summary choice, limits).
    theta_star : dict of str to str
        The random rational point of the global step.
    solutions : tuple of dict
        The admissible solutions (floats), when finitely many.
    witnesses : tuple of dict
        When the Gröbner step did not finish: admissible solutions θ ≠ θ* found
        numerically (:mod:`symid.structural.witness`). Any witness shows the model is not
        globally identifiable (at least ``1 + len(witnesses)`` solutions).
    witnesses_certified : tuple of bool
        Per witness, whether the Krawczyk interval test proved an exact admissible
        solution next to it (see :mod:`symid.structural.witness`).
    n_solutions_at_least : int or None
        When the Gröbner step did not finish and witnesses were certified: 1 + the
        number of certified witnesses, a proven lower bound of the number of admissible
        solutions at θ*. The witness search runs a fixed number of steps and starts, so
        this number does not depend on the machine's speed.
    verdicts_proven : bool
        Whether no verdict is ``"local, global undetermined"``.
    timing : dict of str to float
        Wall time (s) of ``local``, ``global`` and ``total`` (the only part of the
        report that depends on the machine).
    theta_confirm : dict of str to str
        The independent point θ** at which global claims were confirmed (empty when
        nothing was claimed global or the Gröbner step did not finish).
    solution_count : str
        The solution count in words: exact (complex, generic; real and admissible at
        θ*), a certified lower bound with the reason the exact count is missing, or why
        it was not computed.
    engine : str
        Which program solved summary(θ) = summary(θ*): ``"msolve"`` or ``"sympy"``
        (empty when the exact step did not finish), ``"ladder"`` for a mass chain driven and
        measured at one mass, inverted by continued fractions with no Gröbner basis
        (:mod:`symid.structural.ladder` at an end mass; :mod:`symid.structural.ladder_interior`
        at an interior one, whose pole split is a floating-point test;
        :mod:`symid.structural.ladder_adjacent` driven next to the free end and measured
        there, a case analysis with floating-point exclusions), ``"formula"`` when
        checked rational formulas decided every verdict. Like ``timing``, a record of how the
        report was made: the rest of the report is the same whichever ran (the floats of
        ``solutions`` agree to rounding).
    at : dict of str to float
        The values given as ``at=`` (empty without).
    at_status : str
        What is known of other solutions at those values (empty without ``at=``).
    solutions_at : tuple of dict or None
        The other admissible solutions with the response at those values (every one), ``()`` when there is none,
        None when not computed (see ``at_status``).
    """

    model: str
    parameters: tuple[str, ...]
    known: dict[str, float]
    verdict: str
    verdicts: dict[str, str]
    locally_identifiable: dict[str, bool]
    global_determined: bool
    global_status: str
    n_solutions: int | None
    n_solutions_real: int | None
    n_solutions_complex: int | None
    jacobian_ranks: tuple[int, ...]
    summary_kind: str | None
    n_summary: int | None
    necessary_condition: NecessaryCondition
    combinations: tuple[dict[str, Any], ...] = ()
    reparameterisation: dict[str, str] = field(default_factory=dict)
    fix: tuple[str, ...] = ()
    positivity_changed: bool = False
    notes: tuple[str, ...] = ()
    theta_star: dict[str, str] = field(default_factory=dict)
    solutions: tuple[dict[str, float], ...] = ()
    witnesses: tuple[dict[str, float], ...] = ()
    witnesses_certified: tuple[bool, ...] = ()
    n_solutions_at_least: int | None = None
    verdicts_proven: bool = False
    timing: dict[str, float] = field(default_factory=dict)
    theta_confirm: dict[str, str] = field(default_factory=dict)
    solution_count: str = ""
    engine: str = ""
    at: dict[str, float] = field(default_factory=dict)
    at_status: str = ""
    solutions_at: tuple[dict[str, float], ...] | None = None

    @property
    def identifiable(self) -> tuple[str, ...]:
        """Parameters that are locally identifiable."""
        return tuple(p for p in self.parameters if self.locally_identifiable[p])

    @property
    def non_identifiable(self) -> tuple[str, ...]:
        """Parameters that are not locally identifiable."""
        return tuple(p for p in self.parameters if not self.locally_identifiable[p])

    @property
    def shown_not_global(self) -> tuple[str, ...]:
        """Parameters that take another value at some numerical witness (so are not globally identifiable)."""
        out = []
        for p in self.parameters:
            ref = float(Fraction(self.theta_star[p])) if p in self.theta_star else None
            if ref is not None and any(abs(w[p] - ref) > 1e-6 * max(1.0, abs(ref)) for w in self.witnesses):
                out.append(p)
        return tuple(out)

    def summary(self) -> str:
        """The report as a readable table."""
        L = []
        L.append(f"Structural identifiability: {self.model}")
        L.append("=" * min(max(len(L[0]), 40), 100))
        verdict = _VERDICT_TEXT[self.verdict]
        if self.verdict == "local" and self.n_solutions is not None:
            verdict = (f"LOCALLY, NOT GLOBALLY IDENTIFIABLE ({self.n_solutions_complex} complex solutions; "
                       f"{self.n_solutions} admissible at θ*)")
        elif self.verdict == "local" and self.n_solutions_at_least is not None:
            verdict = (f"LOCALLY, NOT GLOBALLY IDENTIFIABLE (proven; at least {self.n_solutions_at_least} "
                       "solutions, exact count not computed)")
        elif self.verdict == "local, global undetermined" and self.witnesses:
            verdict = (f"LOCALLY IDENTIFIABLE (global verdict undetermined; {len(self.witnesses)} other "
                       "solution(s) found numerically, not certified)")
        L.append(f"verdict            : {verdict}")
        if self.known:
            L.append("known              : " + ", ".join(f"{k} = {v:g}" for k, v in self.known.items()))
        L.append(f"necessary condition: {self.necessary_condition}")
        npar = len(self.parameters)
        ranks = ", ".join(f"{r}/{npar}" for r in self.jacobian_ranks)
        if any("floating-point rank" in note for note in self.notes):
            L.append(f"local  (float)     : Jacobian rank {ranks} of the frequency response at a random point")
        else:
            L.append(f"local  (exact)     : Jacobian rank {ranks} at {len(self.jacobian_ranks)} random rational "
                     "points")
        if self.global_determined:
            if self.n_solutions_complex is None:
                sol = "infinitely many (positive-dimensional solution set)"
            else:
                sol = (f"{self.n_solutions} admissible of {self.n_solutions_real} real, "
                       f"{self.n_solutions_complex} complex")
            if self.engine == "ladder":
                how = ("a chain inverted, with floating-point exclusions at wide margins"
                       if any("floating-point test" in note for note in self.notes) else "a chain inverted exactly")
                L.append(f"global (chain)     : summary(θ) = summary(θ*): {sol} ({how}: see the notes)")
            elif self.engine == "formula":
                L.append(f"global (formula)   : summary(θ) = summary(θ*): {sol} (rational formulas, checked exactly)")
            else:
                L.append(f"global (Gröbner)   : summary(θ) = summary(θ*): {sol}")
            L.append(f"summary            : {self.n_summary} {self.summary_kind}")
            if self.theta_confirm:
                L.append("confirmed          : at an independent point θ**")
        elif self.n_solutions_at_least is not None:  # settled by certified witnesses, not by the Gröbner step
            L.append(f"global (witnesses) : {self.global_status}")
        else:
            L.append(f"global (Gröbner)   : {self.global_status}")
        L.append("")
        width = max([9, *(len(p) for p in self.parameters)])
        L.append(f"  {'parameter':<{width}}  verdict")
        L.append(f"  {'-' * width}  -------")
        not_global = set(self.shown_not_global)
        for p in self.parameters:
            v = self.verdicts[p]
            if v == "local" and not self.global_determined:
                v = "local (not global: differs at a certified witness)"
            elif v == "local, global undetermined" and p in not_global:
                v = "local, global undetermined (differs at a numerical witness, not certified)"
            L.append(f"  {p:<{width}}  {v}")
        if self.solution_count:
            L.append("")
            L.append(f"solutions: {self.solution_count}")
        apart = self._telling_apart()
        if apart:
            L.append("")
            L.extend(apart)
        if self.at:
            L.append("")
            L.extend(self._at_lines())
        if self.combinations:
            L.append("")
            L.append("identifiable combinations:")
            for c in self.combinations:
                g = {True: "global", False: "local", None: "local"}[c["global"]]
                L.append(f"  {c['expression']}   [{g}; from {c['source']}]")
        if self.reparameterisation or self.fix:
            L.append("")
            L.append("suggested reparameterisation:")
            for k, v in self.reparameterisation.items():
                L.append(f"  {k} = {v}")
            if self.fix:
                fixes = ", ".join(f"'{p}': ..." for p in self.fix)
                lead = "or fix" if self.reparameterisation else "fix"
                L.append(f"  {lead} {', '.join(self.fix)} (known={{{fixes}}}): the rest become locally identifiable")
        if self.notes:
            L.append("")
            L.append("notes:")
            for n in self.notes:
                L.append(f"  - {n}")
        if self.timing:
            L.append("")
            L.append("time: " + ", ".join(f"{k} {v:.3f} s" for k, v in self.timing.items())
                     + (f" (exact step: {self.engine})" if self.engine else ""))
        return "\n".join(L)

    def _at_lines(self) -> list[str]:
        """The section of the values given as ``at=``: every other admissible solution there."""
        lines = ["at the values given (at=): " + ", ".join(f"{k} = {v:.6g}" for k, v in self.at.items()),
                 f"  other solutions: {self.at_status}"]
        names = [p for p in self.parameters if p in self.at]
        for k, other in enumerate(self.solutions_at or (), start=1):
            diff = [p for p in names if abs(other[p] - self.at[p]) > 1e-9 * max(1.0, abs(self.at[p]))]
            lines.append(f"  {k}: " + ", ".join(f"{p} = {other[p]:.6g}" for p in diff)
                         + ("" if len(diff) == len(names) else " (the rest as given)"))
        return lines

    def _telling_apart(self) -> list[str]:
        """For a model that is locally, not globally identifiable: how the admissible solutions at θ* differ (which
        parameters; a swap said as one) and what keeps one of them."""
        if self.verdict != "local":
            return []
        if len(self.solutions) >= 2:
            first, *others = self.solutions
        elif self.witnesses and self.theta_star:  # the global step stopped early: θ* and the certified witnesses
            first = {p: float(Fraction(v)) for p, v in self.theta_star.items()}
            others = [w for w, ok in zip(self.witnesses, self.witnesses_certified, strict=False) if ok]
        else:
            return []
        lines = ["telling the solutions apart (at θ*):"]
        for other in others[:_APART_SHOWN]:
            diff = [p for p in self.parameters if p in first and p in other
                    and abs(other[p] - first[p]) > 1e-9 * max(1.0, abs(first[p]))]
            if not diff:
                continue
            mine, theirs = sorted(first[p] for p in diff), sorted(other[p] for p in diff)
            swapped = len(diff) > 1 and all(abs(a - b) <= 1e-9 * max(1.0, abs(a)) for a, b in zip(mine, theirs,
                                                                                                   strict=True))
            how = " (the same values, swapped)" if swapped else ""
            lines.append(f"  another solution differs in {', '.join(diff)}{how}: "
                         + ", ".join(f"{p} {first[p]:.4g} or {other[p]:.4g}" for p in diff))
        if len(lines) == 1:
            return []
        if len(others) > _APART_SHOWN:  # a new user counted 3 of 8 and took them for all
            lines.append(f"  … and {len(others) - _APART_SHOWN} more (rep.solutions holds every one; at your own "
                         f"values: si.identifiability(model, at={{...}}))")
        lines.append("  to keep one: bounds that leave only it (si.identify(..., bounds=...) then says UNIQUE WITHIN "
                     "THE BOUNDS), a known value (model.with_known), or another output that separates them")
        return lines

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict[str, Any]:
        """The report as plain data (JSON-serialisable)."""
        out = asdict(self)
        out["necessary_condition"] = asdict(self.necessary_condition)
        return out
