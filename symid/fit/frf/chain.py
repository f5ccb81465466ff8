"""A start for mass-spring-damper chains measured at the driven mass: continued fractions of the response.

A chain of masses driven and measured at one end mass (position, velocity or
acceleration) has a driving-point dynamic stiffness that is a continued fraction of its
elements (Cauer's ladder form; the structure and the algebra are those of
:mod:`symid.structural.ladder`, which proves such chains globally identifiable). Writing
D_j(s) for the dynamic stiffness seen at node j of the sub-chain j … n − 1 (path order
from the driven mass), e_j(s) = c_j s + k_j for the element joining nodes j and j + 1 and
g_j(s) for node j's ground element,

    D_j = m_j s² + g_j + e_j D_{j+1} / (e_j + D_{j+1}),   1 / (D_j − m_j s² − g_j) = 1/e_j + 1/D_{j+1}.

So the elements can be read off the measured response node by node, with no search:

1. **Black box.** The response divided by the known gains and by (jω)^d for a sensor of
   derivative order d is the compliance 1/D_0; a vector fit with 2n poles and no
   constant term (:func:`symid.signal.vectfit.vector_fit`, frequencies scaled by their
   geometric mean) gives it as poles and residues.
2. **Peeling.** Each function is kept as γ s² + α s + β + Σ ρᵢ / (s − zᵢ). Its reciprocal
   has the zeros as poles: the eigenvalues of a (balanced) pencil, then three Newton steps
   on the function itself (the pencil loses digits, the function does not); residues
   1 / f′(ζ); the polynomial part by least squares at 40 points spread over the poles'
   magnitudes (the moment formulas cancel). At node j: m_j = γ; a ground element at the
   driven end is R(0) + R′(0) s of R = D_0 − m_0 s² (the rest of the chain is free, so the
   series term is O(s²) there); c_j = α of what is left (the series term tends to e_j);
   k_j from the pole of 1/e_j at −k_j/c_j, the pole of the reciprocal whose residue matches
   that of 1/e_j; D_{j+1} is the reciprocal of what remains. Where the sub-chain beyond is
   free, D_{j+1} has a double zero at s = 0, so the step divides by s² first (exactly, in
   partial fractions) and multiplies back after. The last node's γ, α, β are its mass and
   its ground element.

On noise-free responses of generated chains whose grid resolves a 1e-3 error
(``benchmarks/chain_start.py``) the values are within 1e-3 of the truth in every draw up to
five masses (median error 1e-12 to 5e-7) and in 16 of 31 at eight, where the deepest
elements lose digits (worst when driven at the free end, the ground at the far one); at
1 % noise rarely within 10 %. The values are a start, not an estimate:
:class:`symid.fit.frf.lm.AutoFRF` runs a pass from them, and keeps it only by the same
success rule as every other pass.

**Driven at an interior mass.** Then D = m s² + S_L + S_R, the stiffness of the two sides
seen through their connecting elements, and the poles of D − m s² belong to one side or
the other (2L of them to a side of L masses). Each split of the conjugate pairs is tried
(35 at eight masses driven at the fourth, 462 at twelve driven at the sixth; with more
than 500 there is no start): the side away from the ground is
free, so S_R(0) = S_R′(0) = 0 fixes how the polynomial part splits, and each side is
peeled as above. A wrong split leaves residues that do not match a chain's, negative
values or a ground element at the free end; the split that matches best is kept.

Only chains that :func:`symid.structural.ladder.ladder_of` recognises (with
``driven_anywhere=True``) are handled: one input and one output at the same mass, path
Laplacians, ground elements at one end only and not at the driven mass, and known gains —
or one gain that is a number times a parameter found in no mass, damper or spring (an
actuator or sensor gain): the chain is then read with that parameter set to 1, which
divides every element by it, and the masses that are known numbers give it. For a
model with several inputs or outputs, each pair of one input and one output is tried as a
model of its own, and the first that is a chain gives the start (its other parameters
stay at the caller's start).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from itertools import combinations
from math import comb
from typing import Any

import numpy as np
import scipy.linalg as sla
import sympy as sp

from symid.errors import DataError, ModelError, ModelWarning, OptionError

__all__ = ["ChainStart", "chain_start"]

_NEWTON = 3  # Newton steps on each zero
_POINTS = 40  # points of the least-squares fit of a polynomial part


@dataclass(frozen=True)
class ChainStart:
    """Values of a chain's parameters read off its driving-point response (:func:`chain_start`).

    Attributes
    ----------
    values : dict
        Parameter name → value, for every free parameter of the chain.
    output, input : int
        The output and input whose response gave them.
    black_box_error : float
        Relative rms error of the vector fit of the compliance.
    """

    values: dict[str, float]
    output: int
    input: int
    black_box_error: float


class _Rational:
    """f(s) = γ s² + α s + β + Σ ρᵢ / (s − zᵢ)."""

    def __init__(self, g: complex, a: complex, b: complex, z: np.ndarray, rho: np.ndarray):
        self.g, self.a, self.b = complex(g), complex(a), complex(b)
        self.z, self.rho = np.asarray(z, dtype=complex), np.asarray(rho, dtype=complex)

    def __call__(self, s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=complex)
        return self.g * s**2 + self.a * s + self.b + np.sum(self.rho / (s[..., None] - self.z), axis=-1)

    def slope(self, s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=complex)
        return 2 * self.g * s + self.a - np.sum(self.rho / (s[..., None] - self.z) ** 2, axis=-1)

    def _degree(self) -> int:
        return 2 if self.g != 0 else (1 if self.a != 0 else 0)

    def zeros(self, count: int) -> np.ndarray:
        """The ``count`` zeros of smallest magnitude, from a balanced pencil, refined by Newton's method."""
        N = self.z.size
        root = np.sqrt(np.abs(self.rho))
        root = np.where(root > 0, root, 1.0)
        bcol = root[:, None].astype(complex)
        crow = (self.rho / root)[None, :]
        if self.g != 0:  # unknowns (x, u, v = s u): (sI − Z) x = b u, s u = v, c x + β u + α v + γ s v = 0
            A = np.block([[-np.diag(self.z), -bcol, np.zeros((N, 1))],
                          [np.zeros((1, N + 1)), -np.ones((1, 1))],
                          [crow, np.array([[self.b, self.a]])]])
            E = np.zeros((N + 2, N + 2), dtype=complex)
            E[:N, :N] = np.eye(N)
            E[N, N] = 1.0
            E[N + 1, N + 1] = self.g
        else:
            A = np.block([[-np.diag(self.z), -bcol], [crow, np.array([[self.b]])]])
            E = np.zeros((N + 1, N + 1), dtype=complex)
            E[:N, :N] = np.eye(N)
            E[N, N] = self.a
        with np.errstate(all="ignore"):
            ev = sla.eigvals(A, -E)
        ev = ev[np.isfinite(ev)]
        zz = ev[np.argsort(np.abs(ev))][:count]
        if zz.size < count:
            raise np.linalg.LinAlgError("fewer zeros than the degrees say")
        for _ in range(_NEWTON):
            with np.errstate(all="ignore"):
                step = self(zz) / self.slope(zz)
            ok = np.isfinite(step) & (np.abs(step) < 0.1 * np.abs(zz) + 1e-300)
            zz = np.where(ok, zz - step, zz)
        return zz

    def reciprocal(self, tail: int) -> _Rational:
        """1/f; ``tail`` is the degree of its polynomial part (0 where f has one of its own, or a constant)."""
        deg = self._degree()
        count = self.z.size + deg if deg else self.z.size - tail
        zz = self.zeros(count)
        with np.errstate(all="ignore"):
            res = 1.0 / self.slope(zz)
        if deg:
            return _Rational(0, 0, 0, zz, res)
        if tail == 0:  # f tends to its constant β ≠ 0
            return _Rational(0, 0, 1.0 / self.b, zz, res)
        # the polynomial part by least squares at points spread over the poles' magnitudes
        mag = np.abs(np.concatenate([self.z, zz]))
        mag = mag[mag > 0] if np.any(mag > 0) else np.ones(1)
        pts = 1j * np.geomspace(0.3 * mag.min(), 3 * mag.max(), _POINTS)
        with np.errstate(all="ignore"):
            lhs = 1.0 / self(pts) - np.sum(res / (pts[:, None] - zz), axis=1)
        V = np.stack([pts**q for q in range(tail + 1)], axis=1)
        A = np.vstack([V.real, V.imag])
        norm = np.linalg.norm(A, axis=0)
        coef = np.linalg.lstsq(A / norm, np.concatenate([lhs.real, lhs.imag]), rcond=None)[0] / norm
        coef = np.concatenate([coef, np.zeros(3 - coef.size)])
        return _Rational(coef[2], coef[1], coef[0], zz, res)

    def over_s2(self) -> _Rational:
        """f / s² for f = α s + β + Σ ρ/(s − z) with f(0) = f′(0) = 0: Σ (ρ/z²)/(s − z)."""
        return _Rational(0, 0, 0, self.z, self.rho / self.z**2)

    def times_s2(self) -> _Rational:
        """s² f for f = β + Σ ρ/(s − z)."""
        return _Rational(self.b, np.sum(self.rho), np.sum(self.rho * self.z), self.z, self.rho * self.z**2)


def _step(R: _Rational, free_beyond: bool) -> tuple[float, float, _Rational, float]:
    """From R = e ∥ D′ (e = c s + k in series with the sub-chain's D′): (c, k, D′, mismatch of the pole's residue)."""
    c = R.a.real
    if free_beyond:  # s²/R = s²/e + s²/D′, and s²/e = s/c − k/c² + (k²/c³)/(s + k/c)
        T = R.over_s2().reciprocal(1)
        want = T.z**2 / c
        miss = np.abs(T.rho - want) / np.abs(want)
        i = int(np.argmin(miss))
        k = -(c * T.z[i]).real
        keep = np.arange(T.z.size) != i
        D = _Rational(0, 0, T.b + k / c**2, T.z[keep], T.rho[keep]).reciprocal(0).times_s2()
    else:  # 1/R = 1/e + 1/D′, 1/e = (1/c)/(s + k/c)
        Ri = R.reciprocal(0)
        miss = np.abs(Ri.rho * c - 1)
        i = int(np.argmin(miss))
        k = -(c * Ri.z[i]).real
        keep = np.arange(Ri.z.size) != i
        D = _Rational(0, 0, 0, Ri.z[keep], Ri.rho[keep]).reciprocal(2)
    return c, k, D, float(miss[i])


def _side(R: _Rational, count: int, far_grounded: bool) -> tuple[list, list, tuple, float]:
    """A sub-chain of ``count`` masses seen through the element joining it: R = e₀ ∥ D₁.

    Returns its masses, its elements e₀ … e_{count−1} as (damper, spring), the far end's
    ground element and the largest residue mismatch of the steps (0 for a true chain)."""
    masses, edges, worst = [], [], 0.0
    for _ in range(count):
        c, k, D, miss = _step(R, not far_grounded)
        edges.append((c, k))
        masses.append(D.g.real)
        worst = max(worst, miss)
        R = _Rational(0, D.a, D.b, D.z, D.rho)
    return masses, edges, (R.a.real, R.b.real), worst


def _peel(compliance: _Rational, n: int, grounded: set[int]) -> tuple[list, list, list]:
    """Masses, (damper, spring) of the elements and of the grounds, node by node from the driven end."""
    D = compliance.reciprocal(2)
    R = _Rational(0, D.a, D.b, D.z, D.rho)
    grounds: list[tuple[float, float]] = [(0.0, 0.0)] * n
    if n == 1:
        grounds[0] = (R.a.real, R.b.real)
        return [D.g.real], [], grounds
    if 0 in grounded:  # the driven end's ground: R(0) + R'(0) s, the free rest being O(s²) there
        zero = np.zeros(1, dtype=complex)
        r0, r1 = complex(R(zero)[0]), complex(R.slope(zero)[0])
        grounds[0] = (r1.real, r0.real)
        R = _Rational(0, R.a - r1, R.b - r0, R.z, R.rho)
    masses, edges, far, _ = _side(R, n - 1, (n - 1) in grounded)
    grounds[n - 1] = far
    return [D.g.real, *masses], edges, grounds


def _units(z: np.ndarray) -> list[list[int]]:
    """Indices of the poles grouped into conjugate pairs and single real poles."""
    left = list(range(z.size))
    out = []
    while left:
        i = left.pop(0)
        if abs(z[i].imag) <= 1e-9 * abs(z[i]):
            out.append([i])
            continue
        j = min(left, key=lambda q: abs(z[q] - np.conj(z[i])), default=None)
        if j is None:
            out.append([i])
            continue
        left.remove(j)
        out.append([i, j])
    return out


_SPLITS = 500  # splits of the poles tried at most for a chain driven at an interior mass (3 s at twelve masses)


def _peel_interior(compliance: _Rational, n: int, at: int, left_grounded: bool) -> tuple[list, list, list]:
    """A chain driven at node ``at`` (0 < at < n − 1, the ground, if any, at node 0), by splitting the poles.

    D = m s² + S_L + S_R with S_X the stiffness of side X seen through its connecting
    element. The poles of D − m s² split between the sides (2·at on the left); the free
    right side has S_R(0) = S_R′(0) = 0, which fixes the split of the polynomial part. Every
    split is peeled; the one whose steps match best (residues as a chain's, values positive) wins.
    """
    D = compliance.reciprocal(2)
    P = _Rational(0, D.a, D.b, D.z, D.rho)
    units = _units(P.z)
    size_left = 2 * at
    best: tuple[float, list, list, list] | None = None
    tried = 0
    if comb(len(units), at) > _SPLITS:  # at least this many (every unit a pair); a start, not a slow one
        raise np.linalg.LinAlgError(f"more than {_SPLITS} splits of the poles between the two sides")
    for r in range(at, min(len(units), size_left) + 1):  # a unit holds one or two poles
        for pick in combinations(range(len(units)), r):
            idx = [i for u in pick for i in units[u]]
            if len(idx) != size_left:
                continue
            tried += 1
            if tried > _SPLITS:  # a long chain driven far from its ends: no start rather than a slow one
                raise np.linalg.LinAlgError(f"more than {_SPLITS} splits of the poles between the two sides")
            mask = np.zeros(P.z.size, dtype=bool)
            mask[idx] = True
            zL, rL, zR, rR = P.z[mask], P.rho[mask], P.z[~mask], P.rho[~mask]
            cR, bR = np.sum(rR / zR**2), np.sum(rR / zR)
            SL = _Rational(0, P.a - cR, P.b - bR, zL, rL)
            SR = _Rational(0, cR, bR, zR, rR)
            try:
                with np.errstate(all="ignore"):
                    mL, eL, gL, missL = _side(SL, at, left_grounded)
                    mR, eR, gR, missR = _side(SR, n - 1 - at, False)
            except (np.linalg.LinAlgError, ValueError, ZeroDivisionError):
                continue
            values = np.array([*mL, *mR, *(v for e in (*eL, *eR) for v in e)])
            # the right side's far end is free: what is left there must be no ground element
            scale_c = np.mean([abs(e[0]) for e in eR]) or 1.0
            scale_k = np.mean([abs(e[1]) for e in eR]) or 1.0
            free_end = abs(gR[0]) / scale_c + abs(gR[1]) / scale_k
            positive = bool(np.all(np.isfinite(values)) and np.all(values > 0))
            score = max(missL, missR, free_end) + (0.0 if positive else 1.0)
            if not np.isfinite(score):
                continue
            if best is None or score < best[0]:
                masses = [*reversed(mL), D.g.real, *mR]
                edges = [*reversed(eL), *eR]
                grounds = [(0.0, 0.0)] * n
                grounds[0] = gL
                best = (score, masses, edges, grounds)
    if best is None:
        raise np.linalg.LinAlgError("no split of the poles gives a chain")
    return best[1], best[2], best[3]


def _siso(model: Any, i: int, j: int, gain: sp.Symbol | None = None) -> Any:
    """Output i, input j of a second-order model as a model of its own (None if it has no parameter);
    ``gain``, a parameter of B or C, set to 1."""
    from symid.model.secondorder import SecondOrderModel

    sym = model.symbolic
    mats = {"M": sym["M"], "V": sym["V"], "K": sym["K"], "B": sym["B"][:, j], "C": sym["C"][i, :]}
    if gain is not None:
        mats["B"], mats["C"] = mats["B"].subs(gain, 1), mats["C"].subs(gain, 1)
    present = set().union(*(m.free_symbols for m in mats.values()))
    params = [p for p in model.parameters if p in present]
    if not params:
        return None
    with warnings.catch_warnings():  # the whole model's construction said what there is to say of its matrices
        warnings.simplefilter("ignore", ModelWarning)
        return SecondOrderModel(**mats, output=model.outputs[i], parameters=params)


def chain_start(model: Any, data: Any) -> ChainStart | None:
    """A chain's parameters read off the measured response (module docstring), or ``None``.

    Parameters
    ----------
    model : SecondOrderModel
    data : FrequencyData

    Returns
    -------
    ChainStart or None
        ``None`` when no input-output pair of the model is a chain driven and measured at
        one mass (module notes), when the data have fewer than
        2n + 2 lines, or when the numbers cannot be read (a black box or a reciprocal
        that fails, values that are not finite).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.chain import chain_start
    >>> m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    >>> chain = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
    ...                             K=[[k1 + k2, -k2], [-k2, k2]], B=[[1], [0]], C=[[1, 0]])
    >>> truth = {"m1": 2.0, "m2": 0.5, "c1": 3.0, "c2": 1.0, "k1": 4e4, "k2": 1e4}
    >>> frf = si.simulate_frf(chain, truth, np.logspace(1.5, 3, 60))
    >>> start = chain_start(chain, frf)
    >>> {k: float(f"{v:.6g}") for k, v in start.values.items()}
    {'m1': 2.0, 'm2': 0.5, 'c2': 1.0, 'k2': 10000.0, 'c1': 3.0, 'k1': 40000.0}
    """
    from symid.structural.ladder import ladder_of

    if not hasattr(model, "n_dof") or not hasattr(model, "output"):
        return None
    w = np.asarray(data.w, dtype=float)
    H = np.asarray(data.H)
    n = int(model.n_dof)
    if w.size < 2 * n + 2:
        return None
    p, m = H.shape[1], H.shape[2]
    sym = model.symbolic
    for i in range(p):
        for j in range(m):
            # cheap test first: the input and the output on the same single mass, the gains known or one of
            # them a number times a parameter found nowhere else in M, V, K (an actuator or sensor gain)
            b_at = [r for r in range(n) if sym["B"][r, j] != 0]
            c_at = [r for r in range(n) if sym["C"][i, r] != 0]
            if len(b_at) != 1 or b_at != c_at:
                continue
            gain = _gain_parameter(sym["B"][b_at[0], j] * sym["C"][i, c_at[0]], model, sym)
            if gain is False:
                continue
            try:
                sub = _siso(model, i, j, gain)
                lad = None if sub is None else ladder_of(sub, driven_anywhere=True)
            except (ModelError, sp.SympifyError):
                continue
            if lad is None:
                continue
            try:
                start = _read(lad, w, H[:, i, j], n, i, j, gain)
                if start is not None:
                    return start
            except (np.linalg.LinAlgError, ValueError, DataError, OptionError, ZeroDivisionError):
                continue
    return None


def _gain_parameter(product: sp.Expr, model: Any, sym: dict) -> sp.Symbol | bool | None:
    """None for a known gain; the parameter p of a gain q·p (p in no mass, damper or spring); False otherwise."""
    if product.is_number:
        return None
    free = product.free_symbols & set(model.parameters)
    if len(free) != 1:
        return False
    p = next(iter(free))
    if not (product / p).is_number or any(p in sym[k].free_symbols for k in ("M", "V", "K")):
        return False
    return p


def _read(lad: Any, w: np.ndarray, h: np.ndarray, n: int, i: int, j: int, gain: sp.Symbol | None = None
          ) -> ChainStart | None:
    from symid.signal.vectfit import vector_fit

    s = 1j * w
    with np.errstate(all="ignore"):
        compliance = h / s**lad.shift / float(lad.gain)
    if not np.all(np.isfinite(compliance)) or not np.any(compliance != 0):
        return None
    w0 = float(np.sqrt(w[0] * w[-1]))
    bb = vector_fit(w / w0, compliance, 2 * n, weight="relative", D=False)
    poles = np.asarray(bb.poles) * w0
    residues = np.asarray(bb.residues).reshape(poles.size, -1)[:, 0] * w0
    grounded = {k for k, g in enumerate(lad.grounds) if any(v != 0 for v in g)}
    if lad.at == 0:
        masses, edges, grounds = _peel(_Rational(0, 0, 0, poles, residues), n, grounded)
    else:
        masses, edges, grounds = _peel_interior(_Rational(0, 0, 0, poles, residues), n, lad.at, 0 in grounded)
    values: dict[str, float] = {}
    slots = [*zip(lad.masses, masses, strict=True),
             *((sym, val) for pair, vals in zip(lad.edges, edges, strict=True)
               for sym, val in zip(pair, vals, strict=True)),
             *((sym, val) for pair, vals in zip(lad.grounds, grounds, strict=True)
               for sym, val in zip(pair, vals, strict=True))]
    for sym, val in slots:
        if isinstance(sym, sp.Symbol):
            values[sym.name] = float(val)
    if gain is not None:
        # the response is p times that of the chain, i.e. that of the chain with every element divided by p:
        # the masses that are known numbers give p
        ratios = [float(sym) / val for sym, val in zip(lad.masses, masses, strict=True)
                  if not isinstance(sym, sp.Symbol) and val != 0]
        if not ratios:
            return None
        p = float(np.median(ratios))
        values = {name: v * p for name, v in values.items()}
        values[gain.name] = p
    if not all(np.isfinite(v) for v in values.values()):
        return None
    return ChainStart(values=values, output=i, input=j, black_box_error=float(bb.rms))
