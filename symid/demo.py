"""``symid demo``: the belt drive of thesis §3-6, end to end, in well under a minute."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

__all__ = ["run_demo"]


def run_demo(out: str | Path = "symid-demo", *, starts: int = 20, seed: int = 0,
             convergence_iterations: int = 400) -> int:
    """Identify the belt drive (3-17) from its 10-point FRF with SCR and IPOPT, side by side.

    Prints the model, its identifiability, the comparison table over ``starts``
    identical starts and the best estimates against the truth (3-18); writes
    ``bode.png`` and ``convergence.png`` to ``out``.

    Parameters
    ----------
    out : str or pathlib.Path
        Output folder (created).
    starts, seed : int
        Number of identical starts for SCR and IPOPT, and the seed of the random ones.
    convergence_iterations : int
        Iterations of the thesis-style SCR run drawn in ``convergence.png`` (every
        equation relaxed, all matrices zero, as thesis Figure 3-2).

    Returns
    -------
    int
        0 when SCR recovered the truth to 1e-6, 1 otherwise (the exit code of the command).
    """
    from symid.fit.compare import compare
    from symid.fit.frf.scr import ScrFRF
    from symid.plots import bode_plot, convergence_plot
    from symid.structural import identifiability
    from symid.zoo import load_model

    t0 = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    entry = load_model("belt_drive")
    model, truth = entry.model, entry.truth
    truth_vec = model.theta_vector(truth)
    print(f"symid demo: {entry.title} [{entry.source}]")
    print(model.summary())
    print()
    rep = identifiability(model, timeout=20)
    print(f"identifiability: {rep.verdict} ({', '.join(f'{k}: {v}' for k, v in rep.verdicts.items())})")
    data = entry.data()
    print(f"data: {entry.recipe}")
    print()
    cmp = compare(model, data, methods=("scr", "ipopt"), starts=starts, seed=seed, truth=truth, progress=True)
    print(cmp.table())
    print()
    print(f"{'parameter':>10s} {'truth':>10s} {'SCR':>14s} {'IPOPT':>14s}")
    scr_theta = cmp["scr"].result.theta_vector
    ip_theta = cmp["ipopt"].result.theta_vector
    for k, name in enumerate(model.parameter_names):
        print(f"{name:>10s} {truth_vec[k]:>10.4g} {scr_theta[k]:>14.9f} {ip_theta[k]:>14.9f}")
    err_scr = float(np.linalg.norm(scr_theta - truth_vec))
    err_ip = float(np.linalg.norm(ip_theta - truth_vec))
    print(f"{'‖θ̂ − θ*‖₂':>10s} {'':>10s} {err_scr:>14.2e} {err_ip:>14.2e}   (thesis (3-21): 3.5e-07)")
    print()
    bode = bode_plot(data, {"truth": (model, truth_vec), "SCR estimate": (model, scr_theta),
                            "IPOPT, best of the starts": (model, ip_theta)}, out / "bode.png",
                     title="Printer belt drive: 10 frequency-response samples around the resonance",
                     h_unit=entry.h_unit(), reference="truth")
    # Figure 3-2 of the thesis: SCR on (3-15) as posed there, every equation relaxed (no
    # presolve), all matrices initialised at zero; with presolve symid solves it in one step.
    raw = ScrFRF(model, data, presolve=False, aux_init="zero", max_iter=convergence_iterations, tol=1e-12)
    sol = raw.solve(np.zeros(model.n_parameters))
    errors = [float(np.linalg.norm(np.asarray(it["theta"]) - truth_vec)) for it in sol.iterates]
    conv = convergence_plot(raw.family_residuals(sol), out / "convergence.png", error=errors,
                            title="Printer belt drive: SCR with every equation relaxed (no presolve),\n"
                                  "all unknowns starting at zero, ADMM back end", error_label="‖θ_k − θ*‖₂")
    k6 = next((k + 1 for k, e in enumerate(errors) if e <= 1e-6), None)
    print(f"SCR as the thesis posed it (every equation relaxed, no presolve, ADMM, θ = 0, Γ = 0): "
          f"‖θ − θ*‖₂ = {errors[-1]:.2e} after {sol.iterations} iterations"
          + (f", first ≤ 1e-6 at iteration {k6}" if k6 else "") + " (thesis (3-21): 3.5e-07 after about 425).")
    print("With presolve (the default) the rows of (3-10) that hold no unknown become linear equalities that fix "
          "every Γᵢ, and the belt drive is solved exactly in one step.")
    print(f"wrote {bode} and {conv}   (total {time.perf_counter() - t0:.1f} s)")
    return 0 if err_scr <= 1e-6 else 1
