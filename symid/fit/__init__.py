"""Estimation: one package per data kind on a shared estimator interface.

* :mod:`symid.fit.base` — the :class:`~symid.fit.base.Estimator` interface, the SCR
  estimator base, the option vocabulary; :mod:`symid.fit.options` checks option values.
* :mod:`symid.fit.frf`, :mod:`symid.fit.spectra`, :mod:`symid.fit.similarity` — each data
  kind: its data check, its misfit, its methods.
* :mod:`symid.fit.registry` — data type → package; :func:`symid.identify`
  (:mod:`symid.fit.identify`) and :func:`symid.compare` (:mod:`symid.fit.compare`)
  dispatch through it.
* :mod:`symid.fit.result`, :mod:`symid.fit.success`, :mod:`symid.fit.starts`,
  :mod:`symid.fit.polish` — what every method shares.

Import rules: a data-kind package imports :mod:`symid.fit` shared modules, the engines
and the model and data layers, never another data-kind package's private names; the
engines (:mod:`symid.engine`) import nothing from :mod:`symid.fit`.
"""
