"""A progress bar for multi-start runs and studies (tqdm, to standard error)."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Iterator
from typing import TypeVar

from tqdm import tqdm

__all__ = ["HEARTBEAT_AFTER_S", "HEARTBEAT_EVERY_S", "HEARTBEAT_S", "Heartbeat", "progress_bar"]

T = TypeVar("T")


HEARTBEAT_S = 30.0
"""Off a terminal and a notebook, with ``enabled=None``: a line on standard error at most this often (none
before it): a long run in a batch job or a redirected script says how far it is."""


HEARTBEAT_AFTER_S = 10.0
"""A :class:`Heartbeat`'s first line comes after this many seconds of a run (by default): the command line's and
``si.identify``'s one start alike (a new user's single SCR start in Python was silent for 30 s)."""

HEARTBEAT_EVERY_S = 20.0
"""A :class:`Heartbeat`'s later lines come this often (by default)."""


def _interactive() -> bool:
    """Standard error is a terminal, or this is a Jupyter kernel (whose standard error is no terminal)."""
    return sys.stderr.isatty() or "ipykernel" in sys.modules


def progress_bar(items: Iterable[T], *, desc: str, enabled: bool | None = None, total: int | None = None
                 ) -> Iterator[T]:
    """Iterate over ``items`` with a tqdm bar on standard error.

    ``enabled=None`` shows the bar when there is more than one item and standard error is a terminal or a
    notebook's; elsewhere (a batch job, output redirected to a file) a plain line, "desc: 3 of 10 done, 61 s",
    at most every :data:`HEARTBEAT_S` seconds and none before (a new user's ``si.compare`` ran 391 s in a
    script without a word). ``True``: the bar always; ``False``: nothing.
    """
    if total is None:  # a sized sequence; an iterator with ``total`` is consumed lazily (as_completed)
        items = list(items)
        total = len(items)
    if enabled is None:
        if total <= 1:
            yield from items
            return
        if not _interactive():
            yield from _heartbeat(items, desc, total)
            return
        enabled = True
    if not enabled:
        yield from items
        return
    yield from tqdm(items, desc=desc, total=total, file=sys.stderr, leave=False, dynamic_ncols=True)


class Heartbeat:
    """A line on standard error every ``every`` seconds once a run has taken ``after``: ``with Heartbeat("lm, 1
    start"):`` around work that shows no bar (one start) says it is alive, "symid: still estimating (lm, 1
    start): 30 s so far"; ``enabled=False`` says nothing. A new user's single start ran 77 s without a word.
    Defaults: :data:`HEARTBEAT_AFTER_S`, :data:`HEARTBEAT_EVERY_S`."""

    def __init__(self, what: str, *, after: float | None = None, every: float | None = None, enabled: bool = True):
        import threading

        self.what, self.enabled = what, enabled
        self.after = HEARTBEAT_AFTER_S if after is None else after
        self.every = HEARTBEAT_EVERY_S if every is None else every
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, daemon=True)

    def _beat(self) -> None:
        t0 = time.monotonic()
        wait = self.after
        while not self._stop.wait(wait):
            print(f"symid: still estimating ({self.what}): {time.monotonic() - t0:.0f} s so far", file=sys.stderr,
                  flush=True)
            wait = self.every

    def __enter__(self) -> Heartbeat:
        if self.enabled:
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()


def _heartbeat(items: Iterable[T], desc: str, total: int) -> Iterator[T]:
    """``items``, with a line on standard error at most every :data:`HEARTBEAT_S` seconds of the run."""
    t0 = last = time.perf_counter()
    for done, item in enumerate(items):
        now = time.perf_counter()
        if now - last >= HEARTBEAT_S:
            print(f"{desc}: {done} of {total} done, {now - t0:.0f} s", file=sys.stderr, flush=True)
            last = now
        yield item
