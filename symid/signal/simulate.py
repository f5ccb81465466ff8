"""Simulated data from a model: frequency responses, spectra and sampled input/output series.

All three simulators take the model, the parameter vector θ (a dict of names or a
sequence in ``model.parameter_names`` order) and the experiment, and return the
matching data container. A :class:`~symid.data.BlackBox` (or a
:class:`~symid.model.lti.StateSpaceMatrices` tuple) may be given as the model with
``theta=None``.

Noise is relative and optional (``noise=None`` or ``0`` gives exact data); ``seed``
makes the draws reproducible (an int, or a :class:`numpy.random.Generator`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.linalg

from symid.data import BlackBox, FrequencyData, IOData, SpectralData, checks
from symid.errors import DataError, ModelError, ModelWarning
from symid.model.lti import StateSpaceMatrices
from symid.model.parametric import ParametricModel, Theta

__all__ = ["foh_discretize", "simulate_frf", "simulate_io", "simulate_spectra", "zoh_discretize"]

Model = ParametricModel | BlackBox | StateSpaceMatrices
Seed = int | np.random.Generator | None


# -- helpers -----------------------------------------------------------------------------

def _system(model: Any, theta: Theta | None) -> tuple[ParametricModel | BlackBox, Any]:
    """Normalise the model argument: a ParametricModel with θ, or a BlackBox without."""
    if isinstance(model, StateSpaceMatrices):
        model = BlackBox.from_state_space(model)
    if isinstance(model, BlackBox):
        if theta is not None:
            raise ModelError("a BlackBox has no parameters; pass theta=None")
        return model, None
    if isinstance(model, ParametricModel):
        if theta is None and model.n_parameters == 0:  # nothing to give
            theta = ()
        if theta is None:
            raise ModelError(f"theta is required: values for {', '.join(model.parameter_names)} "
                             f"(a dict by name or a sequence in model.parameter_names order)")
        vec = model.theta_vector(theta)
        negative = [n for n, v, pos in zip(model.parameter_names, vec, model.positive, strict=True) if pos and v < 0]
        if negative:  # simulated as asked (a study may want it), but said: a new user's C1 = -1000 passed silently
            values = ", ".join(f"{n} = {vec[model.parameter_names.index(n)]:g}" for n in negative)
            warnings.warn(f"simulating at {values}, negative for parameter(s) declared positive: no fit with "
                          f"positivity (the default) can reach these values", ModelWarning, stacklevel=3)
        return model, vec
    raise ModelError(f"model must be a StateSpaceModel, a SecondOrderModel (any symid model) or a BlackBox; "
                     f"got {type(model).__name__}")


def _response(model: ParametricModel | BlackBox, theta: Any, w: np.ndarray) -> np.ndarray:
    if isinstance(model, BlackBox):
        return model.frequency_response(w)
    return np.asarray(model.frequency_response(theta, w))


def _matrices(model: ParametricModel | BlackBox, theta: Any) -> StateSpaceMatrices:
    if isinstance(model, BlackBox):
        return model.state_space()
    return model.state_space(theta)  # type: ignore[attr-defined]


def _noise_level(noise: Any) -> float:
    if noise is None:
        return 0.0
    try:
        level = float(noise)
    except (TypeError, ValueError):
        raise DataError(f"noise must be a number >= 0 (a relative level, e.g. 0.01 for 1 %); got {noise!r}") from None
    if not math.isfinite(level) or level < 0:
        raise DataError(f"noise must be a finite number >= 0 (a relative level); got {level!r}")
    return level


def _generator(seed: Any) -> np.random.Generator:
    """``numpy.random.default_rng(seed)`` for None, a non-negative int or a Generator; a DataError otherwise."""
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is not None and (isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer))
                             or seed < 0):
        raise DataError(f"seed must be None, an int >= 0 or a numpy.random.Generator; got {seed!r}")
    return np.random.default_rng(seed)


def _complex_normal(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    """Circular complex standard normal draws, E|z|² = 1."""
    g = rng.standard_normal((2, *shape))
    return (g[0] + 1j * g[1]) / math.sqrt(2.0)


# -- FRF ---------------------------------------------------------------------------------

def simulate_frf(model: Model, theta: Theta | None, w: Any, *, noise: float | None = None,
                 seed: Seed = None) -> FrequencyData:
    """Frequency response data H(ω, θ) of a model at angular frequencies ``w``.

    Parameters
    ----------
    model : StateSpaceModel, SecondOrderModel or BlackBox
        The system; its ``frequency_response`` is evaluated.
    theta : dict or sequence of float, or None
        Parameter values (by name, or in ``model.parameter_names`` order); ``None`` for a
        :class:`~symid.data.BlackBox`.
    w : array_like, shape (s,)
        Angular frequencies in rad/s, strictly positive and strictly increasing.
    noise : float, optional
        Relative noise level ε ≥ 0. Each entry gets independent circular complex Gaussian
        noise of standard deviation ε·|H_ij(ω)|: ``H + ε |H| (g₁ + j g₂)/√2`` with
        g₁, g₂ ~ N(0, 1), so the rms relative error of every entry is ε. Entries that
        are exactly zero stay zero. ``None`` or 0 gives exact data.
    seed : int or numpy.random.Generator, optional
        Seed of :func:`numpy.random.default_rng`, for reproducible noise.

    Returns
    -------
    FrequencyData
        ``w`` and H of shape (s, p, m).

    Raises
    ------
    DataError
        On bad frequencies or a bad noise level.
    ModelError
        On bad θ, or a pole exactly at one of the frequencies.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, {"m": 1.0, "c": 0.5, "k": 4.0}, [1.0, 2.0])
    >>> np.round(frf.H[:, 0, 0], 6)          # 1 / (k − mω² + jcω)
    array([0.324324-0.054054j, 0.      -1.j      ])
    """
    sys, th = _system(model, theta)
    w_ = checks.frequencies(w, "w")
    level, rng = _noise_level(noise), _generator(seed)
    H = _response(sys, th, w_)
    if level > 0:
        H = H + level * np.abs(H) * _complex_normal(rng, H.shape)
    return FrequencyData(w_, H)


# -- spectra -----------------------------------------------------------------------------

def _spectrum_block(value: Any, m: int, where: str) -> np.ndarray:
    arr = checks.as_array(value, where, complex_ok=True)
    if arr.ndim == 0:
        return arr * np.eye(m)
    if arr.shape == (m, m):
        return arr
    raise DataError(f"{where} must be a scalar (times the identity) or an (m, m) = ({m}, {m}) matrix; "
                    f"got shape {checks.shape_text(arr.shape)}")


def _input_spectrum(Phi_uu: Any, w: np.ndarray, m: int) -> np.ndarray:
    """Φuu as an (s, m, m) complex array, checked finite and Hermitian."""
    out = _input_spectrum_array(Phi_uu, w, m)
    checks.check_finite(out, "Phi_uu")
    checks.check_hermitian(out, "Phi_uu")
    checks.check_power_diagonal(out, "Phi_uu")
    return out


def _input_spectrum_array(Phi_uu: Any, w: np.ndarray, m: int) -> np.ndarray:
    s = w.size
    if callable(Phi_uu):
        fn: Callable[[float], Any] = Phi_uu
        return np.stack([_spectrum_block(fn(float(wi)), m, f"Phi_uu({float(wi):.6g})") for wi in w])
    arr = checks.as_array(Phi_uu, "Phi_uu", complex_ok=True)
    if arr.ndim == 0:
        return np.broadcast_to(arr * np.eye(m), (s, m, m)).copy()
    if arr.ndim == 1 and arr.size == s:
        return arr[:, None, None] * np.eye(m)
    if arr.ndim == 2 and arr.shape == (m, m):
        return np.broadcast_to(arr, (s, m, m)).copy()
    if arr.ndim == 3 and arr.shape == (s, m, m):
        return arr
    raise DataError(f"Phi_uu must be a scalar, a callable of ω, or an array of shape (s, m, m) = ({s}, {m}, {m}), "
                    f"(s,) = ({s},) (a scalar per frequency) or (m, m) = ({m}, {m}) (the same at every "
                    f"frequency); got shape {checks.shape_text(arr.shape)}")


def _hermitian_noise(rng: np.random.Generator, Phi: np.ndarray, level: float) -> np.ndarray:
    """Hermitian noise E with E|E_ij|² = (level·|Φ_ij|)²: real on the diagonal, conjugate pairs off it."""
    s, p, _ = Phi.shape
    G = _complex_normal(rng, Phi.shape)
    upper = np.triu(G, k=1)
    diag = rng.standard_normal((s, p))
    G = upper + np.conj(np.swapaxes(upper, -1, -2))
    idx = np.arange(p)
    G[:, idx, idx] = diag
    return level * np.abs(Phi) * G


def simulate_spectra(model: Model, theta: Theta | None, w: Any, Phi_uu: Any, *, noise: float | None = None,
                     seed: Seed = None) -> SpectralData:
    """Output power spectrum Φyy(ω) = H(ω) Φuu(ω) H(ω)ᴴ for a given input spectrum (thesis (5-3)).

    Parameters
    ----------
    model : StateSpaceModel, SecondOrderModel or BlackBox
        The system with m inputs and p outputs.
    theta : dict or sequence of float, or None
        Parameter values; ``None`` for a :class:`~symid.data.BlackBox`.
    w : array_like, shape (s,)
        Angular frequencies in rad/s, strictly positive and strictly increasing.
    Phi_uu : float, array_like or callable
        The input spectrum, Hermitian with a diagonal ≥ 0 (and positive semidefinite to
        make physical sense; a negative power is a :class:`~symid.errors.DataError`):

        * a scalar φ: white noise of intensity φ on every input, Φuu = φ·I;
        * an array of shape (s, m, m); or (s,), a scalar per frequency times I; or
          (m, m), the same matrix at every frequency;
        * a callable ``f(ω) -> scalar or (m, m) array``, called once per frequency with
          a float, e.g. pink noise ``lambda w: w**-0.5`` (thesis (5-11)).
    noise : float, optional
        Relative noise level ε ≥ 0 on Φyy (Φuu stays exact, being the known input
        statistics). Hermitian noise is added: each diagonal entry gets real Gaussian
        noise of standard deviation ε·|Φyy_ii|, each off-diagonal pair complex Gaussian
        noise of standard deviation ε·|Φyy_ij| with E_ji = conj(E_ij), so Φyy stays
        exactly Hermitian and every entry's rms relative error is ε. A diagonal entry
        that the noise would make negative is set to 0 (a power is ≥ 0; with ε = 0.1 that
        takes a 10-sigma draw, with ε = 0.5 one entry in 44). ``None`` or 0 gives exact
        data.
    seed : int or numpy.random.Generator, optional
        Seed of :func:`numpy.random.default_rng`.

    Returns
    -------
    SpectralData
        ``w``, Φyy of shape (s, p, p) (exactly Hermitian) and Φuu of shape (s, m, m).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], [1.0, 2.0], Phi_uu=2.0)
    >>> np.round(spec.Phi_yy[:, 0, 0].real, 6)   # 2 |H|² = 2 / ((k − mω²)² + (cω)²)
    array([0.216216, 2.      ])
    """
    sys, th = _system(model, theta)
    w_ = checks.frequencies(w, "w")
    level, rng = _noise_level(noise), _generator(seed)
    H = _response(sys, th, w_)
    Puu = _input_spectrum(Phi_uu, w_, H.shape[2])
    Pyy = H @ Puu @ np.conj(np.swapaxes(H, -1, -2))
    Pyy = 0.5 * (Pyy + np.conj(np.swapaxes(Pyy, -1, -2)))
    if level > 0:
        Pyy = Pyy + _hermitian_noise(rng, Pyy, level)
        idx = np.arange(Pyy.shape[1])
        Pyy[:, idx, idx] = np.maximum(Pyy[:, idx, idx].real, 0.0)  # a power stays ≥ 0
    return SpectralData(w_, Pyy, Puu)


# -- input/output series -----------------------------------------------------------------

def zoh_discretize(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretisation: Ad = e^{A dt}, Bd = ∫₀^dt e^{A τ} dτ B.

    Computed with one block-matrix exponential, ``expm([[A, B], [0, 0]] dt) =
    [[Ad, Bd], [0, I]]``.

    Examples
    --------
    >>> import numpy as np
    >>> Ad, Bd = zoh_discretize(np.array([[-1.0]]), np.array([[1.0]]), 0.5)
    >>> bool(np.isclose(Ad[0, 0], np.exp(-0.5))), bool(np.isclose(Bd[0, 0], 1 - np.exp(-0.5)))
    (True, True)
    """
    n, m = B.shape
    big = np.zeros((n + m, n + m))
    big[:n, :n] = A * dt
    big[:n, n:] = B * dt
    E = scipy.linalg.expm(big)
    return E[:n, :n], E[:n, n:]


def foh_discretize(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact first-order-hold discretisation (the input linear between samples): Ad = e^{A dt} and G1, G2 with
    x_{k+1} = Ad x_k + G1 u_k + G2 (u_{k+1} − u_k).

    G1 = ∫₀^dt e^{A σ} dσ B (the zero-order hold's Bd) and G2 = ∫₀^dt e^{A σ} B (dt − σ)/dt dσ, from one block
    exponential ``expm([[A, B, 0], [0, 0, I/dt], [0, 0, 0]] dt) = [[Ad, G1, G2], [0, I, I], [0, 0, I]]``.

    Examples
    --------
    >>> import numpy as np
    >>> Ad, G1, G2 = foh_discretize(np.array([[-1.0]]), np.array([[1.0]]), 0.5)
    >>> h = 0.5   # for dx/dt = −x + u, G2 = 1 − (1 − e^{−h}) / h
    >>> bool(np.isclose(G1[0, 0], 1 - np.exp(-h))), bool(np.isclose(G2[0, 0], 1 - (1 - np.exp(-h)) / h))
    (True, True)
    """
    n, m = B.shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n] = A * dt
    big[:n, n:n + m] = B * dt
    big[n:n + m, n + m:] = np.eye(m)
    E = scipy.linalg.expm(big)
    return E[:n, :n], E[:n, n:n + m], E[:n, n + m:]


def _input_series(u: Any, m: int) -> np.ndarray:
    arr = checks.as_array(u, "u", complex_ok=False)
    if arr.ndim == 1:
        if m != 1:
            raise DataError(f"u of shape (N,) is only accepted for a single-input model; this model has {m} inputs, "
                            f"so u must have shape (N, {m}); got shape {checks.shape_text(arr.shape)}")
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2 or arr.shape[1] != m:
        raise DataError(f"u must have shape (N, m) = (N, {m}) (one row per sample); "
                        f"got shape {checks.shape_text(arr.shape)}")
    if arr.shape[0] < 2:
        raise DataError(f"u must hold at least 2 samples (rows); got N = {arr.shape[0]}")
    checks.check_finite(arr, "u")
    return arr


def _model_initial_state(model: Any, theta: Any, n: int) -> np.ndarray:
    """The model's x(0) at θ (zero for a model without one); a DataError for ``x0="estimate"``."""
    kind = getattr(model, "initial_state_kind", "zero")
    if kind == "zero":
        return np.zeros(n)
    if kind == "estimate":
        raise DataError("the model's initial state is to be estimated (x0='estimate'), so it has no value to "
                        "simulate from: pass x0= (shape (n,)) to simulate_io")
    return model.initial_state(theta)


def simulate_io(model: Model, theta: Theta | None, u: Any, dt: float, *, x0: Any = None,
                noise: float | None = None, noise_std: Any = None, seed: Seed = None,
                time_unit: str | None = None) -> IOData:
    """Sampled response of a model to a zero-order-hold input (exact discretisation).

    The first-order form ``x' = A x + B u, y = C x + D u`` (``model.state_space(θ)``)
    is discretised exactly for an input held constant between samples, ``Ad = e^{A dt}``,
    ``Bd = ∫₀^dt e^{Aτ} dτ B`` (:func:`zoh_discretize`), and run from ``x[0] = x0``:
    ``y[k] = C x[k] + D u[k]``, ``x[k+1] = Ad x[k] + Bd u[k]`` — the samples of the
    continuous-time output at t = k·dt (as :func:`scipy.signal.dlsim` after
    ``cont2discrete(..., method="zoh")``). D matters for a SecondOrderModel with
    acceleration output.

    Parameters
    ----------
    model : StateSpaceModel, SecondOrderModel or BlackBox
        The system with m inputs and p outputs.
    theta : dict or sequence of float, or None
        Parameter values; ``None`` for a :class:`~symid.data.BlackBox`.
    u : array_like, shape (N, m) or (N,)
        Input samples, one row per sample; the 1-D form only for a single-input model.
    dt : float
        Sample time, > 0, in ``time_unit``: the unit the model's rates are per.
    x0 : array_like, shape (n,), optional
        Initial state of the first-order form. By default the model's own
        (``StateSpaceModel(..., x0=...)`` at θ; zero when the model gives none); a
        model whose initial state is to be estimated needs it here. Given, it
        replaces the model's.
    noise : float, optional
        Relative noise level ε ≥ 0 on the output: channel j gets white Gaussian noise of
        standard deviation ε·std(y_j) (the standard deviation over time of the exact
        output). The input stays exact. ``None`` or 0 gives exact data.
    noise_std : float or array_like of shape (p,), optional
        Absolute noise instead (or as well): white Gaussian noise of this standard deviation
        on every output, in the output's units (one value, or one per output; ≥ 0), as a
        sensor of known resolution adds (0.05 K on a thermometer).
    seed : int or numpy.random.Generator, optional
        Seed of :func:`numpy.random.default_rng`.
    time_unit : str, optional
        The record's time unit (``"s"``, ``"ms"``, ``"min"``, ``"h"``, …), which must be the
        one the model's rates are per. Default: the model's own (a model file's
        ``time_unit``, ``model.io_units["time"]``), else seconds; another unit than the
        model's is a DataError (the record would be fitted back with rates off by the
        ratio).

    Returns
    -------
    IOData
        ``u`` (as given, shape (N, m)), ``y`` of shape (N, p), ``dt`` and ``time_unit``.

    Raises
    ------
    DataError
        On a bad input, sample time, initial state or noise level, or if the output
        overflows (an unstable system run for too long).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> a = si.parameters("a")
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]])
    >>> io = si.simulate_io(model, {"a": 1.0}, np.ones(3), dt=0.5)   # step response 1 − e^{−t}
    >>> np.round(io.y[:, 0], 6)
    array([0.      , 0.393469, 0.632121])
    """
    sys, th = _system(model, theta)
    A, B, C, D = _matrices(sys, th)
    n, m = B.shape
    u_ = _input_series(u, m)
    dt_ = checks.check_positive_scalar(dt, "dt")
    unit = _record_time_unit(model, time_unit)
    level, rng = _noise_level(noise), _generator(seed)
    if x0 is None:
        x = _model_initial_state(sys, th, n)
    else:
        x = checks.as_array(x0, "x0", complex_ok=False)
        if x.shape not in ((n,), (n, 1)):
            raise DataError(f"x0 must have shape (n,) = ({n},), the state of the first-order form; "
                            f"got shape {checks.shape_text(x.shape)}")
        checks.check_finite(x, "x0")
        x = x.reshape(n)
    Ad, Bd = zoh_discretize(A, B, dt_)
    N = u_.shape[0]
    Bu = u_ @ Bd.T
    X = np.empty((N, n))
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(N):
            X[k] = x
            x = Ad @ x + Bu[k]
        y = X @ C.T + u_ @ D.T
    if not np.all(np.isfinite(y)):
        k = int(np.argwhere(~np.isfinite(y))[0][0])
        raise DataError(f"the simulated output overflows at sample {k} (t = {k * dt_:g} {unit}); "
                        f"is the system unstable? (max Re λ(A) = {np.linalg.eigvals(A).real.max():.3g})")
    if level > 0:
        y = y + level * np.std(y, axis=0) * rng.standard_normal(y.shape)
    if noise_std is not None:
        std = checks.as_array(noise_std, "noise_std", complex_ok=False)
        if std.shape not in ((), (1,), (y.shape[1],)):
            raise DataError(f"noise_std must be one number or one per output ({y.shape[1]}); got shape "
                            f"{checks.shape_text(std.shape)}")
        checks.check_finite(std, "noise_std")
        if np.any(std < 0):
            raise DataError(f"noise_std must be >= 0 (a standard deviation in the output's units); got {std.tolist()}")
        y = y + std.reshape(-1)[None, :] * rng.standard_normal(y.shape)
    return IOData(u_, y, dt_, time_unit=unit)


def _record_time_unit(model: Any, time_unit: str | None) -> str:
    """The time unit of a simulated record: ``time_unit`` (canonical), else the model's own, else seconds; a unit
    other than the model's is a DataError."""
    from symid.data.units import canonical_unit

    declared = (getattr(model, "io_units", None) or {}).get("time")
    own = canonical_unit(declared[0], "time", "the model's time_unit") if declared else None
    if time_unit is None:
        return own or "s"
    unit = canonical_unit(time_unit, "time", "time_unit")
    if own is not None and unit != own:
        raise DataError(f"time_unit={time_unit!r}, but the model's rates are per {own} (its time_unit): a record in "
                        f"{unit} would be fitted back with every rate off by the ratio; give dt in {own}")
    return unit
