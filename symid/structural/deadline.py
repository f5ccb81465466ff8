"""Run a computation with a wall-clock deadline, never hanging: in a child process killed at the deadline.

sympy's Gröbner bases are pure Python and cannot be interrupted from another thread, and
an in-process alarm signal is unreliable (Python drops an exception raised inside a
weakref callback or a destructor, and the budget is then lost). So every bounded step
runs in a child process (``fork`` on POSIX, ``spawn`` elsewhere) that is killed when
its time is up; the child's result comes back through a pipe (it must be picklable).
:func:`start` returns at once, so two steps can run side by side (the Gröbner basis
and the numerical witness search use both cores); :func:`wait_any` waits for the first
of several; :func:`run_with_deadline` runs one and waits.

The outcome of a job is ``(status, value)``:

* ``("ok", result)``;
* ``("timeout", None)``: not finished in time (the child keeps running until
  :meth:`Running.stop`);
* ``("error", (type name, message, traceback))``: the computation raised;
* ``("died", reason)``: the child ended without a result (killed, a crash such as a
  segmentation fault, out of memory), with the exit code or signal in ``reason``.

A child is always killed and reaped (no zombie) on the way out, Ctrl-C in the parent
included: the child ignores SIGINT (the parent, which receives it too from the
terminal, stops the child), and a child whose parent has gone (killed with SIGKILL,
say) exits by itself within ``_ORPHAN_POLL`` seconds, so no orphan keeps computing. A
Ctrl-C that strikes after the child is forked but before its caller holds the
:class:`Running` leaves it to multiprocessing, which ends daemonic children with
SIGTERM when the parent exits: the child then removes its directory and its group.
On POSIX the child leads its own process group, and stopping it kills the whole group:
a program it runs (msolve, :mod:`~symid.structural.msolve`) is stopped with it, at the
deadline or when the parent has gone. A child killed at its deadline cannot clean up
after itself, so its temporary files (:mod:`tempfile`, e.g. msolve's input and output)
go to a directory of its own that the parent removes when it stops the child. The child
creates that directory itself, under a random name the parent chose: a parent killed
between creating it and starting the child would leave it behind for good.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import secrets
import shutil
import signal
import tempfile
import threading
import time
import traceback
from collections.abc import Callable, Mapping, Sequence
from multiprocessing.connection import wait as _wait_connections
from typing import Any

__all__ = ["Running", "run_with_deadline", "start", "wait_any"]

_ORPHAN_POLL = 0.2
"""Seconds between a child's checks that its parent is still alive."""
_MAX_WAIT = 86400.0
"""Longest single wait (s): longer timeouts are waited in slices (the OS refuses waits beyond ~292 years)."""


def _exit_when_orphaned(parent: int, scratch: str) -> None:  # pragma: no cover - runs in the child process
    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(_ORPHAN_POLL)
        shutil.rmtree(scratch, ignore_errors=True)  # the parent that would have removed it is gone
        _kill_own_group()
        os._exit(70)

    threading.Thread(target=watch, name="symid-orphan-watch", daemon=True).start()


def _lead_own_group() -> None:  # pragma: no cover - runs in the child process
    if hasattr(os, "setpgid"):
        try:
            os.setpgid(0, 0)
        except OSError:  # already done by the parent, or not allowed: the group kill falls back to the process
            pass


def _kill_own_group() -> None:  # pragma: no cover - runs in the child process
    """Kill this child and the programs it started (its process group), when it leads one."""
    if hasattr(os, "killpg") and os.getpgid(0) == os.getpid():
        try:
            os.killpg(os.getpid(), signal.SIGKILL)
        except OSError:
            pass


def _child(conn, fn, kwargs, parent, scratch):  # pragma: no cover - runs in the child process
    # first of all: a Ctrl-C that reaches this process before it leads its own group must not end it between
    # creating its directory and watching for its parent (the parent decides, and stops this process)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    made = False
    try:
        _lead_own_group()
        try:  # created here, not by the parent: a parent killed before the fork leaves no directory behind
            os.mkdir(scratch, 0o700)
            made = True
        except OSError as exc:
            conn.send(("error", (type(exc).__name__, f"the job's temporary directory: {exc}",
                                 traceback.format_exc(limit=8))))
            conn.close()
            return
        tempfile.tempdir = scratch  # this process's temporary files go where the parent removes them

        def terminated(signum, frame):
            # SIGTERM: multiprocessing ends the daemonic children a parent never stopped when it exits (a Ctrl-C
            # that struck while this child was being started, before the parent held it): clean up on the way out
            shutil.rmtree(scratch, ignore_errors=True)
            _kill_own_group()
            os._exit(70)

        signal.signal(signal.SIGTERM, terminated)
        _exit_when_orphaned(parent, scratch)
        try:
            outcome = ("ok", fn(**kwargs))
        except BaseException as exc:
            outcome = ("error", (type(exc).__name__, str(exc), traceback.format_exc(limit=8)))
        try:
            conn.send(outcome)  # pickled before anything is written: a failure sends nothing
        except Exception as exc:  # an unpicklable result or message: say so
            conn.send(("error", (type(exc).__name__, f"the result could not be sent back: {exc!r:.500}",
                                 traceback.format_exc(limit=8))))
        finally:
            conn.close()
    finally:
        # the result went through the pipe, so the directory is no longer needed; removed here too (not only by
        # the parent's stop()) for a child its parent never held: a Ctrl-C that struck the parent during the fork
        # reached this process before it ignored SIGINT, and Python raised it a few instructions later, after
        # the directory was made (seen under load: an empty symid-job-… directory left behind)
        if made:
            shutil.rmtree(scratch, ignore_errors=True)


def _reason(exitcode: int | None) -> str:
    """Why a child ended without a result, from its exit code."""
    if exitcode is None:
        return "its process closed the result pipe and did not exit"
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        return f"its process was killed by {name} (a crash, the out-of-memory killer, or another process)"
    return f"its process exited with code {exitcode}"


class Running:
    """A computation running in a child process (see :func:`start`).

    Attributes
    ----------
    started : float
        ``time.monotonic()`` when it started.
    pid : int
        The child's process id.
    """

    def __init__(self, fn: Callable[..., Any], kwargs: Mapping[str, Any]):
        method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
        ctx = mp.get_context(method)
        self._outcome: tuple[str, Any] | None = None
        self._recv, send = ctx.Pipe(duplex=False)
        # The child creates its temporary directory (see ``_child``) under a name chosen here, so that
        # the parent can remove it after a kill, and a parent killed before the fork leaves nothing.
        self._scratch = os.path.join(tempfile.gettempdir(), f"symid-job-{secrets.token_hex(8)}")
        self._proc = ctx.Process(target=_child, args=(send, fn, dict(kwargs), os.getpid(), self._scratch),
                                 daemon=True, name=f"symid-{getattr(fn, '__name__', 'job')}")
        self.started = time.monotonic()
        try:
            self._proc.start()
            self.pid = self._proc.pid
            if hasattr(os, "setpgid"):  # also here, so that no stop() can come before the child's own setpgid
                try:
                    os.setpgid(self.pid, self.pid)
                except OSError:  # the child did it first, or has already exited
                    pass
        except BaseException:  # e.g. Ctrl-C during the start: a child already forked is stopped first
            self._recv.close()
            if self._proc.pid is not None:
                if hasattr(os, "killpg"):
                    try:
                        os.killpg(self._proc.pid, signal.SIGKILL)
                    except OSError:
                        pass
                self._proc.kill()
                self._proc.join(5)
            shutil.rmtree(self._scratch, ignore_errors=True)
            raise
        finally:
            send.close()  # only the child writes: its death closes the pipe (EOF here)

    @property
    def connection(self):
        """The parent's end of the result pipe (readable when the outcome is ready)."""
        return self._recv

    def wait(self, timeout: float | None) -> tuple[str, Any]:
        """Wait up to ``timeout`` s (``None``: for ever) for the outcome.

        Returns ``("ok", value)``, ``("error", (type name, message, traceback))``,
        ``("died", reason)`` or ``("timeout", None)``; on a timeout the child keeps
        running until :meth:`stop` (so a later :meth:`wait` can still collect it).
        Once collected, the child has been reaped.
        """
        if self._outcome is not None:
            return self._outcome
        if self._recv.closed:  # stopped before it finished
            return "timeout", None
        if not _wait_for([self._recv], timeout):
            return "timeout", None
        try:
            self._outcome = self._recv.recv()
        except (EOFError, OSError):  # the child ended without a word
            self._proc.join(1)
            self._outcome = ("died", _reason(self._proc.exitcode))
        self.stop()
        return self._outcome

    def stop(self) -> None:
        """Kill the child and the programs it started (its process group) if it still runs; reap it (idempotent)."""
        if self._proc.exitcode is None:  # ``exitcode`` polls: a finished child is reaped here
            if hasattr(os, "killpg"):
                try:
                    os.killpg(self.pid, signal.SIGKILL)
                except OSError:  # not a group leader (setpgid refused) or gone already
                    pass
            self._proc.kill()
        self._proc.join(5)
        self._recv.close()
        shutil.rmtree(self._scratch, ignore_errors=True)


def _wait_for(connections: Sequence[Any], timeout: float | None) -> list:
    """The connections ready within ``timeout`` s, waiting in slices of at most ``_MAX_WAIT``."""
    end = None if timeout is None else time.monotonic() + max(timeout, 0.0)
    while True:
        left = _MAX_WAIT if end is None else min(max(end - time.monotonic(), 0.0), _MAX_WAIT)
        ready = _wait_connections(connections, left)
        if ready or (end is not None and time.monotonic() >= end):
            return ready


def wait_any(jobs: Sequence[Running], timeout: float | None) -> list[Running]:
    """Wait up to ``timeout`` s until at least one job's outcome is ready; the ready ones.

    Examples
    --------
    >>> from symid.structural.deadline import start, wait_any
    >>> job = start(dict, {"a": 1})
    >>> wait_any([job], 30) == [job]
    True
    >>> job.wait(0)
    ('ok', {'a': 1})
    """
    done = [j for j in jobs if j._outcome is not None or j.connection.closed]
    if done:
        return done
    ready = _wait_for([j.connection for j in jobs], timeout)
    return [j for j in jobs if j.connection in ready]


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
        ``("ok", result)``, ``("timeout", None)``, ``("error", (type name, message,
        traceback))`` when the computation raised an exception, or ``("died",
        reason)`` when its process ended without a result.

    Examples
    --------
    >>> from symid.structural.deadline import run_with_deadline
    >>> run_with_deadline(dict, {"a": 1}, 5.0)
    ('ok', {'a': 1})
    >>> from fractions import Fraction
    >>> run_with_deadline(Fraction, {"numerator": "?"}, 5.0)[1][:2]
    ('ValueError', "Invalid literal for Fraction: '?'")
    """
    if timeout is None:
        try:
            return "ok", fn(**kwargs)
        except Exception as exc:  # reported as the child would (the caller raises or names the limit)
            return "error", (type(exc).__name__, str(exc), traceback.format_exc(limit=8))
    job = start(fn, kwargs)
    try:
        return job.wait(timeout)
    finally:
        job.stop()
