"""``si.validate``: does a model with these parameters reproduce measured time series?

The model is simulated on each record's sample times from its initial state (exactly,
zero-order-hold input; :class:`~symid.fit.timeseries.oe.OutputError`) and compared with
the measured output, as MATLAB's ``compare`` and ``resid`` do (Ljung, *System
Identification*, 2nd ed., §16.6):

- **fit** per output, the normalised root-mean-square fit
  ``100 (1 − ‖y − ŷ‖ / ‖y − mean(y)‖)`` % (100 % is perfect, 0 % no better than the
  mean, negative worse), and the rms error in data units;
- **residual whiteness**: the normalised autocorrelation ρₑ(τ), τ = 1 … M, of the
  residual ε = y − ŷ (means removed), with the band ±z/√N that a white residual stays in
  (z = 2.58 for 99 %), and the Ljung–Box statistic Q = N(N+2) Σ ρₑ(τ)²/(N − τ),
  χ²(M) for a white residual;
- **input–residual independence**: the normalised cross-correlation ρₑᵤ(τ) of ε(t) with
  u(t − τ), τ = −M … M, with the band ±z √(Σₖ ρₑ(k) ρᵤ(k) / N) (Ljung (16.60); ±z/√N when
  ε is white), and S = N ρᵀ Γ⁺ ρ over ρ = ρₑᵤ(0 … M), where Γ[τ, τ′] = Σₖ ρₑ(k) ρᵤ(k + τ − τ′)
  (k = −M … M) is the covariance of √N ρ when ε is independent of the inputs, and Γ⁺ its
  pseudo-inverse: χ²(rank Γ) then. The lags of a slowly varying input are correlated
  with each other; summing their squares as if they were not (S = N Σ ρₑᵤ(τ)² / P, the
  diagonal of Γ) rejected the true model of a new user's thermal network in 10 of 20
  records, its heater power held for 60 samples at a time, where every lag lay inside its
  band. Correlation at τ < 0 (ε ahead of u) is what feedback produces, and is shown, not
  tested.

Correlations use sample lags, pooled over the records; for non-uniform sample times
they are lags in samples (said in ``notes``). A constant input (an offset) has no
cross-correlation.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symid.errors import DataError, DataWarning

__all__ = ["DEFAULT_MAX_LAG", "Validation", "independence_pvalues", "validate"]

DEFAULT_MAX_LAG = 25  # correlation lags of the residual tests, MATLAB's resid; a quarter of a shorter record

_Z = {0.95: 1.959963984540054, 0.99: 2.5758293035489004}
FINE_BELOW = 500  # records with fewer samples get the simulated output between them too (``t_fine``, ``y_fine``)
FINE_POINTS = 2000  # about as many points on that grid per record
MARKERS_BELOW = 200  # records with fewer samples are drawn as markers, not joined by lines


@dataclass(frozen=True)
class Validation:
    """The comparison of a model's simulated output with measured records (:func:`validate`).

    Attributes
    ----------
    parameter_names : tuple of str
    theta : numpy.ndarray
        The parameters validated.
    fit_percent : numpy.ndarray
        (p,) normalised rms fit per output, % (MATLAB ``compare``).
    rms_error : numpy.ndarray
        (p,) rms of y − ŷ per output, data units.
    t, u, y, y_sim : tuple of numpy.ndarray
        Per record: times, inputs, measured and simulated outputs.
    initial_states : tuple of numpy.ndarray
        The initial state each record was simulated from.
    lags : numpy.ndarray
        0 … M (sample lags).
    autocorrelation : numpy.ndarray
        (p, M + 1) normalised autocorrelation of the residual (1 at lag 0).
    auto_band : float
        Half-width of the confidence band of a white residual, z/√N.
    whiteness_q : numpy.ndarray
        (p,) Ljung–Box statistic; ``whiteness_p`` its p-value under χ²(M).
    cross_lags : numpy.ndarray
        −M … M.
    cross_correlation : numpy.ndarray
        (p, m, 2M + 1) normalised cross-correlation of residual and input (NaN for a constant input).
    cross_band : numpy.ndarray
        (p, m) half-widths of its confidence band.
    independence_s : numpy.ndarray
        (p, m) statistic S over τ = 0 … M (module notes); ``independence_p`` its p-value
        under χ²(rank Γ), M + 1 unless the input's lags are linearly dependent.
    confidence : float
        Level of the bands and tests (0.99 default).
    notes : tuple of str
        What the reader should know (non-uniform sampling, constant inputs ...).
    time_unit : str
    t_fine, y_fine : tuple of numpy.ndarray
        Per record with fewer than ``FINE_BELOW`` samples, the simulated output on a grid
        about ``FINE_POINTS`` long that holds the sample times and even steps between them
        (the input held or linear between samples, as simulated): the curve between
        sparse samples (a concentration's peak between two draws). Empty arrays for longer
        records and for ``hold="bandlimited"``.
    """

    parameter_names: tuple[str, ...]
    theta: np.ndarray
    fit_percent: np.ndarray
    rms_error: np.ndarray
    t: tuple[np.ndarray, ...] = field(repr=False)
    u: tuple[np.ndarray, ...] = field(repr=False)
    y: tuple[np.ndarray, ...] = field(repr=False)
    y_sim: tuple[np.ndarray, ...] = field(repr=False)
    initial_states: tuple[np.ndarray, ...] = field(repr=False)
    lags: np.ndarray = field(repr=False)
    autocorrelation: np.ndarray = field(repr=False)
    auto_band: float = 0.0
    whiteness_q: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    whiteness_p: np.ndarray = field(default_factory=lambda: np.zeros(0))
    cross_lags: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    cross_correlation: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    cross_band: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    independence_s: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    independence_p: np.ndarray = field(default_factory=lambda: np.zeros(0))
    confidence: float = 0.99
    notes: tuple[str, ...] = ()
    time_unit: str = "s"
    t_fine: tuple[np.ndarray, ...] = field(default=(), repr=False)
    y_fine: tuple[np.ndarray, ...] = field(default=(), repr=False)
    channel_names: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """The input and output columns of a table the records were read from (``{"input": (...), "output": (...)}``,
    from ``stated_units``): the labels of :meth:`summary` and :meth:`plot` when no names are given."""

    @property
    def white(self) -> np.ndarray:
        """(p,) whether each output's residual passes the whiteness test at ``confidence``."""
        return self.whiteness_p >= 1 - self.confidence

    @property
    def independent(self) -> np.ndarray:
        """(p, m) whether each residual passes the independence test against each (non-constant) input."""
        with np.errstate(invalid="ignore"):
            return np.where(np.isfinite(self.independence_p), self.independence_p >= 1 - self.confidence, True)

    def _column_names(self, role: str, n: int) -> tuple[str, ...] | None:
        """The table's column names of ``role`` when there are ``n`` of them, else None."""
        names = self.channel_names.get(role, ())
        return tuple(names) if len(names) == n and n else None

    def summary(self, *, output_names: Any = None, input_names: Any = None) -> str:
        """A readable table: fit and tests per output (and input), labelled by number or by the names given."""
        p = self.fit_percent.size
        m = self.cross_correlation.shape[1] if self.cross_correlation.ndim == 3 else 0
        output_names = output_names if output_names is not None else self._column_names("output", p)
        input_names = input_names if input_names is not None else self._column_names("input", m)
        onames = [str(j) for j in range(p)] if output_names is None else _names(output_names, p, "output")
        inames = [str(i) for i in range(m)] if input_names is None else _names(input_names, m, "input")
        wo = max(7, *(len(x) for x in onames))
        wi = max(6, *(len(x) for x in inames)) if m else 6
        level = f"{100 * self.confidence:g} %"
        n = sum(tt.size for tt in self.t)
        lines = [f"validation on {len(self.t)} record(s), {n} samples; tests at {level}, lags 1…{self.lags[-1]}",
                 f"{'output':>{wo}s} {'fit %':>8s} {'rms error':>11s} {'whiteness Q':>12s} {'p-value':>8s} "
                 f"{'lags out':>9s}"]
        for j in range(p):
            out = int(np.sum(np.abs(self.autocorrelation[j, 1:]) > self.auto_band))
            lines.append(f"{onames[j]:>{wo}s} {self.fit_percent[j]:>8.2f} {self.rms_error[j]:>11.4g} "
                         f"{self.whiteness_q[j]:>12.4g} {self.whiteness_p[j]:>8.3g} {out:>9d}")
        if m:
            lines.append(f"{'output':>{wo}s} {'input':>{wi}s} {'S (τ ≥ 0)':>12s} {'p-value':>8s} {'lags out':>9s}")
            for j in range(p):
                for i in range(m):
                    if not np.isfinite(self.independence_s[j, i]):
                        lines.append(f"{onames[j]:>{wo}s} {inames[i]:>{wi}s} {'constant input: not tested':>31s}")
                        continue
                    pos = self.cross_correlation[j, i, self.cross_lags >= 0]
                    out = int(np.sum(np.abs(pos) > self.cross_band[j, i]))
                    lines.append(f"{onames[j]:>{wo}s} {inames[i]:>{wi}s} {self.independence_s[j, i]:>12.4g} "
                                 f"{self.independence_p[j, i]:>8.3g} {out:>9d}")
        verdict = []
        if not np.all(self.white):
            verdict.append("residual NOT white (model or noise structure missing)")
        if not np.all(self.independent):
            verdict.append("residual correlated with past inputs (dynamics not captured)")
        if verdict:  # a failure near the level can be chance: say how often a true model fails one of these tests
            pv = np.concatenate([np.ravel(self.whiteness_p), np.ravel(self.independence_p)])
            pv = pv[np.isfinite(pv)]
            alpha = 1 - self.confidence
            failed = pv[pv < alpha]
            if failed.size and float(failed.min()) >= alpha / 10:
                chance = 1 - self.confidence ** pv.size
                verdict.append(f"marginal (smallest p-value {float(failed.min()):.2g}, within a factor 10 of the "
                               f"level): a true model fails one of these {pv.size} tests in {100 * chance:.0f} % of "
                               f"records, so try another record before concluding")
        lines.append("verdict: " + ("; ".join(verdict) if verdict else "residual white and independent of the "
                                    "inputs at this level"))
        lines.extend(f"note: {t}" for t in self.notes)
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form (without the sample arrays), suitable for JSON."""

        def plain(a: Any) -> Any:
            arr = np.asarray(a, dtype=float)
            return np.where(np.isfinite(arr), arr, None).tolist()

        return {"parameter_names": list(self.parameter_names), "theta": plain(self.theta),
                "fit_percent": plain(self.fit_percent), "rms_error": plain(self.rms_error),
                "lags": self.lags.tolist(), "autocorrelation": plain(self.autocorrelation),
                "auto_band": self.auto_band, "whiteness_q": plain(self.whiteness_q),
                "whiteness_p": plain(self.whiteness_p), "white": self.white.tolist(),
                "cross_lags": self.cross_lags.tolist(), "cross_correlation": plain(self.cross_correlation),
                "cross_band": plain(self.cross_band), "independence_s": plain(self.independence_s),
                "independence_p": plain(self.independence_p), "independent": self.independent.tolist(),
                "confidence": self.confidence, "notes": list(self.notes), "time_unit": self.time_unit,
                "records": len(self.t), "samples": int(sum(tt.size for tt in self.t))}

    # -- figures --------------------------------------------------------------------------------
    def plot(self, path: str | Path, *, output_names: Any = None, output_units: Any = None,
             input_names: Any = None, title: str | None = None) -> tuple[Path, Path]:
        """Write two PNG figures: simulated against measured output, and the residual tests.

        Parameters
        ----------
        path : str or pathlib.Path
            Stem of the files: ``<stem>_output.png`` and ``<stem>_residual.png`` (a
            ``.png`` suffix is dropped first).
        output_names, output_units, input_names : sequence of str, optional
            Axis labels; without units the axis says they are not given.
        title : str, optional

        Returns
        -------
        tuple of pathlib.Path
            The two files written.
        """
        p = self.fit_percent.size
        m = self.cross_correlation.shape[1] if self.cross_correlation.ndim == 3 else 0
        onames = _names(output_names if output_names is not None else self._column_names("output", p), p, "output")
        ounits = _names(output_units, p, None)
        inames = _names(input_names if input_names is not None else self._column_names("input", m), m, "input")
        stem = Path(path)
        if stem.suffix.lower() == ".png":
            stem = stem.with_suffix("")
        first = stem.with_name(stem.name + "_output.png")
        second = stem.with_name(stem.name + "_residual.png")
        plt = _pyplot()
        fig, axes = plt.subplots(2 * p, 1, figsize=(10, 4.2 * p + 0.6), squeeze=False, sharex=True,
                                 gridspec_kw={"height_ratios": [2, 1] * p})
        for j in range(p):
            ax, rax = axes[2 * j, 0], axes[2 * j + 1, 0]
            unit = ounits[j] if ounits[j] else "unit not given"
            for e, (tt, yy, ys) in enumerate(zip(self.t, self.y, self.y_sim, strict=True)):
                lead = e == 0
                fine = e < len(self.t_fine) and self.t_fine[e].size > 0
                if tt.size < MARKERS_BELOW:  # sparse samples: markers, and the model's curve between them
                    ax.plot(tt, yy[:, j], "o", color="0.35", ms=5, label="measured" if lead else None)
                    ax.plot(tt, ys[:, j], "x", color="C3", ms=5, label="simulated at the samples" if lead else None)
                    rax.plot(tt, yy[:, j] - ys[:, j], "o", color="C0", ms=4,
                             label="measured − simulated" if lead else None)
                else:
                    ax.plot(tt, yy[:, j], color="0.55", lw=2.6, alpha=0.8, label="measured" if lead else None)
                    if not fine:
                        ax.plot(tt, ys[:, j], color="C3", lw=1.1, ls=(0, (5, 2)), label="simulated" if lead else None)
                    rax.plot(tt, yy[:, j] - ys[:, j], color="C0", lw=0.8,
                             label="measured − simulated" if lead else None)
                if fine:
                    ax.plot(self.t_fine[e], self.y_fine[e][:, j], color="C3", lw=1.1,
                            label="simulated" if lead else None)
            ax.set_ylabel(f"{onames[j]} ({unit})")
            ax.set_title(f"{onames[j]}: fit {self.fit_percent[j]:.2f} %, rms error {self.rms_error[j]:.3g}"
                         f"{' ' + ounits[j] if ounits[j] else ''}", fontsize=10)
            rax.axhline(0, color="k", lw=0.6)
            rax.set_ylabel(f"residual ({unit})")
            for a in (ax, rax):
                a.grid(alpha=0.3)
                a.legend(loc="best", fontsize=8)
        axes[-1, 0].set_xlabel(f"time ({self.time_unit})")
        if title:
            fig.suptitle(title)
        fig.tight_layout()
        _save(fig, first)
        rows = p
        cols = 1 + m
        fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols + 0.8, 2.9 * rows + 0.6), squeeze=False)
        level = f"{100 * self.confidence:g} % band"
        for j in range(p):
            ax = axes[j, 0]
            ax.axhspan(-self.auto_band, self.auto_band, color="C2", alpha=0.2, label=level)
            ax.vlines(self.lags[1:], 0, self.autocorrelation[j, 1:], color="C0", lw=1.5, label="ρₑ(τ)")
            ax.plot(self.lags[1:], self.autocorrelation[j, 1:], "o", color="C0", ms=3)
            ax.axhline(0, color="k", lw=0.6)
            ax.set_title(f"whiteness of the {onames[j]} residual ({_p_text(self.whiteness_p[j])})", fontsize=9)
            ax.set_xlabel("lag τ (samples)")
            ax.set_ylabel("autocorrelation (–)")
            ax.legend(loc="best", fontsize=8)
            ax.grid(alpha=0.3)
            for i in range(m):
                ax = axes[j, 1 + i]
                rho = self.cross_correlation[j, i]
                if not np.all(np.isfinite(rho)):
                    ax.text(0.5, 0.5, f"input '{inames[i]}' does not vary:\nno cross-correlation", ha="center",
                            va="center", transform=ax.transAxes)
                    ax.set_axis_off()
                    continue
                b = self.cross_band[j, i]
                ax.axhspan(-b, b, color="C2", alpha=0.2, label=level)
                ax.vlines(self.cross_lags, 0, rho, color="C1", lw=1.5, label="ρₑᵤ(τ)")
                ax.plot(self.cross_lags, rho, "o", color="C1", ms=3)
                ax.axhline(0, color="k", lw=0.6)
                ax.axvline(0, color="0.4", lw=0.6, ls=":")
                ax.set_title(f"{onames[j]} residual vs {inames[i]} (τ ≥ 0: {_p_text(self.independence_p[j, i])})",
                             fontsize=9)
                ax.set_xlabel("lag τ (samples; > 0: input leads)")
                ax.set_ylabel("cross-correlation (–)")
                ax.legend(loc="best", fontsize=8)
                ax.grid(alpha=0.3)
        if title:
            fig.suptitle(title)
        fig.tight_layout()
        _save(fig, second)
        return first, second


def _p_text(p: float) -> str:
    return "p < 1e-16" if p < 1e-16 else f"p = {p:.2g}"


def _record_columns(data: Any) -> dict[str, tuple[str, ...]]:
    """The column names the (first) record was read with from a table (``stated_units``), else {}."""
    first = data[0] if isinstance(data, (list, tuple)) and data else data
    stated = getattr(first, "stated_units", None) or {}
    return {role: tuple(name for name, _ in stated.get(role, ())) for role in ("input", "output") if role in stated}


def _names(values: Any, n: int, default: str | None) -> list[str]:
    if values is None:
        return [f"{default} {k}" if default else "" for k in range(n)]
    if isinstance(values, str):
        values = [values]
    out = [str(v) for v in values]
    if len(out) != n:
        raise DataError(f"expected {n} name(s) or unit(s); got {len(out)}: {out}")
    return out


def _pyplot() -> Any:
    import os

    import matplotlib

    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        matplotlib.use("Agg")  # no screen: draw to files only
    import matplotlib.pyplot as plt

    return plt


def _save(fig: Any, path: Path) -> None:
    from symid.runlog import write_atomic

    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        with write_atomic(path, "wb") as fh:
            fig.savefig(fh, dpi=110, format="png")
    finally:
        _pyplot().close(fig)


def _correlations(res: list[np.ndarray], us: list[np.ndarray], M: int) -> tuple[np.ndarray, np.ndarray,
                                                                                   np.ndarray, np.ndarray]:
    """Pooled normalised residual autocorrelations (p, M+1), input autocorrelations (m, 2M+1: lags 0 … 2M),
    cross-correlations (p, m, 2M+1: lags −M … M) and the inputs' rms."""
    p, m = res[0].shape[1], us[0].shape[1]
    e_mean = np.sum([e.sum(axis=0) for e in res], axis=0) / sum(e.shape[0] for e in res)
    u_mean = np.sum([u.sum(axis=0) for u in us], axis=0) / sum(u.shape[0] for u in us)
    E = [e - e_mean for e in res]
    U = [u - u_mean for u in us]
    ee = np.zeros((p, M + 1))
    uu = np.zeros((m, 2 * M + 1))  # to lag 2M: the covariance of the cross-correlations over lags 0 … M needs it
    eu = np.zeros((p, m, 2 * M + 1))
    for e, u in zip(E, U, strict=True):
        N = e.shape[0]
        for tau in range(min(2 * M, N - 1) + 1):
            uu[:, tau] += np.sum(u[tau:] * u[: N - tau], axis=0)
            if tau > M:
                continue
            ee[:, tau] += np.sum(e[tau:] * e[: N - tau], axis=0)
            eu[:, :, M + tau] += e[tau:].T @ u[: N - tau]          # ε(t) u(t − τ)
            if tau:
                eu[:, :, M - tau] += e[: N - tau].T @ u[tau:]      # ε(t) u(t + τ)
    se = np.sqrt(ee[:, :1])
    su = np.sqrt(uu[:, :1])
    with np.errstate(divide="ignore", invalid="ignore"):
        rho_e = ee / se**2
        rho_u = uu / su**2
        rho_eu = eu / (se[:, 0][:, None, None] * su[:, 0][None, :, None])
    return rho_e, rho_u, rho_eu, su[:, 0]


def _independence(rho_e: np.ndarray, rho_u: np.ndarray, rho: np.ndarray, N: int) -> tuple[np.ndarray, np.ndarray]:
    """S = N ρᵀ Γ⁺ ρ and rank Γ per output and input (module notes), ρ = ρₑᵤ(0 … M) (p, m, M+1); ρₑ to lag M,
    ρᵤ to lag 2M."""
    p, m, L = rho.shape
    M = L - 1
    k = np.arange(-M, M + 1)
    s_stat, dof = np.full((p, m), np.nan), np.full((p, m), float(L))
    d = np.subtract.outer(np.arange(L), np.arange(L))  # τ − τ′
    for j in range(p):
        re = rho_e[j, np.abs(k)]  # even in k
        for i in range(m):
            if not np.all(np.isfinite(rho_u[i])) or not np.all(np.isfinite(rho[j, i])):
                continue
            G = np.sum(re[:, None, None] * rho_u[i, np.abs(k[:, None, None] + d[None])], axis=0)
            w, V = np.linalg.eigh((G + G.T) / 2)
            keep = w > 1e-8 * max(float(w.max()), 1e-300)
            proj = V[:, keep].T @ rho[j, i]
            s_stat[j, i] = N * float(np.sum(proj**2 / w[keep]))
            dof[j, i] = float(np.count_nonzero(keep))
    return s_stat, dof


def independence_pvalues(residuals: list[np.ndarray], inputs: list[np.ndarray], max_lag: int | None = None
                         ) -> np.ndarray:
    """The p-values (p, m) of the residual–input independence test of :func:`validate` (module notes): each output's
    residual against each input over lags 0 … M (M = ``max_lag``, else 25 or a quarter of the shortest record);
    NaN for a constant input. ``residuals`` and ``inputs`` hold one (N, p) and one (N, m) array per record.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.validation import independence_pvalues
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((2000, 1))
    >>> white = rng.standard_normal((2000, 1))
    >>> bool(independence_pvalues([white], [u])[0, 0] > 0.01)
    True
    >>> bool(independence_pvalues([white + 0.3 * np.roll(u, 2, axis=0)], [u])[0, 0] < 1e-6)   # u leaks in
    True
    """
    from scipy.stats import chi2

    shortest = min(e.shape[0] for e in residuals)
    M = int(max_lag) if max_lag is not None else min(DEFAULT_MAX_LAG, shortest // 4)
    if M < 1:
        return np.full((residuals[0].shape[1], inputs[0].shape[1]), np.nan)
    rho_e, rho_u, rho_eu, _ = _correlations(residuals, inputs, M)
    N = sum(e.shape[0] for e in residuals)
    s_stat, s_dof = _independence(rho_e, rho_u, rho_eu[:, :, M:], N)
    return chi2.sf(s_stat, s_dof)


def validate(model: Any, theta: Any, data: Any, *, initial_state: Any = None, max_lag: int | None = None,
             confidence: float = 0.99, hold: Any = "zoh", variance: Any = None) -> Validation:
    """Simulate the model at θ on measured records and test what is left (module text).

    The simulation holds the input constant between samples (zero-order hold), as
    :class:`~symid.data.IOData` defines a record and as a digital controller or signal
    generator drives a plant. A band-limited input that was only sampled (a shaker's force
    measured by an acquisition system) is not held: its simulation errs by the hold's
    difference, which grows with frequency, and the residual then tests as coloured and
    correlated with the input although the model is right (a new user's 4-storey frame
    sampled at 8 times its highest mode: fit 68–78 % where the held input gives 99 %).
    For such records give ``hold="bandlimited"``: the input is then its band-limited
    interpolation between samples. ``hold="foh"`` (linear between samples) is nearly that
    for a signal sampled well above its band. Nearly: a sum of sines up to 12 rad/s through
    a 10 rad/s mode, acceleration measured with 2 % noise, fit 80 % held and 97.3 % linear
    at 25 samples a second (90 % and 97.9 % at 50; the noise alone leaves 98 %), and at
    6000 samples the whiteness test still sees the rest; a new user's quarter car (a road
    profile sampled at 500 Hz, the truth): linear, residual correlated with the input
    (p = 1.6e-61); band-limited, white and independent of it.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    theta : dict or sequence of float
        The parameters (e.g. ``result.theta``).
    data : IOData, TimeSeries, or a list of them
        Validation records (preferably not those θ was estimated from).
    initial_state : None, "estimate" or array_like, optional
        ``None``: the model's (zero, known, affine in θ, or least squares for a model with
        ``x0="estimate"``); ``"estimate"``: the least-squares initial state of each record
        (as MATLAB's ``compare`` does by default); numbers (n,): known.
    max_lag : int, optional
        M, the largest correlation lag in samples. Default: 25 (MATLAB's ``resid``), or a
        quarter of the shortest record where that is shorter than 100 samples (a
        clinical record of 15 concentrations: M = 3; the tests need M below the number
        of samples, and a correlation at a lag near it rests on a few products). A note
        says so.
    confidence : {0.99, 0.95}
        Level of the bands and tests.
    hold : {"zoh", "foh", "bandlimited"} or list of them
        How the input moves between samples in the simulation (one per input where they
        differ, :func:`symid.fit.timeseries.oe.parse_hold`): held (``"zoh"``, default, as
        :class:`~symid.data.IOData` defines a record), linear (``"foh"``) or band-limited
        (``"bandlimited"``, for a sampled band-limited input: its band-limited interpolation,
        :func:`symid.fit.timeseries.records.band_limited`), as ``si.identify``'s option of
        the same name for time series.
    variance : dict, float or array_like, optional
        The noise variance of the measured values, as ``si.identify``'s option of the same
        name for time series: an error model ``{"proportional": a, "additive": b}``
        (σ² = (a·ŷ)² + b² from the simulated output ŷ, or from the measured values with
        ``"weights": "measured"``), or numbers. The residual tests then run on the
        standardised residual (y − ŷ)/σ: noise whose level follows the output (a
        concentration's proportional error) is not white in y − ŷ, and the true model of a
        new user's dose–response records failed the whiteness test in 30 of 30 records at
        15 % proportional noise. The fit stays that of y − ŷ.

    Returns
    -------
    Validation

    Raises
    ------
    DataError
        On data that are not time series, records that do not match the model, a lag
        that the records cannot hold, or a confidence level other than 0.95 or 0.99.
    OptionError
        On a variance that is not a number, an array of the records' shape or an error model.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> k, g = si.parameters("k g", positive=True)
    >>> model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> io = si.simulate_io(model, {"k": 0.5, "g": 2.0}, u, dt=0.1, noise=0.05, seed=1)
    >>> v = si.validate(model, {"k": 0.5, "g": 2.0}, io)
    >>> bool(90 < v.fit_percent[0] < 100), bool(v.white[0]), bool(v.independent[0, 0])
    (True, True, True)
    >>> bool(si.validate(model, {"k": 0.25, "g": 2.0}, io).white[0])   # a wrong model leaves structure
    False
    """
    from scipy.stats import chi2

    from symid.fit.timeseries.oe import OutputError

    if max_lag is not None and (isinstance(max_lag, bool) or not isinstance(max_lag, (int, np.integer))
                                or max_lag < 1):
        raise DataError(f"max_lag must be an int >= 1 (sample lags), or None for the default; got {max_lag!r}")
    if confidence not in _Z:
        raise DataError(f"confidence must be 0.95 or 0.99; got {confidence!r}")
    per_input = isinstance(hold, (list, tuple)) or (isinstance(hold, str) and "," in hold)  # parse_hold checks them
    if not per_input and hold not in ("zoh", "foh", "bandlimited"):
        raise DataError(f"hold must be 'zoh' (the input held between samples), 'foh' (linear between them) or "
                        f"'bandlimited' (a sampled band-limited input), or one of them per input; got {hold!r}")
    sim = OutputError(model, data, initial_state=initial_state, variance=variance, hold=hold)
    from symid.fit.identify import unit_mismatches

    for text in unit_mismatches(model, data):  # as identify says it for the records it fits
        warnings.warn(text, DataWarning, stacklevel=2)
    th = model.theta_vector(theta)
    try:
        ys = sim.simulate(th)
        x0s = sim.initial_states(th)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise DataError(f"the model cannot be simulated at θ = {model.theta_dict(th)}: {exc}") from None
    recs, observed = sim.records, sim.observed
    if hold == "bandlimited":  # simulated at points between the samples, which carry no output: back to the samples
        from symid.data.timeseries import TimeSeries
        from symid.fit.timeseries import records as _records

        step = _records.BAND_LIMITED_UPSAMPLE

        recs = [TimeSeries(r.t[::step], r.u[::step], r.y[::step], r.time_unit) for r in recs]
        observed, ys = [o[::step] for o in observed], [y[::step] for y in ys]
    ys_obs = [np.where(o, r.y, np.nan) for r, o in zip(recs, observed, strict=True)]  # NaN: not measured
    # the correlations run over the sample times where every output was measured, lags counted in those samples
    whole = [np.all(o, axis=1) for o in observed]
    N = int(sum(np.count_nonzero(k) for k in whole))
    shortest = min(np.count_nonzero(k) for k in whole)
    measured = " with every output measured" if sim.n_missing else ""
    if max_lag is None:
        if shortest < 4:
            raise DataError(f"the residual tests need records of 4 samples or more; the shortest has {shortest}"
                            f"{measured}")
        M = min(DEFAULT_MAX_LAG, shortest // 4)
    else:
        M = int(max_lag)
        if M >= shortest:
            raise DataError(f"max_lag = {M} needs records longer than {M} samples; the shortest has {shortest}"
                            f"{measured} (leave max_lag out for {min(DEFAULT_MAX_LAG, max(shortest // 4, 1))})")
    y_all = np.vstack(ys_obs)
    e_all = np.vstack([y - s for y, s in zip(ys_obs, ys, strict=True)])
    if not np.all(np.isfinite(np.vstack(ys))):
        raise DataError(f"the simulated output at θ = {model.theta_dict(th)} overflows (an unstable model?)")
    denom = np.sqrt(np.nansum((y_all - np.nanmean(y_all, axis=0)) ** 2, axis=0))
    with np.errstate(divide="ignore", invalid="ignore"):
        fit = 100.0 * (1.0 - np.sqrt(np.nansum(e_all**2, axis=0)) / denom)
    rms = np.sqrt(np.nanmean(e_all**2, axis=0))
    sigma = sim.noise_variance(th) if variance is not None else None
    if sigma is not None and hold == "bandlimited":  # on the points, as the simulation: back to the samples
        sigma = [v[::step] for v in sigma]
    if sigma is None:
        sigma = [np.ones_like(y) for y in ys_obs]
    else:
        sigma = [np.sqrt(v) for v in sigma]
    rho_e, rho_u, rho_eu, su = _correlations([((y - s) / sd)[k] for y, s, sd, k in zip(ys_obs, ys, sigma, whole,
                                                                                      strict=True)],
                                             [r.u[k] for r, k in zip(recs, whole, strict=True)], M)
    z = _Z[confidence]
    taus = np.arange(1, M + 1)
    q = N * (N + 2) * np.sum(rho_e[:, 1:] ** 2 / (N - taus), axis=1)
    q_p = chi2.sf(q, M)
    # Ljung (16.60): P = Σ_k ρε(k) ρu(k), k = −M … M (both even), ±z √(P/N)
    P = rho_e[:, None, 0] * rho_u[None, :, 0] + 2 * np.sum(rho_e[:, None, 1:] * rho_u[None, :, 1:M + 1], axis=2)
    P = np.where(np.isfinite(P) & (P > 0), P, 1.0)
    cross_band = z * np.sqrt(P / N)
    s_stat, s_dof = _independence(rho_e, rho_u, rho_eu[:, :, M:], N)
    s_p = chi2.sf(s_stat, s_dof)
    notes = []
    if max_lag is None and M < DEFAULT_MAX_LAG:
        notes.append(f"correlations up to lag {M}, a quarter of the shortest record ({shortest} samples{measured}), "
                     f"not {DEFAULT_MAX_LAG}")
    constant = np.flatnonzero(~(su > 0))
    if constant.size:
        columns = _record_columns(data).get("input", ())  # by the table's names when read from one (a new user's
        # "input(s) 2 constant" beside tables that named the columns)
        named = [repr(columns[i]) if len(columns) == su.size else str(int(i)) for i in constant]
        notes.append(f"input(s) {', '.join(named)} constant: no cross-correlation")
        s_stat[:, constant] = np.nan
        s_p[:, constant] = np.nan
        rho_eu[:, constant, :] = np.nan
    if not all(r.is_uniform if hasattr(r, "is_uniform") else np.allclose(np.diff(r.t), np.diff(r.t)[0], rtol=1e-6)
               for r in recs):
        notes.append("sample times are not uniform: correlation lags are in samples, not in time")
    if variance is not None:
        notes.append("residual tests on (y − ŷ)/σ, σ from the given variance" + (
            " (an error model, σ from the simulated output)" if isinstance(variance, dict)
            and variance.get("weights", "prediction") == "prediction" else ""))
    if len(recs) > 1:
        notes.append(f"{len(recs)} records pooled (fit over all samples; correlations summed over records)")
    fine = _fine_curves(model, th, recs, x0s, hold)
    if sim.n_missing:
        notes.append(f"{sim.n_missing} output value(s) not measured (NaN): left out of the fit; the correlations "
                     f"run over the {N} sample times where every output was measured, their lags counted in those "
                     f"samples, not in time")
    return Validation(parameter_names=tuple(model.parameter_names), theta=th, fit_percent=fit, rms_error=rms,
                      t=tuple(r.t for r in recs), u=tuple(r.u for r in recs), y=tuple(ys_obs),
                      y_sim=tuple(ys), initial_states=tuple(x0s), lags=np.arange(M + 1), autocorrelation=rho_e,
                      auto_band=float(z / np.sqrt(N)), whiteness_q=q, whiteness_p=q_p,
                      cross_lags=np.arange(-M, M + 1), cross_correlation=rho_eu, cross_band=cross_band,
                      independence_s=s_stat, independence_p=s_p, confidence=float(confidence),
                      notes=tuple(notes), time_unit=getattr(recs[0], "time_unit", "s"),
                      t_fine=fine[0], y_fine=fine[1], channel_names=_record_columns(data))


def _fine_curves(model: Any, theta: np.ndarray, recs: Any, x0s: Any, hold: Any
                 ) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """(t_fine, y_fine) per record (class notes): each sample interval cut into equal steps, the input held (or
    linear, ``hold="foh"``, one per input where they differ) between samples as in the simulation, from the record's
    initial state."""
    from symid.fit.timeseries.oe import parse_hold
    from symid.fit.timeseries.response import simulate_output

    kinds = parse_hold(list(hold) if isinstance(hold, (list, tuple)) else hold, recs[0].u.shape[1])
    kinds = kinds if isinstance(kinds, tuple) else (kinds,) * recs[0].u.shape[1]
    if "bandlimited" in kinds:
        return (), ()
    held = np.array([k == "zoh" for k in kinds])
    A, B, C, D = model.state_space(theta)
    ts, ys = [], []
    for r, x0 in zip(recs, x0s, strict=True):
        N = r.t.size
        if N >= FINE_BELOW or N < 2:
            ts.append(np.zeros(0))
            ys.append(np.zeros((0, C.shape[0])))
            continue
        q = max(1, FINE_POINTS // (N - 1))  # steps per interval: equal within it, few distinct lengths overall
        frac = np.arange(q) / q
        t = np.concatenate([(r.t[:-1, None] + frac[None, :] * np.diff(r.t)[:, None]).ravel(), r.t[-1:]])
        linear = np.column_stack([np.interp(t, r.t, r.u[:, i]) for i in range(r.u.shape[1])])
        steps = np.concatenate([np.repeat(r.u[:-1], q, axis=0), r.u[-1:]])  # held from each sample to the next
        u = np.where(held[None, :], steps, linear)
        ts.append(t)
        ys.append(simulate_output(A, B, C, D, t, u, x0, hold="foh", held=held))
    return tuple(ts), tuple(ys)
