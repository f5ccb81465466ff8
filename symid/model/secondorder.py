"""Symbolic second-order models M(θ) q'' + V(θ) q' + K(θ) q = B(θ) u, y = C(θ) q (or q', q'')."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError, ModelWarning
from symid.model.lti import StateSpaceMatrices, as_frequencies
from symid.model.parametric import ParametricModel, Theta
from symid.model.symbols import as_symbolic_matrix

__all__ = ["MIXED", "OUTPUT_KINDS", "OUTPUT_ORDERS", "SecondOrderModel", "output_factor"]

OUTPUT_KINDS = ("position", "velocity", "acceleration")
OUTPUT_ORDERS = {"position": 0, "velocity": 1, "acceleration": 2}
"""The derivative order d of each output kind: its response is (jω)ᵈ times the position's."""
MIXED = "mixed"


class SecondOrderModel(ParametricModel):
    """A linear second-order (matrix differential equation) model.

    ``M(θ) q''(t) + V(θ) q'(t) + K(θ) q(t) = B(θ) u(t)`` with the output
    ``y = C(θ) q``, ``C(θ) q'`` or ``C(θ) q''`` for ``output="position"``,
    ``"velocity"`` or ``"acceleration"`` (thesis (4-2), (4-9)).

    Parameters
    ----------
    M, V, K : array_like or sympy.Matrix
        Mass, damping and stiffness matrices, each (n, n), affine in the parameters.
        Entries are numbers, sympy expressions or strings
        (:func:`symid.model.symbols.parse_entry`).
    B : array_like or sympy.Matrix
        Input matrix (n, m).
    C : array_like or sympy.Matrix
        Output matrix (p, n).
    output : {"position", "velocity", "acceleration"} or sequence of them
        What the sensors measure. Default ``"position"``. A sequence gives one kind
        per row of C (an accelerometer beside a displacement sensor): row i of the
        output is ``Cᵢ q``, ``Cᵢ q'`` or ``Cᵢ q''``; :attr:`output` is then ``"mixed"``
        and :attr:`outputs` holds the kinds.
    parameters : sequence of sympy.Symbol or str, or str, optional
        Fixes the order of θ (a string is split at spaces and commas); by default the
        order of first appearance, row by row, through M, V, K, B, C (within one
        entry, sympy's canonical order: alphabetical for plain names).
    name : str, optional
        A label used in reports.

    Raises
    ------
    NonAffineError
        If an entry is not affine in the parameters.
    ModelError
        On inconsistent shapes, unparsable entries or an unknown ``output``.

    Notes
    -----
    The first-order form with state ``x = [q; q']`` is thesis (7-2):
    ``A = [[0, I], [−M⁻¹K, −M⁻¹V]]``, ``B = [[0], [M⁻¹B]]``. The thesis's (4-3)
    prints ``−M⁻¹B``; the sign there is a typo (it contradicts (4-2) and (7-2)).
    The output matrix is ``[C, 0]`` for position, ``[0, C]`` for velocity and, for
    acceleration, ``[−CM⁻¹K, −CM⁻¹V]`` with the feedthrough ``D = CM⁻¹B`` (row by row
    for mixed outputs). The response of an output of derivative order d is (jω)ᵈ times
    its position's, a known factor: a model's structural identifiability is the same
    whatever its outputs' kinds, and :func:`symid.identifiability` analyses a mixed
    model as its position twin.

    Examples
    --------
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> ss = model.state_space({"m": 2.0, "c": 1.0, "k": 4.0})
    >>> ss.A
    array([[ 0. ,  1. ],
           [-2. , -0.5]])

    An accelerometer and a displacement sensor on one mass:

    >>> two = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1], [1]],
    ...                           output=["acceleration", "position"])
    >>> two.output, two.outputs
    ('mixed', ('acceleration', 'position'))
    """

    _kind = "second-order"

    def __init__(self, M: Any, V: Any, K: Any, B: Any, C: Any, output: str | Sequence[str] = "position", *,
                 parameters: Sequence[Any] | None = None, name: str | None = None):
        kinds = _output_kinds(output)
        M_ = as_symbolic_matrix(M, "M")
        if M_.rows != M_.cols:
            raise ModelError(f"M must be square; got shape {M_.shape}")
        n = M_.rows
        V_ = as_symbolic_matrix(V, "V", shape=(n, n))
        K_ = as_symbolic_matrix(K, "K", shape=(n, n))
        B_ = as_symbolic_matrix(B, "B", shape=(n, None))
        C_ = as_symbolic_matrix(C, "C", shape=(None, n))
        if not isinstance(kinds, str) and len(kinds) != C_.rows:
            raise ModelError(f"output gives {len(kinds)} kind(s) but C has {C_.rows} row(s): give one kind per row "
                             f"of C, or one kind for all")
        #: The kind of every output row (a tuple of ``OUTPUT_KINDS``, one per row of C).
        self.outputs: tuple[str, ...] = (kinds,) * C_.rows if isinstance(kinds, str) else kinds
        #: The outputs' common kind, or ``"mixed"`` when the rows differ.
        self.output: str = self.outputs[0] if len(set(self.outputs)) == 1 else MIXED
        self._setup([("M", M_), ("V", V_), ("K", K_), ("B", B_), ("C", C_)], parameters, name)
        self._refuse_singular_mass()
        _warn_if_not_symmetric(self._symbolic)

    def _refuse_singular_mass(self) -> None:
        """A ModelError when M(θ) is singular for every θ: singular at two random points (its determinant, a
        polynomial in θ, vanishes identically). No θ could then be simulated or fitted (a new user's thermal network
        C T' + G T = P, written with M = 0, ran 11 passes to "cost inf")."""
        rng = np.random.default_rng(0)
        n = self.n_dof
        for _ in range(2):
            M = np.asarray(self._maps["M"](np.exp(rng.uniform(-1.0, 1.0, self.n_parameters))), dtype=float)
            # rows, then columns, scaled to a largest entry of 1: masses in any units (1e-6 beside 1e6) are not rank
            # loss, a zero row (a massless node) is
            rows = np.max(np.abs(M), axis=1)
            if np.all(rows > 0):
                M = M / rows[:, None]
                M = M / np.max(np.abs(M), axis=0)[None, :]
            sv = np.linalg.svd(M, compute_uv=False)
            if sv[0] > 0 and sv[-1] > 1e-10 * sv[0]:
                return
        rank = 0 if sv[0] == 0 else int(np.sum(sv > 1e-10 * sv[0]))
        what = "every entry is 0" if rank == 0 else f"rank {rank} of {n} at random values"
        raise ModelError(f"M(θ) is singular for every θ ({what}): the second-order model cannot be put in first-order "
                         f"form. A first-order system E x' + F x = B u (a thermal network C T' + G T = P) is "
                         f"SecondOrderModel(M=E, V=F, K=0, B=B, C=C, output='velocity') (x is then q'), or a "
                         f"StateSpaceModel; a massless node (or a mass given as 0 among the known values) needs a "
                         f"mass, or its equation eliminated")

    @property
    def n_dof(self) -> int:
        """Number of degrees of freedom n (size of M)."""
        return self._maps["M"].shape[0]

    @property
    def n_states(self) -> int:
        """Number of states of the first-order form, 2n."""
        return 2 * self.n_dof

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return self._maps["B"].shape[1]

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return self._maps["C"].shape[0]

    @property
    def output_orders(self) -> tuple[int, ...]:
        """The derivative order of every output row: 0 position, 1 velocity, 2 acceleration."""
        return tuple(OUTPUT_ORDERS[k] for k in self.outputs)

    def _shape_text(self) -> str:
        if self.output == MIXED:
            return f"{self.n_dof} DOF, {self.n_inputs} input(s), {self.n_outputs} outputs ({', '.join(self.outputs)})"
        return f"{self.n_dof} DOF, {self.n_inputs} input(s), {self.n_outputs} {self.output} output(s)"

    def _minv(self, M: np.ndarray, theta: np.ndarray) -> np.ndarray:
        try:
            Minv = np.linalg.inv(M)
        except np.linalg.LinAlgError:
            raise ModelError(f"M(θ) is singular at θ = {self.theta_dict(theta)}") from None
        return Minv

    def state_space(self, theta: Theta) -> StateSpaceMatrices:
        """First-order form (A, B, C, D) at θ (thesis (7-2); see the class notes).

        Parameters
        ----------
        theta : dict or sequence of float
            Parameter values by name (or symbol), or in ``parameter_names`` order.

        Returns
        -------
        StateSpaceMatrices
            ``A`` (2n, 2n), ``B`` (2n, m), ``C`` (p, 2n) and ``D`` (p, m) for the state
            ``x = [q; q']``; ``D = C M⁻¹ B`` for acceleration output, zero otherwise.

        Raises
        ------
        ModelError
            On bad θ, or if M(θ) is singular.

        Examples
        --------
        >>> import symid as si
        >>> m, c, k = si.parameters("m c k", positive=True)
        >>> acc = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]], output="acceleration")
        >>> ss = acc.state_space({"m": 2.0, "c": 1.0, "k": 4.0})
        >>> ss.C, ss.D                     # q'' = M⁻¹(B u − K q − V q')
        (array([[-2. , -0.5]]), array([[0.5]]))
        """
        vec = self.theta_vector(theta)
        mats = self.matrices(vec)
        M, V, K, B, C = (mats[k] for k in "MVKBC")
        n = self.n_dof
        Minv = self._minv(M, vec)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ V]])
        Bss = np.vstack([np.zeros_like(B), Minv @ B])
        D = np.zeros((C.shape[0], B.shape[1]))
        Css = np.zeros((C.shape[0], 2 * n))
        for i, kind in enumerate(self.outputs):
            if kind == "position":
                Css[i, :n] = C[i]
            elif kind == "velocity":
                Css[i, n:] = C[i]
            else:
                Css[i] = np.concatenate([-C[i] @ Minv @ K, -C[i] @ Minv @ V])
                D[i] = C[i] @ Minv @ B
        return StateSpaceMatrices(A, Bss, Css, D)

    def symbolic_state_space(self) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix, sp.Matrix]:
        """Symbolic first-order form (A, B, C, D); holds M⁻¹, so it is rational in θ."""
        s = self.symbolic
        M, V, K, B, C = (s[k] for k in "MVKBC")
        n = self.n_dof
        Minv = M.inv()
        Z, I = sp.zeros(n, n), sp.eye(n)
        A = sp.BlockMatrix([[Z, I], [-Minv * K, -Minv * V]]).as_explicit()
        Bss = sp.Matrix.vstack(sp.zeros(*B.shape), Minv * B)
        rows, drows = [], []
        for i, kind in enumerate(self.outputs):
            Ci = C[i, :]
            if kind == "position":
                rows.append(sp.Matrix.hstack(Ci, sp.zeros(1, n)))
                drows.append(sp.zeros(1, B.cols))
            elif kind == "velocity":
                rows.append(sp.Matrix.hstack(sp.zeros(1, n), Ci))
                drows.append(sp.zeros(1, B.cols))
            else:
                rows.append(sp.Matrix.hstack(-Ci * Minv * K, -Ci * Minv * V))
                drows.append(Ci * Minv * B)
        return A, Bss, sp.Matrix.vstack(*rows), sp.Matrix.vstack(*drows)

    def frequency_response(self, theta: Theta, w: Any) -> np.ndarray:
        """H(ω) = C (−ω²M + jωV + K)⁻¹ B, each row times jω (velocity) or −ω² (acceleration).

        Computed directly from M, V, K (no first-order form, no M⁻¹); it equals the
        response of :meth:`state_space` to rounding.

        Parameters
        ----------
        theta : dict or sequence of float
            Parameter values by name (or symbol), or in ``parameter_names`` order.
        w : array_like
            Real angular frequencies in rad/s (a scalar is one frequency).

        Returns
        -------
        numpy.ndarray
            Complex array of shape (len(w), p, m).

        Raises
        ------
        ModelError
            On bad θ, or if −ω²M + jωV + K is singular at one of the frequencies.
        DataError
            If ``w`` is missing, complex, not 1-D or not finite.

        Examples
        --------
        >>> import symid as si
        >>> m, c, k = si.parameters("m c k", positive=True)
        >>> vel = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]], output="velocity")
        >>> vel.frequency_response([1.0, 2.0, 1.0], [1.0])[:, 0, 0]   # jω / (k − mω² + jcω)
        array([0.5+0.j])
        """
        w = as_frequencies(w)
        mats = self.matrices(theta)
        M, V, K, B, C = (mats[k] for k in "MVKBC")
        if not np.any(K) and min(self.output_orders) >= 1:
            # a first-order system E x' + F x = B u written as M = E, V = F, K = 0, measured in velocity (x): H =
            # C (jωM + V)⁻¹ B, finite at ω = 0, where −ω²M + jωV is singular (a new user's LC ladder)
            Z1 = 1j * w[:, None, None] * M + V
            try:
                X = np.linalg.solve(Z1, np.broadcast_to(B.astype(complex), (w.size, *B.shape)))
            except np.linalg.LinAlgError:
                raise ModelError("jωM + V is singular at one of the frequencies (K = 0: a pole at ω = 0?)") from None
            reduced = np.stack([np.ones(w.size, dtype=complex) if d == 1 else 1j * w for d in self.output_orders],
                               axis=1)  # (jω)^(d − 1): the velocity's jω cancelled
            return (C @ X) * reduced[:, :, None]
        Z = -(w**2)[:, None, None] * M + 1j * w[:, None, None] * V + K
        try:
            X = np.linalg.solve(Z, np.broadcast_to(B.astype(complex), (w.size, *B.shape)))
        except np.linalg.LinAlgError:
            raise ModelError("−ω²M + jωV + K is singular at one of the frequencies "
                             "(an undamped resonance or a rigid-body mode at ω = 0)") from None
        return (C @ X) * output_factor(self, w)[:, :, None]

    def summary(self) -> str:
        """Parameters and matrices as readable text."""
        head = f"SecondOrderModel{' ' + repr(self.name) if self.name else ''}: {self._shape_text()}"
        return f"{head}\nparameters: {', '.join(self.parameter_names) or '(none)'}\n{self._matrix_text()}"


def _output_kinds(output: Any) -> str | tuple[str, ...]:
    """One kind, or a tuple of kinds (one per row of C), checked against ``OUTPUT_KINDS``."""
    choices = ", ".join(map(repr, OUTPUT_KINDS))
    if isinstance(output, str):
        if output not in OUTPUT_KINDS:
            raise ModelError(f"output must be one of {choices} (or a list of them, one per row of C); got {output!r}")
        return output
    if isinstance(output, Sequence) and len(output) > 0:
        for i, kind in enumerate(output):
            if not isinstance(kind, str) or kind not in OUTPUT_KINDS:
                raise ModelError(f"output[{i}] must be one of {choices}; got {kind!r}")
        return tuple(output)
    raise ModelError(f"output must be one of {choices}, or a non-empty list of them (one per row of C); "
                     f"got {output!r}")


def output_factor(model: Any, w: np.ndarray) -> np.ndarray:
    """(jω)ᵈ of every frequency and output row, shape (len(w), p): the factor that turns the position response
    C (−ω²M + jωV + K)⁻¹ B into the model's; ones for a model without output kinds (a state-space model).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> two = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1], [1]],
    ...                           output=["velocity", "acceleration"])
    >>> output_factor(two, np.array([2.0]))
    array([[ 0.+2.j, -4.+0.j]])
    """
    w = np.asarray(w, dtype=float)
    orders = getattr(model, "output_orders", None)
    if orders is None:
        return np.ones((w.size, model.n_outputs), dtype=complex)
    # exact columns, not (jω)**d: a complex power leaves an imaginary part of rounding on −ω²
    by_order = (np.ones(w.size, dtype=complex), 1j * w, -(w**2) + 0j)
    return np.stack([by_order[d] for d in orders], axis=1) if orders else np.ones((w.size, 0), dtype=complex)


def _warn_if_not_symmetric(matrices: dict[str, sp.Matrix]) -> None:
    """A ModelWarning naming the first pair of entries of M, V or K that is neither symmetric nor skew: a passive
    structure's are symmetric, a gyroscopic or electromechanical coupling (a DC motor's ±K) skew, and anything else
    is most often a typo (a new user's trial: ``-k3`` where ``-k4`` belonged, fitted without a word)."""
    for name in ("M", "V", "K"):
        mat = matrices[name]
        for i in range(mat.rows):
            for j in range(i + 1, mat.cols):
                # neither symmetric nor skew (a gyroscopic or electromechanical coupling, +K and −K, is skew)
                if sp.expand(mat[i, j] - mat[j, i]) != 0 and sp.expand(mat[i, j] + mat[j, i]) != 0:
                    warnings.warn(f"{name}[{i}, {j}] = {mat[i, j]} but {name}[{j}, {i}] = {mat[j, i]}: {name} is not "
                                  f"symmetric, as a passive structure's is, nor skew, as a gyroscopic coupling is (a "
                                  f"typo?); ignore this for follower forces or active control", ModelWarning,
                                  stacklevel=3)
                    return
