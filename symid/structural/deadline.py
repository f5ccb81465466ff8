"""Run a computation with a wall-clock deadline, never hanging.

sympy's Gröbner bases are pure Python and cannot be interrupted from another thread.
Two isolations are used:

* ``"signal"`` (the default in the main thread on POSIX): a ``SIGALRM`` timer raises an
  exception inside the computation, in-process, with no overhead. Any timer the caller
  had armed is restored afterwards.
* ``"process"`` (elsewhere, e.g. in a worker thread): the computation runs in a forked
  child process that is killed at the deadline (``spawn`` where fork is unavailable).
"""

from __future__ import annotations

import multiprocessing as mp
import signal
import threading
import time
import traceback
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["DeadlineExceeded", "run_with_deadline"]


class DeadlineExceeded(BaseException):
    """Raised inside the computation when its deadline passes (signal isolation)."""


def _alarm(signum, frame):  # pragma: no cover - exercised through timeouts
    raise DeadlineExceeded()


def _signal_available() -> bool:
    return hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()


def _run_signal(fn, kwargs, timeout):
    old_handler = signal.signal(signal.SIGALRM, _alarm)
    start = time.monotonic()
    old_delay, old_interval = signal.setitimer(signal.ITIMER_REAL, max(timeout, 1e-4))
    try:
        return "ok", fn(**kwargs)
    except DeadlineExceeded:
        return "timeout", None
    except Exception as exc:
        return "error", f"{type(exc).__name__}: {exc}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old_handler)
        if old_delay > 0:
            remaining = max(old_delay - (time.monotonic() - start), 1e-3)
            signal.setitimer(signal.ITIMER_REAL, remaining, old_interval)


def _child(conn, fn, kwargs):  # pragma: no cover - runs in the child process
    try:
        conn.send(("ok", fn(**kwargs)))
    except Exception as exc:
        conn.send(("error", f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=3)}"))
    finally:
        conn.close()


def _run_process(fn, kwargs, timeout):
    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    ctx = mp.get_context(method)
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, fn, dict(kwargs)), daemon=True)
    proc.start()
    send.close()
    try:
        if recv.poll(timeout):
            try:
                status, payload = recv.recv()
            except EOFError:
                return "error", "the worker process died without a result"
            return status, payload
        return "timeout", None
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join(5)
        recv.close()


def run_with_deadline(fn: Callable[..., Any], kwargs: Mapping[str, Any], timeout: float | None, *,
                      isolation: str = "auto") -> tuple[str, Any]:
    """Call ``fn(**kwargs)``, giving up after ``timeout`` seconds.

    Parameters
    ----------
    fn : callable
        Must be importable (module level) for the process isolation.
    kwargs : mapping
        Keyword arguments; picklable for the ``spawn`` start method.
    timeout : float or None
        Seconds; ``None`` runs without a deadline.
    isolation : {"auto", "signal", "process"}
        ``"auto"`` uses the signal in the main thread on POSIX, else a child process.

    Returns
    -------
    (status, value)
        ``("ok", result)``, ``("timeout", None)`` or ``("error", message)`` when the
        computation raised an exception (``"ExceptionName: message"``).

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
            return "error", f"{type(exc).__name__}: {exc}"
    if isolation == "auto":
        isolation = "signal" if _signal_available() else "process"
    if isolation == "signal":
        if not _signal_available():
            raise RuntimeError("signal isolation needs the main thread on a POSIX system")
        return _run_signal(fn, kwargs, timeout)
    if isolation == "process":
        return _run_process(fn, kwargs, timeout)
    raise ValueError(f"isolation must be 'auto', 'signal' or 'process'; got {isolation!r}")
