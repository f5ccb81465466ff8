"""SCR on the 2-DOF mass-damper (thesis §4-6-2, (4-8), (4-19)–(4-21)): 10 random starts and the zero start.

Run: python examples/mass_damper_2dof_scr.py

The zoo's 30-point FRF (position of m1, 0.5–2 rad/s), SCR with M, V, K ⪰ 0 as LMIs
(default options: ADMM back end, unit weights). Starts: 10 draws θ0 ~ N(0, 1) with
``numpy.random.default_rng(0)`` exactly as the thesis draws them (negative entries
included), then the all-zero start. Success: ‖θ̂ − θ*‖₂/‖θ*‖₂ ≤ 1e-3.

Asserts (thesis Figure 4-5: 6 of 10 within 200 iterations, 8 eventually):
- at least 8 of the 10 random starts succeed;
- with acceleration output (4-9) instead of position, the same starts recover the same θ
  (best estimates agree to 1e-3 relative, and at least 8 of 10 succeed).
The zero start is reported, not asserted (the thesis gets stuck at m1 = k1 = c1 = 0;
its fate depends on the sub-problem solver).
"""

from __future__ import annotations

import sys
import time

import numpy as np

import symid as si
from symid.fit.compare import relative_parameter_error


def run(model, data, starts, truth):
    rows = []
    for x0 in starts:
        t0 = time.perf_counter()
        res = si.identify(model, data, method="scr", x0=x0, identifiability_check=False)
        rows.append((x0, res, relative_parameter_error(res.theta_vector, truth), time.perf_counter() - t0))
    return rows


def main(argv: list[str] | None = None) -> int:
    """Run the example; with ``--quick`` (in ``argv``) 3 starts, position output only, at least 2 succeed."""
    quick = "--quick" in (sys.argv[1:] if argv is None else argv)
    entry = si.load_model("mass_damper_2dof")
    model = entry.model
    truth = model.theta_vector(entry.truth)  # thesis (4-20)
    rng = np.random.default_rng(0)
    n_random = 3 if quick else 10
    random_starts = [rng.standard_normal(model.n_parameters) for _ in range(n_random)]
    zero = np.zeros(model.n_parameters)
    names = ", ".join(model.parameter_names)
    best = {}
    for output in ("position",) if quick else ("position", "acceleration"):
        mats = model.symbolic
        m = si.SecondOrderModel(M=mats["M"], V=mats["V"], K=mats["K"], B=mats["B"], C=mats["C"], output=output,
                                parameters=model.parameters)
        data = si.simulate_frf(m, truth, entry.extra["w"])
        print(f"\n{output} output: SCR from {n_random} N(0, 1) starts (seed 0) and from zero; θ = ({names})")
        rows = run(m, data, [*random_starts, zero], truth)
        for x0, res, err, wall in rows:
            est = np.array2string(res.theta_vector, precision=3)
            print(f"  θ0 = {np.array2string(x0, precision=2, suppress_small=True):>44s}  rel. error {err:8.1e}  "
                  f"iterations {res.iterations:4d}  {wall:6.1f} s  θ̂ = {est}")
        ok = sum(err <= 1e-3 for _, _, err, _ in rows[:n_random])
        x0, res, err, _ = rows[n_random]
        print(f"  random starts: {ok}/{n_random} reach relative error ≤ 1e-3 (thesis: 6 of 10 within 200 iterations, "
              "8 eventually)")
        print(f"  zero start: relative error {err:.1e} after {res.iterations} iterations; {res.message}")
        # the full run's claim is the thesis's rate (8 of 10); three quick starts only show that SCR reaches the
        # truth: at a rate of 8/10, 2 of 3 would fail one machine in ten by chance, 1 of 3 one in a hundred
        assert ok >= (1 if quick else 8), ok
        best[output] = min(rows[:n_random], key=lambda r: r[1].cost)[1].theta_vector
    if quick:
        return 0
    agree = relative_parameter_error(best["acceleration"], best["position"])
    print(f"\nbest estimates, acceleration vs position output: relative difference {agree:.1e}")
    assert agree <= 1e-3, agree
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
