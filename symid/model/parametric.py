"""Shared machinery of the symbolic model classes: parameter order, θ handling, affine maps."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError, did_you_mean
from symid.model.affine import AffineMap, affine_map, order_parameters

__all__ = ["ParametricModel", "Theta"]

Theta = Mapping[str, float] | Mapping[sp.Symbol, float] | Sequence[float] | np.ndarray




def _unify_symbols(mats: list[tuple[str, sp.Matrix]]) -> list[tuple[str, sp.Matrix]]:
    """Merge symbols that share a name (e.g. one parsed from a string, one from parameters())."""
    by_name: dict[str, list[sp.Symbol]] = {}
    for _, m in mats:
        for s in m.free_symbols:
            by_name.setdefault(s.name, [])
            if s not in by_name[s.name]:
                by_name[s.name].append(s)
    repl = {}
    for syms in by_name.values():
        if len(syms) > 1:
            keep = next((s for s in syms if s.is_positive), None) or next((s for s in syms if s.is_real), syms[0])
            for s in syms:
                if s != keep:
                    repl[s] = keep
    if not repl:
        return mats
    return [(n, m.xreplace(repl)) for n, m in mats]



def pretty(expr: Any) -> str:
    """``expr`` drawn as sympy's pretty printer draws it, each parameter under its own name (sympy writes ``mu`` as
    μ and ``lambda_1`` as λ₁: not the names the user gave, nor those ``parameter_names`` lists).

    Examples
    --------
    >>> import sympy as sp
    >>> from symid.model.parametric import pretty
    >>> print(pretty(sp.Matrix([[sp.Symbol("mu")]])))
    [mu]
    """
    from sympy.printing.pretty.pretty import PrettyPrinter
    from sympy.printing.pretty.stringpict import prettyForm

    class _Names(PrettyPrinter):
        def _print_Symbol(self, e: sp.Symbol, bold_name: bool = False) -> prettyForm:
            return prettyForm(e.name)

    return _Names({"use_unicode": True}).doprint(expr)

class ParametricModel:
    """Base class: named symbolic matrices, their affine maps and the parameter vector θ.

    Subclasses call :meth:`_setup` with their matrices in signature order.
    """

    _kind = "model"

    def _setup(self, matrices: list[tuple[str, sp.Matrix]], parameters: Sequence[Any] | None,
               name: str | None) -> None:
        matrices = _unify_symbols(matrices)
        found = order_parameters(matrices)
        if parameters is None:
            params = found
        else:
            if isinstance(parameters, str):  # "b a" or "b, a", as si.parameters() takes names
                parameters = parameters.replace(",", " ").split()
            params = []
            by_name = {s.name: s for s in found}
            for p in parameters:
                pname = p.name if isinstance(p, sp.Symbol) else str(p)
                if pname not in by_name:
                    raise ModelError(f"parameter {pname!r} given in parameters= does not appear in any matrix")
                params.append(by_name[pname])
            if len({p.name for p in params}) != len(params):
                raise ModelError("parameters= lists a parameter twice")
            missing = [s.name for s in found if s not in params]
            if missing:
                raise ModelError(f"symbols {', '.join(missing)} appear in the matrices but not in parameters=")
            params = tuple(params)
        for p in params:
            if p.is_real is False or (p.is_complex and not p.is_real):
                raise ModelError(f"parameter {p} is declared non-real; symid parameters are real")
        self._parameters: tuple[sp.Symbol, ...] = tuple(params)
        self._symbolic: dict[str, sp.Matrix] = dict(matrices)
        self._maps: dict[str, AffineMap] = {n: affine_map(m, self._parameters, n) for n, m in matrices}
        self.name = name
        #: The units of the inputs and outputs, ``{"input": (...), "output": (...)}``, as a model file declares them
        #: (``input_units``, ``output_units``; set by :func:`symid.load_model`), else ``{}``. symid converts
        #: nothing by them: :func:`symid.identify` compares them with the units a data file states.
        self.io_units: dict[str, tuple[str, ...]] = {}

    # -- parameters ---------------------------------------------------------------
    @property
    def parameters(self) -> tuple[sp.Symbol, ...]:
        """The parameter symbols, in the order of θ."""
        return self._parameters

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The parameter names, in the order of θ."""
        return tuple(p.name for p in self._parameters)

    @property
    def n_parameters(self) -> int:
        """Number of unknown parameters."""
        return len(self._parameters)

    @property
    def positive(self) -> tuple[bool, ...]:
        """Per parameter, whether it was declared positive."""
        return tuple(bool(p.is_positive) for p in self._parameters)

    @property
    def maps(self) -> dict[str, AffineMap]:
        """The affine map of every matrix, by matrix name."""
        return dict(self._maps)

    @property
    def symbolic(self) -> dict[str, sp.Matrix]:
        """The symbolic matrices, by matrix name."""
        return {k: sp.Matrix(v) for k, v in self._symbolic.items()}

    def theta_vector(self, theta: Theta) -> np.ndarray:
        """Convert θ given as a dict (by name or symbol) or a sequence to a float vector.

        Parameters
        ----------
        theta : dict or sequence of float
            A dict keyed by parameter name (or sympy symbol) holding every parameter,
            or a sequence of values in ``parameter_names`` order.

        Returns
        -------
        numpy.ndarray
            θ as floats, shape (n_parameters,), in ``parameter_names`` order.

        Raises
        ------
        ModelError
            On a missing or unknown name, a wrong length, or a non-finite value.

        Examples
        --------
        >>> import symid as si
        >>> k, m = si.parameters("k m", positive=True)
        >>> model = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]])
        >>> model.parameter_names
        ('m', 'k')
        >>> model.theta_vector({"k": 4.0, "m": 2.0})
        array([2., 4.])
        """
        names = self.parameter_names
        if theta is None:
            raise ModelError(f"theta is required: a dict by name or a sequence of {len(names)} value(s) "
                             f"({', '.join(names)})")
        if isinstance(theta, Mapping):
            given = {(k.name if isinstance(k, sp.Symbol) else str(k)): v for k, v in theta.items()}
            unknown = sorted(set(given) - set(names))
            missing = [n for n in names if n not in given]
            if unknown:
                fixed = getattr(self, "_known_values", {})
                held = [n for n in unknown if n in fixed]
                if held:  # a value the user fixed with with_known: say so, not "unknown"
                    raise ModelError(f"theta gives {', '.join(held)}, whose value is known in this model "
                                     f"(with_known: {', '.join(f'{n} = {fixed[n]:g}' for n in held)}); leave it out: "
                                     f"the model's parameters are {', '.join(names) or 'none'}")
                raise ModelError(f"theta names unknown parameter(s) {', '.join(unknown)}"
                                 f"{did_you_mean(unknown, names)}; the model's parameters are "
                                 f"{', '.join(names) or 'none'}")
            if missing:
                raise ModelError(f"theta is missing parameter(s) {', '.join(missing)}")
            vals = [given[n] for n in names]
        else:
            if isinstance(theta, (str, bytes)):
                hint = ("; the initial state is estimated with initial_state=\"estimate\" (identify's x0 is the "
                        "start of the parameters)" if str(theta).strip().lower() == "estimate" else "")
                raise ModelError(f"theta is the text {theta!r}; give a dict by name or a sequence of {len(names)} "
                                 f"number(s) ({', '.join(names)}){hint}")
            if hasattr(theta, "theta") and hasattr(theta, "parameter_names"):  # a result where its estimate belongs
                raise ModelError(f"theta is an {type(theta).__name__}, not parameter values: pass its estimate "
                                 f"(result.theta, or result.polished.theta for the polished one)")
            vals = list(np.asarray(theta, dtype=object).reshape(-1)) if np.ndim(theta) else [theta]
            if len(vals) != len(names):
                raise ModelError(f"theta has {len(vals)} value(s); the model has {len(names)} parameter(s) "
                                 f"({', '.join(names)})")
        try:
            vec = np.array([float(v) for v in vals], dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"theta values must be real numbers; got {vals!r}") from None
        bad = [names[i] for i in np.flatnonzero(~np.isfinite(vec))]
        if bad:
            raise ModelError(f"theta is not finite for {', '.join(bad)}")
        return vec

    @property
    def known_values(self) -> dict[str, float]:
        """The values :meth:`with_known` fixed, by name (empty for a model whose parameters are all its own).

        Examples
        --------
        >>> import symid as si
        >>> m, c, k = si.parameters("m c k", positive=True)
        >>> si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]]).with_known({"m": 2.0}).known_values
        {'m': 2.0}
        """
        return dict(getattr(self, "_known_values", {}))

    def theta_dict(self, theta: Theta) -> dict[str, float]:
        """θ as a dict by parameter name."""
        return dict(zip(self.parameter_names, self.theta_vector(theta).tolist(), strict=True))

    def matrices(self, theta: Theta) -> dict[str, np.ndarray]:
        """Numeric value of every matrix at θ, by matrix name.

        Parameters
        ----------
        theta : dict or sequence of float
            Parameter values (see :meth:`theta_vector`).

        Returns
        -------
        dict of str to numpy.ndarray
            ``{"A": ..., "B": ..., "C": ..., "D": ...}`` or ``{"M": ..., "V": ..., "K": ...,
            "B": ..., "C": ...}``, each X(θ) = X0 + Σ θi Xi as floats.
        """
        vec = self.theta_vector(theta)
        return {n: m(vec) for n, m in self._maps.items()}

    def with_known(self, known: Mapping[str, float]) -> Any:
        """The same model with the parameters whose values are known replaced by those numbers.

        Parameters
        ----------
        known : dict of str to float
            Parameter name → value (finite); the other parameters stay free, in their order.

        Returns
        -------
        StateSpaceModel or SecondOrderModel
            A new model of the same class (this model when ``known`` is empty).

        Raises
        ------
        ModelError
            On a name that is not a parameter, or a value that is not a finite number.

        Examples
        --------
        >>> import symid as si
        >>> m, c, k = si.parameters("m c k", positive=True)
        >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
        >>> model.with_known({"m": 2.0}).parameter_names
        ('c', 'k')
        """
        from symid.modelfile import substitute_known

        out = substitute_known(self, known)
        if out is not self:  # remembered, so that a θ still giving them is told they are known (theta_vector)
            out._known_values = {**getattr(self, "_known_values", {}),
                                 **{(k.name if isinstance(k, sp.Symbol) else str(k)): float(v)
                                    for k, v in known.items()}}
        return out

    def _matrix_text(self) -> str:
        lines = []
        for n, m in self._symbolic.items():
            lines.append(f"{n} =")
            lines.append(pretty(m))
        return "\n".join(lines)

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return (f"<{type(self).__name__}{label}: {self._shape_text()}, "
                f"parameters ({', '.join(self.parameter_names)})>")

    def _shape_text(self) -> str:  # pragma: no cover - overridden
        return ""
