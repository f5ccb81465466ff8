"""Figures a person would rather look at than read: Bode plots and SCR convergence."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["bode_plot", "convergence_plot"]


def _pyplot():
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "png") and not _has_display():
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _has_display() -> bool:
    import os

    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def bode_plot(data: Any, estimates: Mapping[str, tuple[Any, Any]], path: str | Path, *,
              output: int = 0, input: int = 0, n_grid: int = 400, title: str | None = None) -> Path:
    """Bode magnitude and phase of measured data against model estimates, saved as PNG.

    Parameters
    ----------
    data : FrequencyData
        The measured points (drawn as markers).
    estimates : mapping of label to (model, theta)
        Curves drawn on a fine grid spanning the data band (one decade wider each side
        is not used: the grid spans the data band widened by 30% in log scale).
    path : str or pathlib.Path
        Where to write the PNG.
    output, input : int
        The channel drawn.

    Returns
    -------
    pathlib.Path
    """
    plt = _pyplot()
    w = np.asarray(data.w)
    H = np.asarray(data.H)[:, output, input]
    lo, hi = np.log10(max(w.min(), 1e-12)), np.log10(w.max())
    pad = 0.3 * max(hi - lo, 0.2)
    grid = np.logspace(lo - pad, hi + pad, n_grid)
    fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    styles = ["-", "--", ":", "-."]
    for k, (label, (model, theta)) in enumerate(estimates.items()):
        Hm = model.frequency_response(theta, grid)[:, output, input]
        ax_m.semilogx(grid, 20 * np.log10(np.abs(Hm)), styles[k % 4], lw=1.6, label=label)
        ax_p.semilogx(grid, np.degrees(np.unwrap(np.angle(Hm))), styles[k % 4], lw=1.6, label=label)
    ax_m.semilogx(w, 20 * np.log10(np.abs(H)), "ko", ms=5, mfc="none", label="data")
    ax_p.semilogx(w, np.degrees(np.unwrap(np.angle(H))), "ko", ms=5, mfc="none", label="data")
    ax_m.set_ylabel("magnitude (dB)")
    ax_p.set_ylabel("phase (deg)")
    ax_p.set_xlabel("ω (rad/s)")
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, which="both", alpha=0.3)
    ax_m.legend(loc="best", fontsize=8)
    ax_m.set_title(title or f"Bode plot, output {output}, input {input}")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def convergence_plot(groups: Mapping[str, Sequence[float]], path: str | Path, *, title: str | None = None,
                     ylabel: str = "constraint residual") -> Path:
    """Residual per constraint group against SCR iteration (log scale), as thesis Figure 3-2.

    Parameters
    ----------
    groups : mapping of label to sequence of float
        One curve per constraint group (e.g. per bilinear family), one value per iteration.
    path : str or pathlib.Path
        Where to write the PNG.

    Returns
    -------
    pathlib.Path
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for label, values in groups.items():
        v = np.asarray(values, dtype=float)
        v = np.where(v > 0, v, np.nan)
        ax.semilogy(np.arange(1, v.size + 1), v, lw=1.5, label=label)
    ax.set_xlabel("SCR iteration k")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or "SCR convergence per constraint group")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
