"""Error and warning types of symid.

Every error symid raises on purpose derives from :class:`SymidError` and from the
built-in type a caller would expect (``ValueError`` for bad values, ``TypeError`` for
bad types), so ``except ValueError`` keeps working.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = [
    "DataError",
    "DataWarning",
    "IdentifiabilityWarning",
    "ModelError",
    "ModelWarning",
    "NonAffineError",
    "OptionError",
    "SolverError",
    "SymidError",
    "did_you_mean",
]


class SymidError(Exception):
    """Base class of every error raised by symid."""


class ModelError(SymidError, ValueError):
    """A model is malformed: wrong matrix shapes, unknown output kind, bad parameters."""


class NonAffineError(ModelError):
    """A matrix entry is not affine in the parameters.

    Attributes
    ----------
    matrix : str
        Name of the matrix holding the entry (``"A"``, ``"M"``, ...).
    entry : tuple of int
        Zero-based (row, column) index of the offending entry.
    expression : str
        The entry as sympy prints it.
    parameters : tuple of str
        The parameters involved in the non-affine part.
    """

    def __init__(self, message: str, *, matrix: str = "", entry: tuple[int, int] = (-1, -1),
                 expression: str = "", parameters: tuple[str, ...] = ()):
        super().__init__(message)
        self.matrix = matrix
        self.entry = entry
        self.expression = expression
        self.parameters = parameters


class DataError(SymidError, ValueError):
    """Measured or simulated data are malformed (shape, NaN/inf, frequencies, symmetry)."""


class OptionError(SymidError, ValueError):
    """An option of an estimator or an analysis is unknown, misspelt or has a bad value.

    The message names the option and, for an unknown name, lists the valid ones.
    """


class SolverError(SymidError, RuntimeError):
    """A numerical back end failed in a way that leaves no result to report."""


class DataWarning(UserWarning):
    """Something in the user's data that symid cannot check and does not refuse (a unit it does not know)."""


class ModelWarning(UserWarning):
    """Something in a model file that symid passes over and the user probably meant (a misspelt name)."""


class IdentifiabilityWarning(UserWarning):
    """Parameters asked for are not (locally) identifiable from the data kind."""


def did_you_mean(names: Sequence[str], valid: Sequence[str]) -> str:
    """`` (did you mean 'Kt'?)`` for the first of ``names`` close to one of ``valid`` (the same but for case, or
    :func:`difflib.get_close_matches` at a similarity of 0.5, which two-letter names need: "Jn" for "Jm"), else
    ``""``: the part of an error message that names the likely typo.

    Examples
    --------
    >>> from symid.errors import did_you_mean
    >>> did_you_mean(["kt"], ["Jm", "Kt"]), did_you_mean(["Jn"], ["Jm", "Kt"]), did_you_mean(["zz"], ["Jm"])
    (" (did you mean 'Kt'?)", " (did you mean 'Jm'?)", '')
    """
    import difflib

    for name in names:
        same_case = [v for v in valid if v.lower() == str(name).lower()]
        close = same_case or difflib.get_close_matches(str(name), list(valid), n=1, cutoff=0.5)
        if close:
            return f" (did you mean {close[0]!r}?)"
    return ""
