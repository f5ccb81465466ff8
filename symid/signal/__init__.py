"""Signals: simulation (:mod:`~symid.signal.simulate`), Welch spectra (:mod:`~symid.signal.spectra`),
N4SID (:mod:`~symid.signal.subspace`), exact zero-order-hold ``d2c`` (:mod:`~symid.signal.zoh`) and
balanced realisations (:mod:`~symid.signal.realisation`)."""
