"""EMPS, a real positioning system: mass, viscous and Coulomb friction and offset from measured samples.

Run::

    .venv/bin/python examples/emps.py --data DIR          # DIR holds DATA_EMPS.mat and DATA_EMPS_PULSES.mat
    SYMID_EMPS_DATA=DIR .venv/bin/python examples/emps.py  # the same, the folder from the environment
    .venv/bin/python examples/emps.py --quick             # the committed cut examples/data/emps_subset.npz
    .venv/bin/python examples/emps.py --data DIR --make-subset   # rewrite that cut
    (add --out DIR for the validation figures)

The data
--------
The Electro-Mechanical Positioning System benchmark (Janot, Gautier & Brunot, "Data Set
and Reference Models of EMPS", 2019, nonlinearbenchmark.org): a DC motor drives a
ball-screw axis, 1 kHz samples of the motor-side position ``qm`` (m), the reference
``qg`` and the controller output ``vir`` (V); the applied force is τ = gτ·vir, gτ = 35.15
N/V. A PD controller closes the loop (vir = kv (kp (qg − q) − q̇), kp = 160.18 1/s,
kv = 243.45 V s/m). ``DATA_EMPS.mat`` (24.84 s) is for estimation, ``DATA_EMPS_PULSES.mat``
(the same motion with 5 V force pulses added to vir, ``pulses_N``) for validation. The
files are not part of symid: ``--data DIR`` or ``SYMID_EMPS_DATA`` name their folder (an
error says so otherwise). ``examples/data/emps_subset.npz`` holds a cut — the first two
cycles of the motion (12.48 s) of the estimation file and the first cycle (6.24 s) of
the validation file; positions exactly (encoder counts), the other signals to float32
precision, about 200 kB — for ``--quick``, which the test suite runs.

The model and the published values
----------------------------------
M q̈ + Fv q̇ + Fc sign(q̇) + offset = τ, a ``SecondOrderModel`` (K = 0) with three
measured inputs u = (τ, sign(q̇), 1) and B = [1, −Fc, −offset]; sign(q̇) is the sign of
the central difference of the measured position (it changes 7 times in 24.84 s, cleanly:
a 50 Hz filter first changes no sample). The benchmark document's inverse-model least
squares gives M = 95.1089 kg, Fv = 203.5034 N s/m, Fc = 20.3935 N, offset = −3.1648 N.

The route: ``method="svf"``
---------------------------
Both sides of the model equation pass through the same filter λ³/(s + λ)³, whose states
are the filtered position and its first two derivatives exactly; θ is then one linear
least squares over all 24 841 samples, refined by instrumental-variable steps
(:mod:`symid.fit.timeseries.svf`). No decimation and no numerical derivative; the
bandwidth is the library default 0.1/Δt = 100 rad/s (16 Hz). ``hold="foh"``: τ is
taken, like q, as varying linearly between samples (the motor current follows the
amplifier, not a staircase), which is also how the published least squares treats it.

Measured (``--sweep --oe``; relative error to the published values, %)::

    route                                       M       Fv      Fc      offset
    svf (default λ = 100 rad/s, foh, 5 IV)     −0.24   +0.61   −0.32   +0.40
    svf, λ = 2π·10 … 2π·50 rad/s               −0.39 … +0.06, +0.43 … +0.97, −0.68 … −0.17, +0.18 … +0.63
    svf, λ = 2π·5 / 2π·100 rad/s               offset +1.17 / Fv +1.21 (the rest within 1 %)
    svf, hold="zoh" (default λ)                −0.33   +2.04   −1.36   +0.39
    inverse-dynamics LS (baseline)             −0.11   +0.58   −0.58   −0.40
    oe, open loop (τ input)                    +1.01   +17.45  −16.84  −0.11
    oe, closed loop (input qg, nominal gains)  −13.2   −335    −1.46   +0.11

The baseline is the ten-line inverse-dynamics least squares: the position filtered by a
4th-order zero-phase Butterworth filter at 50 Hz, central differences for q̇ and q̈,
least squares of τ on (q̈, q̇, sign q̇, 1) over all samples.

Why not ``oe``? The position is the integral of the force balance: any force the model
lacks — the benchmark itself reports asymmetric viscous friction, 166.7 against
240.4 N s/m by direction — integrates into a drift of the simulated position (misfit
3.5e-4, residual far from white), which output error absorbs by trading Fv against Fc
(+17 % / −17 %). Simulated in closed loop with the nominal controller (input qg), the
errors do not accumulate, but the continuous model then stands for a sampled controller:
its output is held over each 1-ms sample, a delay of about Δt/2, and through the loop
stiffness gτ·kv·kp = 1.37e6 N/m that delay acts as −gτ·kv·kp·Δt/2 ≈ −685 N s/m of
damping, which the fit puts into Fv (it moves by −681 N s/m, −335 %); the recorded vir
also departs from the nominal law (least-squares gains 1.0433 × kv·kp and 1.0453 × kv).
Equation-error routes (``svf``, the baseline) weigh each
instant's force balance alone and need neither. How far the four numbers move with the
route (Fv and Fc by about ±2 % against each other) is the size of what the symmetric
friction model leaves out, and the 1 % mark is met by the routes that weigh the data as
the published least squares does.

Validation
----------
On the validation record (and the estimation record), with ``si.validate`` from a
least-squares initial state, two simulations of the position:

* closed loop, as the benchmark does: the model with the known controller (inputs qg,
  the force pulses, sign(q̇), 1; the closed-loop ``SecondOrderModel``
  M q̈ + (Fv + gτ kv) q̇ + gτ kv kp q = gτ kv kp qg + gτ p − Fc s − offset has the same four
  parameters);
* open loop, stricter: the plant driven by the measured force τ.

Measured::

    parameters            closed loop: fit % / rms error     open loop: fit % / rms error
                          estimation        pulses           estimation        pulses
    published             99.946 / 44.3 µm  99.947 / 43.7 µm  96.128 / 3.20 mm  93.234 / 5.59 mm
    symid svf             99.946 / 44.3 µm  99.947 / 43.7 µm  96.064 / 3.25 mm  93.676 / 5.23 mm
    inverse-dynamics LS   99.946 / 44.3 µm  99.947 / 43.7 µm  96.197 / 3.14 mm  93.014 / 5.77 mm

In closed loop the controller corrects the model's force errors: the three parameter
sets leave the same 44 µm (what none of them models); in open loop the position
integrates them, and the drift of a few millimetres over 25 s is the friction the model
lacks (the residual is far from white in both).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

import symid as si

PUBLISHED = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "offset": -3.1648}  # the benchmark document (2019)
ESTIMATION, VALIDATION = "DATA_EMPS.mat", "DATA_EMPS_PULSES.mat"
SUBSET = Path(__file__).resolve().parent / "data" / "emps_subset.npz"
CUT = (12480, 6240)  # samples of the committed cut: two cycles of the motion, one cycle (period 6.24 s)
QM_STEP = 5e-8       # m, the encoder step: every qm of DATA_EMPS.mat is a whole number of it
FULL_TOL = 0.01      # issue 15: within 1 % of the published values on the full record
QUICK_TOL = {"M": 0.01, "Fv": 0.02, "Fc": 0.02, "offset": 0.05}  # the 12.48-s cut: measured −0.30, +0.80, −0.68, −3.5 %


class DataMissing(FileNotFoundError):
    """The benchmark files are not where ``--data`` or SYMID_EMPS_DATA say."""


# -- data ------------------------------------------------------------------------------------------

def data_folder(arg: str | None) -> Path:
    """The folder of the two .mat files: ``--data`` or ``SYMID_EMPS_DATA``; a clear error otherwise."""
    where = arg or os.environ.get("SYMID_EMPS_DATA")
    if not where:
        raise DataMissing("the EMPS benchmark files are not part of symid: pass --data DIR (the folder holding "
                          f"{ESTIMATION} and {VALIDATION}) or set SYMID_EMPS_DATA=DIR; --quick runs on the "
                          f"committed cut {SUBSET.name}")
    folder = Path(where)
    missing = [f for f in (ESTIMATION, VALIDATION) if not (folder / f).is_file()]
    if missing:
        raise DataMissing(f"{folder} does not hold {', '.join(missing)} (the EMPS benchmark files)")
    return folder


def read_record(path: Path) -> dict[str, np.ndarray | float]:
    """One benchmark file as arrays (t, qm, qg, vir, pulses) and the controller constants."""
    import scipy.io

    raw = scipy.io.loadmat(path)
    rec: dict[str, np.ndarray | float] = {k: np.asarray(raw[k], dtype=float).ravel() for k in ("t", "qm", "qg", "vir")}
    rec["pulses"] = (np.asarray(raw["pulses_N"], dtype=float).ravel() if "pulses_N" in raw
                     else np.zeros_like(rec["t"]))
    for k in ("gtau", "kp", "kv"):
        rec[k] = float(np.asarray(raw[k]).item())
    return rec


def make_subset(folder: Path) -> Path:
    """Write the committed cut: the first CUT samples of each file; positions exactly (as encoder counts of
    QM_STEP where they are whole counts), the other signals in float32 (7 digits)."""
    est, val = read_record(folder / ESTIMATION), read_record(folder / VALIDATION)
    arrays = {}
    for name, rec, n in (("est", est, CUT[0]), ("val", val, CUT[1])):
        qm = np.asarray(rec["qm"])[:n]
        counts = np.round(qm / QM_STEP)
        if np.max(np.abs(counts * QM_STEP - qm)) <= 1e-12:
            arrays[f"{name}_qm_counts"] = counts.astype(np.int32)
        else:  # the validation file's positions are not whole encoder steps: kept as they are
            arrays[f"{name}_qm"] = qm
        for k in ("t", "qg", "vir"):
            arrays[f"{name}_{k}"] = np.asarray(rec[k])[:n].astype(np.float32)
        arrays[f"{name}_pulses"] = np.asarray(rec["pulses"])[:n].astype(np.uint8)
        for k in ("gtau", "kp", "kv"):
            arrays[f"{name}_{k}"] = np.array(rec[k])
    SUBSET.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(SUBSET, **arrays)
    return SUBSET


def read_subset() -> tuple[dict, dict]:
    """The committed cut (estimation, validation)."""
    with np.load(SUBSET, allow_pickle=False) as z:
        out = []
        for name in ("est", "val"):
            rec = {k: np.asarray(z[f"{name}_{k}"], dtype=float) for k in ("t", "qg", "vir", "pulses")}
            rec["qm"] = (np.asarray(z[f"{name}_qm_counts"], dtype=float) * QM_STEP if f"{name}_qm_counts" in z
                         else np.asarray(z[f"{name}_qm"], dtype=float))
            rec.update({k: float(z[f"{name}_{k}"]) for k in ("gtau", "kp", "kv")})
            out.append(rec)
    return out[0], out[1]


# -- models ----------------------------------------------------------------------------------------

def plant_model() -> si.SecondOrderModel:
    """M q̈ + Fv q̇ = τ − Fc sign(q̇) − offset, inputs (τ, sign q̇, 1), position output."""
    M, Fv, Fc, offset = si.parameters("M Fv Fc offset")
    return si.SecondOrderModel(M=[[M]], V=[[Fv]], K=[[0]], B=[[1, -Fc, -offset]], C=[[1]],
                               parameters=[M, Fv, Fc, offset])


def closed_loop_model(rec: dict) -> si.SecondOrderModel:
    """The plant under vir = kv (kp (qg − q) − q̇) + pulses: inputs (qg, pulses, sign q̇, 1)."""
    M, Fv, Fc, offset = si.parameters("M Fv Fc offset")
    g, kp, kv = rec["gtau"], rec["kp"], rec["kv"]
    return si.SecondOrderModel(M=[[M]], V=[[Fv + g * kv]], K=[[g * kv * kp]], B=[[g * kv * kp, g, -Fc, -offset]],
                               C=[[1]], parameters=[M, Fv, Fc, offset])


def velocity_sign(rec: dict) -> np.ndarray:
    """sign(q̇) from the central difference of the measured position."""
    return np.sign(np.gradient(rec["qm"], rec["t"]))


def plant_data(rec: dict) -> si.TimeSeries:
    tau = rec["gtau"] * rec["vir"]
    u = np.column_stack([tau, velocity_sign(rec), np.ones_like(tau)])
    return si.TimeSeries(rec["t"], u, rec["qm"])


def closed_loop_data(rec: dict) -> si.TimeSeries:
    u = np.column_stack([rec["qg"], rec["pulses"], velocity_sign(rec), np.ones_like(rec["t"])])
    return si.TimeSeries(rec["t"], u, rec["qm"])


# -- estimates -------------------------------------------------------------------------------------

def inverse_dynamics_ls(rec: dict, cutoff_hz: float = 50.0) -> dict[str, float]:
    """The baseline: Butterworth-filtered position (zero phase), central differences, least squares."""
    import scipy.signal

    t, fs = rec["t"], 1.0 / float(np.median(np.diff(rec["t"])))
    b, a = scipy.signal.butter(4, cutoff_hz / (fs / 2))
    dq = np.gradient(scipy.signal.filtfilt(b, a, rec["qm"]), t)
    ddq = np.gradient(dq, t)
    X = np.column_stack([ddq, dq, np.sign(dq), np.ones_like(dq)])
    theta = np.linalg.lstsq(X, rec["gtau"] * rec["vir"], rcond=None)[0]
    return dict(zip(PUBLISHED, theta.tolist(), strict=True))


def controller_gains(rec: dict) -> np.ndarray:
    """Least-squares gains of vir − pulses on the control law's two terms kv·kp (qg − q) and −kv q̇ (q̇ the
    backward difference, as a sampled controller computes it), relative to the nominal ones (1 = nominal)."""
    q, dq = rec["qm"], np.r_[0.0, np.diff(rec["qm"])] / np.r_[1.0, np.diff(rec["t"])]
    X = np.column_stack([rec["kv"] * rec["kp"] * (rec["qg"] - q), -rec["kv"] * dq])
    return np.linalg.lstsq(X, rec["vir"] - rec["pulses"], rcond=None)[0]


def relative_errors(theta: dict[str, float]) -> dict[str, float]:
    return {k: theta[k] / PUBLISHED[k] - 1 for k in PUBLISHED}


def row(label: str, theta: dict[str, float]) -> str:
    err = relative_errors(theta)
    return f"{label:<34s}" + "".join(f"{theta[k]:>10.4f} ({100 * err[k]:+6.2f} %)" for k in PUBLISHED)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="folder holding the two EMPS .mat files (default: $SYMID_EMPS_DATA)")
    ap.add_argument("--quick", action="store_true", help="the committed cut (what the test suite runs)")
    ap.add_argument("--make-subset", action="store_true", help="rewrite examples/data/emps_subset.npz and stop")
    ap.add_argument("--oe", action="store_true", help="also fit oe, open and closed loop (about half a minute)")
    ap.add_argument("--sweep", action="store_true", help="also svf over filter bandwidths 5-100 Hz and hold='zoh'")
    ap.add_argument("--out", help="folder for the validation figures (PNG)")
    args = ap.parse_args(argv)
    try:
        if args.make_subset:
            print(f"wrote {make_subset(data_folder(args.data))}")
            return 0
        if args.quick and not args.data:
            est, val = read_subset()
            print(f"data: the committed cut {SUBSET.name} ({est['t'].size} + {val['t'].size} samples)")
        else:
            folder = data_folder(args.data)
            est, val = read_record(folder / ESTIMATION), read_record(folder / VALIDATION)
            print(f"data: {folder} ({est['t'].size} + {val['t'].size} samples)")
    except DataMissing as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    plant = plant_model()
    res = si.identify(plant, plant_data(est), method="svf", hold="foh", initial_state="estimate",
                      identifiability_check=False)
    baseline = inverse_dynamics_ls(est)
    print(f"\n{'estimate':<34s}" + "".join(f"{k:>21s}" for k in PUBLISHED))
    print(row("published (inverse-model LS)", PUBLISHED))
    print(row("symid svf (default λ, foh, IV)", res.theta))
    print(row("inverse-dynamics LS baseline", baseline))
    print(f"svf: {res.message}")
    if args.sweep:
        for hz in (5, 10, 20, 30, 50, 100):
            r = si.identify(plant, plant_data(est), method="svf", hold="foh", bandwidth=2 * np.pi * hz,
                            initial_state="estimate", identifiability_check=False)
            print(row(f"svf λ = 2π·{hz} rad/s", r.theta))
        r = si.identify(plant, plant_data(est), method="svf", initial_state="estimate", identifiability_check=False)
        print(row("svf hold='zoh' (default λ)", r.theta))
    if args.oe:
        oe = si.identify(plant, plant_data(est), method="oe", x0=res.theta, initial_state="estimate",
                         identifiability_check=False)
        print(row("symid oe, open-loop position", oe.theta))
        print(f"  oe: {oe.fit}")
        cl = si.identify(closed_loop_model(est), closed_loop_data(est), method="oe", x0=res.theta,
                         initial_state="estimate", identifiability_check=False)
        print(row("symid oe, closed loop (nominal gains)", cl.theta))
        gains = controller_gains(est)
        print(f"  the recorded vir against the control law: gains {gains[0]:.4f} × kv·kp and {gains[1]:.4f} × kv")
    print("\nvalidation (si.validate, least-squares initial state): simulated against measured position")
    print(f"{'parameters':<30s} {'simulation':<30s} {'record':<11s} {'fit %':>8s} {'rms error (µm)':>15s}")
    figures = []
    views = (("closed loop, input qg", closed_loop_model, closed_loop_data),
             ("open loop, measured force", lambda rec: plant, plant_data))
    for label, theta in (("published", PUBLISHED), ("symid svf", res.theta), ("inverse-dynamics LS", baseline)):
        for view, make_model, make_data in views:
            for rec_name, rec in (("estimation", est), ("pulses", val)):
                v = si.validate(make_model(rec), theta, make_data(rec), initial_state="estimate")
                print(f"{label:<30s} {view:<30s} {rec_name:<11s} {v.fit_percent[0]:>8.3f} "
                      f"{1e6 * v.rms_error[0]:>15.1f}")
                if args.out and label == "symid svf" and rec_name == "pulses":
                    inputs = (["reference qg", "force pulses", "sign(dq/dt)", "constant"] if view.startswith("closed")
                              else ["force tau", "sign(dq/dt)", "constant"])
                    figures += v.plot(Path(args.out) / f"emps_{view.split(',')[0].replace(' ', '_')}",
                                      output_names=["motor position"], output_units=["m"], input_names=inputs,
                                      title=f"EMPS pulses record, symid svf estimate, {view}")
    for f in figures:
        print(f"figure: {f}")
    tol = QUICK_TOL if args.quick and not args.data else {k: FULL_TOL for k in PUBLISHED}
    err = relative_errors(res.theta)
    bad = {k: f"{100 * e:+.2f} %" for k, e in err.items() if abs(e) > tol[k]}
    assert not bad, f"svf estimate off the published values beyond {tol}: {bad}"
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
