"""Results that survive an interruption: run-by-run logs and atomic writes.

* :class:`RunLog`: a JSON Lines file with one record per finished run (a start of a
  method, a problem of a study), appended and flushed as each run ends. Opening an
  existing log resumes it: finished runs are found by their key and not run again. A
  last line cut by an interruption is dropped (and cut from the file); any other
  damaged line is an error.
* :func:`write_atomic` / :func:`write_json_atomic`: write to a temporary file in the
  target's folder and rename it over the target, so a reader sees the old file or the
  new one, never half of one.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from symid.errors import DataError

__all__ = ["RunLog", "json_safe", "write_atomic", "write_json_atomic"]


def json_safe(obj: Any) -> Any:
    """A JSON-safe copy: numpy scalars and arrays become Python numbers and lists, NaN and ±inf become ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.runlog import json_safe
    >>> json_safe({"a": np.float64(1.5), "b": [np.inf, np.arange(2)]})
    {'a': 1.5, 'b': [None, [0, 1]]}
    """
    if isinstance(obj, Mapping):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if hasattr(obj, "tolist") and not isinstance(obj, (str, bytes)):
        return json_safe(obj.tolist())
    if isinstance(obj, bool) or obj is None or isinstance(obj, (int, str)):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    return repr(obj)


@contextmanager
def write_atomic(path: str | os.PathLike, mode: str = "w", *, encoding: str | None = "utf-8") -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on success it replaces ``path`` in one rename.

    On an exception (Ctrl-C included) the temporary file is removed and ``path`` is
    left as it was.

    Parameters
    ----------
    path : str or path-like
    mode : {"w", "wb"}
    encoding : str, optional
        For text mode (default UTF-8).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from symid.runlog import write_atomic
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with write_atomic(target) as fh:
    ...     _ = fh.write("done")
    >>> target.read_text()
    'done'
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb'; got {mode!r}")
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        # mkstemp's file is private (0600): give it the mode a plain open would (the user's umask), or the mode of
        # the file it replaces
        try:
            os.fchmod(fd, path.stat().st_mode & 0o777 if path.exists() else 0o666 & ~_umask())
        except (AttributeError, OSError):  # no fchmod (Windows) or a file system without modes: as created
            pass
        with os.fdopen(fd, mode, encoding=None if mode == "wb" else encoding) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def _umask() -> int:
    """The process's umask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_json_atomic(path: str | os.PathLike, obj: Any, *, indent: int | None = 1) -> None:
    """Write ``json_safe(obj)`` to ``path`` atomically (:func:`write_atomic`)."""
    text = json.dumps(json_safe(obj), indent=indent, allow_nan=False)
    with write_atomic(path) as fh:
        fh.write(text + "\n")


class RunLog:
    """A resumable JSON Lines log: one record per finished run, written as it finishes.

    Parameters
    ----------
    path : str or path-like
        The ``.jsonl`` file; created (with its folder) if missing, resumed if present.
    fresh : bool, optional
        Start over: an existing file is replaced by an empty one.
    prefix : str, optional
        Prepended to every key (see :meth:`scoped`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from symid.runlog import RunLog
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "study.jsonl"
    >>> log = RunLog(path)
    >>> log.append("belt_drive/scr/0", {"cost": 1e-12})
    >>> RunLog(path).get("belt_drive/scr/0")["cost"]     # a new process resumes from the file
    1e-12
    """

    def __init__(self, path: str | os.PathLike, *, fresh: bool = False, prefix: str = ""):
        self.path = Path(path)
        self.prefix = prefix
        self._records: dict[str, dict[str, Any]] = {}
        if fresh or not self.path.exists():
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with write_atomic(self.path) as fh:
                fh.write("")
        else:
            self._load()

    @classmethod
    def _view(cls, parent: RunLog, prefix: str) -> RunLog:
        view = cls.__new__(cls)
        view.path, view.prefix, view._records = parent.path, parent.prefix + prefix, parent._records
        return view

    def scoped(self, prefix: str) -> RunLog:
        """A view of the same file whose keys get ``prefix`` in front (e.g. ``"belt_drive/"``)."""
        return RunLog._view(self, prefix)

    def _load(self) -> None:
        raw = self.path.read_bytes()
        complete = raw.rfind(b"\n") + 1
        if complete < len(raw):  # the last line was cut by an interruption: drop it
            with open(self.path, "r+b") as fh:
                fh.truncate(complete)
        for lineno, line in enumerate(raw[:complete].decode("utf-8", errors="strict").splitlines(), start=1):
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except json.JSONDecodeError as exc:
                raise DataError(f"{self.path}: line {lineno} is not JSON ({exc.msg}); the log is damaged — "
                                f"start a new one (fresh=True) or remove that line") from None
            if not isinstance(rec, dict) or not isinstance(rec.get("key"), str):
                raise DataError(f"{self.path}: line {lineno} is not a run record (an object with a 'key' string)")
            self._records[rec["key"]] = rec

    def __contains__(self, key: str) -> bool:
        return self.prefix + key in self._records

    def __len__(self) -> int:
        return sum(k.startswith(self.prefix) for k in self._records)

    def get(self, key: str) -> dict[str, Any] | None:
        """The record of a finished run, or ``None``."""
        return self._records.get(self.prefix + key)

    def records(self) -> list[dict[str, Any]]:
        """Every record under this view's prefix, in the order they were written."""
        return [r for k, r in self._records.items() if k.startswith(self.prefix)]

    def forget(self, key: str) -> None:
        """Drop a finished run from this view so that it is run again (nothing if it is not there).

        The file keeps the old line; the record appended for the new run supersedes it
        when the log is read back (the last line with a key wins)."""
        self._records.pop(self.prefix + key, None)

    def append(self, key: str, record: Mapping[str, Any]) -> None:
        """Write one finished run (flushed and synced before returning)."""
        full = self.prefix + key
        rec = {"key": full, **json_safe(dict(record))}
        line = json.dumps(rec, allow_nan=False) + "\n"
        with open(self.path, "a", encoding="utf-8") as fh:
            fh.write(line)
            fh.flush()
            os.fsync(fh.fileno())
        self._records[full] = rec
