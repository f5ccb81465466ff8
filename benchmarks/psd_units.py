"""SCR on output spectra of models in physical units: the spectra's typical values as the scale, or θ as it is.

Shear buildings of n = 2, 3, 4 storeys in SI units (masses log-uniform in 5e3–5e4 kg,
storey stiffnesses in 1e7–1e8 N/m, dampers giving damping ratios of a few %), driven by
a white force of intensity 1e6 N²·s at the roof, every floor's displacement measured
(the full sensor set Algorithm 5.1 needs), 60 lines log-spaced from 0.5 times the lowest
to 2 times the highest natural frequency; exact spectra and 2 % relative noise
(``si.simulate_spectra(..., noise=0.02)``). Two draws per size, three starts each
(``si.identify``'s default draws, around the typical values the spectra give). Variants:
SCR with the ADMM back end as it is by default (``unit_scale=True``: the typical values
become the scale, the model being in physical units) and with ``unit_scale=False``
(θ as it is, the thesis's relaxation), and IPOPT on (5-13) from the same starts.
Success: exact spectra, the largest relative parameter error ≤ 1e-3; noisy spectra, a
misfit within 1 % of, or a largest error within twice, that of IPOPT started at the truth.

Run (about 10 minutes)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/psd_units.py

Prints a table; writes ``benchmarks/results/psd_units.json``.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from _study import RESULTS, git_commit  # benchmarks/ (the script's folder) is on the path

import symid as si
from symid.runlog import write_json_atomic

VARIANTS = {"scr": ("scr", {"backend": "admm"}), "scr-unit_scale=False": ("scr", {"backend": "admm",
                                                                               "unit_scale": False}),
            "ipopt": ("ipopt", {})}
NOISES = (0.0, 0.02)
TIME_LIMIT = 60.0


def building(n: int, draw: int) -> tuple[si.SecondOrderModel, np.ndarray, np.ndarray]:
    """An n-storey shear building with random SI values, its truth and its frequency grid."""
    rng = np.random.default_rng([n, draw, 17])
    m = si.parameters(" ".join(f"m{i}" for i in range(1, n + 1)), positive=True)
    c = si.parameters(" ".join(f"c{i}" for i in range(1, n + 1)), positive=True)
    k = si.parameters(" ".join(f"k{i}" for i in range(1, n + 1)), positive=True)
    m, c, k = (list(v) if isinstance(v, (list, tuple)) else [v] for v in (m, c, k))

    def chain(e: list) -> list[list]:
        out = [[0] * n for _ in range(n)]
        for i in range(n):
            out[i][i] = e[i] + (e[i + 1] if i + 1 < n else 0)
            if i + 1 < n:
                out[i][i + 1] = out[i + 1][i] = -e[i + 1]
        return out

    model = si.SecondOrderModel(M=[[m[i] if i == j else 0 for j in range(n)] for i in range(n)], V=chain(c),
                                K=chain(k), B=[[0]] * (n - 1) + [[1]], C=np.eye(n).tolist())
    mv = np.exp(rng.uniform(np.log(5e3), np.log(5e4), n))
    kv = np.exp(rng.uniform(np.log(1e7), np.log(1e8), n))
    cv = 2 * rng.uniform(0.02, 0.08, n) * np.sqrt(kv * mv)  # a damping ratio of a few % per storey
    truth = np.concatenate([mv, cv, kv])
    lam = np.abs(np.linalg.eigvals(model.state_space(truth).A))
    w = np.logspace(np.log10(0.5 * lam.min()), np.log10(2 * lam.max()), 60)
    return model, truth, w


def fit(model: si.SecondOrderModel, spec: si.SpectralData, variant: str, x0: list[float] | None,
        starts: int, *, variants: dict | None = None, time_limit: float = TIME_LIMIT) -> si.IdentificationResult:
    """``si.identify`` with the variant's method and options (``variants``: this study's, or another's table),
    seed 0, no identifiability check, warnings silenced."""
    method, opts = (VARIANTS if variants is None else variants)[variant]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return si.identify(model, spec, method=method, x0=x0, starts=starts, seed=0, identifiability_check=False,
                           time_limit=time_limit, **opts)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2,3,4")
    ap.add_argument("--draws", type=int, default=2)
    ap.add_argument("--starts", type=int, default=3)
    args = ap.parse_args(argv)
    t_all = time.perf_counter()
    rows = []
    for n in (int(v) for v in args.sizes.split(",")):
        for draw in range(args.draws):
            model, truth, w = building(n, draw)
            for noise in NOISES:
                spec = si.simulate_spectra(model, truth, w, 1e6, noise=noise or None, seed=draw)
                ref = None
                if noise:
                    r = fit(model, spec, "ipopt", truth.tolist(), 1)
                    ref = {"cost": float(r.cost), "error": float(np.max(np.abs(r.theta_vector / truth - 1)))}
                for variant in VARIANTS:
                    t0 = time.perf_counter()
                    res = fit(model, spec, variant, None, args.starts)
                    seconds = time.perf_counter() - t0
                    for i, s in enumerate(res.starts):
                        err = float(np.max(np.abs(np.asarray(s.theta) / truth - 1)))
                        ok = err <= 1e-3 if not noise else (s.cost <= 1.01 * ref["cost"] or err <= 2 * ref["error"])
                        rows.append({"problem": f"building-n{n}-{draw}", "noise": noise, "variant": variant,
                                     "start": i, "success": bool(ok), "success_reported": bool(s.success),
                                     "error": err, "cost": float(s.cost), "seconds": float(s.wall_time),
                                     "reference": ref})
                    print(f"building-n{n}-{draw} noise {noise:g} {variant:22s} "
                          f"{sum(r['success'] for r in rows[-len(res.starts):])}/{len(res.starts)} "
                          f"({seconds:.1f} s)", flush=True)
    table = []
    print(f"\n{'variant':22s} {'exact':>7s} {'2 %':>7s} {'median s/start':>15s}")
    for variant in VARIANTS:
        cells = {}
        for noise in NOISES:
            sel = [r for r in rows if r["variant"] == variant and r["noise"] == noise]
            cells[noise] = f"{sum(r['success'] for r in sel)}/{len(sel)}"
        med = float(np.median([r["seconds"] for r in rows if r["variant"] == variant]))
        table.append({"variant": variant, "exact": cells[0.0], "noise 2 %": cells[0.02], "median_s": med})
        print(f"{variant:22s} {cells[0.0]:>7s} {cells[0.02]:>7s} {med:15.2f}")
    out = RESULTS / "psd_units.json"
    write_json_atomic(out, {"benchmark": "psd_units", "git_commit": git_commit(), "table": table, "rows": rows,
                            "time_limit": TIME_LIMIT, "wall_time": time.perf_counter() - t_all})
    print(f"wrote {out} ({time.perf_counter() - t_all:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
