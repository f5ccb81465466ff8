"""Symbolic models: parameters, exact affine maps, state-space and second-order models.

* :mod:`symid.model.symbols` — :func:`~symid.model.symbols.parameters` and safe parsing of matrix entries;
* :mod:`symid.model.affine` — exact affine maps X(θ) = X0 + Σ θi Xi;
* :mod:`symid.model.parametric` — the base of the model classes;
* :mod:`symid.model.statespace`, :mod:`symid.model.secondorder` — the two model kinds;
* :mod:`symid.model.lti` — numeric helpers (frequencies, H(ω)) without sympy, for the data layer.

Nothing is imported here, so the data layer can use :mod:`symid.model.lti` without
loading the symbolic modules.
"""
