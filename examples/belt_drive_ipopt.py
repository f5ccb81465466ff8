"""IPOPT on the belt drive (thesis §3-7): the three cases where the thesis reports MATLAB's PEM failing.

Run: python examples/belt_drive_ipopt.py

IPOPT (CasADi ``nlpsol``, exact Hessian, objective Σ‖Hᵢ − H(ωᵢ, θ)‖² / Σ‖Hᵢ‖², real and
imaginary parts) on the zoo's 10-point FRF, from: the all-zero start; 10 draws
θ0 ~ N(0, 1) (``numpy.random.default_rng(0)``); and θ0 = (−0.5, −0.5, −0.2, −0.1).
SCR (default options) from the same starts. Success: ‖θ − θ*‖₂/‖θ*‖₂ ≤ 1e-3.

Prints per start the final θ, the relative misfit and the solver status. Asserts what
the README states about SCR: it succeeds from every one of these starts. IPOPT's
outcome is reported, not asserted (the thesis's PEM failed in all three cases: fit
−8.5% from zeros, best fit 68.5% over 10 random starts, and a miss from the close start).
"""

from __future__ import annotations

import numpy as np

import symid as si
from symid.fit.compare import relative_parameter_error


def main(argv: list[str] | None = None) -> int:
    """Run the comparison (about 2 s; ``argv`` is accepted for a uniform interface and ignored)."""
    entry = si.load_model("belt_drive")
    model, data = entry.model, entry.data()
    truth = model.theta_vector(entry.truth)  # thesis (3-18)
    rng = np.random.default_rng(0)
    cases = {"zeros": [np.zeros(4)], "10 x N(0,1), seed 0": [rng.standard_normal(4) for _ in range(10)],
             "(-0.5, -0.5, -0.2, -0.1)": [np.array([-0.5, -0.5, -0.2, -0.1])]}
    for label, starts in cases.items():
        print(f"\nstart: {label}")
        for method in ("ipopt", "scr"):
            ok = 0
            for x0 in starts:
                res = si.identify(model, data, method=method, x0=x0, identifiability_check=False)
                err = relative_parameter_error(res.theta_vector, truth)
                ok += err <= 1e-3
                print(f"  {method:>5s}  θ0 = {np.array2string(x0, precision=2):>28s}  "
                      f"θ̂ = {np.array2string(res.theta_vector, precision=4, max_line_width=200):>48s}  "
                      f"rel. error {err:8.1e}  misfit {res.cost:8.1e}  {res.message[:60]}")
            print(f"  {method}: {ok}/{len(starts)} succeed")
            if method == "scr":
                assert ok == len(starts), (label, ok)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
