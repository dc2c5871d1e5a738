"""Tables the tetrahedral kernel families share: de Casteljau reduction steps and dense
weight rows padded to whole vectors of the ray kernel."""

from __future__ import annotations

import numpy as np


def reduction_table(degree: int) -> np.ndarray:
    """(n_{degree-1}, 4) positions of alpha + e_m among the degree-``degree`` multi-indices
    (the de Casteljau step of :mod:`splineviz.core.bform`, as a table for the kernel)."""
    from splineviz.core import bform

    pos = bform.index_map(degree)
    lower = bform.multi_indices(degree - 1)
    out = np.empty((len(lower), 4), dtype=np.int32)
    for a, alpha in enumerate(lower):
        for m in range(4):
            beta = [int(v) for v in alpha]
            beta[m] += 1
            out[a, m] = pos[tuple(beta)]
    return out



def padded_rows(weights: np.ndarray, width: int) -> np.ndarray:
    """Dense coefficient weights ``(T, K, C)`` as float32, the last axis zero-padded to a
    multiple of ``width`` (whole vectors of the ray kernel): ``(T, K, width * ceil(C /
    width))``."""
    t, k, c = weights.shape
    out = np.zeros((t, k, width * -(-c // width)), np.float32)
    out[..., :c] = weights
    return out

