"""The ADMM back end's SVT of complex-pair terms through the complex matrices (a quarter of the Gram size).

The real representation (2-8) of a complex term makes its SCR matrix (2-6) a permuted real
representation of a complex matrix, whose singular values are those of the complex one,
each twice: singular value thresholding of either gives the same matrix.
"""

from __future__ import annotations

import numpy as np
import pytest

from symid.engine.scr.backend_admm import _is_realrep, _svt, _svt_complex


def _rr(Z: np.ndarray) -> np.ndarray:
    return np.block([[Z.real, -Z.imag], [Z.imag, Z.real]])


def _stack(rng: np.random.Generator, j: int, k: int, l: int, m: int, s: int) -> tuple[np.ndarray, tuple]:
    """s real SCR matrices [[C.., (A+Q)P], [P(B+R), P]] of complex terms, j×k A, l×m B (complex sizes)."""
    X = np.empty((s, 2 * (j + k), 2 * (m + l)))
    for t in range(s):
        b = [[rng.standard_normal((a, c)) + 1j * rng.standard_normal((a, c)) for c in (m, l)] for a in (j, k)]
        X[t] = np.block([[_rr(b[0][0]), _rr(b[0][1])], [_rr(b[1][0]), _rr(b[1][1])]])
    J, K, L, M = 2 * j, 2 * k, 2 * l, 2 * m
    layout = (np.r_[0:j, J:J + k], np.r_[j:J, J + k:J + K], np.r_[0:m, M:M + l], np.r_[m:M, M + l:M + L])
    return X, layout


@pytest.mark.parametrize("dims", [(3, 1, 1, 3), (2, 2, 1, 1), (1, 1, 2, 3)])
def test_svt_through_the_complex_matrices_is_the_svt_of_the_real_representation(dims):
    rng = np.random.default_rng(sum(dims))
    X, layout = _stack(rng, *dims, s=6)
    assert _is_realrep(X, layout)
    tau = rng.uniform(0.1, 3.0, 6)
    np.testing.assert_allclose(_svt_complex(X, tau, layout), _svt(X, tau), atol=1e-12)
    X[0, 0, 0] += 1.0  # no longer a real representation: the back end keeps the real SVT then
    assert not _is_realrep(X, layout)
