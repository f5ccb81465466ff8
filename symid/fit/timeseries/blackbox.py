"""The N4SID route for measured samples, judged on the samples.

Methods ``scr``, ``als``, ``gb``, ``ipopt``, ``ls`` on one :class:`~symid.data.IOData`
estimate θ from a black box (N4SID + exact ``d2c``; thesis Algorithms 6.1, 7.1;
:mod:`symid.fit.similarity`): they fit the black box's matrices or frequency response,
not the samples. A misfit to that black box says nothing about the measurements — a
model that reproduces a noisy black box to 1e-15 can be several per cent off — so here
the method runs unchanged and its estimate is then judged like ``oe``'s: ``cost`` is the
relative output misfit to the measured samples (the model simulated from its initial
state, :class:`~symid.fit.timeseries.oe.OutputError`), ``success`` the same fit test on
those residuals, the black-box misfit stays in ``message``, ``polish=True`` refines by
output error on the samples, and the uncertainty is that of the output-error estimate
evaluated at θ̂ (with a note: the route's own estimate is not that estimate).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symid.fit.base import Estimator
from symid.fit.result import StartOutcome
from symid.fit.timeseries.oe import OutputError
from symid.fit.uncertainty import FisherInformation

__all__ = ["JudgedOnSamples", "ThroughBlackBox"]


class JudgedOnSamples(Estimator, FisherInformation):
    """Base of the time-series methods that do not fit the samples themselves: their cost, success, polish
    and uncertainty come from the output-error view of the records (``self.samples``)."""

    cost_kind = OutputError.cost_kind
    samples: OutputError
    route: str = ""

    def misfit(self, theta: np.ndarray) -> float:
        """The relative output misfit to the measured samples."""
        return self.samples.misfit(theta)

    def residuals(self, theta: np.ndarray) -> np.ndarray | None:
        """Time-ordered output residuals (for the whiteness part of the fit test)."""
        try:
            return self.samples.residuals(theta)
        except (np.linalg.LinAlgError, ValueError):
            return None

    def n_data(self) -> int:
        """Number of measured output values."""
        return self.samples.n_data()

    def polisher(self) -> Estimator:
        """Output error on the samples (method ``oe``)."""
        return self.samples

    # -- uncertainty: the output-error Fisher information at θ̂ ------------------------------------
    def jacobian(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """The output-error residual and Jacobian (:meth:`OutputError.jacobian`)."""
        return self.samples.jacobian(theta)

    def residual_channels(self) -> np.ndarray:
        """Output of every residual entry."""
        return self.samples.residual_channels()

    def noise_shape(self, theta: Any) -> np.ndarray:
        """One noise level per output."""
        return self.samples.noise_shape(theta)

    def given_noise(self, noise_std: Any) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`OutputError.given_noise`."""
        return self.samples.given_noise(noise_std)

    def uncertainty_note(self) -> str:
        """The method does not minimise the sample misfit."""
        return (f"method {self.method!r} fits {self.route}, not the samples: this is the covariance of the "
                "output-error estimate, evaluated at its θ̂ (polish=True refines on the samples)")


class ThroughBlackBox(JudgedOnSamples):
    """A black-box-route estimator whose outcomes are judged on the measured samples.

    Parameters
    ----------
    inner : Estimator
        The similarity estimator built on the N4SID black box.
    samples : OutputError
        The output-error view of the same records (cost, residuals, Fisher information, polish).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> a, b = si.parameters("a b", positive=True)
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]])
    >>> u = np.random.default_rng(0).standard_normal(400)
    >>> io = si.simulate_io(model, [0.5, 2.0], u, dt=0.1, noise=0.02, seed=1)
    >>> res = si.identify(model, io, method="ipopt", x0=[1.0, 1.0], identifiability_check=False)
    >>> res.cost_kind.startswith("relative output misfit to the measured samples"), "black-box misfit" in res.message
    (True, True)
    """

    route = "the N4SID black box"

    def __init__(self, inner: Estimator, samples: OutputError):
        self.inner, self.samples = inner, samples
        self.model, self.data = inner.model, samples.data
        self.method = inner.method  # type: ignore[misc]
        self.noise_floor = inner.noise_floor
        self.options = {**inner.options,
                        "fits": "the N4SID black box (thesis Algorithms 6.1/7.1); cost, success and uncertainty on "
                                "the measured samples"}

    def run(self, x0: np.ndarray) -> StartOutcome:
        """The route's method from ``x0``, its estimate judged on the samples."""
        out = self.inner.run(x0)
        return self.outcome(out.start, out.theta, finished=out.finished, status=out.status,
                            message=f"{out.message}; black-box misfit {out.cost:.3e}", iterations=out.iterations,
                            wall_time=out.wall_time, history=out.history)
