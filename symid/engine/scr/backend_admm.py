"""ADMM back end (Algorithm 2.2 extended with LMIs), pure numpy/scipy, vectorised over blocks.

One SCR sub-problem, for fixed Q, R, is

    min_z  f(z) + Σ_t w_t (||Y_t||_* − <W_t, Y_t>)
    s.t.   Y_t = M_t(z),  S_e = E_e(z),  S_e ⪰ 0,  D z = d

(W_t = 0 for the plain nuclear norm). All blocks Y_t and S_e are stacked in one vector
y = 𝒜 z + c, with 𝒜 a sparse matrix assembled once per SCR iteration from the batched
blocks of :mod:`symid.engine.scr.blocks`. Scaled-form ADMM with one shared ρ and
over-relaxation α (Boyd et al. 2011, §3.4.3):

* z-update: the equality-constrained least squares of appendix B (B-9), solved from one
  factorisation of the KKT matrix [[2H + ρ𝒜ᵀ𝒜 + δI, Dᵀ], [D, 0]] per SCR iteration
  (δ is a tiny proximal term keeping it nonsingular; dense LU when small, SuperLU
  otherwise); one sparse product with 𝒜ᵀ and one with 𝒜 per inner iteration;
* Y-update: singular value thresholding (2-12), batched with one ``np.linalg.eigh`` call
  per group of equal-shape blocks; for complex terms on the complex matrices their real
  representation (2-8) stands for (Hermitian Gram matrices of a quarter the size: 22 %
  less time per inner iteration on ``msd3_psd``, 5 of 5 starts);
* S-update: projection onto the PSD cone by eigenvalue clipping, batched likewise, so
  LMI problems need no interior-point solver;
* stop on the primal and dual residuals (Boyd et al. 2011, §3.3.1), checked every
  ``check_every`` inner iterations. The relative part of the dual tolerance is scaled by
  ρ‖u‖ times the RMS column norm of 𝒜 rather than by ‖𝒜ᵀΛ‖, which vanishes at the
  optimum of a feasibility problem;
* the tolerances shrink with the last bilinear residual, or a tenth of the last SCR step
  when that is smaller (``tighten``), so the reachable SCR residual is not capped by the ADMM
  tolerance (with fixed loose tolerances the bilinear residual stalls near them:
  tests/test_scr_problem.py shows it), and on noisy data, where the residual cannot
  fall, the steps settle instead of jittering at the residual's level;
* ρ is rebalanced from the ratio of the normalised residuals (residual balancing, as in
  OSQP) when they differ by more than a factor 5; the KKT matrix is then refactorised.
* each LMI block b has its own penalty ρκ_b (``lmi_rho``, on by default), balanced on the
  block's own normalised residuals like ρ; in the iteration it is a row factor √κ_b of
  the block (ŷ_b = √κ_b y_b, as the equilibration below), so a change of κ keeps the dual
  Λ = ρ D u and refactorises the KKT matrix. An idle LMI otherwise holds z at its last
  value with the weight of a whole block (see :class:`ADMMOptions`);
* optionally (``equilibrate``, off by default), 𝒜 is equilibrated before every sub-problem
  by :func:`ruiz`: ŷ = D y with one factor per block (a scalar keeps a block's nuclear
  norm, (w/d)‖Ŷ‖_*, and its PSD cone), ẑ = E⁻¹ z with one factor per variable, as SCS
  and OSQP scale their data; the iteration on (ẑ, ŷ) is ADMM on the original problem
  with one ρ per block, ρ d_b². The stopping rule is evaluated on the residuals of the
  original problem (as both solvers do by default), ρ is balanced on the scaled ones (as
  OSQP does), and the dual Λ = ρ D u is carried unchanged to the next sub-problem when
  the factors change. What it gains and where it does not: :class:`ADMMOptions`.

No Python loop runs over blocks: only over the few groups of equal-shape blocks. The state
(z, the scaled duals) is kept between SCR iterations (warm start); the inner-iteration
budget is raised by the SCR loop when the residual stalls.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg.lapack as lapack
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from symid.engine.scr.blocks import LMIGroup, TermGroup
from symid.engine.scr.presolve import Reduced
from symid.errors import ModelError

__all__ = ["ADMMBackend", "ADMMOptions"]


@dataclass(frozen=True)
class ADMMOptions:
    """Options of the ADMM back end.

    Attributes
    ----------
    rho : float or None
        Penalty ρ shared by all blocks; ``None`` uses 2 × the median term weight.
    alpha : float
        Over-relaxation factor in (0, 2) (Boyd et al. 2011, §3.4.3); 1 is plain ADMM.
    inner : int
        Initial cap on ADMM iterations per SCR iteration (raised ×2 on stalls).
    inner_first : int
        Cap for the first (cold-started) sub-problem.
    inner_max : int
        Largest cap.
    eps_abs, eps_rel : float
        Absolute and relative tolerances on the primal and dual residuals.
    check_every : int
        Inner iterations between two evaluations of the stopping rule.
    adaptive_rho : bool
        Rebalance ρ from the ratio of the normalised primal and dual residuals (as OSQP
        does; Boyd et al. 2011, §3.4.1) when they differ by more than a factor 5, at most
        every ``adapt_every`` inner iterations; the KKT matrix is then refactorised.
        The adapted ρ carries over to the next SCR iteration.
    adapt_every : int
        Smallest number of inner iterations between two changes of ρ.
    tighten : float or None
        Inexact SCR: the primal tolerance of a sub-problem is lowered to ``tighten`` × the
        smaller of the last bilinear residual and a tenth of the last SCR step when that is smaller
        (the dual one in proportion), so the sub-problems get more accurate as SCR
        converges instead of capping the reachable residual at the ADMM tolerance.
        ``None`` keeps the fixed tolerances.
    equilibrate : bool
        Ruiz equilibration of the stacked map 𝒜 before every sub-problem: one factor per
        block (each bilinear term's matrix, each LMI, so that the nuclear norm and the PSD
        cone of a block are kept) and one per variable, which is ADMM with one ρ per block
        (see the module notes). Off by default. Measured (``benchmarks/admm_scaling.py``):
        with one ρ for all blocks (``lmi_rho=False``) it brought single sub-problems of the
        spectra of thesis §5-6 10–40× closer to Clarabel's optimum in 2000 inner iterations
        (relative gap 1.3e-5 against 4.9e-4 near θ*), but SCR still failed from every start:
        what held θ was not the scale of the blocks but the idle LMIs (``lmi_rho``). With
        ``lmi_rho`` it adds nothing there: SCR reaches the truth from 5 of 5 starts either
        way, in the same time (5.7 against 5.5 s per start), and far from θ* (ε = 0.3) a
        sub-problem stopped 3.0 from Clarabel's θ where the plain iteration came within 4e-5.
        Its per-variable factors cannot help here: with no objective in θ the z-update
        projects onto the range of 𝒜, which no change of variables of z alters; only the
        block factors act. On the 2-DOF example of §4-6-2 it changes nothing but the time,
        and on the belt drive with whole blocks relaxed (presolve off) SCR stopped short of
        the tolerance where the plain iteration met it.
    lmi_rho : bool
        One penalty per LMI block, ρκ_b, balanced on that block's own residuals (the rule
        of ``adaptive_rho``, κ_b in [1e-8, 1e4], at most every ``adapt_every`` inner
        iterations) instead of the terms' ρ. Default on. An LMI that does not bind still
        enters the z-update as the proximal term ρκ_b‖𝒜_b(z − z_k)‖², which pins z where
        the bilinear terms' map is nearly singular: on the spectra of thesis §5-6
        (``msd3_psd``) that map has singular values from 5 down to 4e-5 against √2 for the
        LMI rows, and with one shared ρ ADMM ended every sub-problem where it started
        (1e-3–2e-2 above Clarabel's value after 2000 inner iterations, θ still 13–10⁴ from
        Clarabel's optimum; tests/test_scr_admm_lmi_rho.py). κ of an idle LMI falls to its
        floor, of a binding one stays large. Measured on ``msd3_psd``
        (``benchmarks/admm_scaling.py``, 5 starts, one run): SCR reaches the truth from 5
        of 5 starts in a median 5.5 s per start, against 0 of 5 (max_iter after 21 s, largest
        relative errors 79–701) with one ρ, and Clarabel's 5 of 5 in 77 s (14× slower); the
        belt drive and the 2-DOF of §4-6-2 are unchanged (10/10 each).

    Examples
    --------
    >>> from symid import scr
    >>> scr.ADMMOptions(rho=1.0, inner=100).alpha
    1.6
    """

    rho: float | None = None
    alpha: float = 1.6
    inner: int = 50
    inner_first: int = 2000
    inner_max: int = 1000
    eps_abs: float = 1e-7
    eps_rel: float = 1e-6
    check_every: int = 5
    adaptive_rho: bool = True
    adapt_every: int = 25
    tighten: float | None = 1.0
    equilibrate: bool = False
    lmi_rho: bool = True

    def __post_init__(self) -> None:
        if self.rho is not None and not (np.isfinite(self.rho) and self.rho > 0):
            raise ModelError(f"ADMMOptions.rho must be finite and > 0, got {self.rho}")
        if not 0 < self.alpha < 2:
            raise ModelError(f"ADMMOptions.alpha must lie in (0, 2), got {self.alpha}")
        for name in ("inner", "inner_first", "inner_max", "check_every", "adapt_every"):
            if int(getattr(self, name)) < 1:
                raise ModelError(f"ADMMOptions.{name} must be ≥ 1, got {getattr(self, name)}")
        if self.tighten is not None and not (np.isfinite(self.tighten) and self.tighten > 0):
            raise ModelError(f"ADMMOptions.tighten must be finite and > 0 or None, got {self.tighten}")
        for name in ("eps_abs", "eps_rel"):
            if not getattr(self, name) >= 0:
                raise ModelError(f"ADMMOptions.{name} must be ≥ 0, got {getattr(self, name)}")


_DENSE_MAX = 200  # KKT size up to which a dense LU beats SuperLU here
_DENSE_OPERATOR = 250_000  # entries of 𝒜 up to which dense products beat sparse ones


class _KKT:
    """Factorisation of the KKT matrix [[N, Dᵀ], [D, 0]]; dense LAPACK LU when small, SuperLU otherwise.

    The sparse factorisation orders the symmetric pattern (minimum degree on K + Kᵀ) and
    prefers diagonal pivots: with SuperLU's default column ordering and partial pivoting
    the arrow-shaped matrices of SCR (shared parameters coupling many private blocks)
    filled in ~100× more.
    """

    def __init__(self, N: sps.spmatrix, D: sps.spmatrix, dense_max: int = _DENSE_MAX):
        m = D.shape[0]
        K = sps.bmat([[N, D.T], [D, None]], format="csc") if m else sps.csc_matrix(N)
        self.nz = N.shape[0]
        self.empty = K.shape[0] == 0
        if self.empty:
            self.sparse = None
        elif K.shape[0] <= dense_max:
            self.lu, self.piv, info = lapack.dgetrf(K.toarray())
            if info != 0:
                raise np.linalg.LinAlgError(f"singular KKT matrix (LAPACK getrf info={info})")
            self.sparse = None
        else:
            self.sparse = spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.01)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if self.empty:
            return np.zeros(0)
        if self.sparse is None:
            x, _ = lapack.dgetrs(self.lu, self.piv, rhs)
        else:
            x = self.sparse.solve(rhs)
        return x[: self.nz]


def _svt(X: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Singular value thresholding (2-12) of a stack X (s, p, q) with thresholds tau (s,).

    Uses the eigen-decomposition of the smaller Gram matrix (one batched ``eigh``, about
    twice as fast as a batched SVD for the small blocks SCR produces):
    Y = X V diag(max(1 − τ/σ, 0)) Vᵀ.
    """
    transpose = X.shape[1] < X.shape[2]
    Xt = X.transpose(0, 2, 1) if transpose else X
    Xh = Xt.transpose(0, 2, 1).conj() if np.iscomplexobj(Xt) else Xt.transpose(0, 2, 1)
    lam, V = np.linalg.eigh(Xh @ Xt)
    sig = np.sqrt(np.maximum(lam, 0.0))
    f = np.where(sig > tau[:, None], 1.0 - tau[:, None] / np.where(sig > 0, sig, 1.0), 0.0)
    Vh = V.transpose(0, 2, 1).conj() if np.iscomplexobj(V) else V.transpose(0, 2, 1)
    Y = Xt @ ((V * f[:, None, :]) @ Vh)
    return Y.transpose(0, 2, 1) if transpose else Y


def _complex_layout(g: TermGroup) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """Rows and columns of the real and imaginary parts when every term of g is a complex pair.

    The real representation (2-8) of a complex term makes every block of M (2-6) a real
    representation [[Re, −Im], [Im, Re]], so M is, up to a permutation, that of the complex
    (p/2) × (q/2) matrix M_c, with the singular values of M_c, each twice: the SVT of M is
    that of M_c, on Hermitian Gram matrices a quarter of the size. ``None`` otherwise.
    """
    j, k, l, m = g.dims
    if not np.all(g.norm_factor < 1.0) or any(v % 2 for v in (j, k, l, m)):
        return None
    rre = np.r_[0:j // 2, j:j + k // 2]
    rim = np.r_[j // 2:j, j + k // 2:j + k]
    cre = np.r_[0:m // 2, m:m + l // 2]
    cim = np.r_[m // 2:m, m + l // 2:m + l]
    return rre, rim, cre, cim


def _is_realrep(X: np.ndarray, layout: tuple[np.ndarray, ...]) -> bool:
    """Whether every matrix of the stack X has the structure of :func:`_complex_layout`."""
    rre, rim, cre, cim = layout
    re, re2 = X[:, rre][:, :, cre], X[:, rim][:, :, cim]
    im, im2 = X[:, rim][:, :, cre], X[:, rre][:, :, cim]
    scale = max(float(np.abs(X).max(initial=0.0)), 1e-300)
    tol = 1e-12 * scale
    return bool(np.abs(re - re2).max(initial=0.0) <= tol and np.abs(im + im2).max(initial=0.0) <= tol)


def _svt_complex(X: np.ndarray, tau: np.ndarray, layout: tuple[np.ndarray, ...]) -> np.ndarray:
    """:func:`_svt` of a stack of real representations (:func:`_complex_layout`), through the complex matrices."""
    rre, rim, cre, cim = layout
    h, w = rre.size, cre.size
    pr, pc = np.concatenate([rre, rim]), np.concatenate([cre, cim])
    Xp = X[:, pr][:, :, pc]  # [[Re, −Im], [Im, Re]]
    Xc = 0.5 * (Xp[:, :h, :w] + Xp[:, h:, w:]) + 0.5j * (Xp[:, h:, :w] - Xp[:, :h, w:])
    Yc = _svt(Xc, tau)
    re, im = Yc.real, Yc.imag
    Yp = np.concatenate([np.concatenate([re, -im], axis=2), np.concatenate([im, re], axis=2)], axis=1)
    return Yp[:, np.argsort(pr)][:, :, np.argsort(pc)]


def _psd(X: np.ndarray) -> np.ndarray:
    """Projection of a stack of square matrices onto the PSD cone (eigenvalue clipping)."""
    ev, V = np.linalg.eigh(0.5 * (X + X.transpose(0, 2, 1)))
    return (V * np.maximum(ev, 0.0)[:, None, :]) @ V.transpose(0, 2, 1)


def _block_rows(offset: int, idx: np.ndarray, coef: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """COO triplets of the rows ``offset + t*P + r`` of a batched local map coef (s, P, u) on z[idx (s, u)]."""
    s, P, u = coef.shape
    rows = offset + np.arange(s * P).reshape(s, P, 1)
    rows = np.broadcast_to(rows, (s, P, u))
    cols = np.broadcast_to(idx[:, None, :], (s, P, u))
    keep = (cols >= 0) & (coef != 0)
    return rows[keep], cols[keep], coef[keep]


def _segment_max(vals: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Largest value of each segment vals[starts[i]:starts[i+1]] (0 for an empty one)."""
    out = np.zeros(starts.size - 1)
    full = starts[:-1] < starts[1:]
    if vals.size and full.any():
        out[full] = np.maximum.reduceat(vals, starts[:-1][full])
    return out


_KAPPA = (1e-8, 1e4)  # range of the LMI blocks' penalties relative to ρ
_RUIZ_PASSES = 25  # as SCS (NUM_RUIZ_PASSES)
_RUIZ_TOL = 0.1  # stop once every block and column maximum is within 10 % of 1
_SCALE_RANGE = (1e-4, 1e4)  # bounds on the accumulated factors, as OSQP (MIN_SCALING, MAX_SCALING)


def ruiz(A: sps.csr_matrix, block_starts: np.ndarray, H: sps.spmatrix | None = None,
         passes: int = _RUIZ_PASSES) -> tuple[np.ndarray, np.ndarray]:
    """Modified Ruiz equilibration of A (m × n) with one row factor per block of rows.

    Rows ``block_starts[b]:block_starts[b+1]`` share one factor ``d[b]`` (SCS keeps a cone's
    rows together the same way), columns get one factor each, ``e``; the largest entry of
    every block and of every column of diag(d) A diag(e) — and of every column of
    diag(e) H diag(e), if ``H`` is given — is driven to 1 by alternately dividing by the
    square roots of the current maxima (Ruiz 2001). Blocks and columns without entries keep
    factor 1. Returns (d, e).

    Examples
    --------
    Two blocks, row 0 and rows 1–2, five decades apart:

    >>> import numpy as np, scipy.sparse as sps
    >>> A = sps.csr_matrix(np.array([[1e3, 2e3], [1e-2, 3e-2], [4e-2, 1e-2]]))
    >>> d, e = ruiz(A, np.array([0, 1, 3]))
    >>> B = abs(d[[0, 1, 1], None] * A.toarray() * e)
    >>> maxima = [B[:1].max(), B[1:].max(), *B.max(axis=0)]  # of each block, of each column
    >>> bool(np.allclose(maxima, 1.0, atol=0.1)), bool(d[1] / d[0] > 1e4)
    (True, True)
    """
    A = sps.csr_matrix(A)
    m, n = A.shape
    nb = block_starts.size - 1
    d, e = np.ones(nb), np.ones(n)
    if A.nnz == 0 and (H is None or H.nnz == 0):
        return d, e
    absval = np.abs(A.data)
    rows = np.repeat(np.arange(m), np.diff(A.indptr))
    block_of_row = np.repeat(np.arange(nb), np.diff(block_starts))
    blk = block_of_row[rows]
    cols = A.indices
    b_starts = A.indptr[block_starts]  # entries of a CSR matrix are ordered by row, hence by block
    order = np.argsort(cols, kind="stable")
    c_starts = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=n))])
    if H is not None and H.nnz:
        Hc = sps.coo_matrix(H)
        h_abs, h_r, h_c = np.abs(Hc.data), Hc.row, Hc.col
    else:
        h_abs = None
    lo, hi = _SCALE_RANGE
    for _ in range(passes):
        vals = absval * d[blk] * e[cols]
        bmax = _segment_max(vals, b_starts)
        cmax = _segment_max(vals[order], c_starts)
        if h_abs is not None:
            hv = h_abs * e[h_r] * e[h_c]
            hmax = np.zeros(n)
            np.maximum.at(hmax, h_c, hv)
            cmax = np.maximum(cmax, hmax)
        bm, cm = bmax[bmax > 0], cmax[cmax > 0]
        if max(np.abs(bm - 1).max(initial=0.0), np.abs(cm - 1).max(initial=0.0)) <= _RUIZ_TOL:
            break
        d = np.clip(d / np.sqrt(np.where(bmax > 0, bmax, 1.0)), lo, hi)
        e = np.clip(e / np.sqrt(np.where(cmax > 0, cmax, 1.0)), lo, hi)
    return d, e


class ADMMBackend:
    """Solve the SCR sub-problems by ADMM; see the module docstring."""

    name = "admm"

    def __init__(self, red: Reduced, groups: list[TermGroup], lmis: list[LMIGroup], options: ADMMOptions):
        self.red, self.groups, self.lgroups, self.opt = red, groups, lmis, options
        ws = np.concatenate([g.weight for g in groups]) if groups else np.ones(1)
        self.rho = float(options.rho) if options.rho is not None else 2.0 * float(np.median(ws))
        self.inner = int(options.inner)
        self.iterations: list[int] = []
        self.hit_cap = False
        # layout of the stacked vector y: term groups first, then LMI groups
        sizes = [g.s * int(np.prod(g.pq)) for g in groups] + [g.E0.size for g in lmis]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.m = int(self.offsets[-1])
        # one block per term and per LMI: the rows that share one equilibration factor
        bsizes = [np.full(g.s, int(np.prod(g.pq))) for g in groups] + [np.full(g.s, g.E0[0].size) for g in lmis]
        self.block_starts = np.concatenate([[0], np.cumsum(np.concatenate(bsizes) if bsizes else [])]).astype(int)
        self._term_blocks = np.concatenate([[0], np.cumsum([g.s for g in groups])]).astype(int)
        trip = [_block_rows(int(self.offsets[len(groups) + k]), g.idx, g.G()) for k, g in enumerate(lmis)]
        self._lmi_rows = tuple(np.concatenate([t[i] for t in trip]) if trip else np.zeros(0) for i in range(3))
        self._lmi_c = np.concatenate([g.E0.reshape(-1) for g in lmis]) if lmis else np.zeros(0)
        self.z = np.zeros(red.nz)
        self.u = np.zeros(self.m)  # scaled dual of the equilibrated problem, u = D⁻¹Λ/ρ
        self.started = False
        self.d_blocks = np.ones(self.block_starts.size - 1)  # row factor of each block
        self.d_base = np.ones(self.block_starts.size - 1)  # Ruiz factors (1 without equilibration)
        self.kappa = np.ones(self.block_starts.size - 1)  # penalty of each block relative to ρ (LMIs adapted)
        self._lmi_first = int(self._term_blocks[-1])  # blocks from here on are LMIs
        self.lmi_adapt = bool(options.lmi_rho) and self.block_starts.size - 1 > self._lmi_first
        self.scaled = bool(options.equilibrate) or self.lmi_adapt  # the iteration runs on ŷ = D y, ẑ = E⁻¹z
        self.d_rows = np.ones(self.m)
        self.e_cols = np.ones(red.nz)  # column factor of each variable
        self.scalings: list[tuple[float, float]] = []  # (spread of d, spread of e) per sub-problem
        self._layouts = [_complex_layout(g) for g in groups]  # complex pairs: SVT on the complex matrices
        self._complex = [False] * len(groups)
        self._set_taus()

    def _set_taus(self) -> None:
        """Thresholds of the SVT per group: w_t / (ρ d_t)."""
        tb = self._term_blocks
        self.taus = [g.weight / (self.rho * self.d_blocks[tb[k]:tb[k + 1]]) for k, g in enumerate(self.groups)]

    def on_stall(self) -> None:
        """Double the inner-iteration cap if the last sub-problem hit it."""
        if self.hit_cap:
            self.inner = min(2 * self.inner, self.opt.inner_max)

    def _assemble(self, built: list[tuple[np.ndarray, np.ndarray]]) -> tuple[sps.csr_matrix, np.ndarray]:
        """The stacked affine map y = 𝒜 z + c of every block, from the groups' M = m0 + G z."""
        rows, cols, vals, cs = [], [], [], []
        for k, (g, (m0, G)) in enumerate(zip(self.groups, built, strict=True)):
            t = _block_rows(int(self.offsets[k]), g.idx, G)
            rows.append(t[0])
            cols.append(t[1])
            vals.append(t[2])
            cs.append(m0.reshape(-1))
        rows.append(self._lmi_rows[0])
        cols.append(self._lmi_rows[1])
        vals.append(self._lmi_rows[2])
        cs.append(self._lmi_c)
        A = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows).astype(np.int64),
                                                    np.concatenate(cols).astype(np.int64))),
                           shape=(self.m, self.red.nz))
        return A, np.concatenate(cs)

    def _equilibrate(self, A: sps.csr_matrix) -> None:
        """New block and column factors for the map A; the scaled dual carried over (Λ unchanged)."""
        d, e = ruiz(A, self.block_starts, self.red.H if self.red.H.nnz else None)
        if not self.started and self.opt.rho is None and self.groups:  # ρ from the weights of the scaled problem
            tb = self._term_blocks
            self.rho = 2.0 * float(np.median(np.concatenate(
                [g.weight / d[tb[k]:tb[k + 1]] for k, g in enumerate(self.groups)])))
        self.d_base, self.e_cols = d, e
        self._set_d()
        spread = [float(v.max() / v.min()) if v.size else 1.0 for v in (d, e)]
        self.scalings.append((spread[0], spread[1]))

    def _set_d(self) -> None:
        """Row factors from the Ruiz factors and the block penalties κ (ρ_b = ρ d_b² κ_b); Λ = ρ D u is kept."""
        d = self.d_base * np.sqrt(self.kappa)
        d_rows = np.repeat(d, np.diff(self.block_starts))
        self.u *= self.d_rows / d_rows
        self.d_blocks, self.d_rows = d, d_rows
        self._set_taus()

    def _prox(self, x: np.ndarray, shifts: list[np.ndarray | None]) -> np.ndarray:
        """Y-update (SVT) and S-update (PSD projection) on the stacked vector x."""
        y = np.empty_like(x)
        off = self.offsets
        for k, g in enumerate(self.groups):
            X = x[off[k]:off[k + 1]].reshape(g.s, *g.pq)
            if shifts[k] is not None:
                X = X + shifts[k]
            Y = _svt_complex(X, self.taus[k], self._layouts[k]) if self._complex[k] else _svt(X, self.taus[k])
            y[off[k]:off[k + 1]] = Y.reshape(-1)
        return y

    def _project(self, x: np.ndarray, y: np.ndarray) -> None:
        off, ng = self.offsets, len(self.groups)
        for k, g in enumerate(self.lgroups):
            e = g.E0.shape[1]
            sl = slice(off[ng + k], off[ng + k + 1])
            y[sl] = _psd(x[sl].reshape(g.s, e, e)).reshape(-1)

    def _factor(self, AtA: sps.csr_matrix, H: sps.spmatrix, D: sps.spmatrix) -> tuple[_KKT, float]:
        """Factorise the KKT matrix of the z-update for the current ρ; returns it and δ."""
        nz = self.red.nz
        N = sps.csr_matrix(2 * H + self.rho * AtA)
        delta = 1e-10 * max(1.0, float(N.diagonal().max(initial=0.0)))
        return _KKT(N + delta * sps.identity(nz, format="csr"), D), delta

    def _refactor(self, AtA: sps.csr_matrix, H: sps.spmatrix, D: sps.spmatrix, tm: dict[str, float],
                  t: float) -> tuple[_KKT, float] | str:
        """:meth:`_factor` after a change of the penalties, its time (from ``t``) added to ``tm["factor"]``; the
        reason as a message when the KKT matrix cannot be factorised."""
        try:
            fac = self._factor(AtA, H, D)
        except (RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
            return f"ADMM: the KKT matrix could not be factorised ({exc})"
        tm["factor"] += time.perf_counter() - t
        return fac

    def _set_rho(self, rho: float) -> None:
        self.u *= self.rho / rho  # the scaled dual u = Λ/ρ
        self.rho = rho
        self._set_taus()

    def _scaled(self, A0: sps.csr_matrix, c0: np.ndarray) -> tuple:
        """The data of the iteration on ẑ = E⁻¹z, ŷ = D y for the current factors: A, Aᵀ, AᵀA, c, H, D, g."""
        red = self.red
        H, Dm, g = red.H, red.D, red.g
        A, c = A0, c0
        if self.scaled:
            dr, ec = self.d_rows, self.e_cols
            A = sps.csr_matrix(sps.diags(dr) @ A0 @ sps.diags(ec))
            c = dr * c0
            H = sps.csr_matrix(sps.diags(ec) @ H @ sps.diags(ec))
            Dm = sps.csr_matrix(Dm @ sps.diags(ec))
            g = ec * g
        AT = A.T.tocsr()
        AtA = AT @ A
        if self.m * red.nz <= _DENSE_OPERATOR:  # small problems: dense products have less overhead
            A, AT = A.toarray(), AT.toarray()
        return A, AT, AtA, c, H, Dm, g

    def _lmi_ratios(self, A: np.ndarray | sps.csr_matrix, az: np.ndarray, y_new: np.ndarray, y: np.ndarray,
                    a_rms: float) -> np.ndarray:
        """Residual-balancing ratio of every LMI block, √((r_p/scale_p) / (r_d/scale_d)) on the scaled problem
        (1 where both residuals vanish)."""
        lo = int(self.offsets[len(self.groups)])
        starts = self.block_starts[self._lmi_first:] - lo
        b = starts[:-1]

        def norms(v: np.ndarray) -> np.ndarray:
            return np.sqrt(np.add.reduceat(v * v, b))

        rp = norms((az - y_new)[lo:])
        sp_ = np.maximum(norms(az[lo:]), norms(y_new[lo:]))
        AL = A[lo:] if isinstance(A, np.ndarray) else A[lo:].toarray()
        rd = self.rho * np.linalg.norm(np.add.reduceat(AL * (y_new - y)[lo:, None], b, axis=0), axis=1)
        sd = self.rho * norms(self.u[lo:]) * a_rms
        num = rp * np.maximum(sd, 1e-300)
        den = rd * np.maximum(sp_, 1e-300)
        out = np.ones(rp.size)
        moving = (num > 0) | (den > 0)
        out[moving] = np.sqrt(num[moving]) / np.sqrt(np.maximum(den[moving], 1e-300))  # no overflow
        return out

    def step(self, built: list[tuple[np.ndarray, np.ndarray]], W: list[np.ndarray] | None,
             z0: np.ndarray, residual: float = np.inf, deadline: float | None = None
             ) -> tuple[np.ndarray, bool, str, dict]:
        """One SCR sub-problem for the blocks M = m0 + G z of ``built``; returns (z, ok, message, timing).

        ``deadline`` (a ``time.perf_counter()`` value): the inner loop stops at the first check
        after it, keeping its inexact iterate (``timing["time_limit"]`` is then true).

        ``residual`` is the accuracy SCR asks for (the smaller of the last bilinear residual and a tenth
        of the last step); with ``tighten`` the tolerances shrink with it.

        With ``equilibrate`` the iteration runs on ẑ = E⁻¹z and ŷ = D y, D and E from
        :func:`ruiz`; the stopping rule is evaluated on the residuals of the original problem
        (as SCS and OSQP do), ρ is balanced on those of the scaled one (as OSQP does).
        """
        red, opt = self.red, self.opt
        nz, m = red.nz, self.m
        tm = {"build": 0.0, "factor": 0.0, "solve": 0.0, "svd": 0.0, "projection": 0.0}
        t = time.perf_counter()
        A0, c0 = self._assemble(built)
        for k, (g, (m0, G)) in enumerate(zip(self.groups, built, strict=True)):
            lay = self._layouts[k]
            self._complex[k] = W is None and lay is not None and _is_realrep(m0, lay) and _is_realrep(
                G.reshape(g.s, *g.pq, -1).transpose(0, 3, 1, 2).reshape(-1, *g.pq), lay)
        scaled = self.scaled
        a_rms = np.sqrt(float(A0.data @ A0.data) / max(nz, 1)) if scaled else 0.0  # RMS column norm of 𝒜
        if opt.equilibrate:
            self._equilibrate(A0)
        A, AT, AtA, c, H, Dm, g = self._scaled(A0, c0)
        ec = self.e_cols
        a_rms_s = np.sqrt(float(AtA.diagonal().sum()) / max(nz, 1))  # (of the equilibrated 𝒜 if scaled)
        if not scaled:
            a_rms = a_rms_s
        tm["build"] += time.perf_counter() - t
        t = time.perf_counter()
        try:
            kkt, delta = self._factor(AtA, H, Dm)
        except (RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
            return z0, False, f"ADMM: the KKT matrix could not be factorised ({exc})", tm
        tm["factor"] += time.perf_counter() - t
        if not self.started:
            self.z = z0.copy()
        z = self.z / self.e_cols if scaled else self.z
        y = A @ z + c
        neq = Dm.shape[0]
        rhs = np.zeros(nz + neq)
        rhs[nz:] = red.d
        alpha = opt.alpha
        sqm, sqn = np.sqrt(max(m, 1)), np.sqrt(max(nz, 1))
        ok = False
        it = 0
        rp = rd = np.inf
        cap = self.inner if self.started else max(self.inner, opt.inner_first)
        check = max(1, int(opt.check_every))
        accuracy = opt.tighten * residual if opt.tighten is not None else np.inf
        last_change = 0
        timed_out = False
        shifts: list[np.ndarray | None] = [None] * len(self.groups)
        for it in range(1, cap + 1):
            rho, u = self.rho, self.u
            if W is not None and it == last_change + 1:
                shifts = [tau[:, None, None] * w for tau, w in zip(self.taus, W, strict=True)]
            t = time.perf_counter()
            rhs[:nz] = rho * (AT @ (y - u - c)) - g + delta * z
            z = kkt.solve(rhs)
            az = A @ z + c
            ah = alpha * az + (1 - alpha) * y if alpha != 1 else az
            x = ah + u
            t2 = time.perf_counter()
            tm["solve"] += t2 - t
            y_new = self._prox(x, shifts)
            t3 = time.perf_counter()
            tm["svd"] += t3 - t2
            self._project(x, y_new)
            tm["projection"] += time.perf_counter() - t3
            self.u = u = x - y_new
            if it % check == 0 or it == cap or m == 0:
                t = time.perf_counter()
                aty = AT @ (y_new - y)
                if scaled:  # residuals of the original problem: D⁻¹ on rows, E⁻¹ on the dual
                    dr = self.d_rows
                    rp = float(np.linalg.norm((az - y_new) / dr))
                    rd = rho * float(np.linalg.norm(aty / ec))
                    scale_p = max(float(np.linalg.norm(az / dr)), float(np.linalg.norm(y_new / dr)))
                    scale_d = rho * float(np.linalg.norm(u * dr)) * a_rms
                    rps, rds = float(np.linalg.norm(az - y_new)), rho * float(np.linalg.norm(aty))
                    scale_ps = max(float(np.linalg.norm(az)), float(np.linalg.norm(y_new)))
                    scale_ds = rho * float(np.linalg.norm(u)) * a_rms_s
                else:
                    rp = float(np.linalg.norm(az - y_new))
                    rd = rho * float(np.linalg.norm(aty))
                    scale_p = max(float(np.linalg.norm(az)), float(np.linalg.norm(y_new)))
                    # ||𝒜ᵀΛ|| of Boyd et al. vanishes at the optimum of a feasibility problem; ||Λ|| times the
                    # RMS column norm of 𝒜 is the scale of the terms whose difference the dual residual is
                    scale_d = rho * float(np.linalg.norm(u)) * a_rms
                    rps, rds, scale_ps, scale_ds = rp, rd, scale_p, scale_d
                tm["solve"] += time.perf_counter() - t
                eps_p = sqm * opt.eps_abs + opt.eps_rel * scale_p
                eps_d = sqn * opt.eps_abs + opt.eps_rel * scale_d
                if accuracy < eps_p:  # inexact SCR: the sub-problem no sloppier than the bilinear residual
                    eps_p, eps_d = accuracy, eps_d * max(accuracy / eps_p, 1e-6)
                if rp <= eps_p and rd <= eps_d:
                    ok = True
                    break
                if deadline is not None and time.perf_counter() >= deadline:
                    timed_out = True
                    y = y_new
                    break
                if opt.adaptive_rho and it - last_change >= opt.adapt_every and rps > 0 and rds > 0:
                    ratio = np.sqrt((rps / max(scale_ps, 1e-300)) / (rds / max(scale_ds, 1e-300)))
                    if not 0.2 <= ratio <= 5.0:
                        t = time.perf_counter()
                        self._set_rho(float(np.clip(rho * ratio, 1e-6, 1e6)))
                        fac = self._refactor(AtA, H, Dm, tm, t)
                        if isinstance(fac, str):
                            return z0, False, fac, tm
                        kkt, delta = fac
                        last_change = it
                if self.lmi_adapt and it - last_change >= opt.adapt_every:
                    ratio = self._lmi_ratios(A, az, y_new, y, a_rms_s)
                    kappa = self.kappa.copy()
                    lmi = kappa[self._lmi_first:]
                    change = (ratio < 0.2) | (ratio > 5.0)
                    lmi[change] = np.clip(lmi[change] * ratio[change], _KAPPA[0], _KAPPA[1])
                    if np.any(kappa != self.kappa):  # (not when every change is held at a bound)
                        t = time.perf_counter()
                        d_old = self.d_rows
                        self.kappa = kappa
                        self._set_d()
                        y_new = y_new * (self.d_rows / d_old)  # ŷ = D y in the new factors
                        A, AT, AtA, c, H, Dm, g = self._scaled(A0, c0)
                        fac = self._refactor(AtA, H, Dm, tm, t)
                        if isinstance(fac, str):
                            return z0, False, fac, tm
                        kkt, delta = fac
                        last_change = it
            y = y_new
        if scaled:
            z = z * self.e_cols
        self.started = True
        self.z = z
        self.hit_cap = not ok
        self.iterations.append(it)
        tm["inner_iterations"] = it
        tm["primal_residual"] = float(rp)
        tm["dual_residual"] = float(rd)
        tm["rho"] = self.rho
        if self.lmi_adapt:
            tm["lmi_kappa_min"] = float(self.kappa[self._lmi_first:].min())
        if not np.all(np.isfinite(z)):
            return z0, False, "ADMM diverged (non-finite iterate)", tm
        tm["time_limit"] = timed_out
        if timed_out:
            msg = f"ADMM stopped by the time limit after {it} inner iterations (primal {rp:.2e}, dual {rd:.2e})"
        else:
            msg = "" if ok else f"ADMM stopped at its cap of {cap} inner iterations (primal {rp:.2e}, dual {rd:.2e})"
        return z, True, msg, tm
