"""Batched numeric blocks: terms of equal shape stacked, M(x; Q, R) of (2-6) built with einsum.

A group holds ``s`` terms with the same (j, k, l, m); each term touches ``u`` entries of
z (padded with zero coefficients), so building every M_t(z) = m0_t + G_t z[idx_t] costs
O(s) and no Python loop runs over the terms.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from symid.engine.scr.maps import LocalMap, stack_index, stack_maps
from symid.engine.scr.presolve import RealTerm

__all__ = ["LMIGroup", "TermGroup", "group_lmis", "group_terms"]


@dataclass(eq=False)
class TermGroup:
    """Bilinear terms of one shape, stacked."""

    members: np.ndarray  # positions in Reduced.terms
    sources: np.ndarray  # user term index
    idx: np.ndarray  # (s, u) free positions, -1 padding
    A0: np.ndarray
    Ac: np.ndarray
    P: np.ndarray
    B0: np.ndarray
    Bc: np.ndarray
    C0: np.ndarray
    Cc: np.ndarray
    weight: np.ndarray
    norm_factor: np.ndarray  # 1/√2 for complex pairs (Frobenius of the complex matrix)

    @property
    def s(self) -> int:
        return self.idx.shape[0]

    @property
    def dims(self) -> tuple[int, int, int, int]:
        _, j, k = self.A0.shape
        _, l, m = self.B0.shape
        return j, k, l, m

    @property
    def pq(self) -> tuple[int, int]:
        j, k, l, m = self.dims
        return j + k, m + l

    @cached_property
    def _slots(self) -> tuple[slice | np.ndarray, slice | np.ndarray, np.ndarray, np.ndarray]:
        """Local slots u with a nonzero coefficient in some A (resp. B) of the group, and those coefficients."""
        out: list[slice | np.ndarray] = []
        for c in (self.Ac, self.Bc):
            used = np.flatnonzero(np.any(c != 0, axis=(0, 1, 2)))
            contiguous = used.size and used[-1] - used[0] + 1 == used.size
            out.append(slice(int(used[0]), int(used[-1]) + 1) if contiguous else used)
        return out[0], out[1], np.ascontiguousarray(self.Ac[..., out[0]]), np.ascontiguousarray(self.Bc[..., out[1]])

    def gather(self, z: np.ndarray) -> np.ndarray:
        """z at the term's indices, (s, u), zero at padding."""
        return np.where(self.idx >= 0, z[np.maximum(self.idx, 0)], 0.0)

    def A(self, z: np.ndarray) -> np.ndarray:
        return self.A0 + np.einsum("sjku,su->sjk", self.Ac, self.gather(z))

    def B(self, z: np.ndarray) -> np.ndarray:
        return self.B0 + np.einsum("slmu,su->slm", self.Bc, self.gather(z))

    def C(self, z: np.ndarray) -> np.ndarray:
        return self.C0 + np.einsum("sjmu,su->sjm", self.Cc, self.gather(z))

    def residual(self, z: np.ndarray) -> np.ndarray:
        """Frobenius norm of A P B − C per term (of the complex matrix for complex pairs)."""
        r = self.A(z) @ self.P @ self.B(z) - self.C(z)
        return np.sqrt(np.einsum("sij,sij->s", r, r)) * self.norm_factor

    def build(self, Q: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """M(z) = m0 + G z_loc of (2-6) for given Q (s,j,k), R (s,l,m).

        Returns m0 (s, p, q) and G (s, p*q, u), row-major vec.
        """
        j, k, l, m = self.dims
        s, u = self.idx.shape
        P = self.P
        PR = P @ R
        QP = Q @ P
        m0 = np.empty((s, j + k, m + l))
        m0[:, :j, :m] = self.C0 + self.A0 @ PR + QP @ self.B0 + QP @ R
        m0[:, :j, m:] = (self.A0 + Q) @ P
        m0[:, j:, :m] = P @ (self.B0 + R)
        m0[:, j:, m:] = P
        G = np.zeros((s, j + k, m + l, u))
        G[:, :j, :m] = self.Cc
        a, b, Ac, Bc = self._slots  # only the slots A (resp. B) depends on: typically a few shared parameters
        G[:, :j, :m, a] += np.einsum("sjku,skm->sjmu", Ac, PR)
        G[:, :j, :m, b] += np.einsum("sjl,slmu->sjmu", QP, Bc)
        G[:, :j, m:, a] = np.einsum("sjku,skl->sjlu", Ac, P)
        G[:, j:, :m, b] = np.einsum("skl,slmu->skmu", P, Bc)
        return m0, G.reshape(s, (j + k) * (m + l), u)


@dataclass(eq=False)
class LMIGroup:
    """LMIs of one size, stacked: E(z) = E0 + Σ z_u E_u."""

    idx: np.ndarray
    E0: np.ndarray
    Ec: np.ndarray

    @property
    def s(self) -> int:
        return self.idx.shape[0]

    def gather(self, z: np.ndarray) -> np.ndarray:
        return np.where(self.idx >= 0, z[np.maximum(self.idx, 0)], 0.0)

    def E(self, z: np.ndarray) -> np.ndarray:
        return self.E0 + np.einsum("sabu,su->sab", self.Ec, self.gather(z))

    def G(self) -> np.ndarray:
        s, e, _, u = self.Ec.shape
        return self.Ec.reshape(s, e * e, u)


def group_terms(terms: list[RealTerm]) -> list[TermGroup]:
    """Stack terms of equal shape."""
    by: dict[tuple[int, ...], list[int]] = defaultdict(list)
    for i, t in enumerate(terms):
        by[t.dims].append(i)
    out = []
    for members in by.values():
        ts = [terms[i] for i in members]
        idx = stack_index([[t.A, t.B, t.C] for t in ts])
        A0, Ac = stack_maps([t.A for t in ts], idx)
        B0, Bc = stack_maps([t.B for t in ts], idx)
        C0, Cc = stack_maps([t.C for t in ts], idx)
        P = np.stack([t.P for t in ts])
        out.append(TermGroup(np.asarray(members), np.asarray([t.source for t in ts]), idx, A0, Ac, P, B0, Bc, C0, Cc,
                             np.asarray([t.weight for t in ts]),
                             np.asarray([np.sqrt(0.5) if t.complex_pair else 1.0 for t in ts])))
    return out


def group_lmis(lmis: list[LocalMap]) -> list[LMIGroup]:
    """Stack LMIs of equal size."""
    by: dict[int, list[int]] = defaultdict(list)
    for i, m in enumerate(lmis):
        by[m.shape[0]].append(i)
    out = []
    for members in by.values():
        ms = [lmis[i] for i in members]
        idx = stack_index([[m] for m in ms])
        E0, Ec = stack_maps(ms, idx)
        out.append(LMIGroup(idx, E0, Ec))
    return out
