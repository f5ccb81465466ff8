"""Symbolic first-order continuous-time models x' = A(θ) x + B(θ) u, y = C(θ) x + D(θ) u."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError
from symid.model.lti import StateSpaceMatrices, as_frequencies, frequency_response_ss
from symid.model.parametric import ParametricModel, Theta
from symid.model.symbols import as_symbolic_matrix

__all__ = ["StateSpaceModel"]


class StateSpaceModel(ParametricModel):
    """A linear continuous-time state-space model with affinely parameterised matrices.

    ``x'(t) = A(θ) x(t) + B(θ) u(t)``, ``y(t) = C(θ) x(t) + D(θ) u(t)``.

    Parameters
    ----------
    A, B, C : array_like or sympy.Matrix
        System matrices of shapes (n, n), (n, m), (p, n). Entries are numbers, sympy
        expressions or strings (:func:`symid.model.symbols.parse_entry`: every bare name in
        a string is a real parameter, ``pi`` excepted), each affine in the parameters.
        A scalar is a 1 x 1 matrix; a 1-D sequence is refused as ambiguous.
    D : array_like or sympy.Matrix, optional
        Feedthrough of shape (p, m); zero when omitted.
    parameters : sequence of sympy.Symbol or str, or str, optional
        Fixes the order of θ (a string is split at spaces and commas). By default it
        is the order of first appearance, row by row, through A, B, C, D (within one
        entry, sympy's canonical order: alphabetical for plain names).
    name : str, optional
        A label used in reports.

    Raises
    ------
    NonAffineError
        If an entry is not affine in the parameters.
    ModelError
        On inconsistent shapes or unparsable entries.

    Examples
    --------
    >>> import symid as si
    >>> a, b = si.parameters("a b")
    >>> model = si.StateSpaceModel(A=[[0, 1], [-a, -b]], B=[[0], [1]], C=[[1, 0]])
    >>> model.parameter_names
    ('a', 'b')
    >>> model.frequency_response({"a": 1.0, "b": 0.5}, [0.0]).real
    array([[[1.]]])
    """

    _kind = "state-space"

    def __init__(self, A: Any, B: Any, C: Any, D: Any | None = None, *,
                 parameters: Sequence[Any] | None = None, name: str | None = None):
        A_ = as_symbolic_matrix(A, "A")
        if A_.rows != A_.cols:
            raise ModelError(f"A must be square; got shape {A_.shape}")
        n = A_.rows
        B_ = as_symbolic_matrix(B, "B", shape=(n, None))
        C_ = as_symbolic_matrix(C, "C", shape=(None, n))
        D_ = sp.zeros(C_.rows, B_.cols) if D is None else as_symbolic_matrix(D, "D", shape=(C_.rows, B_.cols))
        self._setup([("A", A_), ("B", B_), ("C", C_), ("D", D_)], parameters, name)

    @property
    def n_states(self) -> int:
        """Number of states n."""
        return self._maps["A"].shape[0]

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return self._maps["B"].shape[1]

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return self._maps["C"].shape[0]

    def _shape_text(self) -> str:
        return f"{self.n_states} states, {self.n_inputs} input(s), {self.n_outputs} output(s)"

    def state_space(self, theta: Theta) -> StateSpaceMatrices:
        """Numeric matrices (A, B, C, D) at θ.

        Parameters
        ----------
        theta : dict or sequence of float
            Parameter values by name (or symbol), or in ``parameter_names`` order.

        Returns
        -------
        StateSpaceMatrices
            Named tuple of float arrays ``A`` (n, n), ``B`` (n, m), ``C`` (p, n), ``D`` (p, m).

        Raises
        ------
        ModelError
            On a missing, unknown or non-finite parameter value.

        Examples
        --------
        >>> import symid as si
        >>> a = si.parameters("a")
        >>> si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[2]]).state_space({"a": 3.0}).A
        array([[-3.]])
        """
        mats = self.matrices(theta)
        return StateSpaceMatrices(mats["A"], mats["B"], mats["C"], mats["D"])

    def symbolic_state_space(self) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix, sp.Matrix]:
        """Symbolic matrices (A, B, C, D)."""
        s = self.symbolic
        return s["A"], s["B"], s["C"], s["D"]

    def frequency_response(self, theta: Theta, w: Any) -> np.ndarray:
        """Frequency response H(ω) = C (jωI − A)⁻¹ B + D at angular frequencies ``w`` (rad/s).

        Parameters
        ----------
        theta : dict or sequence of float
            Parameter values by name (or symbol), or in ``parameter_names`` order.
        w : array_like
            Real angular frequencies in rad/s (any order and sign; a scalar is one frequency).

        Returns
        -------
        numpy.ndarray
            Complex array of shape (len(w), p, m).

        Raises
        ------
        ModelError
            On bad θ, or if jωI − A is singular at one of the frequencies.
        DataError
            If ``w`` is missing, complex, not 1-D or not finite.

        Examples
        --------
        >>> import symid as si
        >>> a = si.parameters("a")
        >>> model = si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]])
        >>> model.frequency_response([1.0], [0.0, 1.0])[:, 0, 0]   # 1 / (jω + a)
        array([1. +0.j , 0.5-0.5j])
        """
        ss = self.state_space(theta)
        return frequency_response_ss(ss, as_frequencies(w))

    def summary(self) -> str:
        """Parameters and matrices as readable text."""
        head = f"StateSpaceModel{' ' + repr(self.name) if self.name else ''}: {self._shape_text()}"
        return f"{head}\nparameters: {', '.join(self.parameter_names) or '(none)'}\n{self._matrix_text()}"
