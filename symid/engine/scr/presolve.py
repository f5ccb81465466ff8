"""Presolve: keep bilinear only what is bilinear, go real, normalise.

1. For every bilinear term, rows of A(x) that are constant make the same rows of
   A(x) P B(x) − C(x) affine, and so do constant columns of B(x): those rows and columns
   become linear equalities and leave the nuclear-norm block.
2. Variables that the linear equalities determine (e_k in the row space of D) are fixed
   at their value and substituted everywhere; that can make more rows constant, so 1 and
   2 repeat until nothing changes. A term with no row or column left disappears, and a
   problem with no bilinear term left is convex and is solved exactly in one step.
3. Equalities are reduced to linearly independent rows of unit norm. With
   ``equalities="least_squares"``, a set of equalities that noise has made inconsistent
   (measured data never satisfy an over-determined linear system exactly) is replaced
   by its least-squares solution set: each connected set of rows D x = d becomes
   D x = D x̂ with x̂ its least-squares solution. When the rows determine every unknown
   of the set, x̂ minimises Σ_r (D_r x − d_r)² / T_r², each real equation's error
   relative to the size of its terms at the solution, T_r = ‖(D_r1 x̂_1, …, D_rn x̂_n,
   d_r)‖₂ (a fixed point, found by reweighted least squares from the unit-row
   solution), so that x̂ does not depend on the units of any unknown or equation;
   otherwise rows of unit norm weigh alike (d projected onto the range of D). Sets are
   solved in the order the passes of step 2 determine them: a later set sees the
   values an earlier one fixed. The relative residual — the RMS over the equations of
   |D_r x̂ − d_r| / T_r, as independent of units as x̂ — is reported (largest over the
   sets) in ``info["equality_residual"]``. With ``"exact"`` (the default) a relative
   residual above :data:`INCONSISTENT_TOL` (1e-8) marks the problem inconsistent,
   whatever the units of the data; so does an equation left without unknowns, 0 = d_r,
   whose d_r exceeds 1e-8 of the size of the terms it came from.
4. Complex terms go through the real representation (2-8), with half the weight, so that
   λ weighs the nuclear norm of the complex matrix.
5. Each remaining term is equilibrated without changing its solution set: P is divided
   by its spectral norm (C with it), each row of the equation by the largest coefficient
   of that row of A and C, each column by the largest coefficient of that column of B
   and C. A weight λ therefore means the same in problems whose data have other units.
6. A P of rank r below its row count k or column count l (e.g. the stacked
   Pᵢ = [−ωᵢ²I; jωᵢI; I] of thesis (4-8)) is compressed by its thin SVD P = U Σ Vᵀ:
   A ← A U, P ← Σ, B ← Vᵀ B (each side only when rank-deficient). The matrix M of (2-6)
   becomes diag(I, Uᵀ) M diag(I, V), whose singular values are M's, so every SCR
   sub-problem is the same, on a block of (j + r) × (m + r) instead of (j + k) × (m + l).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
from scipy.sparse.csgraph import connected_components

from symid.engine.scr.maps import LocalMap, _clean
from symid.engine.scr.problem import BilinearProblem, CompiledTerm

__all__ = ["INCONSISTENT_TOL", "RealTerm", "Reduced", "presolve"]


@dataclass(frozen=True, eq=False)
class RealTerm:
    """A real bilinear term on the free variables z, after presolve and scaling."""

    A: LocalMap
    P: np.ndarray
    B: LocalMap
    C: LocalMap
    weight: float
    source: int  # index of the user's term
    complex_pair: bool  # built by the real representation (2-8)

    @property
    def dims(self) -> tuple[int, int, int, int]:
        j, k = self.A.shape
        l, m = self.B.shape
        return j, k, l, m


@dataclass(eq=False)
class Reduced:
    """The problem the back ends see: variables z = x[free], all data real."""

    n: int
    free: np.ndarray
    xfix: np.ndarray
    terms: list[RealTerm]
    D: sps.csr_matrix
    d: np.ndarray
    lmis: list[LocalMap]
    H: sps.csr_matrix
    g: np.ndarray
    c: float
    inconsistent: float = 0.0  # relative residual of the equalities (exact mode; 0 in least squares)
    info: dict = field(default_factory=dict)

    @property
    def nz(self) -> int:
        return int(self.free.size)

    def lift(self, z: np.ndarray) -> np.ndarray:
        x = self.xfix.copy()
        x[self.free] = z
        return x

    def objective(self, z: np.ndarray) -> float:
        return float(z @ (self.H @ z) + self.g @ z + self.c)


def _substitute(m: LocalMap, fixed: np.ndarray, xfix: np.ndarray) -> LocalMap:
    if not m.idx.size:
        return m
    mask = fixed[m.idx]
    if not mask.any():
        return m
    const = m.const + m.coef[:, :, mask] @ xfix[m.idx[mask]]
    return LocalMap(const, m.idx[~mask], m.coef[:, :, ~mask])


def _union(*maps: LocalMap) -> np.ndarray:
    return np.unique(np.concatenate([m.idx for m in maps])).astype(np.int64)


def _constant_residual(eq: LocalMap, size: np.ndarray) -> float:
    """Largest |d| / size of the entries of an equality map that hold no unknown (0 = d), relative to the
    size of the terms they came from; 0 when every entry still holds an unknown."""
    const_only = ~np.any(eq.coef != 0, axis=2) if eq.coef.size else np.ones(eq.const.shape, dtype=bool)
    if not const_only.any():
        return 0.0
    r = np.abs(eq.const[const_only])
    sz = size[const_only]
    return float(np.max(np.where(sz > 0, r / np.where(sz > 0, sz, 1.0), np.where(r > 0, 1.0, 0.0))))


def _split_term(t: CompiledTerm) -> tuple[CompiledTerm | None, list[LocalMap], float]:
    """Move the affine rows/columns of A P B − C out of the term, as equalities; also the largest
    relative residual of the equations among them that hold no unknown any more."""
    A, B, C, P = t.A, t.B, t.C, t.P
    eqs: list[LocalMap] = []
    bad = 0.0
    crow = A.constant_rows()
    if crow.any():
        idx = _union(B, C)
        A0P = A.const[crow] @ P
        const = A0P @ B.const - C.const[crow]
        coef = np.einsum("il,lmu->imu", A0P, B.on(idx)) - C.on(idx)[crow]
        eqs.append(_clean(idx, coef, const))
        bad = max(bad, _constant_residual(eqs[-1], np.abs(A0P) @ np.abs(B.const) + np.abs(C.const[crow])))
    keep = ~crow
    if not keep.any():
        return None, eqs, bad
    A, C = A.rows(keep), C.rows(keep)
    ccol = B.constant_cols()
    if ccol.any():
        idx = _union(A, C)
        PB0 = P @ B.const[:, ccol]
        const = A.const @ PB0 - C.const[:, ccol]
        coef = np.einsum("iku,kc->icu", A.on(idx), PB0) - C.on(idx)[:, ccol]
        eqs.append(_clean(idx, coef, const))
        bad = max(bad, _constant_residual(eqs[-1], np.abs(A.const) @ np.abs(PB0) + np.abs(C.const[:, ccol])))
    keepc = ~ccol
    if not keepc.any():
        return None, eqs, bad
    B, C = B.cols(keepc), C.cols(keepc)
    return CompiledTerm(t.name, A, P, B, C, t.weight), eqs, bad


def _rows(maps: list[LocalMap], n: int) -> tuple[sps.csr_matrix, np.ndarray]:
    """Real rows D x = d of the equalities 'map(x) = 0' (complex entries give two rows)."""
    ri, ci, vs, dd = [], [], [], []
    r = 0
    for m in maps:
        nr = m.const.size
        co = m.coef.reshape(nr, -1)
        c0 = m.const.reshape(-1)
        for part, keep in ((np.real, None), (np.imag, True)):
            cp, c0p = part(co), part(c0)
            if keep:
                sel = np.flatnonzero(np.any(cp != 0, axis=1) | (c0p != 0))
            else:
                sel = np.arange(nr)
            if not sel.size:
                continue
            rr, uu = np.nonzero(cp[sel])
            ri.append(r + rr)
            ci.append(m.idx[uu])
            vs.append(cp[sel][rr, uu])
            dd.append(-c0p[sel])
            r += sel.size
    if not dd:
        return sps.csr_matrix((0, n)), np.zeros(0)
    D = sps.csr_matrix((np.concatenate(vs), (np.concatenate(ri), np.concatenate(ci))), shape=(r, n))
    return D, np.concatenate(dd)


INCONSISTENT_TOL = 1e-8
"""Relative residual of a set of linear equalities above which ``equalities="exact"`` calls them inconsistent."""

_IRLS_MAX = 30  # reweighting passes of the least-squares estimate (each gains about a factor noise)


def _term_weighted_lstsq(Dd: np.ndarray, dc: np.ndarray) -> np.ndarray:
    """The least-squares solution of D x = d with each row's error relative to the size of its terms.

    Minimises Σ_r (D_r x − d_r)² / T_r² with T_r = ‖(D_r1 x̂_1, …, D_rn x̂_n, d_r)‖₂ at the
    solution x̂ itself (a fixed point, found by reweighting from the unit-row solution).
    Rescaling any unknown or any row leaves x̂ (in its units) unchanged.
    """
    def solve(W: np.ndarray, b: np.ndarray) -> np.ndarray:  # columns of unit norm, so units cannot matter
        cn = np.linalg.norm(W, axis=0)
        cn = np.where(cn > 0, cn, 1.0)
        return np.linalg.lstsq(W / cn, b, rcond=None)[0] / cn

    xs = solve(Dd, dc)
    for _ in range(_IRLS_MAX):
        T = np.sqrt(np.sum((Dd * xs) ** 2, axis=1) + dc**2)
        top = float(T.max(initial=0.0))
        if top == 0.0:
            return xs
        T = np.where(T > 0, T, top)  # a row whose terms all vanish at x̂ (no floor relative to other rows:
        # rows in other units may be 1e-13 times smaller and must keep their weight)
        x_new = solve(Dd / T[:, None], dc / T)
        done = np.linalg.norm(x_new - xs) <= 1e-14 * max(np.linalg.norm(x_new), 1e-300)
        xs = x_new
        if done:
            break
    return xs


def _relative_residual(Dd: np.ndarray, dc: np.ndarray, xs: np.ndarray) -> float:
    """RMS over the equations of |D_r x̂ − d_r| / T_r, T_r the size of the equation's terms at x̂
    (independent of the units of unknowns and equations); an equation whose terms all vanish counts
    1 if it is not met."""
    T = np.sqrt(np.sum((Dd * xs) ** 2, axis=1) + dc**2)
    r = np.abs(Dd @ xs - dc)
    rel = np.where(T > 0, r / np.where(T > 0, T, 1.0), np.where(r > 0, 1.0, 0.0))
    return float(np.sqrt(np.mean(rel**2))) if rel.size else 0.0


def _analyse(D: sps.csr_matrix, d: np.ndarray, active: np.ndarray, lsq: bool = False):
    """Independent rows, determined variables and their values, the relative inconsistency (exact mode)
    and the relative least-squares residual (``lsq``: every component replaced by its least-squares
    solution set), per component."""
    n = D.shape[1]
    nrm = np.sqrt(np.asarray(D.multiply(D).sum(axis=1)).ravel())
    empty = nrm == 0  # 0 = d_r: judged where the row lost its last unknown (a component, or _split_term)
    bad = 0.0
    lsq_res = 0.0
    D = sps.diags(np.where(empty, 0.0, 1.0 / np.where(empty, 1.0, nrm))) @ D
    d = np.where(empty, 0.0, d / np.where(empty, 1.0, nrm))
    rows_keep: list[int] = []
    determined = np.zeros(n, dtype=bool)
    values = np.zeros(n)
    live = np.flatnonzero(~empty)
    if live.size:
        Dl = D[live].tocsc()
        cols = np.flatnonzero(np.diff(Dl.indptr) > 0)
        Dc = Dl[:, cols]
        pat = abs(Dc).T @ abs(Dc)
        ncomp, lab = connected_components(pat, directed=False)
        row_lab = lab[np.asarray(abs(Dc).argmax(axis=1)).ravel()]
        for comp in range(ncomp):
            vc = np.flatnonzero(lab == comp)
            rc = np.flatnonzero(row_lab == comp)
            Dd = Dc[rc][:, vc].toarray()
            dc = d[live[rc]]
            # columns of unit norm: rank, determined unknowns and solution do not depend on their units
            cn = np.linalg.norm(Dd, axis=0)
            cn = np.where(cn > 0, cn, 1.0)
            Ds = Dd / cn
            Qm, R, piv = sla.qr(Ds.T, mode="economic", pivoting=True)
            diag = np.abs(np.diag(R))
            rank = int(np.sum(diag > 1e-10 * max(diag[0], 1e-300))) if diag.size else 0
            rows_keep.extend(live[rc[piv[:rank]]].tolist())
            full = rank == vc.size and rc.size > rank  # over-determined, every unknown determined
            xs = (_term_weighted_lstsq(Ds, dc) if full else np.linalg.lstsq(Ds, dc, rcond=None)[0]) / cn
            fit = Dd @ xs
            rel = _relative_residual(Dd, dc, xs)
            if lsq:  # keep the least-squares solution set: d replaced by D x̂
                lsq_res = max(lsq_res, rel)
                d = d.copy()
                d[live[rc]] = fit
            else:
                bad = max(bad, rel)
            lev = np.sum(Qm[:, :rank] ** 2, axis=1)
            det = lev > 1 - 1e-9
            gv = cols[vc[det]]
            determined[gv] = True
            values[gv] = xs[det]
    determined &= active
    keep = np.sort(np.asarray(rows_keep, dtype=np.int64))
    return D[keep], d[keep], determined, values, bad, lsq_res


def _realrep(m: LocalMap) -> LocalMap:
    X, Y = m.const.real, m.const.imag
    const = np.block([[X, -Y], [Y, X]]).astype(complex)
    cx, cy = m.coef.real, m.coef.imag
    coef = np.concatenate([np.concatenate([cx, -cy], axis=1), np.concatenate([cy, cx], axis=1)], axis=0)
    return LocalMap(const, m.idx, coef.astype(complex))


def _realrep_p(P: np.ndarray) -> np.ndarray:
    return np.block([[P.real, -P.imag], [P.imag, P.real]])


def _reindex(m: LocalMap, pos: np.ndarray) -> LocalMap:
    return LocalMap(m.const, pos[m.idx], m.coef)


def _rowmax(m: LocalMap) -> np.ndarray:
    return np.maximum(np.abs(m.const).max(axis=1), np.abs(m.coef).max(axis=(1, 2), initial=0.0))


def _colmax(m: LocalMap) -> np.ndarray:
    return np.maximum(np.abs(m.const).max(axis=0), np.abs(m.coef).max(axis=(0, 2), initial=0.0))


_EQUILIBRATE_ROUNDS = 60


def _scale(t: CompiledTerm) -> CompiledTerm:
    pn = float(np.linalg.norm(t.P, 2))
    P = t.P / pn
    A, B, C = t.A, t.B, LocalMap(t.C.const / pn, t.C.idx, t.C.coef / pn)
    # Rows by the size of A P (what reaches the equation through P) and of C, columns by that of P B and
    # C, and A against B (A P B = C is unchanged by A ← αA, B ← B/α): repeated to a fixed point, so that
    # the result does not depend on how the user (or the units) spread the scale over rows, columns, A and
    # B. A row of A P (a column of P B) is measured by its 2-norm along P, the largest over the unknowns:
    # what the rank compression of P (step 6) leaves unchanged, and what does not move when a stacked
    # P = [−ω²I; jωI; I] (thesis (4-8)) trades scale with the columns of A (other units of time). Measured:
    # with rows by A alone, A P was ~1/ω² beside P B on problems in physical units.
    AP = np.concatenate([(A.const @ P)[:, :, None], np.einsum("jku,kl->jlu", A.coef, P)], axis=2)
    PB = np.concatenate([(P @ B.const)[:, :, None], np.einsum("kl,lmu->kmu", P, B.coef)], axis=2)
    Cc = np.concatenate([C.const[:, :, None], C.coef], axis=2)
    ap_row = np.linalg.norm(AP, axis=1).max(axis=1)  # (j,)
    pb_col = np.linalg.norm(PB, axis=0).max(axis=1)  # (m,)
    c_abs = np.abs(Cc).max(axis=2)  # (j, m)
    rs, cs, alpha = np.ones(ap_row.size), np.ones(pb_col.size), 1.0

    def inv(x: np.ndarray) -> np.ndarray:
        return np.where(x > 0, 1.0 / np.where(x > 0, x, 1.0), 1.0)

    for _ in range(_EQUILIBRATE_ROUNDS):
        r = inv(np.maximum(alpha * rs * ap_row, (rs[:, None] * c_abs * cs[None, :]).max(axis=1, initial=0.0)))
        rs = rs * r
        c = inv(np.maximum(cs * pb_col / alpha, (rs[:, None] * c_abs * cs[None, :]).max(axis=0, initial=0.0)))
        cs = cs * c
        a_size = float((alpha * rs * ap_row).max(initial=0.0))
        b_size = float((cs * pb_col / alpha).max(initial=0.0))
        bal = np.sqrt(b_size / a_size) if a_size > 0 and b_size > 0 else 1.0
        alpha *= bal
        if max(np.abs(r - 1).max(initial=0.0), np.abs(c - 1).max(initial=0.0), abs(bal - 1)) <= 1e-14:
            break
    A = LocalMap(A.const * (alpha * rs)[:, None], A.idx, A.coef * (alpha * rs)[:, None, None])
    B = LocalMap(B.const * (cs / alpha)[None, :], B.idx, B.coef * (cs / alpha)[None, :, None])
    C = LocalMap(C.const * rs[:, None] * cs[None, :], C.idx, C.coef * rs[:, None, None] * cs[None, :, None])
    return CompiledTerm(t.name, A, P, B, C, t.weight)


def _compress(A: LocalMap, P: np.ndarray, B: LocalMap) -> tuple[LocalMap, np.ndarray, LocalMap]:
    """Drop the null directions of a rank-deficient real P (step 6 of the module docstring)."""
    k, l = P.shape
    U, sv, Vt = np.linalg.svd(P, full_matrices=False)
    r = int(np.sum(sv > 1e-12 * sv[0])) if sv.size else 0
    if r == 0 or r == k == l:
        return A, P, B
    U, sv, Vt = U[:, :r], sv[:r], Vt[:r]
    # the singular vectors are accurate relative to ‖P‖, not entry by entry: where P's rows (columns) span
    # many decades (P = [−ω²I; jωI; I] with ω far from 1) A U is formed as (A P) V Σ⁻¹ (Vᵀ B as Σ⁻¹ Uᵀ (P B)),
    # from the other, accurate factor; otherwise A U with A's large coefficients on U's tiny entries would
    # lose the relative accuracy the units of time should not cost
    rn, cn = np.linalg.norm(P, axis=1), np.linalg.norm(P, axis=0)

    def spread(x: np.ndarray) -> float:
        x = x[x > 0]
        return float(x.max() / x.min()) if x.size else 1.0

    rows_wide = spread(rn) > spread(cn)
    P0 = P
    if r < k:
        if rows_wide:
            W = Vt.T / sv
            A = LocalMap(A.const @ P0 @ W, A.idx, np.einsum("jku,kr->jru", A.coef, P0 @ W))
        else:
            A = LocalMap(A.const @ U, A.idx, np.einsum("jku,kr->jru", A.coef, U))
        P = U.T @ P
    if r < l:
        if rows_wide:
            B = LocalMap(Vt @ B.const, B.idx, np.einsum("rl,lmu->rmu", Vt, B.coef))
        else:
            W = U.T / sv[:, None]
            B = LocalMap(W @ P0 @ B.const, B.idx, np.einsum("rl,lmu->rmu", W @ P0, B.coef))
        P = P @ Vt.T
    return A, P, B


def presolve(prob: BilinearProblem, *, split: bool = True, normalize: bool = True,
             equalities: str = "exact") -> Reduced:
    """Reduce ``prob`` to the real problem on the free variables that the back ends solve.

    Parameters
    ----------
    prob : BilinearProblem
    split : bool, optional
        Move affine rows/columns of the bilinear terms to linear equalities and eliminate
        variables the equalities determine (default ``True``). ``False`` keeps every term
        whole, as in the thesis, for experiments.
    normalize : bool, optional
        Equilibrate each bilinear term (default ``True``); see the module docstring.
    equalities : {"exact", "least_squares"}, optional
        What inconsistent linear equalities mean: an inconsistent problem (``"exact"``,
        default), or noise, kept in the least-squares sense (step 3 of the module docstring).
    """
    if equalities not in ("exact", "least_squares"):
        raise ValueError(f"equalities must be 'exact' or 'least_squares', got {equalities!r}")
    lsq = equalities == "least_squares"
    n = prob.n
    fixed = np.zeros(n, dtype=bool)
    xfix = np.zeros(n)
    terms: list[tuple[int, CompiledTerm]] = list(enumerate(prob.terms))
    eqmaps = list(prob.equalities)
    # a given equality with no unknown, 0 = d, holds only for d = 0
    bad = max((1.0 for m in eqmaps if not np.any(m.coef != 0) and np.any(m.const != 0)), default=0.0)
    lsq_res = 0.0
    passes = 0
    while True:
        passes += 1
        new_eq = 0
        if split:
            kept = []
            for src, t in terms:
                t = CompiledTerm(t.name, _substitute(t.A, fixed, xfix), t.P, _substitute(t.B, fixed, xfix),
                                 _substitute(t.C, fixed, xfix), t.weight)
                rest, eqs, bad_split = _split_term(t)
                if lsq:
                    lsq_res = max(lsq_res, bad_split)
                else:
                    bad = max(bad, bad_split)
                eqmaps.extend(eqs)
                new_eq += len(eqs)
                if rest is not None:
                    kept.append((src, rest))
            terms = kept
        D, d = _rows([_substitute(m, fixed, xfix) for m in eqmaps], n)
        D, d, det, val, bad_pass, lres = _analyse(D, d, ~fixed, lsq)
        bad = max(bad, bad_pass)
        lsq_res = max(lsq_res, lres)
        if not split or (not det.any() and not new_eq) or passes > 20:
            break
        fixed |= det
        xfix[det] = val[det]
        eqmaps = [_substitute(m, fixed, xfix) for m in eqmaps]
        eqmaps = [m for m in eqmaps if m.idx.size or np.any(m.const != 0)]
    free = np.flatnonzero(~fixed)
    pos = np.full(n, -1, dtype=np.int64)
    pos[free] = np.arange(free.size)
    real_terms = []
    for src, t in terms:
        t = CompiledTerm(t.name, _substitute(t.A, fixed, xfix), t.P, _substitute(t.B, fixed, xfix),
                         _substitute(t.C, fixed, xfix), t.weight)
        if normalize:
            t = _scale(t)
        cplx = bool(t.A.is_complex or t.B.is_complex or t.C.is_complex or np.any(t.P.imag != 0))
        A, B, C, P, w = t.A, t.B, t.C, t.P, t.weight
        if cplx:
            A, B, C, P, w = _realrep(A), _realrep(B), _realrep(C), _realrep_p(P), w / 2
        A, B, C = (LocalMap(m.const.real, pos[m.idx], m.coef.real) for m in (A, B, C))
        A, P, B = _compress(A, np.asarray(P.real, dtype=float), B)
        real_terms.append(RealTerm(A, P, B, C, w, src, cplx))
    lmis = []
    for m in prob.lmis:
        m = _substitute(m, fixed, xfix)
        if m.is_complex:
            m = _realrep(m)
        s = max(float(np.abs(m.const).max()), float(np.abs(m.coef).max(initial=0.0)), 1e-300)
        lmis.append(LocalMap(m.const.real / s, pos[m.idx], m.coef.real / s))
    Dz = D[:, free] if D.shape[0] else sps.csr_matrix((0, free.size))
    H = prob.H
    Hx = H @ xfix
    Hz = sps.csr_matrix(H[free][:, free])
    gz = prob.g[free] + 2 * Hx[free]
    c = prob.objective_value(xfix)
    info = {"passes": passes, "fixed": int(fixed.sum()), "equalities": int(Dz.shape[0]),
            "bilinear_terms": len(real_terms), "equalities_mode": equalities, "equality_residual": lsq_res}
    return Reduced(n, free, xfix, real_terms, sps.csr_matrix(Dz), np.asarray(d), lmis, Hz, gz, c, bad, info)
