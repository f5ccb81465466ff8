"""Run a computation with a wall-clock deadline, never hanging: in a child process killed at the deadline.

sympy's Gröbner bases are pure Python and cannot be interrupted from another thread, and
an in-process alarm signal is unreliable (Python drops an exception raised inside a
weakref callback or a destructor, and the budget is then lost). So every bounded step
runs in a child process (``fork`` on POSIX, ``spawn`` elsewhere) that is killed when
its time is up; the child's result comes back through a pipe (it must be picklable).
:func:`start` returns at once, so two steps can run side by side (the Gröbner basis
and the numerical witness search use both cores); :func:`run_with_deadline` waits.
A child is always killed and reaped on the way out, Ctrl-C in the parent included.
"""

from __future__ import annotations

import multiprocessing as mp
import time
import traceback
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["Running", "run_with_deadline", "start"]


def _child(conn, fn, kwargs):  # pragma: no cover - runs in the child process
    try:
        conn.send(("ok", fn(**kwargs)))
    except BaseException as exc:
        try:
            conn.send(("error", (type(exc).__name__, str(exc), traceback.format_exc(limit=6))))
        except Exception:  # an unpicklable payload: at least say what happened
            conn.send(("error", (type(exc).__name__, repr(exc)[:500], "")))
    finally:
        conn.close()


class Running:
    """A computation running in a child process (see :func:`start`).

    Attributes
    ----------
    started : float
        ``time.monotonic()`` when it started.
    """

    def __init__(self, fn: Callable[..., Any], kwargs: Mapping[str, Any]):
        method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
        ctx = mp.get_context(method)
        self._recv, send = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(target=_child, args=(send, fn, dict(kwargs)), daemon=True)
        self.started = time.monotonic()
        self._proc.start()
        send.close()
        self._outcome: tuple[str, Any] | None = None

    def wait(self, timeout: float | None) -> tuple[str, Any]:
        """Wait up to ``timeout`` s (``None``: for ever) for the result.

        Returns ``("ok", value)``, ``("error", (type name, message, traceback))`` or
        ``("timeout", None)``; on a timeout the child keeps running until :meth:`stop`
        (so a later :meth:`wait` can still collect it).
        """
        if self._outcome is not None:
            return self._outcome
        try:
            ready = self._recv.poll(None if timeout is None else max(timeout, 0.0))
        except (EOFError, OSError):
            ready = True
        if not ready:
            return "timeout", None
        try:
            self._outcome = self._recv.recv()
        except (EOFError, OSError):  # the child died without a word (killed, out of memory, a crash)
            self._proc.join(1)
            code = self._proc.exitcode
            self._outcome = ("error", ("ChildDied", f"the worker process died (exit code {code}) without a result",
                                       ""))
        self.stop()
        return self._outcome

    def stop(self) -> None:
        """Kill the child if it still runs, and reap it."""
        if self._proc.is_alive():
            self._proc.kill()
        self._proc.join(5)
        self._recv.close()


def start(fn: Callable[..., Any], kwargs: Mapping[str, Any]) -> Running:
    """Start ``fn(**kwargs)`` in a child process and return at once.

    Examples
    --------
    >>> from symid.structural.deadline import start
    >>> job = start(dict, {"a": 1})
    >>> job.wait(30)
    ('ok', {'a': 1})
    """
    return Running(fn, kwargs)


def run_with_deadline(fn: Callable[..., Any], kwargs: Mapping[str, Any], timeout: float | None) -> tuple[str, Any]:
    """Call ``fn(**kwargs)``, giving up after ``timeout`` seconds.

    Parameters
    ----------
    fn : callable
        Must be importable (module level) for the ``spawn`` start method.
    kwargs : mapping
        Keyword arguments; picklable for the ``spawn`` start method.
    timeout : float or None
        Seconds; ``None`` runs in this process without a deadline.

    Returns
    -------
    (status, value)
        ``("ok", result)``, ``("timeout", None)`` or ``("error", (type name, message,
        traceback))`` when the computation raised an exception.

    Examples
    --------
    >>> from symid.structural.deadline import run_with_deadline
    >>> run_with_deadline(dict, {"a": 1}, 5.0)
    ('ok', {'a': 1})
    """
    if timeout is None:
        try:
            return "ok", fn(**kwargs)
        except Exception as exc:
            return "error", (type(exc).__name__, str(exc), traceback.format_exc(limit=6))
    job = start(fn, kwargs)
    try:
        out = job.wait(timeout)
    finally:
        job.stop()
    return out
