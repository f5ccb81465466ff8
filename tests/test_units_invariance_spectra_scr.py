"""SCR on spectra follows a parameter's units (issue 14, item 3).

Reference: the one-mass model of ScrPSD's docstring, truth (m, c, k) = (1, 0.5, 4) (thesis §5 form, C and B
known), exact spectra on 8 lines. The mass declared in units of 1e-3 or 1e3 kg, the start converted with it:
the estimate converted back equals the estimate in kg to the engine's tolerance (tol 1e-8 on the residual;
measured 6e-10 relative), asserted to rtol 1e-7 (the residual tolerance times the
problem's conditioning, not one version's last digits).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symid as si


def model(mass_unit=1.0):
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[m * mass_unit]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])


@pytest.mark.parametrize("unit", [1e-3, 1e3])
def test_scr_on_spectra_with_the_mass_in_other_units(unit):
    spec = si.simulate_spectra(model(), [1.0, 0.5, 4.0], np.linspace(0.5, 3, 8), Phi_uu=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        base = si.identify(model(), spec, method="scr", x0=[2.0, 1.0, 2.0]).theta
        other = si.identify(model(unit), spec, method="scr", x0=[2.0 / unit, 1.0, 2.0]).theta
    np.testing.assert_allclose([other["m"] * unit, other["c"], other["k"]], [base["m"], base["c"], base["k"]],
                               rtol=1e-7)
