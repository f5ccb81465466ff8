"""Frequency response function (FRF) data: H(ω) at a set of angular frequencies."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np

from symid.data import _files, checks
from symid.data._base import DataContainer, naming_file
from symid.errors import DataError

__all__ = ["FrequencyData"]


@dataclass(frozen=True, init=False, eq=False, repr=False)
class FrequencyData(DataContainer):
    """Frequency response data H(ω_i) ∈ ℂ^{p×m} at angular frequencies ω_1 < ... < ω_s (rad/s).

    The object is immutable; its arrays are read-only copies of the inputs.

    Parameters
    ----------
    w : array_like, shape (s,)
        Angular frequencies in rad/s: finite, strictly positive (ω = 0 is refused) and
        strictly increasing (no duplicates).
    H : array_like, shape (s, p, m) or (s,)
        The frequency response, ``H[i]`` being the p×m matrix at ``w[i]``; real input
        is stored as complex. A 1-D array of length s is accepted for a single-input
        single-output FRF and stored with shape (s, 1, 1). Any other shape is refused.

    Raises
    ------
    DataError
        On NaN or inf, a wrong number of dimensions, a length mismatch between ``w`` and
        ``H``, or non-positive, duplicated or unsorted frequencies. The message names the
        array and what was expected.

    Notes
    -----
    CSV layout (see :meth:`to_csv`)::

        # symid FrequencyData csv v2
        # n_outputs: p
        # n_inputs: m
        # n_rows: N
        w,H[0][0].re,H[0][0].im,H[0][1].re,H[0][1].im,...
        <one row per frequency>
        # end

    The H entries run row-major over (output i, input j).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data import FrequencyData
    >>> w = np.array([0.5, 1.0, 2.0])
    >>> frf = FrequencyData(w, 1 / (1j * w + 1))   # SISO: H of shape (s,)
    >>> frf.H.shape
    (3, 1, 1)
    >>> frf.n_frequencies, frf.n_outputs, frf.n_inputs
    (3, 1, 1)
    """

    w: np.ndarray
    H: np.ndarray

    _kind: ClassVar[str] = "FrequencyData"
    _npz_keys: ClassVar[tuple[str, ...]] = ("w", "H")

    def __init__(self, w: Any, H: Any):
        w_ = checks.frequencies(w, "w")
        s = w_.size
        H_ = checks.as_array(H, "H", complex_ok=True)
        if H_.ndim == 1:
            H_ = H_.reshape(-1, 1, 1)
        elif H_.ndim != 3:
            raise DataError(f"H must have shape (s, p, m) = (len(w), outputs, inputs), or (s,) for a SISO FRF; "
                            f"got shape {checks.shape_text(H_.shape)}")
        if H_.shape[0] != s:
            raise DataError(f"H has {H_.shape[0]} frequencies (shape {checks.shape_text(H_.shape)}) but w has {s}; "
                            f"expected H of shape ({s}, p, m)")
        if H_.shape[1] < 1 or H_.shape[2] < 1:
            raise DataError(f"H must have at least one output and one input; got shape {checks.shape_text(H_.shape)}")
        checks.check_finite(H_, "H")
        object.__setattr__(self, "w", w_)
        object.__setattr__(self, "H", checks.frozen(H_))

    # -- properties -----------------------------------------------------------------
    @property
    def n_frequencies(self) -> int:
        """Number of frequencies s."""
        return int(self.w.size)

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return int(self.H.shape[1])

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return int(self.H.shape[2])

    @property
    def shape(self) -> tuple[int, int, int]:
        """(s, p, m)."""
        return (self.n_frequencies, self.n_outputs, self.n_inputs)

    # -- text -----------------------------------------------------------------------
    def __repr__(self) -> str:
        return (f"FrequencyData({self.n_frequencies} frequencies in [{self.w[0]:.4g}, {self.w[-1]:.4g}] rad/s, "
                f"{self.n_outputs} output(s), {self.n_inputs} input(s))")

    def summary(self) -> str:
        """A short readable description: sizes, frequency range, magnitude range."""
        mag = np.abs(self.H)
        return "\n".join([
            "FrequencyData",
            f"  frequencies : {self.n_frequencies}, {self.w[0]:.6g} to {self.w[-1]:.6g} rad/s",
            f"  outputs p   : {self.n_outputs}",
            f"  inputs m    : {self.n_inputs}",
            f"  |H|         : {mag.min():.4g} to {mag.max():.4g}",
        ])

    # -- CSV ------------------------------------------------------------------------
    @staticmethod
    def _columns(p: int, m: int) -> list[str]:
        cols = ["w"]
        for i in range(p):
            for j in range(m):
                cols += [f"H[{i}][{j}].re", f"H[{i}][{j}].im"]
        return cols

    def to_csv(self, path: _files.PathLike) -> None:
        """Write the data as CSV text (layout in the class notes); the round trip is exact.

        Examples
        --------
        >>> import tempfile, os
        >>> from symid.data import FrequencyData
        >>> frf = FrequencyData([1.0, 2.0], [0.5 - 0.5j, 0.2 - 0.4j])
        >>> path = os.path.join(tempfile.mkdtemp(), "frf.csv")
        >>> frf.to_csv(path)
        >>> print(open(path).read(), end="")
        # symid FrequencyData csv v2
        # n_outputs: 1
        # n_inputs: 1
        # n_rows: 2
        w,H[0][0].re,H[0][0].im
        1.0,0.5,-0.5
        2.0,0.2,-0.4
        # end
        >>> FrequencyData.from_csv(path) == frf
        True
        """
        s, p, m = self.shape
        table = np.empty((s, 1 + 2 * p * m))
        table[:, 0] = self.w
        flat = self.H.reshape(s, p * m)
        table[:, 1::2] = flat.real
        table[:, 2::2] = flat.imag
        rows = [[_files.fmt(x) for x in row] for row in table.tolist()]
        _files.write_csv(path, self._kind, {"n_outputs": p, "n_inputs": m}, self._columns(p, m), rows)

    @classmethod
    def from_csv(cls, path: _files.PathLike) -> Self:
        """Read a file written by :meth:`to_csv`.

        Raises
        ------
        DataError
            If the file is not a symid FrequencyData CSV file, was cut short, declares
            sizes that its rows and columns do not match, or its contents fail the
            constructor's checks (rules in the notes of ``symid.data._files``).
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.

        Warns
        -----
        UserWarning
            For a version-1 file, whose completeness cannot be checked.
        """
        meta, columns, rows = _files.read_csv(path, cls._kind)
        p = _files.meta_int(meta, "n_outputs", path, at_most=len(columns))
        m = _files.meta_int(meta, "n_inputs", path, at_most=len(columns))
        _files.expect_width(columns, 1 + 2 * p * m, path, "1 + 2 × n_outputs × n_inputs")
        _files.expect_columns(columns, cls._columns(p, m), path)
        table = _files.parse_float_rows(rows, path, len(columns))
        H = _files.complex_from_parts(table[:, 1::2], table[:, 2::2]).reshape(-1, p, m)
        with naming_file(path):
            return cls(table[:, 0], H)
