"""Printer belt drive of thesis §3-6, eqs. (3-17) and (3-18) (after reference [28] there).

System
------
A third-order SISO state-space model with four unknown entries::

    A(θ) = [[0,  -1,  0.15],      B(θ) = [[0 ],      C = [0, 1, 0]
            [0.2, 0,  0   ],              [0 ],
            [θ1,  θ2, θ3  ]]              [θ4]]

with the true values (3-18) θ = (−1, −0.5, −0.2, −0.15). The θ are negative, so the
parameters are declared real, not positive.

Data recipe
-----------
Frequency response at 10 log-spaced frequencies between 0.4 and 0.6 rad/s
(``np.logspace(np.log10(0.4), np.log10(0.6), 10)``), fed to Algorithm 3.1; all SCR
matrices start at zero.

Transcription choices and discrepancies
---------------------------------------
* Units. The thesis says the Bode plot has "a frequency spike at roughly 0.6 Hz" and
  samples "the frequency range 0.4 – 0.6 Hz". The spike (Figure 3-1) is the lightly
  damped pole pair −0.020 ± 0.586j, i.e. a resonance at 0.586 rad/s (0.093 Hz). The
  band 0.4–0.6 only brackets the spike in rad/s, so the numbers are rad/s and "Hz" is a
  slip of the text. We use rad/s.
* The thesis's data are the noise-free FRF; ``noise`` adds relative noise through
  :func:`symid.simulate_frf`.
"""

from __future__ import annotations

import numpy as np

import symid as si

W = np.logspace(np.log10(0.4), np.log10(0.6), 10)  # rad/s (the thesis's "Hz" are rad/s, see above)


def make_data(model, truth, noise=None, seed=None):
    """FRF of the truth at the 10 log-spaced frequencies in 0.4–0.6 rad/s."""
    from symid.signal.simulate import simulate_frf

    return simulate_frf(model, truth, W, noise=noise, seed=seed)


theta1, theta2, theta3, theta4 = si.parameters("theta1 theta2 theta3 theta4")
model = si.StateSpaceModel(
    A=[[0, -1, 0.15], [0.2, 0, 0], [theta1, theta2, theta3]],
    B=[[0], [0], [theta4]],
    C=[[0, 1, 0]],
    name="belt_drive",
)
truth = {"theta1": -1.0, "theta2": -0.5, "theta3": -0.2, "theta4": -0.15}  # thesis (3-18)
title = "Printer belt drive, 3 states, 4 unknown entries (SISO)"
source = "thesis §3-6, eqs. (3-17), (3-18); Figure 3-1"
recipe = ("FRF at 10 log-spaced frequencies in 0.4–0.6 rad/s (the thesis writes 'Hz'; the "
          "resonance it samples is at 0.586 rad/s, so the numbers are rad/s)")
notes = ("Thesis labels the band 0.4–0.6 'Hz'; the spike of Figure 3-1 is at 0.586 rad/s, "
         "so the band is read as rad/s. θ are negative: parameters are real, not positive.")
extra = {"w": W, "resonance_rad_s": 0.586}
