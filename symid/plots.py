"""Figures a person would rather look at than read: Bode plots and SCR convergence."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["bode_plot", "convergence_plot", "frf_estimate_plot", "start_convergence_plot"]


def _pyplot():
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "png") and not _has_display():
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _has_display() -> bool:
    import os

    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _escape(text: str) -> str:
    """A label shown as written: ``$`` would start matplotlib's math mode."""
    return text.replace("$", r"\$")


def _log_axis(ax: Any) -> None:
    """Plain numbers (0.4, 2, 50) on a log frequency axis instead of 4×10⁻¹; minor labels at 2 and 5 over
    narrow spans."""
    from matplotlib.ticker import FuncFormatter, LogLocator

    lo, hi = ax.get_xlim()
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    if hi / lo < 100:
        ax.xaxis.set_minor_locator(LogLocator(subs=(2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0)))
        lead = (2, 5) if hi / lo > 10 else (2, 3, 4, 5, 6, 7, 8, 9)
        ax.xaxis.set_minor_formatter(FuncFormatter(
            lambda x, _: f"{x:g}" if round(x / 10 ** np.floor(np.log10(x))) in lead else ""))


# Curves drawn on top of one another stay visible: the first is a wide, pale band, each later one
# thinner and dashed differently, so a curve hidden under another still shows at its edges and gaps.
_CURVE_STYLES = [dict(lw=5.0, alpha=0.35, ls="-"), dict(lw=2.2, ls="-"), dict(lw=1.6, ls=(0, (5, 3))),
                 dict(lw=1.4, ls=(0, (1, 2))), dict(lw=1.4, ls=(0, (6, 2, 1, 2)))]


def bode_plot(data: Any, estimates: Mapping[str, tuple[Any, Any]], path: str | Path, *,
              output: int = 0, input: int = 0, n_grid: int = 400, title: str | None = None,
              h_unit: str | None = None, reference: str | None = None, hz: bool = False) -> Path:
    """Bode magnitude and phase of measured data against model estimates, saved as PNG.

    Parameters
    ----------
    data : FrequencyData
        The measured points (drawn as markers).
    estimates : mapping of label to (model, theta)
        Curves drawn on a fine grid spanning the data band widened by 30 % in log scale,
        each in its own colour and dash pattern, so curves that coincide all stay visible.
    path : str or pathlib.Path
        Where to write the PNG.
    output, input : int
        The channel drawn.
    n_grid : int
        Points of the model curves.
    title : str, optional
    h_unit : str, optional
        The physical unit of H (output unit per input unit, e.g. ``"m/N"``): the magnitude
        axis reads "|H| (dB re 1 m/N)". Without it the axis says the unit is not given.
    reference : str, optional
        The label of a curve to draw as a wide pale band under the others (e.g. the truth).
    hz : bool
        Frequency axis in Hz (as the data were given) instead of rad/s.

    Returns
    -------
    pathlib.Path

    Notes
    -----
    Each measured phase is drawn at the turn (a multiple of 360°) nearest to the reference curve's (the
    ``reference`` estimate, else the first), whose phase is unwrapped along the fine grid: unwrapping the
    measured points themselves put a good fit 360° off, and noisy lines at ±900° (a new user's motor).
    """
    plt = _pyplot()
    w = np.asarray(data.w)
    H = np.asarray(data.H)[:, output, input]
    lo, hi = np.log10(max(w.min(), 1e-12)), np.log10(w.max())
    pad = 0.3 * max(hi - lo, 0.2)
    grid = np.logspace(lo - pad, hi + pad, n_grid)
    fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 6.2))
    x = 1 / (2 * np.pi) if hz else 1.0
    k = 0
    ref_phase = None
    for label, (model, theta) in sorted(estimates.items(), key=lambda item: item[0] != reference):
        Hm = model.frequency_response(theta, grid)[:, output, input]
        if label == reference:
            style = _CURVE_STYLES[0]
        else:
            k += 1
            style = _CURVE_STYLES[1 + (k - 1) % (len(_CURVE_STYLES) - 1)]
        phase = np.unwrap(np.angle(Hm))
        if ref_phase is None and np.all(np.isfinite(phase)):
            ref_phase = phase
        line, = ax_m.semilogx(grid * x, 20 * np.log10(np.abs(Hm)), label=_escape(label), **style)
        ax_p.semilogx(grid * x, np.degrees(phase), color=line.get_color(), **style)
    measured = _measured_phase(w, H, grid, ref_phase)
    ax_m.semilogx(w * x, 20 * np.log10(np.abs(H)), "ko", ms=5, mfc="none", label="data", zorder=5)
    ax_p.semilogx(w * x, np.degrees(measured), "ko", ms=5, mfc="none", zorder=5)
    unit = f"dB re 1 {_escape(h_unit)}" if h_unit else "dB; unit of H not given"
    ax_m.set_ylabel(f"magnitude |H| ({unit})")
    ax_p.set_ylabel("phase ∠H (degrees)")
    ax_p.set_xlabel("frequency f (Hz)" if hz else "angular frequency ω (rad/s)")
    for ax in (ax_m, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    _log_axis(ax_p)
    ax_m.legend(loc="best", fontsize=8, framealpha=0.9)
    suffix = "" if np.asarray(data.H).shape[1:] == (1, 1) else f" (output {output}, input {input})"
    ax_m.set_title(_escape(title or "Bode plot") + suffix, fontsize=11)
    fig.tight_layout()
    return _save(fig, path, dpi=110)


def _measured_phase(w: np.ndarray, H: np.ndarray, grid: np.ndarray, ref_phase: np.ndarray | None) -> np.ndarray:
    """The measured phases (rad), each at the turn nearest the reference curve's unwrapped phase on ``grid`` (the
    measured points unwrapped among themselves without one).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.plots import _measured_phase
    >>> grid = np.array([1.0, 10.0])
    >>> H = np.exp(1j * np.array([0.9 * np.pi, -0.9 * np.pi]))   # 162° and −162°: both near −180° and 180°
    >>> np.degrees(_measured_phase(np.array([1.0, 10.0]), H, grid, np.array([-np.pi, -np.pi]))).round(1).tolist()
    [-198.0, -162.0]
    """
    if ref_phase is None:
        return np.unwrap(np.angle(H))
    near = np.interp(np.log(w), np.log(grid), ref_phase)
    return near + np.angle(H * np.exp(-1j * near))


def convergence_plot(groups: Mapping[str, Sequence[float]], path: str | Path, *, title: str | None = None,
                     ylabel: str = "residual per family, ‖A P B − C‖_F", total: bool = True,
                     error: Sequence[float] | None = None, error_label: str = "‖θ_k − θ*‖₂") -> Path:
    """Residual per constraint group against SCR iteration (log scale), as thesis Figure 3-2.

    Parameters
    ----------
    groups : mapping of label to sequence of float
        One curve per constraint group (e.g. the families f1…f4 of (3-15)), one value
        per iteration: the summed residual of the group's equations.
    path : str or pathlib.Path
        Where to write the PNG.
    title, ylabel : str, optional
        Figure title and y-axis label of the residuals.
    total : bool
        Also draw the sum over the groups, as the thesis's "total" curve: a wide pale
        band under the groups, so a group that carries nearly all of it stays visible.
    error : sequence of float, optional
        Parameter error per iteration (e.g. ‖θ_k − θ*‖₂ when the truth is known), drawn
        in a panel of its own below, with its own axis label.
    error_label : str
        Axis label and legend entry of ``error``.

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from symid.plots import convergence_plot
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "conv.png"
    >>> convergence_plot({"f1": [1.0, 0.1, 1e-3], "f2": [0.5, 0.05, 1e-4]}, out, error=[1.0, 0.2, 1e-3]).is_file()
    True
    """
    plt = _pyplot()
    if error is None:
        fig, ax = plt.subplots(figsize=(8, 4.8))
        ax_e = None
    else:
        fig, (ax, ax_e) = plt.subplots(2, 1, sharex=True, figsize=(8, 6.6), height_ratios=(2, 1))
    curves = {label: np.asarray(v, dtype=float) for label, v in groups.items()}
    if total and len(curves) > 1:
        ax.semilogy(np.arange(1, len(next(iter(curves.values()))) + 1), _positive(sum(curves.values())),
                    color="0.5", lw=6, alpha=0.35, label="total (sum of the families)")
    styles = _CURVE_STYLES[1:]
    for k, (label, v) in enumerate(curves.items()):
        note = "  (≡ 0: exact)" if not np.any(v > 0) else ""  # e.g. equations that presolve made linear
        ax.semilogy(np.arange(1, v.size + 1), _positive(v), label=_escape(label) + note, **styles[k % len(styles)])
    ax.set_ylabel(ylabel)
    ax.grid(True, which="major", alpha=0.4)
    ax.grid(True, which="minor", alpha=0.12)
    ax.legend(loc="best", fontsize=8.5, framealpha=0.9)
    ax.set_title(_escape(title or "SCR convergence per constraint family"), fontsize=11)
    bottom = ax
    if ax_e is not None:
        e = np.asarray(error, dtype=float)
        ax_e.semilogy(np.arange(1, e.size + 1), _positive(e), "k-", lw=1.5, label=_escape(error_label))
        ax_e.set_ylabel(f"parameter error\n{_escape(error_label)}")
        ax_e.grid(True, which="major", alpha=0.4)
        ax_e.grid(True, which="minor", alpha=0.12)
        bottom = ax_e
    bottom.set_xlabel("SCR iteration k")
    fig.tight_layout()
    return _save(fig, path, dpi=120)


def _save(fig: Any, path: str | Path, dpi: int) -> Path:
    """Save and close ``fig``; the file appears whole or not at all (written beside it, then renamed)."""
    from symid.runlog import write_atomic

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        with write_atomic(path, "wb") as fh:
            fig.savefig(fh, dpi=dpi, format=path.suffix.lstrip(".").lower() or "png")
    finally:
        _pyplot().close(fig)
    return path


def _positive(v: np.ndarray) -> np.ndarray:
    """Values for a log axis: non-positive ones are not drawn."""
    return np.where(v > 0, v, np.nan)


def start_convergence_plot(outcome: Any, path: str | Path, *, truth: Any = None, title: str | None = None) -> Path:
    """Figure 3-2 for one start of an SCR run: residual per constraint family per iteration.

    Parameters
    ----------
    outcome : StartOutcome
        A start of an SCR result (``result.best_start``); its ``history`` holds, per
        iteration, the family residuals and θ.
    path : str or pathlib.Path
        Where to write the PNG.
    truth : array_like, optional
        True parameter vector; adds ‖θ_k − θ*‖₂.
    title : str, optional

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import symid as si
    >>> from symid.plots import start_convergence_plot
    >>> entry = si.load_model("mass_damper_2dof")
    >>> res = si.identify(entry.model, entry.data(), method="scr", seed=1, max_iter=5, identifiability_check=False)
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "conv.png"
    >>> start_convergence_plot(res.best_start, out).is_file()
    True
    """
    hist = outcome.history
    if not hist or not hist[0].families:
        raise ValueError("this start has no per-family history (only SCR runs on a frequency response keep one)")
    groups = {f: [h.families[f] for h in hist] for f in hist[0].families}
    error = None
    if truth is not None:
        t = np.asarray(truth, dtype=float)
        error = [float(np.linalg.norm(np.asarray(h.theta) - t)) for h in hist]
    return convergence_plot(groups, path, error=error, error_label="‖θ_k − θ*‖₂",
                            title=title or f"SCR convergence from θ0 = {np.array2string(outcome.start, precision=2)}")


def frf_estimate_plot(frf: Any, path: str | Path, *, coherence: Any = None, output: int = 0, input: int = 0,
                      confidence: float = 0.95, hz: bool = True, unit: str | None = None,
                      estimates: Mapping[str, tuple[Any, Any]] | None = None, title: str | None = None) -> Path:
    """An estimated frequency response: |H| with its confidence band, the phase and the coherence, saved as PNG.

    Parameters
    ----------
    frf : FrequencyData
        The estimate, e.g. from :func:`symid.estimate_frf`; with a ``variance`` the band
        |Ĥ| ± z·σ/√2 is shaded (σ² = the entry's variance, half of it in the direction
        of Ĥ for circular noise; z the normal quantile of ``confidence``) and the noise
        level σ drawn dotted.
    path : str or pathlib.Path
        Where to write the PNG.
    coherence : array_like, shape (s,) or (s, p), optional
        The coherence at ``frf.w`` (:func:`symid.estimate_coherence`), drawn in a third panel.
    output, input : int
        The entry drawn.
    confidence : float
        Level of the shaded band (default 0.95).
    hz : bool
        Frequency axis in Hz (default) or in rad/s.
    unit : str, optional
        The unit of H for the axis label, e.g. ``"(m/s²)/N"``.
    estimates : mapping of label to (model, theta), optional
        Model responses drawn over the data on a fine grid of the data's band.
    title : str, optional

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.plots import frf_estimate_plot
    >>> w = np.linspace(1.0, 10.0, 50)
    >>> frf = si.FrequencyData(w, 1 / (5 - 0.05 * w**2 + 0.1j * w), variance=np.full(50, 1e-4))
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "frf.png"
    >>> frf_estimate_plot(frf, out, coherence=np.full(50, 0.99)).is_file()
    True
    """
    from scipy.stats import norm

    plt = _pyplot()
    w = np.asarray(frf.w, dtype=float)
    H = np.asarray(frf.H)[:, output, input]
    scale = 1 / (2 * np.pi) if hz else 1.0
    x = w * scale
    coh = None
    if coherence is not None:
        coh = np.asarray(coherence, dtype=float)
        coh = coh[:, output] if coh.ndim == 2 else coh
        if coh.shape != w.shape:
            raise ValueError(f"coherence must have one value per frequency of frf ({w.size}); got shape {coh.shape}")
    rows = 3 if coh is not None else 2
    fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(8, 2.6 * rows + 0.6),
                             gridspec_kw={"height_ratios": [2.2, 1.2, 1.0][:rows]})
    ax_m, ax_p = axes[0], axes[1]
    mag = np.abs(H)
    log_x = x[-1] / x[0] > 20
    plot = ax_m.loglog if log_x else ax_m.semilogy
    plot(x, mag, "k.-", ms=3, lw=0.8, label="estimate |Ĥ|")
    if frf.variance is not None:
        sigma = np.sqrt(np.asarray(frf.variance)[:, output, input])
        z = float(norm.ppf(0.5 + confidence / 2))
        half = z * sigma / np.sqrt(2)
        lo = np.where(mag - half > 0, mag - half, np.nan)
        ax_m.fill_between(x, lo, mag + half, color="tab:blue", alpha=0.3, lw=0,
                          label=f"{100 * confidence:g} % confidence band")
        plot(x, _positive(sigma), ":", color="tab:red", lw=1.2, label="noise std σ")
    ax_p.plot(x, np.degrees(np.unwrap(np.angle(H))), "k.-", ms=3, lw=0.8, label="estimate")
    if estimates:
        grid = np.geomspace(w[0], w[-1], 800) if log_x else np.linspace(w[0], w[-1], 800)
        for k, (label, (model, theta)) in enumerate(estimates.items()):
            Hm = model.frequency_response(theta, grid)[:, output, input]
            style = ["-", "--", "-.", ":"][k % 4]
            ax_m.plot(grid * scale, np.abs(Hm), style, lw=1.5, label=label)
            ax_p.plot(grid * scale, np.degrees(np.unwrap(np.angle(Hm))), style, lw=1.5, label=label)
    if log_x:
        ax_p.set_xscale("log")
    ax_m.set_ylabel(f"|H| {unit}" if unit else "|H|")
    ax_p.set_ylabel("phase (deg)")
    ax_m.legend(loc="best", fontsize=8)
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    if coh is not None:
        ax_c = axes[2]
        ax_c.plot(x, coh, "g.-", ms=3, lw=0.8)
        ax_c.set_ylim(-0.02, 1.02)
        ax_c.set_ylabel("coherence γ²")
    axes[-1].set_xlabel("frequency (Hz)" if hz else "ω (rad/s)")
    ax_m.set_title(title or f"Estimated frequency response, output {output}, input {input}")
    fig.tight_layout()
    return _save(fig, path, dpi=110)
