"""The F-16 ground vibration test, end to end: measured multisine → FRF with noise → modal grey box → validation.

Run::

    .venv/bin/python examples/f16_gvt.py --data DIR          # DIR holds the two .mat files below
    SYMID_F16_DATA=DIR .venv/bin/python examples/f16_gvt.py   # the same, the folder from the environment
    .venv/bin/python examples/f16_gvt.py --quick             # the committed subset, one pass of "lm", checked
    .venv/bin/python examples/f16_gvt.py --data DIR --make-subset   # rewrite examples/data/f16_subset.npz

The data
--------
The F-16 ground vibration test benchmark (J.P. Noël and M. Schoukens, 2017, one of the
"nonlinear system identification benchmarks"): a shaker under the right wing of a
decommissioned F-16 excites it; three accelerometers measure the response, at
fs = 400 Hz. Two files are used (MATLAB v5):

* ``F16Data_FullMSine_Level1.mat`` (estimation): ``Force`` (N) and ``Acceleration``
  (m/s², 3 sensors), a multisine with every line excited over 2–15 Hz, 9 periods of
  8192 samples, the first holding the start-up transient. Level 1, about 12 N rms, is
  the lowest amplitude, where the structure is closest to linear.
* ``F16Data_SpecialOddMSine_Level1_Validation.mat`` (validation only): another
  multisine (odd lines, 1–60 Hz, random phases), 3 periods of 16 384 samples of which
  the last two are in steady state.

The data are not part of symid. ``--data DIR`` or the environment variable
``SYMID_F16_DATA`` name the folder; without either, the full run stops with an error
saying so. ``examples/data/f16_subset.npz`` (about 60 kB, written by ``--make-subset``)
holds what the analysis needs from the two files: the FRF estimate of force →
acceleration at sensor 1 over 2–15 Hz (267 lines with their noise variance and
coherence), and the DFT lines in 2–15 Hz of the two steady-state validation periods.
``--quick`` (what the test suite runs) works from it alone: one deterministic pass of
``"lm"`` from the library's start (a few seconds), then it checks what the data notes
say — a validation fit of at least 71 % and the six structural modes within 3 % of
their frequencies — and stops with an error if either fails.

The analysis
------------
1. ``si.estimate_frf(io, period=8192, transient_periods=1, band=2–15 Hz)``: periods 2–9
   averaged; the spread between periods gives the noise variance of every line (about
   0.1 % of |H|); ``si.estimate_coherence`` and ``frf_estimate_plot`` show both.
2. The modal grey box: eight second-order modes in modal coordinates, M = I,
   V = diag(v), K = diag(k), B = b (residues, any sign), C = [1 … 1], acceleration
   output, so that H(ω) = Σᵣ −ω² bᵣ / (kᵣ − ω² + jω vᵣ): six structural modes in the
   band and two residual terms, one below and one above it, that stand for the modes
   outside the band; 24 parameters, kᵣ = ωᵣ² and vᵣ = 2ζᵣωᵣ declared positive.
3. The fit: ``si.identify(model, frf, method=..., starts=..., seed=0)`` with the
   library's own starts (no start computed here). The first is the black-box start
   (:func:`symid.fit.frf.modal.black_box_start`: a vector fit of the FRF with 16 poles,
   the model's poles placed on its poles, then the residues and every parameter fitted
   with the poles held); the others are draws within a factor 3 of its magnitudes. The
   start is printed with its own misfit and validation. Routes side by side: ``"lm"``
   (one pass of Levenberg–Marquardt on log-parameters), ``"auto"`` (the same with
   restarts), ``"ipopt"`` and SCR followed by an IPOPT polish; each start within
   ``--time-limit`` seconds.
4. Validation on the other record: the model's steady-state response to the
   validation force is computed line by line, Ŷ(ωₖ) = H(jωₖ, θ̂) U(ωₖ), on the DFT lines
   of the two steady-state periods in 2–15 Hz, and compared with the measured
   acceleration band-passed the same way (both signals periodic: this is exact, with no
   transient and no assumption on how the force varies between samples). The fit is
   MATLAB ``compare``'s, 100 (1 − ‖y − ŷ‖ / ‖y − mean y‖) %, and is the last line printed.

Reference values (measured on these files outside symid): a hand-started fit of this
model reaches a relative FRF misfit of about 0.01 and a validation fit of 71 %; an
N4SID black box 67 %. On the steady-state lines used here the same hand-started fit
validates at 80.6 % (``tests/test_f16_example.py`` asserts at least 71 %).

What ``success`` means here: the lines are measured to about 0.1 % of |H|, so noise
alone would leave a relative misfit of 1.5e-6 (Σ variance / Σ |H|²); a misfit of 0.01
is model error (eight linear modes for a structure with a mildly nonlinear
wing-torsion mode at 7.3 Hz and more modes outside the band). symid's rule (a fit is a
success only when what is left is noise) therefore reports ``success=False`` even for
the best fit, and says why in the fit test printed under each route; the validation on
the other record is what tells whether the model is useful.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

import symid as si
from symid.fit.frf.misfit import relative_misfit
from symid.fit.frf.modal import black_box_start

FS = 400.0
BAND_HZ = (2.0, 15.0)
ESTIMATION = "F16Data_FullMSine_Level1.mat"
VALIDATION = "F16Data_SpecialOddMSine_Level1_Validation.mat"
EST_PERIOD, VAL_PERIOD = 8192, 16384
SUBSET = Path(__file__).resolve().parent / "data" / "f16_subset.npz"
N_MODES = 8  # six structural modes + two residual terms
SENSOR = 0  # acceleration sensor 1


class DataMissing(SystemExit):
    """The benchmark files are not where the arguments or SYMID_F16_DATA say."""


def _band_rad() -> tuple[float, float]:
    return 2 * np.pi * BAND_HZ[0], 2 * np.pi * BAND_HZ[1]


# -- data --------------------------------------------------------------------------------------

def data_folder(arg: str | None) -> Path:
    """The folder of the two .mat files: ``--data`` or ``SYMID_F16_DATA``; a clear error otherwise."""
    where = arg or os.environ.get("SYMID_F16_DATA")
    if not where:
        raise DataMissing("the F-16 benchmark files are not part of symid: pass --data DIR (the folder holding "
                          f"{ESTIMATION} and {VALIDATION}) or set SYMID_F16_DATA=DIR; --quick runs on the committed "
                          f"subset {SUBSET.name}")
    folder = Path(where)
    missing = [n for n in (ESTIMATION, VALIDATION) if not (folder / n).is_file()]
    if missing:
        raise DataMissing(f"{folder} does not hold {', '.join(missing)} (the F-16 ground vibration test files)")
    return folder


def _load_mat(path: Path) -> dict[str, np.ndarray]:
    import scipy.io

    raw = scipy.io.loadmat(path)  # MATLAB v5 numeric arrays; no pickles are involved
    return {k: np.asarray(raw[k], dtype=float) for k in ("Force", "Acceleration")}


def estimation_record(folder: Path) -> si.IOData:
    """Force → acceleration at the chosen sensor, the whole estimation record."""
    d = _load_mat(folder / ESTIMATION)
    return si.IOData(d["Force"].reshape(-1), d["Acceleration"].reshape(3, -1)[SENSOR], 1 / FS)


def validation_lines(folder: Path) -> dict[str, np.ndarray]:
    """DFT lines in the band of the two steady-state validation periods (force U and acceleration Y)."""
    d = _load_mat(folder / VALIDATION)
    u = d["Force"].reshape(-1)
    y = d["Acceleration"].reshape(3, -1)[SENSOR]
    if u.size % VAL_PERIOD:
        raise SystemExit(f"{VALIDATION}: {u.size} samples are not whole periods of {VAL_PERIOD}")
    n_per = u.size // VAL_PERIOD
    U = np.fft.rfft(u.reshape(n_per, VAL_PERIOD)[1:], axis=1)  # periods 2, 3: steady state
    Y = np.fft.rfft(y.reshape(n_per, VAL_PERIOD)[1:], axis=1)
    f = np.arange(U.shape[1]) * FS / VAL_PERIOD
    lines = np.flatnonzero((f >= BAND_HZ[0]) & (f <= BAND_HZ[1]))
    return {"lines": lines, "U": U[:, lines], "Y": Y[:, lines]}


def analyse_records(folder: Path) -> dict[str, Any]:
    """Everything the analysis takes from the two files (what the subset stores)."""
    io = estimation_record(folder)
    opts = {"period": EST_PERIOD, "transient_periods": 1, "band": _band_rad()}
    frf = si.estimate_frf(io, **opts)
    _, coh = si.estimate_coherence(io, **opts)
    return {"frf": frf, "coherence": coh[:, 0], **validation_lines(folder)}


def write_subset(parts: dict[str, Any], path: Path = SUBSET) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    frf = parts["frf"]
    np.savez_compressed(path, w=frf.w, H=frf.H[:, 0, 0], variance=frf.variance[:, 0, 0], coherence=parts["coherence"],
                        lines=parts["lines"], U=parts["U"], Y=parts["Y"],
                        source=np.array(f"{ESTIMATION} periods 2-9 (FRF, band {BAND_HZ} Hz, sensor {SENSOR + 1}); "
                                        f"{VALIDATION} periods 2-3 (DFT lines in the band)"))
    return path


def read_subset(path: Path = SUBSET) -> dict[str, Any]:
    with np.load(path, allow_pickle=False) as z:
        return {"frf": si.FrequencyData(z["w"], z["H"], variance=z["variance"]), "coherence": z["coherence"],
                "lines": z["lines"], "U": z["U"], "Y": z["Y"]}


# -- model, fit, validation --------------------------------------------------------------------

def modal_model() -> si.SecondOrderModel:
    """Eight modes in modal coordinates, acceleration output (module notes, step 2)."""
    import sympy as sp

    b = si.parameters(" ".join(f"b{r}" for r in range(1, N_MODES + 1)))  # residues: either sign
    v = si.parameters(" ".join(f"v{r}" for r in range(1, N_MODES + 1)), positive=True)  # 2 ζ ω
    k = si.parameters(" ".join(f"k{r}" for r in range(1, N_MODES + 1)), positive=True)  # ω²
    return si.SecondOrderModel(M=sp.eye(N_MODES), V=sp.diag(*v), K=sp.diag(*k), B=sp.Matrix(b),
                               C=sp.ones(1, N_MODES), output="acceleration", parameters=[*b, *v, *k])


def modes(theta: dict[str, float]) -> list[tuple[float, float]]:
    """(natural frequency in Hz, damping ratio) of every mode, sorted by frequency."""
    out = []
    for r in range(1, N_MODES + 1):
        k, v = theta[f"k{r}"], theta[f"v{r}"]
        wn = np.sqrt(max(k, 0.0))
        out.append((wn / (2 * np.pi), v / (2 * wn) if wn > 0 else float("nan")))
    return sorted(out)


def validation_fit(model: Any, theta: Any, val: dict[str, np.ndarray]) -> tuple[float, np.ndarray, np.ndarray]:
    """Fit % of the band-passed steady-state validation output, and the two signals (module notes, step 4)."""
    w = 2 * np.pi * val["lines"] * FS / VAL_PERIOD
    H = model.frequency_response(theta, w)[:, 0, 0]
    full = VAL_PERIOD // 2 + 1

    def signal(X: np.ndarray) -> np.ndarray:
        spec = np.zeros((X.shape[0], full), dtype=complex)
        spec[:, val["lines"]] = X
        return np.fft.irfft(spec, VAL_PERIOD, axis=1).reshape(-1)

    y, y_hat = signal(val["Y"]), signal(H[None, :] * val["U"])
    fit = 100 * (1 - np.linalg.norm(y - y_hat) / np.linalg.norm(y - y.mean()))
    return float(fit), y, y_hat


ROUTES = {"lm": {"method": "lm"}, "auto": {"method": "auto"}, "ipopt": {"method": "ipopt"},
          "scr+polish": {"method": "scr", "polish": True}}
NOTES_HZ = (3.5, 4.0, 5.2, 6.6, 7.3, 9.2)  # the data notes' structural modes
TARGET = 71.0  # validation fit % of a hand-started fit (data notes)


def structural_modes(theta: dict[str, float]) -> list[tuple[float, float]]:
    """The lightly damped modes (ζ < 10 %) between 3 and 10 Hz."""
    return [m for m in modes(theta) if 3.0 < m[0] < 10.0 and m[1] < 0.1]


def quick_checks(theta: dict[str, float], fit: float) -> list[str]:
    """What the data notes say, checked on an estimate: the failures, if any."""
    failures = []
    if not fit >= TARGET:
        failures.append(f"validation fit {fit:.1f} % < {TARGET:g} %")
    found = [m[0] for m in structural_modes(theta)]
    if len(found) != len(NOTES_HZ) or not np.allclose(found, NOTES_HZ, rtol=0.03):
        failures.append(f"structural modes {np.round(found, 2).tolist()} Hz, not within 3 % of {list(NOTES_HZ)}")
    return failures


def fit_routes(model: Any, frf: si.FrequencyData, *, methods: list[str], starts: int, time_limit: float
               ) -> dict[str, Any]:
    """The chosen routes with the library's starts; each result kept with its wall time."""
    routes: dict[str, Any] = {}
    for name in methods:
        kw = ROUTES[name]
        t0 = time.perf_counter()
        res = si.identify(model, frf, starts=starts, seed=0, time_limit=time_limit, identifiability_check=False,
                          **kw)
        best = res.polished if res.polished is not None and res.polished.cost <= res.cost else res
        routes[name] = {"result": best, "seconds": time.perf_counter() - t0}
    return routes


# -- plots -------------------------------------------------------------------------------------

def plots(out: Path, parts: dict[str, Any], model: Any, theta: Any, y: np.ndarray, y_hat: np.ndarray, fit: float
          ) -> list[Path]:
    import matplotlib

    if not os.environ.get("DISPLAY"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from symid.plots import frf_estimate_plot

    out.mkdir(parents=True, exist_ok=True)
    paths = [frf_estimate_plot(parts["frf"], out / "f16_frf.png", coherence=parts["coherence"], unit="(m/s²)/N",
                               estimates={"modal grey box": (model, theta)},
                               title="F-16 GVT: force → acceleration (sensor 1), periods 2–9")]
    t = np.arange(y.size) / FS
    fig, (ax, ax_e) = plt.subplots(2, 1, sharex=True, figsize=(9, 5.5), gridspec_kw={"height_ratios": [2, 1]})
    show = t < 4.0
    ax.plot(t[show], y[show], "k", lw=0.9, label="measured, band-passed 2–15 Hz")
    ax.plot(t[show], y_hat[show], "tab:orange", lw=0.9, ls="--", label="modal grey box")
    ax.set_ylabel("acceleration (m/s²)")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"Validation record, steady state (first 4 s of 82 s shown): fit {fit:.1f} %")
    ax_e.plot(t[show], (y - y_hat)[show], "tab:red", lw=0.8)
    ax_e.set_ylabel("error (m/s²)")
    ax_e.set_xlabel("time (s)")
    for a in (ax, ax_e):
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "f16_validation.png", dpi=110)
    plt.close(fig)
    paths.append(out / "f16_validation.png")
    return paths


# -- main --------------------------------------------------------------------------------------

def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="folder holding the two F-16 .mat files (default: $SYMID_F16_DATA)")
    ap.add_argument("--quick", action="store_true",
                    help="the committed subset, one start of 'lm', then the data notes' facts are checked")
    ap.add_argument("--methods", default=None,
                    help=f"routes, comma-separated, of {', '.join(ROUTES)} (default all; --quick lm)")
    ap.add_argument("--make-subset", action="store_true", help="rewrite examples/data/f16_subset.npz and stop")
    ap.add_argument("--starts", type=int, default=None, help="starts per route (default 5; --quick 1)")
    ap.add_argument("--time-limit", type=float, default=None, help="seconds per start (default 120; --quick 60)")
    ap.add_argument("--out", default="f16-out", help="folder for the figures (default ./f16-out)")
    args = ap.parse_args(argv)

    if args.quick and not args.data:
        parts = read_subset()
        print(f"data: the committed subset {SUBSET.name}")
    else:
        folder = data_folder(args.data)
        parts = analyse_records(folder)
        print(f"data: {folder}")
        if args.make_subset:
            print(f"written {write_subset(parts)}")
            return 0
    frf = parts["frf"]
    rel_noise = np.sqrt(frf.variance[:, 0, 0]) / np.abs(frf.H[:, 0, 0])
    print(f"FRF: {frf.n_frequencies} lines over {BAND_HZ[0]:g}-{BAND_HZ[1]:g} Hz, noise std / |H| median "
          f"{np.median(rel_noise):.2e} (max {rel_noise.max():.2e}), coherence min {parts['coherence'].min():.4f}")

    model = modal_model()
    starts = args.starts or (1 if args.quick else 5)
    limit = args.time_limit or (60.0 if args.quick else 120.0)
    methods = (args.methods or ("lm" if args.quick else ",".join(ROUTES))).split(",")
    unknown = [m for m in methods if m not in ROUTES]
    if unknown:
        ap.error(f"unknown route(s) {', '.join(unknown)}; choose from {', '.join(ROUTES)}")
    plain = si.FrequencyData(frf.w, frf.H)  # for the unweighted relative misfit printed beside each criterion
    t0 = time.perf_counter()
    start = black_box_start(model, frf, seed=0)  # what identify makes its first start (the library's own)
    if start is None:
        print("start: no black-box start (the library draws around typical values)")
    else:
        fit0, _, _ = validation_fit(model, model.theta_dict(start.theta), parts)
        print(f"start (black box, {time.perf_counter() - t0:.1f} s): vector fit of {model.n_states} poles, relative "
              f"rms {start.black_box_error:.3f}; the start's relative misfit "
              f"{relative_misfit(model, plain, start.theta):.4f}, validation fit {fit0:.1f} %")
    routes = fit_routes(model, frf, methods=methods, starts=starts, time_limit=limit)
    best_name, best = None, None
    for name, r in routes.items():
        res = r["result"]
        fit, _, _ = validation_fit(model, res.theta, parts)
        r["validation"] = fit
        unweighted = relative_misfit(model, plain, res.theta_vector)
        print(f"{name:>11}: FRF misfit {res.cost:.4f} (unweighted {unweighted:.4f}), success {res.success}, "
              f"{r['seconds']:.0f} s for {starts} start(s); validation fit {fit:.1f} %")
        print(f"{'':>13}fit test: {res.fit}")
        if best is None or res.cost < best.cost:
            best_name, best = name, res
    print(f"best route: {best_name}; modes (Hz, damping ratio):")
    for f_hz, zeta in modes(best.theta):
        print(f"  {f_hz:7.3f} Hz  ζ = {zeta:.4f}")
    fit, y, y_hat = validation_fit(model, best.theta, parts)
    out = Path(args.out)
    for p in plots(out, parts, model, best.theta, y, y_hat, fit):
        print(f"figure: {p}")
    failures = quick_checks(best.theta, fit) if args.quick else []
    if args.quick and not failures:
        print(f"checked: validation fit >= {TARGET:g} %, the six structural modes within 3 % of the data notes'")
    print(f"validation fit: {fit:.1f} %")
    if failures:
        raise SystemExit("f16_gvt --quick: " + "; ".join(failures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
