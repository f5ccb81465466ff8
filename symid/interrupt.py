"""Ctrl-C that stops work at once and keeps what was done.

Two pieces:

* :class:`Interrupted`, a :class:`KeyboardInterrupt` that carries the partial result of
  a multi-start run (``exc.partial``): :func:`symid.identify` and :func:`symid.compare`
  raise it when Ctrl-C arrives after at least one start has finished, so a script still
  stops, and an interactive user still has the finished starts.
* :func:`native_interrupts`, for compiled solvers that would otherwise swallow or
  delay Ctrl-C: CasADi's IPOPT interface catches the ``KeyboardInterrupt`` it sees and
  returns a status (``NonIpopt_Exception_Thrown``) as if the start had merely failed,
  and Clarabel does not look at signals at all during a solve. Inside the block a
  SIGINT sets a flag (and, with ``raise_now=True``, raises so that CasADi aborts the
  solve); solvers poll :func:`interrupt_pending` (Clarabel through its termination
  callback), and when the block ends a ``KeyboardInterrupt`` is raised if Ctrl-C was
  pressed. Signals reach only the main thread, so elsewhere the block does nothing.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["Interrupted", "interrupt_pending", "native_interrupts"]


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a multi-start run; ``partial`` holds what had finished.

    Parameters
    ----------
    message : str
        What was interrupted and how much had finished.
    partial : object
        The partial result (an :class:`~symid.IdentificationResult` or a
        :class:`~symid.Comparison` of the finished starts).

    Examples
    --------
    >>> from symid.interrupt import Interrupted
    >>> try:
    ...     raise Interrupted("interrupted after 3 of 10 starts", partial="the 3 starts")
    ... except KeyboardInterrupt as exc:
    ...     print(exc.partial)
    the 3 starts
    """

    def __init__(self, message: str, partial: Any):
        super().__init__(message)
        self.partial = partial


_state = threading.local()


def interrupt_pending() -> bool:
    """Whether Ctrl-C was pressed inside the innermost :func:`native_interrupts` block."""
    return bool(getattr(_state, "pending", False))


@contextmanager
def native_interrupts(*, raise_now: bool) -> Iterator[None]:
    """Turn Ctrl-C inside a compiled solver into a prompt ``KeyboardInterrupt`` after it.

    Parameters
    ----------
    raise_now : bool
        ``True``: the handler also raises ``KeyboardInterrupt`` at once, for solvers
        that check for it and abort (CasADi). ``False``: it only sets the flag, for
        solvers that poll :func:`interrupt_pending` from a Python callback (Clarabel),
        where an exception would have to cross the compiled code.

    Notes
    -----
    Only in the main thread, and only when SIGINT has Python's default handler
    (a handler the caller installed is left alone).

    Examples
    --------
    >>> from symid.interrupt import interrupt_pending, native_interrupts
    >>> with native_interrupts(raise_now=False):
    ...     interrupt_pending()
    False
    """
    main = threading.current_thread() is threading.main_thread()
    if not main or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    outer = getattr(_state, "pending", None)
    _state.pending = False

    def handler(signum: int, frame: Any) -> None:
        _state.pending = True
        if raise_now:
            raise KeyboardInterrupt

    signal.signal(signal.SIGINT, handler)
    failed: BaseException | None = None
    try:
        yield
    except Exception as exc:  # e.g. the solver's error for a solve stopped half way
        failed = exc
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        pressed = _state.pending
        _state.pending = outer
    if pressed:
        raise KeyboardInterrupt
    if failed is not None:
        raise failed
