"""Initial similarity transforms (T₀, S₀) shared by every similarity method, so starts are identical.

A start of :func:`symid.identify` is a parameter vector x₀. The similarity methods work
on (θ, T) (and SCR also on S, its substitute for T⁻¹); they derive the same (θ₀, T₀, S₀)
from x₀, in one of four ways (``aux_init``):

``"random"`` (no prior knowledge, thesis §6-6-2 and §6-7-1)
    When x₀ already explains the black box — F(x₀, T) ≤ 1e-12 of the energy of its
    terms for the least-squares T of x₀, e.g. the truth on noise-free data — the start is
    kept as ``"model"`` would keep it. Otherwise
    T₀ = α G₁ and S₀ = G₂ / α with G₁, G₂ independent N(0, 1) matrices ("S and T with
    entries drawn from a random distribution"), seeded by ``seed`` and the start
    (:func:`start_key`: numbers of the start's model that no unit changes), so the same x₀
    gives the same G₁, G₂ in every method and every run, and so does the same start in
    other units (ALS, GB and IPOPT scale them in the units of :func:`working_problem`, SCR
    in the model's own, so their T₀ are not the same matrix); θ₀ =
    argmin_θ F(θ, T₀), the least squares (C-8). α is the scale the data imply for T
    (:func:`transform_scale`), so that T₀ and S₀ = T₀⁻¹-sized draws are both plausible.
``"model"`` (prior knowledge on θ, thesis §6-7-2)
    θ₀ = x₀, T₀ = argmin_T F(θ₀, T), the least squares (C-7), and S₀ = T₀⁺.
``"zero"``, ``"identity"``
    T₀ = S₀ = 0 or I (thesis §6-6-2 reports that zero fails); θ₀ by (C-8).

F is the similarity misfit (C-1), ‖T𝔸 − A(θ)T‖² + ‖T𝔹 − B(θ)‖² + ‖ℂ − C(θ)T‖²
(+ ‖𝔻 − D(θ)‖² when D holds parameters). ALS, GB and IPOPT take it, and these starts,
on :func:`working_problem`'s pair: the same equations in units where the blocks weigh
alike (time, inputs, outputs, the model's states and T of size one), so that their
iterations do not depend on the units the model and data are given in.
"""

from __future__ import annotations

import dataclasses
import zlib
from typing import Any

import numpy as np

from symid.errors import ModelError

__all__ = ["INITS", "WorkingProblem", "initial_point", "io_time_normalised", "least_squares_theta",
           "least_squares_transform", "random_pair", "start_key", "state_sizes", "time_unit", "transform_scale",
           "unknown_scale", "working_problem"]

INITS = ("random", "model", "zero", "identity")
_EXPLAINS = 1e-12  # relative similarity misfit below which a start explains the black box ("random" keeps it)


def least_squares_transform(maps: dict[str, Any], bb: Any, theta: np.ndarray) -> np.ndarray:
    """T minimising ‖T𝔸 − A(θ)T‖² + ‖T𝔹 − B(θ)‖² + ‖ℂ − C(θ)T‖² for fixed θ (thesis (C-7)).

    Column-major vec: vec(T X) = (Xᵀ ⊗ I) vec T and vec(Y T) = (I ⊗ Y) vec T.
    """
    A, B, C = (maps[k](theta) for k in "ABC")
    n = A.shape[0]
    eye = np.eye(n)
    lhs = np.vstack([np.kron(bb.A.T, eye) - np.kron(eye, A), np.kron(bb.B.T, eye), np.kron(eye, C)])
    rhs = np.concatenate([np.zeros(n * n), B.ravel(order="F"), bb.C.ravel(order="F")])
    return np.linalg.lstsq(lhs, rhs, rcond=None)[0].reshape(n, n, order="F")


def random_pair(n: int, key: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Two independent N(0, 1) n×n matrices, seeded by ``seed`` and the start's ``key`` (:func:`start_key`)."""
    rng = np.random.default_rng([int(seed), int(key)])
    return rng.standard_normal((n, n)), rng.standard_normal((n, n))


_KEY_DIGITS = 5  # significant digits of the start's unit-free numbers that seed its random T₀
_KEY_ZERO = 1e-9  # relative size below which a part of such a number counts as 0


def _key_text(values: np.ndarray) -> list[str]:
    """Each complex number rounded to ``_KEY_DIGITS`` significant digits; parts below ``_KEY_ZERO`` of the
    largest |value| are 0, so rounding noise (an imaginary part of 1e-17) does not change the text."""
    v = np.asarray(values, dtype=complex).ravel()
    v = np.where(np.isfinite(v), v, 0.0)
    big = float(np.max(np.abs(v))) if v.size else 0.0
    re = np.where(np.abs(v.real) > _KEY_ZERO * big, v.real, 0.0)
    im = np.where(np.abs(v.imag) > _KEY_ZERO * big, np.abs(v.imag), 0.0)  # a conjugate pair: the same text
    return [f"{a:.{_KEY_DIGITS - 1}e},{b:.{_KEY_DIGITS - 1}e}" for a, b in zip(re, im, strict=True)]


def start_key(A: np.ndarray, B: np.ndarray, C: np.ndarray, bb: Any) -> int:
    """A number that tells starts apart and does not depend on units: the seed of a start's random T₀.

    It is read off the start's model (A, B, C) = (A(x₀), B(x₀), C(x₀)) against the black box,
    through numbers that no choice of units changes: the model's eigenvalues in units of
    the black box's rate ρ(𝔸) = 1/:func:`time_unit` (sorted), and the ratio of each entry of
    the model's |H(iρ)| to the black box's. Each is rounded to 5 significant digits, and the
    text hashed (CRC-32). The same start in other units of time, inputs, outputs, states
    or parameters — the same system — gives the same key (unless one of these numbers lies
    within rounding of a rounding boundary, about once in 10⁹), so it draws the same T₀;
    before, the bytes of x₀ seeded it, and a start in other units drew another T₀. Two
    starts with the same poles and gains at ρ draw the same G₁, G₂ (scaled each by its own
    T's size).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.similarity.start import start_key
    >>> bb = si.BlackBox(np.diag([-1.0, -4.0]), np.ones((2, 1)), np.ones((1, 2)))
    >>> A, B, C = np.diag([-1.5, -3.0]), np.array([[2.0], [1.0]]), np.array([[1.0, 1.0]])
    >>> d = np.array([1e3, 1e-3])                               # the states in other units
    >>> start_key(A, B, C, bb) == start_key(A, d[:, None] * B, C / d, bb)
    True
    >>> start_key(A, B, C, bb) == start_key(2 * A, B, C, bb)   # another start
    False
    """
    from symid.model.lti import StateSpaceMatrices, frequency_response_ss

    A, B, C = (np.asarray(X, dtype=float) for X in (A, B, C))
    rho = 1.0 / time_unit(bb)
    parts = sorted(_key_text(np.linalg.eigvals(A) / rho)) if A.size else []
    w, D = np.array([rho]), np.zeros((C.shape[0], B.shape[1]))  # the strictly proper parts, without D
    try:
        Hm = frequency_response_ss(StateSpaceMatrices(A, B, C, D), w)[0]
        Hb = frequency_response_ss(StateSpaceMatrices(*(np.asarray(X, dtype=float) for X in (bb.A, bb.B, bb.C)), D),
                                   w)[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(np.abs(Hb) > 0, np.abs(Hm) / np.abs(Hb), 0.0)
        parts += _key_text(ratio)
    except (ModelError, ValueError):
        pass  # iρ a pole, or shapes that do not match: the eigenvalues alone
    return zlib.crc32(";".join(parts).encode("ascii"))


def least_squares_theta(maps: dict[str, Any], bb: Any, T: np.ndarray) -> np.ndarray:
    """θ minimising F(θ, T) for fixed T (thesis (C-8)); when not unique, the solution of least norm in
    parameters scaled to unit columns (so that neither the rank decision nor the choice depends on the
    parameters' units)."""
    J, r = theta_system(maps, bb, T)
    cols = np.linalg.norm(J, axis=0)
    cols = np.where((cols > 0) & np.isfinite(cols), cols, 1.0)
    return np.linalg.lstsq(J / cols, r, rcond=None)[0] / cols


def theta_system(maps: dict[str, Any], bb: Any, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(J, r) with F(θ, T) = ‖J θ − r‖² (the residual of (C-1) is affine in θ)."""
    mA, mB, mC = maps["A"], maps["B"], maps["C"]
    cols = [np.concatenate([(Ai @ T).ravel(), Bi.ravel(), (Ci @ T).ravel()]) for Ai, Bi, Ci in
            zip(mA.Xi, mB.Xi, mC.Xi, strict=True)]
    r = np.concatenate([(T @ bb.A - mA.X0 @ T).ravel(), (T @ bb.B - mB.X0).ravel(), (bb.C - mC.X0 @ T).ravel()])
    J = np.array(cols).T.reshape(r.size, len(cols))
    if "D" in maps and not maps["D"].is_constant:
        J = np.vstack([J, maps["D"].Xi.reshape(len(cols), -1).T])
        r = np.concatenate([r, (bb.D - maps["D"].X0).ravel()])
    return J, r


def time_unit(bb: Any) -> float:
    """τ = 1/ρ(𝔸), ρ the geometric mean of the black box's nonzero |eigenvalues| (1 when there are none).

    A rate of the black box that does not depend on its basis, and that follows the unit of
    time: with 𝔸 times c, τ is divided by c.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.similarity.start import time_unit
    >>> bb = si.BlackBox(np.diag([-1.0, -100.0]), np.ones((2, 1)), np.ones((1, 2)))
    >>> round(time_unit(bb), 12)
    0.1
    """
    lam = np.abs(np.linalg.eigvals(np.asarray(bb.A, dtype=float))) if np.size(bb.A) else np.zeros(0)
    lam = lam[np.isfinite(lam) & (lam > 0)]
    return float(np.exp(-np.mean(np.log(lam)))) if lam.size else 1.0


def _diagonal(amap: Any, left: np.ndarray | None = None, right: np.ndarray | None = None) -> Any:
    """The affine map diag(left) X(θ) diag(right), numerically (X0, Xi; the symbolic fields are the model's)."""
    X0, Xi = amap.X0, amap.Xi
    if left is not None:
        X0, Xi = left[:, None] * X0, left[None, :, None] * Xi
    if right is not None:
        X0, Xi = X0 * right[None, :], Xi * right[None, None, :]
    return dataclasses.replace(amap, X0=X0, Xi=Xi)


def _norms(X: np.ndarray, axis: int) -> np.ndarray:
    """Row (axis=1) or column (axis=0) norms of X, 1 where a norm is 0 or not finite."""
    v = np.linalg.norm(np.asarray(X, dtype=float), axis=axis)
    return np.where(np.isfinite(v) & (v > 0), v, 1.0)


def state_sizes(maps: dict[str, Any], theta: np.ndarray) -> np.ndarray | None:
    """The size of each of the model's states at θ, in the units the model declares them in; ``None`` if unknown.

    sᵢ = √Pᵢᵢ, P the controllability Gramian of (A(θ), B(θ)): the rms of state i driven
    by unit white noise at the inputs. With state i in units d times smaller Pᵢᵢ grows by
    d², so sᵢ grows by d; outputs do not enter. Where some Pᵢᵢ is not positive (a state
    the inputs do not reach), 1/√Qᵢᵢ with Q the observability Gramian. The Lyapunov
    equations are solved after balancing A (LAPACK gebal, powers of two), so that states
    in units 1e±6 apart do not cost digits. ``None`` where A(θ) is not stable or neither
    Gramian has a positive diagonal.
    """
    import scipy.linalg

    try:
        A, B, C = (np.asarray(maps[k](theta), dtype=float) for k in "ABC")
        if A.size == 0 or not (np.all(np.isfinite(A)) and np.all(np.isfinite(B)) and np.all(np.isfinite(C))):
            return None
        Ab, (d, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)  # A = D Ab D⁻¹
        if np.max(np.linalg.eigvals(Ab).real) >= 0:
            return None
        with np.errstate(all="ignore"):
            Bb = B / d[:, None]
            p = np.diag(scipy.linalg.solve_continuous_lyapunov(Ab, -Bb @ Bb.T)) * d**2
            if np.all(np.isfinite(p)) and np.all(p > 0):
                return np.sqrt(p)
            Cb = C * d[None, :]
            q = np.diag(scipy.linalg.solve_continuous_lyapunov(Ab.T, -Cb.T @ Cb)) / d**2
    except (np.linalg.LinAlgError, ValueError, scipy.linalg.LinAlgError):
        return None
    if np.all(np.isfinite(q)) and np.all(q > 0):
        return 1.0 / np.sqrt(q)
    return None


@dataclasses.dataclass(frozen=True)
class WorkingProblem:
    """The similarity problem a method solves for one start, in units where (C-1)'s blocks weigh alike.

    The model's maps (numeric parts X0, Xi only) and the black box after :func:`working_problem`'s changes of
    units. The equations T𝔸 = A(θ)T, T𝔹 = B(θ), ℂ = C(θ)T (𝔻 = D(θ)) hold for the same θ, and a T̃ of this
    problem is ``alpha * sizes[:, None] * T̃`` for the model and black box as given (:meth:`original_T`): only the
    weights of the misfit change, to ones that do not depend on the units of time, inputs, outputs or states.

    Attributes
    ----------
    maps : dict
        A, B, C (and D) of the model in these units.
    bb : BlackBox
        The black box in these units.
    sizes : numpy.ndarray
        The size of each model state at the start (:func:`state_sizes`; ones where unknown).
    alpha : float
        The size of T that the start implies (step 4 of :func:`working_problem`).
    """

    maps: dict[str, Any]
    bb: Any
    sizes: np.ndarray
    alpha: float

    def original_T(self, T: np.ndarray) -> np.ndarray:
        """T for the model and black box as given."""
        return self.alpha * self.sizes[:, None] * np.asarray(T, dtype=float)


def working_problem(maps: dict[str, Any], bb: Any, x0: np.ndarray, *, keep_states: bool = False,
                    keep_io: bool = False) -> WorkingProblem:
    """:class:`WorkingProblem` for the start x₀ (``keep_states=True``: without step 2; ``keep_io=True``: inputs
    and outputs as given in step 1; see below). In turn:

    1. **time** in units of τ = :func:`time_unit` (A, B, 𝔸, 𝔹 times τ), and **each input and
       output** in units of its own size (B → B U, C → V C, D → V D U, the same for the black
       box; :func:`io_time_normalised`);
    2. **the model's states** of size one at x₀ where its Gramians exist
       (:func:`state_sizes`: A → W A W⁻¹, B → W B, C → C W⁻¹, W = diag(1/s));
    3. **the black box's state** scaled by α = √(‖B(x₀)‖/‖𝔹‖ · ‖ℂ‖/‖C(x₀)‖), the size of T
       that T𝔹 = B and ℂ = CT imply, so that T is of size one.

    ``keep_states=True`` leaves the model's states in the units it declares them in, and
    ``keep_io=True`` the inputs and outputs in theirs (SCR uses both, with its parameters in
    units of their start values: its relaxation is sensitive to how T is scaled, and state
    sizes taken at a random start are noise to it — on the e-nose (6-19), 40 random starts,
    it reached the truth from 5 with them and 15 without; :mod:`symid.fit.similarity.scr`).
    A change of units that changes the model's states unequally is then not followed.

    Without these, (C-1) sums blocks in different units (‖T𝔸 − AT‖² is a rate, ‖ℂ − CT‖²
    an output), and a model with time, outputs or states in other units gave other
    estimates (measured on a two-state model with time in units of 1e-6: ALS stopped after
    one sweep, GB after 4 iterations, IPOPT at its iteration limit, 40 % off).
    """
    from symid.data import BlackBox

    x0 = np.asarray(x0, dtype=float)
    work, bb_io = io_time_normalised(maps, bb, io=not keep_io)
    rows = None if keep_states else state_sizes(work, x0)
    rows = np.ones(bb.n_states) if rows is None else rows
    work["A"] = _diagonal(work["A"], left=1.0 / rows, right=rows)
    work["B"], work["C"] = _diagonal(work["B"], left=1.0 / rows), _diagonal(work["C"], right=rows)
    norms = [float(np.linalg.norm(x)) for x in (work["B"](x0), bb_io.B, bb_io.C, work["C"](x0))]
    alpha = 1.0
    if all(np.isfinite(x) and x > 0 for x in norms):
        alpha = float(np.sqrt(norms[0] / norms[1] * norms[2] / norms[3]))
    return WorkingProblem(work, BlackBox(bb_io.A, bb_io.B * alpha, bb_io.C / alpha, bb_io.D), rows, alpha)


def io_time_normalised(maps: dict[str, Any], bb: Any, io: bool = True) -> tuple[dict[str, Any], Any]:
    """Step 1 of :func:`working_problem` (it depends on the black box only): the maps and the black box with time
    in units of τ = :func:`time_unit`, then (unless ``io=False``) each input and output in units of its own size.

    The sizes do not depend on the black box's basis nor on the unit of time: input i's is
    the rms output energy √(𝔹ᵢᵀ Q 𝔹ᵢ) it drives (Q the observability Gramian), output j's
    the rms √(ℂⱼ P ℂⱼᵀ) it shows under unit white noise at the inputs thus scaled (P the
    controllability Gramian); for an unstable black box, the norms of 𝔹's columns and ℂ's
    rows instead.
    """
    import scipy.linalg

    from symid.data import BlackBox

    tau = time_unit(bb)
    At, Bt, C = bb.A * tau, bb.B * tau, np.asarray(bb.C, dtype=float)
    u, v = 1.0 / _norms(Bt, 0), 1.0 / _norms(C, 1)
    if not io:
        u, v = np.ones(Bt.shape[1]), np.ones(C.shape[0])
    try:
        if io and At.size and np.max(np.linalg.eigvals(At).real) < 0:
            with np.errstate(all="ignore"):
                Q = scipy.linalg.solve_continuous_lyapunov(At.T, -C.T @ C)
                gu = np.einsum("ij,ik,kj->j", Bt, Q, Bt)
                Bu = Bt * (1.0 / np.sqrt(gu))[None, :]
                P = scipy.linalg.solve_continuous_lyapunov(At, -Bu @ Bu.T)
                gy = np.einsum("ji,ik,jk->j", C, P, C)
            if np.all(np.isfinite(gu)) and np.all(gu > 0) and np.all(np.isfinite(gy)) and np.all(gy > 0):
                u, v = 1.0 / np.sqrt(gu), 1.0 / np.sqrt(gy)
    except (np.linalg.LinAlgError, ValueError, scipy.linalg.LinAlgError):
        pass
    rate = np.full(bb.n_states, tau)
    work = dict(maps)
    work["A"] = _diagonal(maps["A"], left=rate)
    work["B"] = _diagonal(maps["B"], left=rate, right=u)
    work["C"] = _diagonal(maps["C"], left=v)
    if "D" in maps:
        work["D"] = _diagonal(maps["D"], left=v, right=u)
    return work, BlackBox(At, Bt * u[None, :], v[:, None] * C, v[:, None] * bb.D * u[None, :])


def transform_scale(maps: dict[str, Any], bb: Any) -> float:
    """The scale α of a similarity transform T with T𝔹 = B(θ) and ℂ = C(θ)T, from the known parts.

    If T were α times an orthogonal matrix, ‖B‖ = α‖𝔹‖ and ‖ℂ‖ = α‖C‖. With the
    constant parts B₀, C₀ of the model (the known entries), α₁ = ‖B₀‖/‖𝔹‖ and
    α₂ = ‖ℂ‖/‖C₀‖; α is their geometric mean, the one available, or 1 when both are zero.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> a = si.parameters("a")
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]])
    >>> transform_scale(model.maps, si.BlackBox([[-2.0]], [[0.25]], [[4.0]]))
    4.0
    """
    nb, nc = float(np.linalg.norm(bb.B)), float(np.linalg.norm(bb.C))
    b0, c0 = float(np.linalg.norm(maps["B"].X0)), float(np.linalg.norm(maps["C"].X0))
    est = []
    if b0 > 0 and nb > 0:
        est.append(b0 / nb)
    if c0 > 0 and nc > 0:
        est.append(nc / c0)
    return float(np.sqrt(np.prod(est))) if len(est) == 2 else (est[0] if est else 1.0)


def initial_point(init: str, x0: np.ndarray, seed: int, maps: dict[str, Any], bb: Any
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ₀, T₀, S₀) for the start x₀ (see the module notes).

    Parameters
    ----------
    init : {"random", "model", "zero", "identity"}
    x0 : numpy.ndarray
        The start from :func:`symid.fit.starts.make_starts` (θ₀ itself for ``"model"``).
    seed : int
        Seed of the random T₀, S₀.
    maps : dict
        The model's state-space affine maps A, B, C (and D).
    bb : BlackBox
        The black box (𝔸, 𝔹, ℂ, 𝔻).
    """
    x0 = np.asarray(x0, dtype=float)
    n = bb.n_states
    if init == "model":
        T = least_squares_transform(maps, bb, x0)
        return x0, T, np.linalg.pinv(T)
    if init == "random":
        # a start that already explains the black box (to 1e-6 rms) keeps its own T: random T₀ would walk away
        # from it (found on a two-compartment model started at the truth on noise-free records: 'scr' ended at
        # misfit 0.44). The similarity misfit is affine in θ for the least-squares T of the start.
        T = least_squares_transform(maps, bb, x0)
        J, r = theta_system(maps, bb, T)
        resid = J @ x0 - r
        if np.all(np.isfinite(resid)) and float(resid @ resid) <= _EXPLAINS * float(r @ r + (J @ x0) @ (J @ x0)):
            return x0, T, np.linalg.pinv(T)
        alpha = transform_scale(maps, bb)
        G1, G2 = random_pair(n, start_key(*(maps[k](x0) for k in "ABC"), bb), seed)
        T, S = alpha * G1, G2 / alpha
    elif init == "zero":
        T, S = np.zeros((n, n)), np.zeros((n, n))
    elif init == "identity":
        T, S = np.eye(n), np.eye(n)
    else:
        raise ModelError(f"init must be one of {', '.join(map(repr, INITS))}; got {init!r}")
    return least_squares_theta(maps, bb, T), T, S


def unknown_scale(theta0: np.ndarray, T0: np.ndarray, lower: np.ndarray | None = None) -> np.ndarray:
    """Typical magnitudes of z = (θ, vec T) (row-major) at a start, for methods that work on z / s.

    θ: |θ₀| per parameter (:func:`symid.engine.ipopt.start_scale`: where θ₀ is 0, the
    largest finite bound, else 1), so that a parameter declared in other units is the
    same unknown. T: every entry of row i by ‖T₀ᵢ‖ (row i of T maps into the model's state
    i, whose units it carries; rows of 0 take the largest row norm, a T₀ of 0 takes 1).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.similarity.start import unknown_scale
    >>> unknown_scale(np.array([-2e3, 0.5]), np.array([[3.0, 4.0], [0.0, 0.0]])).tolist()
    [2000.0, 0.5, 5.0, 5.0, 5.0, 5.0]
    """
    from symid.engine.ipopt import start_scale

    theta0 = np.asarray(theta0, dtype=float)
    lower = np.full(theta0.size, -np.inf) if lower is None else np.asarray(lower, dtype=float)
    st = start_scale(theta0, lower, np.full(theta0.size, np.inf))
    rows = np.linalg.norm(np.asarray(T0, dtype=float), axis=1)
    rows = np.where(np.isfinite(rows), rows, 0.0)
    top = float(rows.max(initial=0.0))
    rows = np.where(rows > 0, rows, top if top > 0 else 1.0)
    return np.concatenate([st, np.repeat(rows, rows.size)])
