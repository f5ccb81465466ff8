"""A progress bar for multi-start runs and studies (tqdm, to standard error)."""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from typing import TypeVar

from tqdm import tqdm

__all__ = ["progress_bar"]

T = TypeVar("T")


def progress_bar(items: Iterable[T], *, desc: str, enabled: bool | None = None, total: int | None = None
                 ) -> Iterator[T]:
    """Iterate over ``items`` with a tqdm bar on standard error.

    ``enabled=None`` shows the bar when there is more than one item and standard
    error is a terminal; ``True`` always, ``False`` never.
    """
    if total is None:  # a sized sequence; an iterator with ``total`` is consumed lazily (as_completed)
        items = list(items)
        total = len(items)
    if enabled is None:
        enabled = total > 1 and sys.stderr.isatty()
    if not enabled:
        yield from items
        return
    yield from tqdm(items, desc=desc, total=total, file=sys.stderr, leave=False, dynamic_ncols=True)
