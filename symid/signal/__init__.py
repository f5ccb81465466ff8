"""Signals: simulation (:mod:`~symid.signal.simulate`), Welch spectra (:mod:`~symid.signal.spectra`),
frequency responses from records with their noise (:mod:`~symid.signal.frf`), N4SID
(:mod:`~symid.signal.subspace`), exact zero-order-hold ``d2c`` (:mod:`~symid.signal.zoh`) and
balanced realisations (:mod:`~symid.signal.realisation`)."""
