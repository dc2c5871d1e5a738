"""Ghost layers around a volume so that a spline covers the whole data box (thesis Remark 1).

The quasi-interpolants use data a few samples beyond the box. Ghost samples are made by linear
extrapolation from the two outermost samples of each axis, ``f(-m) = (1+m) f(0) - m f(1)``,
one axis after the other. This keeps linear reproduction up to the boundary (constant padding
would not); an axis with a single sample is extended constantly.
"""

from __future__ import annotations

import numpy as np


def pad_linear(data: np.ndarray, layers: int) -> np.ndarray:
    """Extend a 3-D array by ``layers`` ghost samples on every side.

    Parameters
    ----------
    data : (nx, ny, nz) array
    layers : int >= 0

    Returns
    -------
    (nx + 2 layers, ny + 2 layers, nz + 2 layers) float64 array; ``out[layers:-layers, ...]``
    is ``data``.
    """
    out = np.asarray(data, dtype=np.float64)
    if layers <= 0:
        return out.copy()
    m = np.arange(1, layers + 1, dtype=np.float64)
    for axis in range(3):
        a = np.moveaxis(out, axis, 0)
        if a.shape[0] == 1:
            lo = np.repeat(a[:1], layers, axis=0)
            hi = lo
        else:
            d0, d1 = a[0], a[1]
            e0, e1 = a[-1], a[-2]
            # rows ordered from far to near for the low side
            lo = ((1 + m[::-1])[:, None, None] * d0 - m[::-1][:, None, None] * d1)
            hi = ((1 + m)[:, None, None] * e0 - m[:, None, None] * e1)
        out = np.moveaxis(np.concatenate([lo, a, hi], axis=0), 0, axis)
    return np.ascontiguousarray(out)
