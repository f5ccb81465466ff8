"""Clarabel through cvxpy, stoppable by Ctrl-C.

cvxpy's own Clarabel interface runs a solve to its end whatever the user presses: the
solver is compiled code and never looks at Python's signals, and one SCR sub-problem
can take seconds. This cvxpy custom solver builds the Clarabel solver exactly as cvxpy's
``CLARABEL`` interface does (same matrices, cones and settings; a test compares the two)
and adds a termination callback, polled once per interior-point iteration, that stops
the solve when Ctrl-C was pressed (:func:`symid.interrupt.native_interrupts`).

If cvxpy's internals it relies on move, :data:`INTERRUPTIBLE_CLARABEL` is ``None`` and
the back end falls back to cvxpy's ``"CLARABEL"`` (correct, but Ctrl-C then waits for
the sub-problem to finish).
"""

from __future__ import annotations

from typing import Any

from symid.interrupt import interrupt_pending

__all__ = ["INTERRUPTIBLE_CLARABEL"]


def _make() -> Any:
    try:
        import scipy.sparse as sps
        from cvxpy import settings as cps
        from cvxpy.reductions.solvers.conic_solvers.clarabel_conif import CLARABEL, dims_to_solver_cones
        from cvxpy.reductions.solvers.conic_solvers.conic_solver import ConicSolver
    except ImportError:  # pragma: no cover - a cvxpy whose internals moved
        return None

    class InterruptibleClarabel(CLARABEL):
        """cvxpy's Clarabel interface with a Ctrl-C check once per iteration."""

        def name(self) -> str:
            return "SYMID_CLARABEL"  # cvxpy requires custom solvers to have their own name

        def solve_via_data(self, data: dict, warm_start: bool, verbose: bool, solver_opts: dict,
                           solver_cache: dict | None = None) -> Any:
            import clarabel

            A, b, q = data[cps.A], data[cps.B], data[cps.C]
            P = data[cps.P] if cps.P in data else sps.csc_array((q.size, q.size))
            P = sps.triu(P).tocsc()
            cones = dims_to_solver_cones(data[ConicSolver.DIMS])
            solver = clarabel.DefaultSolver(P, q, A, b, cones, self.parse_solver_opts(verbose, solver_opts))
            solver.set_termination_callback(lambda info: interrupt_pending())
            return solver.solve()

    return InterruptibleClarabel()


INTERRUPTIBLE_CLARABEL = _make()
"""A cvxpy solver instance (pass as ``solver=``), or ``None`` if cvxpy's internals moved."""
