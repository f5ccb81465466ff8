"""Power spectral density data: output and input spectra Φyy(ω), Φuu(ω)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np

from symid.data import _files, checks
from symid.data._base import DataContainer, naming_file
from symid.errors import DataError

__all__ = ["SpectralData"]


def _spectrum(x: Any, name: str, s: int, size: str) -> np.ndarray:
    arr = checks.as_array(x, name, complex_ok=True)
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1, 1)
    elif arr.ndim != 3:
        raise DataError(f"{name} must have shape (s, {size}, {size}), or (s,) for a single channel; "
                        f"got shape {checks.shape_text(arr.shape)}")
    if arr.shape[0] != s:
        raise DataError(f"{name} has {arr.shape[0]} frequencies (shape {checks.shape_text(arr.shape)}) but w has "
                        f"{s}; expected {name} of shape ({s}, {size}, {size})")
    if arr.shape[1] != arr.shape[2] or arr.shape[1] < 1:
        raise DataError(f"{name} must hold square matrices, shape (s, {size}, {size}); "
                        f"got shape {checks.shape_text(arr.shape)}")
    checks.check_finite(arr, name)
    checks.check_hermitian(arr, name)
    checks.check_power_diagonal(arr, name)
    return checks.frozen(arr)


@dataclass(frozen=True, init=False, eq=False, repr=False)
class SpectralData(DataContainer):
    """Output and input power spectra at angular frequencies ω_1 < ... < ω_s (rad/s).

    For a system H(ω) driven by a stationary input, ``Φyy(ω) = H(ω) Φuu(ω) H(ω)ᴴ``
    (thesis (5-3)). Both spectra are Hermitian at every frequency, and their diagonals
    (auto-spectra, powers) are ≥ 0. Positive semidefiniteness beyond that is not enforced
    (noisy estimates may violate it slightly).

    Parameters
    ----------
    w : array_like, shape (s,)
        Angular frequencies in rad/s: finite, strictly positive and strictly increasing.
    Phi_yy : array_like, shape (s, p, p) or (s,)
        Output spectrum; a 1-D array is a single output (stored as (s, 1, 1)).
    Phi_uu : array_like, shape (s, m, m) or (s,)
        Input spectrum; a 1-D array is a single input (stored as (s, 1, 1)).

    Raises
    ------
    DataError
        On NaN or inf, wrong shapes, a length mismatch with ``w``, bad frequencies, or a
        spectrum that is not Hermitian to 1e-8 relative to its Frobenius norm
        (``max |Φ − Φᴴ| <= 1e-8 ||Φ||_F`` at each frequency), or a diagonal entry below
        −1e-8 times the largest diagonal entry (a negative power).

    Notes
    -----
    CSV layout (see :meth:`to_csv`)::

        # symid SpectralData csv v2
        # n_outputs: p
        # n_inputs: m
        # n_rows: N
        w,Phi_yy[0][0].re,Phi_yy[0][0].im,...,Phi_uu[0][0].re,Phi_uu[0][0].im,...
        <one row per frequency>
        # end

    Full matrices are written (not only a triangle), row-major, first Φyy then Φuu. Spectra
    that :func:`symid.estimate_spectra` made carry how (``estimated_from``) in further
    lines, ``# welch_samples``, ``# welch_nperseg``, ``# welch_noverlap``, ``# welch_dt``,
    ``# welch_window`` and ``# welch_input``, read back as they were: the number of
    averages behind each line, which ``method="auto"`` weighs the spectra and judges the
    fit by (a new user's spectra saved and refitted lost it, and the unweighted fit
    accepted a local minimum with a mass 430 times its value).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data import SpectralData
    >>> w = np.array([0.5, 1.0, 2.0])
    >>> H = 1 / (1j * w + 1)
    >>> spec = SpectralData(w, np.abs(H) ** 2, np.ones(3))   # white input of intensity 1
    >>> spec.Phi_yy.shape, spec.n_inputs
    ((3, 1, 1), 1)
    """

    w: np.ndarray
    Phi_yy: np.ndarray
    Phi_uu: np.ndarray

    _kind: ClassVar[str] = "SpectralData"
    _npz_keys: ClassVar[tuple[str, ...]] = ("w", "Phi_yy", "Phi_uu")
    estimated_from: ClassVar[dict[str, Any]] = {}
    """How :func:`symid.estimate_spectra` made these spectra from sampled records: ``{"dt", "nperseg", "window",
    "resolution" (the line spacing, rad/s), "samples", "noverlap", "input" ("given" or "measured")}``; ``{}`` for
    spectra from anywhere else. Set on the object made (not kept by a copy or a file): :func:`symid.identify` names
    the window's bias when it moves the estimate (:mod:`symid.fit.frf.leakage`), and ``method="auto"`` weighs the
    spectra by their scatter and judges the fit against it (:mod:`symid.fit.spectra.welch`)."""

    def __init__(self, w: Any, Phi_yy: Any, Phi_uu: Any):
        w_ = checks.frequencies(w, "w")
        object.__setattr__(self, "w", w_)
        object.__setattr__(self, "Phi_yy", _spectrum(Phi_yy, "Phi_yy", w_.size, "p"))
        object.__setattr__(self, "Phi_uu", _spectrum(Phi_uu, "Phi_uu", w_.size, "m"))

    # -- properties -----------------------------------------------------------------
    @property
    def n_frequencies(self) -> int:
        """Number of frequencies s."""
        return int(self.w.size)

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return int(self.Phi_yy.shape[1])

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return int(self.Phi_uu.shape[1])

    # -- text -----------------------------------------------------------------------
    def __repr__(self) -> str:
        return (f"SpectralData({self.n_frequencies} frequencies in [{self.w[0]:.4g}, {self.w[-1]:.4g}] rad/s, "
                f"{self.n_outputs} output(s), {self.n_inputs} input(s))")

    def summary(self) -> str:
        """A short readable description: sizes, frequency range, ranges of the spectra's diagonals."""
        dy = np.real(np.diagonal(self.Phi_yy, axis1=1, axis2=2))
        du = np.real(np.diagonal(self.Phi_uu, axis1=1, axis2=2))
        return "\n".join([
            "SpectralData",
            f"  frequencies : {self.n_frequencies}, {self.w[0]:.6g} to {self.w[-1]:.6g} rad/s",
            f"  outputs p   : {self.n_outputs}",
            f"  inputs m    : {self.n_inputs}",
            f"  diag Phi_yy : {dy.min():.4g} to {dy.max():.4g}",
            f"  diag Phi_uu : {du.min():.4g} to {du.max():.4g}",
        ])

    # -- CSV ------------------------------------------------------------------------
    @staticmethod
    def _columns(p: int, m: int) -> list[str]:
        cols = ["w"]
        for name, k in (("Phi_yy", p), ("Phi_uu", m)):
            for i in range(k):
                for j in range(k):
                    cols += [f"{name}[{i}][{j}].re", f"{name}[{i}][{j}].im"]
        return cols

    def to_csv(self, path: _files.PathLike) -> None:
        """Write the data as CSV text (layout in the class notes); the round trip is exact."""
        s, p, m = self.n_frequencies, self.n_outputs, self.n_inputs
        flat = np.hstack([self.Phi_yy.reshape(s, p * p), self.Phi_uu.reshape(s, m * m)])
        table = np.empty((s, 1 + 2 * flat.shape[1]))
        table[:, 0] = self.w
        table[:, 1::2] = flat.real
        table[:, 2::2] = flat.imag
        rows = [[_files.fmt(x) for x in row] for row in table.tolist()]
        _files.write_csv(path, self._kind, {"n_outputs": p, "n_inputs": m, **_welch_meta(self.estimated_from)},
                         self._columns(p, m), rows)

    @classmethod
    def from_csv(cls, path: _files.PathLike) -> Self:
        """Read a file written by :meth:`to_csv`.

        Raises
        ------
        DataError
            If the file is not a symid SpectralData CSV file, was cut short, declares
            sizes that its rows and columns do not match, or its contents fail the
            constructor's checks (rules in the notes of ``symid.data._files``).
        FileNotFoundError, IsADirectoryError, PermissionError
            If the file cannot be opened.

        Warns
        -----
        UserWarning
            For a version-1 file, whose completeness cannot be checked.
        """
        meta, columns, rows = _files.read_csv(path, cls._kind, meta_keys=("n_outputs", "n_inputs", *_WELCH_KEYS))
        p = _files.meta_int(meta, "n_outputs", path, at_most=len(columns))
        m = _files.meta_int(meta, "n_inputs", path, at_most=len(columns))
        _files.expect_width(columns, 1 + 2 * (p * p + m * m), path, "1 + 2 (n_outputs² + n_inputs²)")
        _files.expect_columns(columns, cls._columns(p, m), path)
        table = _files.parse_float_rows(rows, path, len(columns))
        flat = _files.complex_from_parts(table[:, 1::2], table[:, 2::2])
        Phi_yy = flat[:, : p * p].reshape(-1, p, p)
        Phi_uu = flat[:, p * p:].reshape(-1, m, m)
        with naming_file(path):
            out = cls(table[:, 0], Phi_yy, Phi_uu)
        made = _welch_from_meta(meta, path)
        if made:
            object.__setattr__(out, "estimated_from", made)
        return out


_WELCH_KEYS = ("welch_samples", "welch_nperseg", "welch_noverlap", "welch_dt", "welch_window", "welch_input")


def _welch_meta(made: dict[str, Any]) -> dict[str, Any]:
    """The CSV metadata lines of ``estimated_from`` (none when it is empty or its window is not a name)."""
    window = made.get("window")
    if not made or not isinstance(window, str) or not made.get("nperseg"):
        return {}
    return {"welch_samples": int(made["samples"]), "welch_nperseg": int(made["nperseg"]),
            "welch_noverlap": int(made.get("noverlap", int(made["nperseg"]) // 2)),
            "welch_dt": repr(float(made["dt"])), "welch_window": window, "welch_input": made.get("input", "given")}


def _welch_from_meta(meta: dict[str, str], path: Any) -> dict[str, Any]:
    """``estimated_from`` from a file's metadata lines; {} without them; a DataError naming a malformed one."""
    given = [k for k in _WELCH_KEYS if k in meta]
    if not given:
        return {}
    if len(given) != len(_WELCH_KEYS):
        missing = ", ".join(k for k in _WELCH_KEYS if k not in meta)
        raise DataError(f"{_files._where(path)}: the Welch metadata lines are incomplete (missing {missing}); "
                        f"remove them all or write the file again with to_csv")
    samples = _files.meta_int(meta, "welch_samples", path)
    nperseg = _files.meta_int(meta, "welch_nperseg", path, at_most=samples)
    noverlap = _files.meta_int(meta, "welch_noverlap", path, at_most=max(nperseg - 1, 0))
    dt = _files.meta_float(meta, "welch_dt", path)
    window, source = meta["welch_window"], meta["welch_input"]
    if not (window.isascii() and window.replace("_", "").isalnum() and len(window) <= 40):
        raise DataError(f"{_files._where(path)}: '# welch_window: {window[:40]}' is not a window's name (hann, "
                        f"hamming, ...)")
    try:
        import scipy.signal

        scipy.signal.get_window(window, 8)
    except (ValueError, TypeError):
        raise DataError(f"{_files._where(path)}: '# welch_window: {window}' is not a window scipy knows") from None
    if source not in ("given", "measured"):
        raise DataError(f"{_files._where(path)}: '# welch_input: {source[:40]}' must be 'given' or 'measured'")
    if not (dt > 0 and np.isfinite(dt)) or nperseg < 8:
        raise DataError(f"{_files._where(path)}: the Welch metadata need welch_dt > 0 and welch_nperseg >= 8")
    return {"dt": dt, "nperseg": nperseg, "window": window, "resolution": 2 * np.pi / (nperseg * dt),
            "samples": samples, "noverlap": noverlap, "input": source}
