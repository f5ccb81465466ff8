"""Symbolic first-order continuous-time models x' = A(θ) x + B(θ) u, y = C(θ) x + D(θ) u."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError
from symid.model.lti import StateSpaceMatrices, as_frequencies, frequency_response_ss
from symid.model.parametric import ParametricModel, Theta, pretty
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
    x0 : array_like of length n, or "estimate", optional
        The initial state x(0) of every experiment: zero when omitted; numbers or
        expressions affine in the parameters (e.g. ``[dose / V, 0]`` for a bolus into
        compartment 1 — parameters that appear only here join θ after those of the
        matrices); or ``"estimate"``, an unknown initial state that the time-domain
        methods estimate per experiment beside θ. Frequency-domain data carry no
        information on x0 (it only shapes transients).
    name : str, optional
        A label used in reports.

    Raises
    ------
    NonAffineError
        If an entry (of x0 too) is not affine in the parameters.
    ModelError
        On inconsistent shapes or unparsable entries, or an x0 of the wrong length.

    Examples
    --------
    >>> import symid as si
    >>> a, b = si.parameters("a b")
    >>> model = si.StateSpaceModel(A=[[0, 1], [-a, -b]], B=[[0], [1]], C=[[1, 0]])
    >>> model.parameter_names
    ('a', 'b')
    >>> model.frequency_response({"a": 1.0, "b": 0.5}, [0.0]).real
    array([[[1.]]])

    A bolus of unknown size ``d`` in the first of two compartments:

    >>> k10, k12, k21, d = si.parameters("k10 k12 k21 d", positive=True)
    >>> pk = si.StateSpaceModel(A=[[-k10 - k12, k21], [k12, -k21]], B=[[0], [0]], C=[[1, 0]], x0=[d, 0])
    >>> pk.parameter_names, pk.initial_state_kind
    (('k10', 'k12', 'k21', 'd'), 'affine')
    >>> pk.initial_state({"k10": 0.1, "k12": 0.2, "k21": 0.3, "d": 5.0})
    array([5., 0.])
    """

    _kind = "state-space"

    def __init__(self, A: Any, B: Any, C: Any, D: Any | None = None, *, x0: Any = None,
                 parameters: Sequence[Any] | None = None, name: str | None = None):
        A_ = as_symbolic_matrix(A, "A")
        if A_.rows != A_.cols:
            raise ModelError(f"A must be square; got shape {A_.shape}")
        n = A_.rows
        B_ = as_symbolic_matrix(B, "B", shape=(n, None))
        C_ = as_symbolic_matrix(C, "C", shape=(None, n))
        D_ = sp.zeros(C_.rows, B_.cols) if D is None else as_symbolic_matrix(D, "D", shape=(C_.rows, B_.cols))
        mats = [("A", A_), ("B", B_), ("C", C_), ("D", D_)]
        self._x0_estimate = isinstance(x0, str) and x0 == "estimate"
        if x0 is not None and not self._x0_estimate:
            mats.append(("x0", _initial_state_matrix(x0, n)))
        self._setup(mats, parameters, name)
        # x(0) is not a system matrix: kept apart so that every method working on (A, B, C, D) is unchanged
        self._x0_map = self._maps.pop("x0", None)
        self._x0_symbolic = self._symbolic.pop("x0", None)

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

    @property
    def initial_state_kind(self) -> str:
        """How x(0) is given: ``"zero"``, ``"known"`` (numbers), ``"affine"`` (in θ) or ``"estimate"``."""
        if self._x0_estimate:
            return "estimate"
        if self._x0_map is None:
            return "zero"
        return "known" if self._x0_map.is_constant else "affine"

    @property
    def initial_state_map(self) -> Any:
        """The affine map θ ↦ x(0) as an (n, 1) :class:`~symid.model.affine.AffineMap`, or ``None``
        (x(0) zero, or to be estimated)."""
        return self._x0_map

    def initial_state(self, theta: Theta) -> np.ndarray:
        """x(0) at θ, shape (n,).

        Raises
        ------
        ModelError
            When the model's initial state is to be estimated (``x0="estimate"``): it has no
            value until an estimator gives it one; pass ``x0=`` to the simulator.

        Examples
        --------
        >>> import symid as si
        >>> a = si.parameters("a")
        >>> si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]], x0=[[2 * a]]).initial_state({"a": 1.5})
        array([3.])
        """
        if self._x0_estimate:
            raise ModelError("this model's initial state is to be estimated (x0='estimate'): it has no value at θ; "
                             "give x0= explicitly to simulate it")
        vec = self.theta_vector(theta)
        if self._x0_map is None:
            return np.zeros(self.n_states)
        return np.asarray(self._x0_map(vec), dtype=float).reshape(-1)

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
        text = f"{head}\nparameters: {', '.join(self.parameter_names) or '(none)'}\n{self._matrix_text()}"
        if self._x0_estimate:
            return f"{text}\nx0 = estimated per experiment"
        if self._x0_symbolic is not None:
            return f"{text}\nx0 =\n{pretty(self._x0_symbolic)}"
        return text


def _initial_state_matrix(x0: Any, n: int) -> sp.Matrix:
    """x0 as an (n, 1) symbolic column: a 1-D sequence or an (n, 1) / (1, n) matrix; a ModelError otherwise."""
    if isinstance(x0, str):
        raise ModelError(f"x0 must be numbers or expressions (one per state) or the word 'estimate'; got {x0!r}")
    if isinstance(x0, np.ndarray) and x0.ndim == 1:
        x0 = x0.reshape(-1, 1)
    elif isinstance(x0, (list, tuple)) and x0 and not any(isinstance(v, (list, tuple, np.ndarray)) for v in x0):
        x0 = [[v] for v in x0]
    X = as_symbolic_matrix(x0, "x0")
    if X.rows == 1 and X.cols == n and n != 1:
        X = X.T
    if X.shape != (n, 1):
        raise ModelError(f"x0 must hold one value per state, n = {n}; got shape {X.shape}")
    return X
