"""Output-only identification of M, V, K from estimated power spectra (thesis ch. 5, issue 6 item 4).

Run: python examples/psd_output_only.py [--out DIR] [--seed S] [--backend admm|cvxpy] [--repeat K] [--quick]

``--quick`` is the reduced variant the test suite runs: 30 s of record, nperseg 1024, SCR
only, and every parameter asserted within ``QUICK_TOL`` (shorter records and segments
give larger errors; see the module notes on Welch settings).

The experiment
--------------
A two-storey frame, the 2-DOF chain of thesis (4-19) with both positions measured
(C = I), is shaken on the first mass by a white-noise force of known intensity
φ = 1 N²·s (E[u(t) u(s)] = φ δ(t − s)) that the estimator never sees. Truth:
m1 = m2 = 1 kg, c1 = 40 and c2 = 5 N·s/m, k1 = 20 and k2 = 10 kN/m: modes at 76.7 and
184.4 rad/s (12.2 and 29.4 Hz), damping ratios 4.8 % and 11.6 %. Five minutes are
recorded at dt = 1 ms (N = 300 000 samples after 2 s of discarded start-up, about 50
decay times of the slow mode), simulated by ``si.simulate_io`` with the force held
between samples at variance φ/dt. Then, output-only::

    spec = si.estimate_spectra(y, dt=dt, Phi_uu=φ, band=(23, 370), nperseg=4096)
    res = si.identify(model, spec, method="scr", backend="admm")     # Algorithm 5.1

Asserted: every parameter and each of M, V, K (Frobenius) within 5 % of the truth (issue 6
item 4). Printed for comparison: IPOPT on (5-13) from the same starts, and the Cramér–Rao
lower bound of the record. A figure compares the Welch estimate with the model spectra
at the truth and at the estimate.

Why not the thesis values (4-20)?
---------------------------------
With m1 = m2 = 1, c1 = 0.1, c2 = 0.3, k1 = 2, k2 = 1 the slow mode has a period of 8 s and
c1 carries only 14 % of either mode's damping: from five minutes of output-only data no
unbiased estimator can know c1 to better than ±91 % (one standard deviation; the
Cramér–Rao bound this script prints). Damping is learnt per cycle: the relative
uncertainty of a modal damping ratio falls like 1/√(ζ ω T). The frame above is the same
chain at laboratory scale (modes ~100 times faster), with c1 the main damper, so that a
few minutes hold enough cycles: its bound is 0.5–1.6 % for all six parameters.

Why these Welch settings?
-------------------------
Segments of nperseg = 4096 samples (4.1 s) give bins Δω = 1.53 rad/s apart and a Hann
resolution (equivalent noise bandwidth 1.5 bins) of 2.3 rad/s, against a half-power
bandwidth 2ζω = 7.4 rad/s of the sharper mode: the window's smoothing bias at the peak,
≈ (1/3)(2.3/7.4)² ≈ 3 %, shrinks to a few tenths of a percent in the damping
estimates. Every bin in 23–370 rad/s (0.3 ω1 to 2 ω2, 227 bins, each the average of 145
half-overlapping segments) is used: thinning them to log-spaced points throws away
averaging, and shorter segments bias the damping upwards. Measured with ``--repeat``
(rms / mean of the relative errors over the seeds, in %, c1 the worst parameter):

=========================  ======  ================  =============  ================
settings                   seeds   c1 rms / mean     c2 rms / mean  worst |error|
=========================  ======  ================  =============  ================
nperseg 4096, all bins     40      1.63 / +0.13      1.27 / +0.35   4.40
nperseg 2048, all bins     12      2.19 / +1.51      1.04 / +0.67   4.60
=========================  ======  ================  =============  ================

(shorter segments: the damping bias is visible; 4096 is close to the Cramér–Rao bound,
1.57 % for c1 and 0.72 % for c2.) The held force's spectrum is φ·sinc²(ω dt/2), 1.1 %
below φ at the top of the band; ``--zoh`` passes that exact spectrum instead of φ and
moves the mean errors by less than 0.3 %.

Units and back ends
-------------------
Stiffness is in kN/m (the model multiplies by 1000) so that the six parameters are of
similar size, 1 to 40. The ADMM back end needs that: with k in N/m (θ from 1 to 20 000)
its first iterates collapse to θ ≈ 0 and it ends at 100 % error, while Clarabel is not
affected. With kN/m both back ends give the same estimate; ADMM takes ~8 s per start,
the cvxpy/Clarabel back end ~4 s per SCR iteration on these 227 frequencies (~3 min per
start). SCR reports "maximum number of iterations" rather than success: on noisy
spectra X Pᵢ Xᴴ = Qᵢ cannot hold, so the residual stopping rule is never met, but the
iterate is stationary after ~13 iterations.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import symid as si
from symid.progress import progress_bar

TRUTH = {"m1": 1.0, "m2": 1.0, "c1": 40.0, "c2": 5.0, "k1": 20.0, "k2": 10.0}  # kg, N·s/m, kN/m
THESIS = {"m1": 1.0, "m2": 1.0, "c1": 0.1, "c2": 0.3, "k1": 0.002, "k2": 0.001}  # thesis (4-20), k in kN/m
PHI = 1.0  # force intensity, N²·s
DT = 1e-3  # s
BAND = (23.0, 370.0)  # rad/s: 0.3 ω1 to 2 ω2
TOL = 0.05  # issue 6 item 4: M, V, K within 5 % relative error
QUICK_TOL = 0.15  # --quick: 3 × the worst Cramér–Rao std. of a 30 s record (c1: 5.0 %); seeds 0–2 gave ≤ 7.4 %
BURN_IN = 2.0  # s of start-up discarded


def frame_model() -> si.SecondOrderModel:
    """Thesis (4-19): force on mass 1, both positions measured; stiffness in kN/m."""
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    kn = 1000  # N/m per kN/m
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[kn * (k1 + k2), -kn * k2], [-kn * k2, kn * k2]], B=[[1], [0]],
                               C=[[1, 0], [0, 1]])


def modes(model: si.SecondOrderModel, theta: dict) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequencies (rad/s) and damping ratios, slowest first."""
    lam = np.linalg.eigvals(model.state_space(theta).A)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(np.abs(lam))]
    return np.abs(lam), -lam.real / np.abs(lam)


def simulate(model: si.SecondOrderModel, seed: int, duration: float) -> np.ndarray:
    """Positions (N, 2) of ``duration`` seconds under the white force, start-up discarded."""
    skip, n = round(BURN_IN / DT), round(duration / DT)
    force = np.random.default_rng(seed).standard_normal(skip + n) * np.sqrt(PHI / DT)  # intensity φ
    return si.simulate_io(model, TRUTH, force, DT).y[skip:]


def input_spectrum(zoh: bool):
    """φ, or the exact spectrum φ·sinc²(ω dt/2) of the force held between samples."""
    if not zoh:
        return PHI
    return lambda w: PHI * np.sinc(w * DT / (2 * np.pi)) ** 2  # np.sinc(x) = sin(πx)/(πx)


def cramer_rao(model: si.SecondOrderModel, theta: dict, band: tuple[float, float], duration: float,
               n_grid: int = 4000) -> np.ndarray:
    """Relative Cramér–Rao bounds (standard deviations) of θ from output-only spectra.

    One white force and noise-free sensors on every DOF: the cross spectra give the
    ratios hⱼ/h₁ of H = C X⁻¹ B exactly, and only Φ₁₁ = φ|h₁|² carries the sampling
    noise of a spectrum estimate. Whittle's approximation gives the Fisher information
    of the periodogram ordinates in the band, (duration/2π) ∫ ∇log Φ₁₁ ∇log Φ₁₁ᵀ dω,
    here restricted to the directions of log θ that keep the ratios fixed.
    """
    w = np.linspace(*band, n_grid)
    vec = model.theta_vector(theta)

    def parts(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        h = model.frequency_response(th, w)[:, :, 0]
        ratio = h[:, 1:] / h[:, :1]
        return np.log(np.abs(h[:, 0]) ** 2), np.concatenate([ratio.real.ravel(), ratio.imag.ravel()])

    step = 1e-6
    grads, ratios = [], []
    for k in range(vec.size):  # central differences in log θₖ
        up, down = vec.copy(), vec.copy()
        up[k] *= np.exp(step)
        down[k] *= np.exp(-step)
        (g_up, r_up), (g_down, r_down) = parts(up), parts(down)
        grads.append((g_up - g_down) / (2 * step))
        ratios.append((r_up - r_down) / (2 * step))
    _, sv, vt = np.linalg.svd(np.array(ratios).T)
    free = vt[int(np.sum(sv > 1e-8 * sv[0])):].T
    G = np.array(grads).T @ free  # (frequencies, free directions)
    fisher = G.T @ G * (w[1] - w[0]) * duration / (2 * np.pi)
    return np.sqrt(np.diag(free @ np.linalg.inv(fisher) @ free.T))


def matrix_errors(model: si.SecondOrderModel, theta: np.ndarray) -> dict[str, float]:
    """‖X̂ − X‖_F / ‖X‖_F for X = M, V, K."""
    est, ref = model.matrices(theta), model.matrices(TRUTH)
    return {k: float(np.linalg.norm(est[k] - ref[k]) / np.linalg.norm(ref[k])) for k in "MVK"}


def report(label: str, model: si.SecondOrderModel, res: si.IdentificationResult) -> np.ndarray:
    """Print truth / estimate / relative error per parameter and per matrix; return the errors."""
    truth = model.theta_vector(TRUTH)
    err = (res.theta_vector - truth) / truth
    print(f"\n{label}: {res.n_starts} start(s), {res.wall_time:.1f} s; best start: {res.message}")
    print(f"  {'parameter':>9s} {'truth':>9s} {'estimate':>10s} {'rel. error':>11s}")
    for name, t, e, r in zip(model.parameter_names, truth, res.theta_vector, err, strict=True):
        print(f"  {name:>9s} {t:9.4g} {e:10.5g} {r:+11.2%}")
    mats = matrix_errors(model, res.theta_vector)
    print("  M, V, K: " + ", ".join(f"{k} {v:.2%}" for k, v in mats.items()) + " (Frobenius)")
    return np.concatenate([np.abs(err), list(mats.values())])


def plot_spectra(model: si.SecondOrderModel, spec: si.SpectralData, welch_all: si.SpectralData,
                 estimate: np.ndarray, path: Path, title: str) -> Path:
    """|Φyy[a, b]| of the Welch estimate against the model at the truth and at the estimate."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    grid = np.geomspace(BAND[0] / 3, BAND[1] * 3, 800)
    curves = {"model at the truth": (TRUTH, "-", "k"), "model at the SCR estimate": (estimate, "--", "C3")}
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5), sharex=True)
    for a in range(2):
        for b in range(2):
            ax = axes[a, b]
            keep = (welch_all.w >= grid[0]) & (welch_all.w <= grid[-1])
            ax.loglog(welch_all.w[keep], np.abs(welch_all.Phi_yy[keep, a, b]), ".", ms=2, color="0.7",
                      label="Welch, outside the band")
            ax.loglog(spec.w, np.abs(spec.Phi_yy[:, a, b]), ".", ms=3, color="C0", label="Welch, fitted bins")
            for label, (theta, style, color) in curves.items():
                Phi = si.simulate_spectra(model, theta, grid, PHI).Phi_yy[:, a, b]
                ax.loglog(grid, np.abs(Phi), style, color=color, lw=1.3, label=label)
            for edge in BAND:
                ax.axvline(edge, color="0.5", lw=0.6, ls=":")
            ax.set_title(f"|Φyy[{a + 1},{b + 1}]|")
            ax.grid(True, which="both", alpha=0.3)
            if a == 1:
                ax.set_xlabel("ω (rad/s)")
            if b == 0:
                ax.set_ylabel("m²·s (two-sided, per rad/s / 2π)")
    axes[0, 0].legend(fontsize=8, loc="lower left")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def single_run(args: argparse.Namespace, model: si.SecondOrderModel) -> None:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    w_modes, zeta = modes(model, TRUTH)
    print(f"truth: {TRUTH} (kg, N·s/m, kN/m); modes {np.round(w_modes, 1)} rad/s, damping ratios "
          f"{np.round(zeta, 3)}")
    t0 = time.perf_counter()
    y = simulate(model, args.seed, args.duration)
    t1 = time.perf_counter()
    spec = si.estimate_spectra(y, dt=DT, Phi_uu=input_spectrum(args.zoh), band=BAND, nperseg=args.nperseg)
    t2 = time.perf_counter()
    print(f"record: {y.shape[0]} samples ({args.duration:g} s at dt = {DT:g} s), seed {args.seed}; simulated in "
          f"{t1 - t0:.1f} s. Welch (nperseg {args.nperseg}): {spec.w.size} bins in {BAND} rad/s, {t2 - t1:.1f} s")
    crb = cramer_rao(model, TRUTH, BAND, args.duration)
    print("Cramér–Rao bound (rel. std.) for this record: "
          + ", ".join(f"{n} {v:.2%}" for n, v in zip(model.parameter_names, crb, strict=True)))
    w_thesis = modes(model, THESIS)[0]
    crb_thesis = cramer_rao(model, THESIS, (0.3 * w_thesis[0], 2 * w_thesis[1]), args.duration)
    print("  the same for the thesis values (4-20) and the same duration: "
          + ", ".join(f"{n} {v:.0%}" for n, v in zip(model.parameter_names, crb_thesis, strict=True)))

    scr = si.identify(model, spec, method="scr", backend=args.backend, starts=args.starts, seed=args.seed)
    scr_err = report(f"SCR (Algorithm 5.1, {args.backend})", model, scr)
    if not args.quick:
        ipopt = si.identify(model, spec, method="ipopt", starts=args.starts, seed=args.seed)
        report("IPOPT on (5-13), the same starts (for comparison, not asserted)", model, ipopt)

    path = plot_spectra(model, spec, si.estimate_spectra(y, dt=DT, Phi_uu=PHI, nperseg=args.nperseg),
                        scr.theta_vector, out / "spectra.png",
                        f"Output-only 2-DOF frame: Welch estimate of {args.duration:g} s (nperseg {args.nperseg}) "
                        f"against the model spectra; SCR max. rel. error {scr_err[:6].max():.2%}")
    print(f"\nplot: {path}   total time {time.perf_counter() - t0:.1f} s")
    tol = QUICK_TOL if args.quick else TOL
    assert np.all(scr_err <= tol), f"SCR misses the {tol:.0%} target: {scr_err}"


def repeated_runs(args: argparse.Namespace, model: si.SecondOrderModel) -> None:
    """The distribution of the SCR errors over ``args.repeat`` seeds (the numbers of the module notes)."""
    truth = model.theta_vector(TRUTH)
    seeds = range(args.seed, args.seed + args.repeat)
    errors = []
    print(f"SCR ({args.backend}) on {args.repeat} records of {args.duration:g} s, nperseg {args.nperseg}, "
          f"input spectrum {'φ·sinc²(ω dt/2)' if args.zoh else 'φ'}")
    for seed in progress_bar(seeds, desc="records"):
        spec = si.estimate_spectra(simulate(model, seed, args.duration), dt=DT, Phi_uu=input_spectrum(args.zoh),
                                   band=BAND, nperseg=args.nperseg)
        res = si.identify(model, spec, method="scr", backend=args.backend, starts=args.starts, seed=seed,
                          identifiability_check=False)
        errors.append((res.theta_vector - truth) / truth)
        print(f"  seed {seed:3d}: " + " ".join(f"{e:+7.2%}" for e in errors[-1]))
    E = np.array(errors)
    names = model.parameter_names
    print(f"{len(names) * ' ':>12s}" + " ".join(f"{n:>7s}" for n in names))
    print(f"{'rms':>12s}" + " ".join(f"{v:7.2%}" for v in np.sqrt(np.mean(E**2, axis=0))))
    print(f"{'mean':>12s}" + " ".join(f"{v:+7.2%}" for v in E.mean(axis=0)))
    print(f"{'worst |err|':>12s}" + " ".join(f"{v:7.2%}" for v in np.abs(E).max(axis=0)))
    inside = int(np.sum(np.abs(E).max(axis=1) <= TOL))
    print(f"records with every parameter within {TOL:.0%}: {inside}/{len(E)}")


def main(argv: list[str] | None = None) -> int:
    """Run the example with command-line arguments ``argv`` (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="./psd-output-only/", help="directory of the PNG (default %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the force and of the starts")
    parser.add_argument("--duration", type=float, default=300.0, help="seconds recorded (default %(default)s)")
    parser.add_argument("--nperseg", type=int, default=4096, help="samples per Welch segment (default %(default)s)")
    parser.add_argument("--backend", choices=("admm", "cvxpy"), default="admm", help="SCR back end")
    parser.add_argument("--starts", type=int, default=1, help="starts of SCR and IPOPT (default %(default)s)")
    parser.add_argument("--zoh", action="store_true", help="pass the held force's exact spectrum φ·sinc²(ω dt/2)")
    parser.add_argument("--repeat", type=int, default=0,
                        help="instead: SCR on this many seeded records, print the error distribution")
    parser.add_argument("--quick", action="store_true",
                        help="reduced variant: 30 s record, nperseg 1024, SCR only (what the tests run)")
    args = parser.parse_args(argv)
    if args.quick:
        args.duration, args.nperseg = 30.0, 1024
    model = frame_model()
    if args.repeat:
        repeated_runs(args, model)
    else:
        single_run(args, model)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
