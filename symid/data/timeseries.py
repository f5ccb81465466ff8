"""Input/output samples at arbitrary (non-uniform) sample times."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np

from symid.data import checks
from symid.data._base import DataContainer
from symid.errors import DataError

__all__ = ["TimeSeries"]


def _times(t: Any) -> np.ndarray:
    arr = checks.as_array(t, "t", complex_ok=False)
    if arr.ndim != 1:
        raise DataError(f"t must be a 1-D array of sample times (seconds); got shape {checks.shape_text(arr.shape)}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise DataError(f"t[{bad[0]}] is {arr[bad[0]]}; sample times must be finite (drop that sample)")
    step = np.diff(arr)
    dup = np.flatnonzero(step == 0)
    if dup.size:
        k = int(dup[0])
        raise DataError(f"t[{k}] and t[{k + 1}] are both {arr[k]:g}: duplicated sample time; average the two "
                        "samples or drop one")
    back = np.flatnonzero(step < 0)
    if back.size:
        k = int(back[0])
        raise DataError(f"t[{k + 1}] = {arr[k + 1]:g} comes before t[{k}] = {arr[k]:g}: sample times must increase; "
                        "sort the samples by time")
    return arr.astype(float)


def _channels(x: Any, name: str, N: int) -> np.ndarray:
    arr = checks.as_array(x, name, complex_ok=False)
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2 or arr.shape[0] != N or arr.shape[1] < 1:
        raise DataError(f"{name} must have shape ({N}, channels) or ({N},), one row per sample time; "
                        f"got shape {checks.shape_text(arr.shape)}")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        k, j = (int(v) for v in bad[0])
        raise DataError(f"{name}[{k}, {j}] is {arr[k, j]} (at t[{k}]); samples must be finite: drop that sample "
                        "time or fill the gap")
    return arr


@dataclass(frozen=True, init=False, eq=False, repr=False)
class TimeSeries(DataContainer):
    """Input/output samples u(t_k), y(t_k) at increasing times t_k, not necessarily equally spaced.

    The input is held constant from one sample time to the next (zero-order hold), as
    :class:`~symid.data.IOData` assumes for its uniform grid; ``y[k]`` is the output at
    ``t[k]``. A free response (no input) has ``u`` all zero.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times in seconds, finite and strictly increasing.
    u : array_like, shape (N, m) or (N,)
        Input samples; ``u[k]`` acts on [t_k, t_{k+1}).
    y : array_like, shape (N, p) or (N,)
        Output samples.

    Raises
    ------
    DataError
        On NaN or inf (naming the sample), duplicated or decreasing times (naming the
        pair), shapes that do not match ``t``, or fewer than two samples.

    Notes
    -----
    NPZ files only (``to_npz`` / ``from_npz``); :meth:`from_iodata` converts a uniform
    record.

    Examples
    --------
    >>> from symid.data.timeseries import TimeSeries
    >>> ts = TimeSeries(t=[0.0, 0.5, 2.0], u=[0.0, 0.0, 0.0], y=[1.0, 0.7, 0.2])
    >>> ts.n_samples, ts.n_inputs, ts.uniform_dt is None
    (3, 1, True)
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray

    _kind: ClassVar[str] = "TimeSeries"
    _npz_keys: ClassVar[tuple[str, ...]] = ("t", "u", "y")

    def __init__(self, t: Any, u: Any, y: Any):
        t_ = _times(t)
        if t_.size < 2:
            raise DataError(f"a time series needs at least 2 samples; got {t_.size}")
        u_ = _channels(u, "u", t_.size)
        y_ = _channels(y, "y", t_.size)
        object.__setattr__(self, "t", checks.frozen(t_))
        object.__setattr__(self, "u", checks.frozen(u_))
        object.__setattr__(self, "y", checks.frozen(y_))

    @classmethod
    def _from_npz_arrays(cls, arrays: dict[str, np.ndarray]) -> Self:
        return cls(arrays["t"], arrays["u"], arrays["y"])

    @classmethod
    def from_iodata(cls, io: Any) -> TimeSeries:
        """The same samples at times k·dt."""
        return cls(io.t, io.u, io.y)

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return int(self.u.shape[1])

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return int(self.y.shape[1])

    @property
    def uniform_dt(self) -> float | None:
        """The sample time when the times are equally spaced (to 1e-12 relative), else ``None``."""
        step = np.diff(self.t)
        return float(step.mean()) if np.ptp(step) <= 1e-12 * step.mean() else None

    def __repr__(self) -> str:
        return (f"TimeSeries({self.n_samples} samples over {self.t[0]:g}…{self.t[-1]:g} s, "
                f"{self.n_inputs} input(s), {self.n_outputs} output(s))")

    def summary(self) -> str:
        """Sizes, time span, spacing and the rms of every channel."""
        step = np.diff(self.t)
        return "\n".join([
            "TimeSeries",
            f"  samples N   : {self.n_samples} over {self.t[0]:.6g} … {self.t[-1]:.6g} s",
            f"  spacing     : {step.min():.4g} … {step.max():.4g} s",
            f"  inputs m    : {self.n_inputs}, rms {', '.join(f'{v:.4g}' for v in np.sqrt(np.mean(self.u**2, 0)))}",
            f"  outputs p   : {self.n_outputs}, rms {', '.join(f'{v:.4g}' for v in np.sqrt(np.mean(self.y**2, 0)))}",
        ])
