"""The table of every method's options and defaults, per data kind, read from the estimators themselves.

Each estimator's options are the keyword-only arguments of its ``__init__`` and their
meaning is its numpydoc ``Parameters`` section, so this table cannot drift from the code.
"""

from __future__ import annotations

import inspect
import re

__all__ = ["estimator_classes", "options_table"]


def estimator_classes() -> list[tuple[str, str, type]]:
    """(data kind, method, estimator class) for every estimator symid has.

    Examples
    --------
    >>> from symid.fit.catalog import estimator_classes
    >>> [(k, m) for k, m, _ in estimator_classes()][:3]
    [('frequency response', 'auto'), ('frequency response', 'lm'), ('frequency response', 'scr')]
    """
    from symid.fit.frf.ipopt import IpoptFRF
    from symid.fit.frf.lm import AutoFRF, LmFRF
    from symid.fit.frf.ls import LinearFRF
    from symid.fit.frf.scr import ScrFRF
    from symid.fit.similarity.als import AlsSimilarity
    from symid.fit.similarity.gb import GbSimilarity
    from symid.fit.similarity.ipopt import IpoptSimilarity, IpoptSimilarityFRF
    from symid.fit.similarity.scr import ScrSimilarity
    from symid.fit.similarity.second_order import LinearSimilarity2nd, ScrSimilarity2nd
    from symid.fit.spectra.auto import AutoPSD
    from symid.fit.spectra.ipopt import IpoptPSD
    from symid.fit.spectra.scr import ScrPSD
    from symid.fit.timeseries.auto import AutoOutputError
    from symid.fit.timeseries.oe import OutputError
    from symid.fit.timeseries.srivc import SimplifiedRIVC
    from symid.fit.timeseries.svf import StateVariableFilter

    frf, spec, bb = "frequency response", "spectra", "black box / I/O"
    return [(frf, "auto", AutoFRF), (frf, "lm", LmFRF), (frf, "scr", ScrFRF), (frf, "ipopt", IpoptFRF),
            (frf, "ls", LinearFRF),
            (spec, "auto", AutoPSD), (spec, "scr", ScrPSD), (spec, "ipopt", IpoptPSD),
            ("time series", "auto", AutoOutputError),
            ("time series", "oe", OutputError),
            ("time series", "svf", StateVariableFilter), ("time series", "srivc", SimplifiedRIVC),
            (bb, "scr (state space)", ScrSimilarity), (bb, "als", AlsSimilarity), (bb, "gb", GbSimilarity),
            (bb, "ipopt (state space)", IpoptSimilarity), (bb, "scr (second order)", ScrSimilarity2nd),
            (bb, "ls (second order)", LinearSimilarity2nd), (bb, "ipopt (second order)", IpoptSimilarityFRF)]


def _meaning(doc: str, name: str) -> str:
    """The first sentence of the description of ``name`` in a numpydoc Parameters section."""
    lines = doc.splitlines()
    for k, line in enumerate(lines):
        head = line.strip().split(" : ")[0]
        if line.startswith("    ") and not line.startswith("     ") and name in [h.strip() for h in head.split(",")]:
            body = []
            for nxt in lines[k + 1:]:
                if not nxt.startswith("        "):
                    break
                body.append(nxt.strip())
            text = " ".join(body)
            text = re.sub(r":(?:func|class|meth|mod):`~?([^`]+)`", r"\1", text).replace("``", "`")
            sentence = re.split(r"(?<=\.)\s", text, maxsplit=1)[0]
            if len(sentence) > 160:
                sentence = sentence[:157].rsplit(" ", 1)[0] + " …"
            return sentence.replace("|", "\\|")
    return ""


def options_table() -> str:
    """A Markdown table: data kind, method, option, default, meaning (first sentence of its docstring).

    Examples
    --------
    >>> from symid.fit.catalog import options_table
    >>> print(options_table().splitlines()[0])
    | data | method | option | default | meaning |
    """
    lines = ["| data | method | option | default | meaning |", "|---|---|---|---|---|"]
    for kind, method, cls in estimator_classes():
        doc = cls.__doc__ or ""
        for p in inspect.signature(cls.__init__).parameters.values():
            if p.kind is not inspect.Parameter.KEYWORD_ONLY:
                continue
            default = "—" if p.default is inspect.Parameter.empty else f"`{p.default!r}`"
            lines.append(f"| {kind} | {method} | `{p.name}` | {default} | {_meaning(doc, p.name)} |")
    return "\n".join(lines) + "\n"
