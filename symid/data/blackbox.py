"""A numeric continuous-time state-space model (an identified black box)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np

from symid.data import _files, checks
from symid.data._base import DataContainer, naming_file
from symid.errors import DataError
from symid.model.lti import StateSpaceMatrices, as_frequencies, frequency_response_ss

__all__ = ["BlackBox"]

_NAMES = ("A", "B", "C", "D")


@dataclass(frozen=True, init=False, eq=False, repr=False)
class BlackBox(DataContainer):
    """A continuous-time black-box model x' = A x + B u, y = C x + D u with numeric matrices.

    It is data for the grey-box formulations that match a structured model to a
    black-box realisation (thesis chapters 6 and 7): the realisation is only known up to
    a similarity transform.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Real, square state matrix.
    B : array_like, shape (n, m) or (n,)
        Real input matrix; a 1-D array of length n is a single input column.
    C : array_like, shape (p, n) or (n,)
        Real output matrix; a 1-D array of length n is a single output row.
    D : array_like, shape (p, m), optional
        Real feedthrough; zero when omitted. A scalar is accepted when p = m = 1.

    Raises
    ------
    DataError
        On NaN or inf, complex entries, a non-square ``A`` or inconsistent shapes.

    Notes
    -----
    ``BlackBox(*ss)`` and ``BlackBox.from_state_space(ss)`` accept a
    :class:`~symid.model.lti.StateSpaceMatrices` tuple (from ``model.state_space(θ)``).

    CSV layout (see :meth:`to_csv`), one entry per line in long form::

        # symid BlackBox csv v2
        # n_states: n
        # n_inputs: m
        # n_outputs: p
        # n_rows: (n + p)(n + m)
        matrix,row,col,value
        A,0,0,-1.0
        ...
        # end

    Every entry of A, B, C and D appears exactly once, in that order, row-major.

    Examples
    --------
    >>> from symid.data import BlackBox
    >>> bb = BlackBox(A=[[0, 1], [-2, -0.5]], B=[0, 1], C=[1, 0])
    >>> bb.n_states, bb.n_inputs, bb.n_outputs
    (2, 1, 1)
    >>> bb.frequency_response([1.0]).shape
    (1, 1, 1)
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray

    _kind: ClassVar[str] = "BlackBox"
    _npz_keys: ClassVar[tuple[str, ...]] = _NAMES

    def __init__(self, A: Any, B: Any, C: Any, D: Any | None = None):
        A_ = checks.as_array(A, "A", complex_ok=False)
        if A_.ndim != 2 or A_.shape[0] != A_.shape[1] or A_.shape[0] < 1:
            raise DataError(f"A must be a square matrix of shape (n, n) with n >= 1; "
                            f"got shape {checks.shape_text(A_.shape)}")
        n = A_.shape[0]
        B_ = checks.as_array(B, "B", complex_ok=False)
        if B_.ndim == 1 and B_.size == n:
            B_ = B_.reshape(n, 1)
        if B_.ndim != 2 or B_.shape[0] != n or B_.shape[1] < 1:
            raise DataError(f"B must have shape (n, m) = ({n}, m) to match A, or ({n},) for one input; "
                            f"got shape {checks.shape_text(B_.shape)}")
        C_ = checks.as_array(C, "C", complex_ok=False)
        if C_.ndim == 1 and C_.size == n:
            C_ = C_.reshape(1, n)
        if C_.ndim != 2 or C_.shape[1] != n or C_.shape[0] < 1:
            raise DataError(f"C must have shape (p, n) = (p, {n}) to match A, or ({n},) for one output; "
                            f"got shape {checks.shape_text(C_.shape)}")
        p, m = C_.shape[0], B_.shape[1]
        if D is None:
            D_ = np.zeros((p, m))
        else:
            D_ = checks.as_array(D, "D", complex_ok=False)
            if D_.ndim == 0 and p == m == 1:
                D_ = D_.reshape(1, 1)
            if D_.shape != (p, m):
                raise DataError(f"D must have shape (p, m) = ({p}, {m}) to match C and B; "
                                f"got shape {checks.shape_text(D_.shape)}")
        for name, arr in zip(_NAMES, (A_, B_, C_, D_), strict=True):
            checks.check_finite(arr, name)
            object.__setattr__(self, name, checks.frozen(arr))

    @classmethod
    def from_state_space(cls, ss: StateSpaceMatrices | tuple[Any, Any, Any, Any]) -> Self:
        """Build from a :class:`~symid.model.lti.StateSpaceMatrices` (or any (A, B, C, D) tuple).

        Examples
        --------
        >>> import symid as si
        >>> from symid.data import BlackBox
        >>> m, c, k = si.parameters("m c k", positive=True)
        >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
        >>> BlackBox.from_state_space(model.state_space([1.0, 0.2, 4.0])).n_states
        2
        """
        try:
            A, B, C, D = ss
        except (TypeError, ValueError):
            raise DataError("from_state_space expects a 4-tuple (A, B, C, D), such as model.state_space(theta)") \
                from None
        return cls(A, B, C, D)

    def state_space(self) -> StateSpaceMatrices:
        """The matrices as a :class:`~symid.model.lti.StateSpaceMatrices` of writable copies."""
        return StateSpaceMatrices(self.A.copy(), self.B.copy(), self.C.copy(), self.D.copy())

    # -- properties -----------------------------------------------------------------
    @property
    def n_states(self) -> int:
        """Number of states n."""
        return int(self.A.shape[0])

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return int(self.B.shape[1])

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return int(self.C.shape[0])

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of A (a new array)."""
        return np.linalg.eigvals(self.A)

    def frequency_response(self, w: Any) -> np.ndarray:
        """H(ω) = C (jωI − A)⁻¹ B + D at angular frequencies ``w`` (rad/s), shape (len(w), p, m).

        Raises
        ------
        ModelError
            If jωI − A is singular at one of the frequencies.
        """
        return frequency_response_ss(StateSpaceMatrices(self.A, self.B, self.C, self.D), as_frequencies(w))

    # -- text -----------------------------------------------------------------------
    def __repr__(self) -> str:
        return f"BlackBox({self.n_states} states, {self.n_inputs} input(s), {self.n_outputs} output(s))"

    def summary(self) -> str:
        """A short readable description: sizes, poles, matrices."""
        poles = np.sort_complex(self.poles)
        with np.printoptions(precision=4, suppress=True):
            return "\n".join([
                "BlackBox (continuous time)",
                f"  states n  : {self.n_states}",
                f"  inputs m  : {self.n_inputs}",
                f"  outputs p : {self.n_outputs}",
                f"  poles     : {', '.join(f'{z:.4g}' for z in poles)}",
                *(f"{k} =\n{getattr(self, k)}" for k in _NAMES),
            ])

    # -- CSV ------------------------------------------------------------------------
    def to_csv(self, path: _files.PathLike) -> None:
        """Write the matrices as CSV text in long form (layout in the class notes); the round trip is exact."""
        rows = []
        for name in _NAMES:
            mat = getattr(self, name)
            for (i, j), x in np.ndenumerate(mat):
                rows.append([name, str(i), str(j), _files.fmt(x)])
        meta = {"n_states": self.n_states, "n_inputs": self.n_inputs, "n_outputs": self.n_outputs}
        _files.write_csv(path, self._kind, meta, ["matrix", "row", "col", "value"], rows)

    @classmethod
    def from_csv(cls, path: _files.PathLike) -> Self:
        """Read a file written by :meth:`to_csv`.

        Raises
        ------
        DataError
            If the file is not a symid BlackBox CSV file, its sizes do not match the
            number of entries, an entry is missing, repeated or out of range, or the
            matrices fail the constructor's checks.
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.
        """
        meta, columns, rows = _files.read_csv(path, cls._kind, complete_by_content=True,
                                              meta_keys=("n_states", "n_inputs", "n_outputs"))
        n = _files.meta_int(meta, "n_states", path, at_most=len(rows))
        m = _files.meta_int(meta, "n_inputs", path, at_most=len(rows))
        p = _files.meta_int(meta, "n_outputs", path, at_most=len(rows))
        _files.expect_columns(columns, ["matrix", "row", "col", "value"], path)
        if len(rows) != (n + p) * (n + m):  # every entry of A, B, C, D once, before any matrix is built
            raise DataError(f"{str(path)!r} declares n_states {n}, n_inputs {m}, n_outputs {p}, i.e. "
                            f"{(n + p) * (n + m)} entries, but holds {len(rows)} rows (one per entry of A, B, C and D: "
                            f"n² + n·m + p·n + p·m): the header does not match the data")
        shapes = {"A": (n, n), "B": (n, m), "C": (p, n), "D": (p, m)}
        mats = {k: np.full(shp, np.nan) for k, shp in shapes.items()}
        seen = {k: np.zeros(shp, dtype=bool) for k, shp in shapes.items()}
        where = repr(str(path))
        for line, text in rows:
            name, row, col, value = (c.strip() for c in text.split(","))
            if name not in shapes:
                raise DataError(f"{where}, line {line}: unknown matrix {name[:40]!r}; expected A, B, C or D")
            try:
                if not (row.isdigit() and col.isdigit()):  # ASCII already (read_csv): plain digits, no sign
                    raise ValueError(row)
                i, j, x = int(row), int(col), float(value)
            except ValueError:
                raise DataError(f"{where}, line {line}: row and col must be integers ≥ 0 and value a number; "
                                f"got {row[:40]!r}, {col[:40]!r}, {value[:40]!r}") from None
            if not (i < shapes[name][0] and j < shapes[name][1]):
                raise DataError(f"{where}, line {line}: entry {name}[{i},{j}] is outside {name}'s shape "
                                f"{shapes[name]}")
            if seen[name][i, j]:
                raise DataError(f"{where}, line {line}: entry {name}[{i},{j}] appears twice")
            seen[name][i, j] = True
            mats[name][i, j] = x
        # no entry can be missing: as many rows as entries, each in range and none twice
        with naming_file(path):
            return cls(mats["A"], mats["B"], mats["C"], mats["D"])
