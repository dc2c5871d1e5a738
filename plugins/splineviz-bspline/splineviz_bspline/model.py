"""C2 tricubic B-spline interpolation of a volume, with exact derivatives.

The coefficients ``c`` solve the interpolation conditions s(i, j, k) = data[i, j, k] with the
cubic B-spline prefilter of :func:`scipy.ndimage.spline_filter` (mirror boundary: the
samples are extended symmetrically about the first and last sample). On the cell with
corner ``b`` and local coordinates ``t`` in [0, 1]^3 (index space),

    s(b + t) = sum_{p,q,r = -1..2} c[b + (p, q, r)] B_p(t_x) B_q(t_y) B_r(t_z),

with the uniform cubic B-spline weights B_{-1} = (1-t)^3/6, B_0 = (3t^3 - 6t^2 + 4)/6,
B_1 = (-3t^3 + 3t^2 + 3t + 1)/6, B_2 = t^3/6 and their exact first and second derivatives.
Data convention: index space of the volume (grid spacing 1); the base class maps world
coordinates and scales derivatives.
"""

from __future__ import annotations

import numpy as np

from splineviz.core.splines.base import Spline

# pairs of derivative orders (x, y, z) of the Hessian entries, row major
_HESSIAN_ORDERS = [tuple(int(a == i) + int(a == j) for a in range(3))
                   for i in range(3) for j in range(3)]


def bspline_weights(t: np.ndarray) -> np.ndarray:
    """Cubic B-spline weights of offsets -1, 0, 1, 2 and their derivatives.

    Parameters
    ----------
    t : (N,) float64 in [0, 1]

    Returns
    -------
    (3, N, 4) float64: weights, first and second derivatives with respect to t.
    """
    t = np.asarray(t, dtype=np.float64)
    s = 1.0 - t
    t2, t3 = t * t, t * t * t
    w = np.stack([s**3 / 6, (3 * t3 - 6 * t2 + 4) / 6, (-3 * t3 + 3 * t2 + 3 * t + 1) / 6,
                  t3 / 6], axis=-1)
    d1 = np.stack([-(s**2) / 2, (3 * t2 - 4 * t) / 2, (-3 * t2 + 2 * t + 1) / 2, t2 / 2],
                  axis=-1)
    d2 = np.stack([s, 3 * t - 2, 1 - 3 * t, t], axis=-1)
    return np.stack([w, d1, d2])


def mirror_index(i: np.ndarray, n: int) -> np.ndarray:
    """Indices reflected about the first and last sample (scipy.ndimage ``mode="mirror"``)."""
    if n == 1:
        return np.zeros_like(i)
    period = 2 * (n - 1)
    i = np.mod(i, period)
    return np.where(i > n - 1, period - i, i)


class TricubicBSpline(Spline):
    """C2 tricubic B-spline interpolant (module docstring for the formulas)."""

    model = "tricubic-bspline"

    def __init__(self, volume):
        from scipy.ndimage import spline_filter

        super().__init__(volume)
        self.coefficients = spline_filter(np.asarray(self.volume.data, dtype=np.float64),
                                          order=3, mode="mirror")

    def index_derivatives(self, upoints: np.ndarray, order: int) -> np.ndarray:
        n = np.asarray(self.coefficients.shape)
        u = np.asarray(upoints, dtype=np.float64)
        base = np.clip(np.floor(u).astype(np.int64), 0, np.maximum(n - 2, 0))
        t = u - base
        weights = [bspline_weights(t[:, a]) for a in range(3)]
        idx = [mirror_index(base[:, a, None] + np.arange(-1, 3), int(n[a])) for a in range(3)]
        c = self.coefficients[idx[0][:, :, None, None], idx[1][:, None, :, None],
                              idx[2][:, None, None, :]]  # (N, 4, 4, 4)

        def part(dx, dy, dz):
            return np.einsum("ni,nj,nk,nijk->n", weights[0][dx], weights[1][dy],
                             weights[2][dz], c, optimize=True)

        cols = [part(0, 0, 0)]
        if order >= 1:
            cols += [part(1, 0, 0), part(0, 1, 0), part(0, 0, 1)]
        if order >= 2:
            cols += [part(*o) for o in _HESSIAN_ORDERS]
        return np.stack(cols, axis=1)
