"""Frequency response function (FRF) data: H(ω) at a set of angular frequencies."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np

from symid.data import _files, checks
from symid.data._base import DataContainer, naming_file
from symid.errors import DataError

__all__ = ["FrequencyData"]


def _dof(x: Any, variance: Any) -> float | None:
    """The degrees of freedom of an estimated variance: None, or a finite number > 0 beside a variance."""
    if x is None:
        return None
    if variance is None:
        raise DataError("variance_dof is given without a variance: it counts the degrees of freedom of an estimated "
                        "variance")
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)) \
            or not np.isfinite(x) or x <= 0:
        raise DataError(f"variance_dof must be a finite number > 0 (the degrees of freedom of the estimated "
                        f"variance); got {x!r}")
    return float(x)


def _variance(x: Any, shape: tuple[int, ...]) -> np.ndarray:
    """A per-entry noise variance: real, finite, ≥ 0, of ``shape`` (a 1-D array for a SISO FRF)."""
    arr = checks.as_array(x, "variance", complex_ok=False)
    if arr.ndim == 1 and shape[1:] == (1, 1):
        arr = arr.reshape(-1, 1, 1)
    if arr.shape != shape:
        raise DataError(f"variance must have the shape of H, {checks.shape_text(shape)}; got shape "
                        f"{checks.shape_text(arr.shape)}")
    checks.check_finite(arr, "variance")
    neg = np.argwhere(arr < 0)
    if neg.size:
        idx = tuple(int(i) for i in neg[0])
        raise DataError(f"variance must be >= 0 (a noise variance): variance[{', '.join(map(str, idx))}] = "
                        f"{float(arr[idx])!r} ({len(neg)} negative value(s))")
    return checks.frozen(arr)


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
    variance : array_like, shape (s, p, m) or (s,), optional
        The noise variance of each entry of ``H``, ``E|Ĥᵢ − Hᵢ|²`` (real and imaginary
        parts together; for circular complex noise each part has half of it), as
        :func:`symid.estimate_frf` estimates it: real, finite and ≥ 0, the shape of ``H``
        (a 1-D array for a SISO FRF). A zero says the entry is known exactly. ``None``
        (default): no noise model. It is kept by :meth:`to_csv`, :meth:`to_npz`,
        pickling and frequency selection (``frf[k]``).
    variance_dof : float, optional
        The degrees of freedom of an estimated ``variance`` (real ones, the same for every
        entry: 2(P − 1) from P periods, 2(n_eff − m) from Welch averages), as
        :func:`symid.estimate_frf` sets it; ``None`` (default): the variance is known. A fit
        weighted by the inverse of an estimated variance leaves a misfit ν/(ν − 2) times
        what the variance says at the truth (the mean of an F(2, ν) ratio), which the fits'
        noise floor allows for. Kept with the variance.

    Raises
    ------
    DataError
        On NaN or inf, a wrong number of dimensions, a length mismatch between ``w`` and
        ``H``, or non-positive, duplicated or unsorted frequencies; a ``variance`` that is
        complex, negative, not finite or not shaped like ``H``; a ``variance_dof`` that is
        not a finite number > 0, or given without a variance. The message names the
        array and what was expected.

    Notes
    -----
    CSV layout (see :meth:`to_csv`)::

        # symid FrequencyData csv v2
        # n_outputs: p
        # n_inputs: m
        # variance_dof: ν        (only for an estimated variance)
        # n_rows: N
        w,H[0][0].re,H[0][0].im,H[0][1].re,H[0][1].im,...
        <one row per frequency>
        # end

    The H entries run row-major over (output i, input j). With a ``variance``, the
    columns ``var[0][0],var[0][1],...`` (same order) follow the H columns.

    ``frf[k]`` with a slice, an integer array or a boolean mask over the frequencies
    gives a new FrequencyData of those frequencies (in increasing order), variance
    included.

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
    variance: np.ndarray | None
    variance_dof: float | None

    _kind: ClassVar[str] = "FrequencyData"
    _npz_keys: ClassVar[tuple[str, ...]] = ("w", "H")
    estimated_from: ClassVar[dict[str, Any]] = {}
    """How :func:`symid.estimate_frf` made this response from sampled records, ``{"dt": sample time, "hold": the
    option}`` and, for a Welch estimate, ``"nperseg"``, ``"window"``, ``"resolution"`` (the line spacing, rad/s) and
    ``"samples"`` (the shortest record); ``{}`` for a response from anywhere else. Set on the object made (not kept
    by a copy or a file): :func:`symid.identify` names the hold when a fit of a response estimated without one
    fails, and the window's bias when it moves the estimate (:mod:`symid.fit.frf.leakage`)."""

    def __init__(self, w: Any, H: Any, variance: Any = None, variance_dof: Any = None):
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
        object.__setattr__(self, "variance", None if variance is None else _variance(variance, H_.shape))
        object.__setattr__(self, "variance_dof", _dof(variance_dof, variance))

    # -- optional variance: equality, pickling, files and selection keep it ------------------
    def _payload(self) -> dict[str, np.ndarray]:
        out = super()._payload()
        if self.variance is not None:
            out["variance"] = self.variance
        if self.variance_dof is not None:
            out["variance_dof"] = np.array(self.variance_dof)
        return out

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        mine, theirs = self._payload(), other._payload()
        return mine.keys() == theirs.keys() and all(np.array_equal(mine[k], theirs[k]) for k in mine)

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[type, tuple[Any, ...]]:
        return (type(self), (self.w, self.H, self.variance, self.variance_dof))

    def __getitem__(self, index: Any) -> FrequencyData:
        try:
            k = np.arange(self.n_frequencies)[index]
        except (IndexError, TypeError, ValueError) as exc:
            raise DataError(f"FrequencyData selects frequencies by a slice, an integer array or a boolean mask of "
                            f"length {self.n_frequencies}; {exc}") from None
        k = np.atleast_1d(k)
        if k.ndim != 1:
            raise DataError(f"FrequencyData selects frequencies along one axis; the index {index!r} adds axes")
        if k.size == 0:
            raise DataError("the selection holds no frequency; at least one is needed")
        return type(self)(self.w[k], self.H[k], None if self.variance is None else self.variance[k],
                          self.variance_dof)

    @classmethod
    def from_npz(cls, path: _files.PathLike) -> Self:
        """Read data written by :meth:`to_npz` (the ``variance`` member is read when present).

        Raises
        ------
        DataError
            If the file is not a symid FrequencyData NPZ file, is damaged or declares more
            than it can hold, or its arrays fail the constructor's checks (rules in the
            notes of ``symid.data._files``).
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.
        """
        arrays = _files.read_npz(path, cls._kind, cls._npz_keys, optional=("variance", "variance_dof"))
        dof = arrays.get("variance_dof")
        with naming_file(path):
            if dof is not None and dof.shape != ():
                raise DataError(f"variance_dof must be one number; got shape {checks.shape_text(dof.shape)}")
            return cls(arrays["w"], arrays["H"], arrays.get("variance"), None if dof is None else dof.item())

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
            *([] if self.variance is None else
              [f"  noise std   : {np.sqrt(self.variance).min():.4g} to {np.sqrt(self.variance).max():.4g} "
               "(per entry, from the variance" + ("" if self.variance_dof is None else
                                                  f", estimated with {self.variance_dof:.4g} degrees of freedom")
               + ")"]),
        ])

    # -- CSV ------------------------------------------------------------------------
    @staticmethod
    def _columns(p: int, m: int, variance: bool = False) -> list[str]:
        cols = ["w"]
        for i in range(p):
            for j in range(m):
                cols += [f"H[{i}][{j}].re", f"H[{i}][{j}].im"]
        if variance:
            cols += [f"var[{i}][{j}]" for i in range(p) for j in range(m)]
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
        has_var = self.variance is not None
        if has_var:
            table = np.hstack([table, self.variance.reshape(s, p * m)])
        rows = [[_files.fmt(x) for x in row] for row in table.tolist()]
        meta = {"n_outputs": p, "n_inputs": m}
        if self.variance_dof is not None:
            meta["variance_dof"] = _files.fmt(self.variance_dof)
        _files.write_csv(path, self._kind, meta, self._columns(p, m, has_var), rows)

    @classmethod
    def from_table(cls, table: Any, *, columns: dict[str, Any], units: dict[str, str] | None = None,
                   delimiter: str = ",") -> Self:
        """Read a frequency response from the user's own table, its columns and units declared.

        Parameters
        ----------
        table : str, os.PathLike, pandas.DataFrame or dict
            A plain CSV file, a MATLAB ``.mat`` file, a DataFrame or a dict of arrays
            (:mod:`symid.data.table`).
        columns : dict
            Role → column: ``"frequency"``, and ``"real"``/``"imag"`` or
            ``"magnitude"``/``"phase"``; for several inputs or outputs ``"real[i][j]"``
            etc. per entry, or a nested list of names.
        units : dict
            ``"frequency"``: ``"Hz"``, ``"kHz"`` or ``"rad/s"``; with magnitude and phase,
            ``"magnitude"``: ``"dB"`` or ``"linear"`` and ``"phase"``: ``"deg"`` or
            ``"rad"``. Converted here (ω = 2π f, |H| = 10^(dB/20)); none is guessed.
        delimiter : str
            Separator of a CSV file (default ``","``).

        Returns
        -------
        FrequencyData

        Raises
        ------
        DataError
            On a column the table does not hold, a role or unit missing or unknown, a unit
            stated in the file that contradicts the declared one, or values that fail the
            constructor's checks; the message gives a two-line example.

        Examples
        --------
        >>> from symid.data import FrequencyData
        >>> table = {"f_Hz": [1.0, 2.0], "re": [0.5, 0.1], "im": [-0.5, -0.3]}
        >>> FrequencyData.from_table(table, columns={"frequency": "f_Hz", "real": "re", "imag": "im"},
        ...                          units={"frequency": "Hz"})
        FrequencyData(2 frequencies in [6.283, 12.57] rad/s, 1 output(s), 1 input(s))
        """
        from symid.data.table import frequency_data_from_table

        return frequency_data_from_table(table, columns=columns, units=units, delimiter=delimiter)

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
        meta, columns, rows = _files.read_csv(path, cls._kind, meta_keys=("n_outputs", "n_inputs", "variance_dof"))
        p = _files.meta_int(meta, "n_outputs", path, at_most=len(columns))
        m = _files.meta_int(meta, "n_inputs", path, at_most=len(columns))
        has_var = len(columns) == 1 + 3 * p * m
        _files.expect_width(columns, 1 + (3 if has_var else 2) * p * m, path,
                            "1 + 2 × n_outputs × n_inputs, or 1 + 3 × n_outputs × n_inputs with variances")
        _files.expect_columns(columns, cls._columns(p, m, has_var), path)
        table = _files.parse_float_rows(rows, path, len(columns))
        k = 1 + 2 * p * m
        H = _files.complex_from_parts(table[:, 1:k:2], table[:, 2:k:2]).reshape(-1, p, m)
        dof = meta.get("variance_dof")
        with naming_file(path):
            if dof is not None:
                try:
                    dof = float(dof)
                except ValueError:
                    raise DataError(f"variance_dof is {dof!r}, not a number") from None
            return cls(table[:, 0], H, table[:, k:].reshape(-1, p, m) if has_var else None, dof)
