"""Spectra: ``auto`` (IPOPT with restarts, then SCR) against IPOPT and SCR alone, from the same starts.

Problems: the shear buildings of ``benchmarks/psd_units.py`` (n = 2, 3, 4 storeys in SI units, two draws each,
a white roof force, 60 lines) measured three ways: every floor's displacement, every floor's acceleration, and
the first floor's displacement with the others' accelerations (one ``output=`` kind per row); exact spectra and
2 % relative noise. Three starts per problem, ``si.identify``'s default draws around the spectra's typical values
(the same for every method: the same seed). Success: exact, the largest relative parameter error ≤ 1e-3; noisy, a
misfit within 1 % of, or a largest error within twice, that of IPOPT started at the truth. SCR with its default
back end (Clarabel) and with ADMM. Each start has a budget of ``--time-limit`` seconds.

Run (about 15 minutes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/psd_auto.py

Prints a table per sensor set and in all; writes ``benchmarks/results/psd_auto.json``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path
from psd_units import building
from psd_units import fit as fit_variant

import symid as si
from symid.runlog import write_json_atomic

METHODS = {"auto": ("auto", {}), "ipopt": ("ipopt", {}), "scr": ("scr", {}), "scr-admm": ("scr", {"backend": "admm"})}
SENSORS = ("position", "acceleration", "mixed")
NOISES = (0.0, 0.02)


def measured(model: si.SecondOrderModel, sensors: str) -> si.SecondOrderModel:
    """The same building with other sensors (the first floor's displacement and accelerations for "mixed")."""
    n = model.n_dof
    kinds = sensors if sensors != "mixed" else ["position"] + ["acceleration"] * (n - 1)
    s = model.symbolic
    return si.SecondOrderModel(M=s["M"], V=s["V"], K=s["K"], B=s["B"], C=s["C"], output=kinds,
                               parameters=model.parameters)


def fit(model: si.SecondOrderModel, spec: si.SpectralData, method: str, x0: list[float] | None, starts: int,
        time_limit: float) -> si.IdentificationResult:
    return fit_variant(model, spec, method, x0, starts, variants=METHODS, time_limit=time_limit)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2,3,4")
    ap.add_argument("--draws", type=int, default=2)
    ap.add_argument("--starts", type=int, default=3)
    ap.add_argument("--sensors", default=",".join(SENSORS))
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--time-limit", type=float, default=60.0)
    args = ap.parse_args(argv)
    methods = args.methods.split(",")
    t_all = time.perf_counter()
    rows = []
    for sensors in args.sensors.split(","):
        for n in (int(v) for v in args.sizes.split(",")):
            for draw in range(args.draws):
                base, truth, w = building(n, draw)
                model = measured(base, sensors)
                for noise in NOISES:
                    spec = si.simulate_spectra(model, truth, w, 1e6, noise=noise or None, seed=draw)
                    ref = None
                    if noise:
                        r = fit(model, spec, "ipopt", truth.tolist(), 1, args.time_limit)
                        ref = {"cost": float(r.cost), "error": float(np.max(np.abs(r.theta_vector / truth - 1)))}
                    for method in methods:
                        t0 = time.perf_counter()
                        res = fit(model, spec, method, None, args.starts, args.time_limit)
                        seconds = time.perf_counter() - t0
                        for i, s in enumerate(res.starts):
                            err = float(np.max(np.abs(np.asarray(s.theta) / truth - 1)))
                            ok = err <= 1e-3 if not noise else (s.cost <= 1.01 * ref["cost"]
                                                                or err <= 2 * ref["error"])
                            rows.append({"problem": f"building-n{n}-{draw}", "sensors": sensors, "noise": noise,
                                         "method": method, "start": i, "success": bool(ok),
                                         "success_reported": bool(s.success), "error": err, "cost": float(s.cost),
                                         "seconds": float(s.wall_time), "reference": ref})
                        got = sum(r["success"] for r in rows[-len(res.starts):])
                        print(f"{sensors:12s} building-n{n}-{draw} noise {noise:g} {method:6s} "
                              f"{got}/{len(res.starts)} ({seconds:.1f} s)", flush=True)
    table = []
    print(f"\n{'sensors':12s} {'method':6s} {'exact':>7s} {'2 %':>7s} {'median s/start':>15s} {'time to sol. s':>15s}")
    for sensors in [*args.sensors.split(","), "all"]:
        for method in methods:
            sel = [r for r in rows if r["method"] == method and (sensors == "all" or r["sensors"] == sensors)]
            if not sel:
                continue
            cells = {}
            for noise in NOISES:
                part = [r for r in sel if r["noise"] == noise]
                cells[noise] = f"{sum(r['success'] for r in part)}/{len(part)}"
            med = float(np.median([r["seconds"] for r in sel]))
            ok = sum(r["success"] for r in sel)
            tts = float(sum(r["seconds"] for r in sel) / ok) if ok else float("inf")
            table.append({"sensors": sensors, "method": method, "exact": cells[0.0], "noise 2 %": cells[0.02],
                          "median_s": med, "time_to_solution_s": tts})
            print(f"{sensors:12s} {method:6s} {cells[0.0]:>7s} {cells[0.02]:>7s} {med:15.2f} {tts:15.2f}")
    out = RESULTS / "psd_auto.json"
    write_json_atomic(out, {"benchmark": "psd_auto", "git_commit": git_commit(), "table": table, "rows": rows,
                            "time_limit": args.time_limit, "wall_time": time.perf_counter() - t_all})
    print(f"wrote {out} ({time.perf_counter() - t_all:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
