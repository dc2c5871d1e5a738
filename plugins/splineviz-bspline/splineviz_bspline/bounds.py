"""Value bounds of the tricubic B-spline on each unit cell, from its Bernstein (Bezier) form.

On a cell the spline is a tensor-product cubic whose 4 x 4 x 4 Bernstein coefficients are
convex combinations of the cell's B-spline coefficients (per axis the matrix
:data:`BSPLINE_TO_BERNSTEIN`); the spline on the cell lies within their range. That range is
much tighter than the B-spline coefficients' own: the interpolation prefilter makes the
coefficients of noisy data overshoot the data, so nearly every cell near a surface straddles
the isovalue by its coefficients, and only a few by its Bernstein coefficients.
"""

from __future__ import annotations

import numpy as np

#: Bernstein coefficients on [0, 1] (rows) of the uniform cubic B-spline weights of the
#: coefficient offsets -1, 0, 1, 2 (columns); every row is >= 0 and sums to 1
BSPLINE_TO_BERNSTEIN = np.array([[1.0, 4.0, 1.0, 0.0],
                                 [0.0, 4.0, 2.0, 0.0],
                                 [0.0, 2.0, 4.0, 0.0],
                                 [0.0, 1.0, 4.0, 1.0]]) / 6.0

# x-slabs of cells converted at a time: bounds the float64 temporaries to ~16 copies of a slab
_SLAB = 32


def _to_bernstein(c: np.ndarray, axis: int) -> list[np.ndarray]:
    """The 4 Bernstein coefficient arrays along ``axis`` of the cells of ``c`` (n - 3 along
    that axis: cell i reads c[i .. i + 3])."""
    n = c.shape[axis] - 3
    parts = [np.take(c, np.arange(a, a + n), axis=axis) for a in range(4)]
    return [sum(m[a] * parts[a] for a in range(4) if m[a] != 0.0)
            for m in BSPLINE_TO_BERNSTEIN]


def cell_bounds(coefficients: np.ndarray) -> np.ndarray:
    """Lower and upper bounds of the spline on every cell.

    Parameters
    ----------
    coefficients : (nx + 3, ny + 3, nz + 3) float
        B-spline coefficients; cell (i, j, k) reads coefficients i..i+3, j..j+3, k..k+3.

    Returns
    -------
    (nx, ny, nz, 2) float64: the min and max of each cell's Bernstein coefficients (NaN where
    a coefficient the cell reads is NaN).
    """
    c = np.asarray(coefficients, dtype=np.float64)
    nx = c.shape[0] - 3
    out = np.empty((nx, c.shape[1] - 3, c.shape[2] - 3, 2))
    for x0 in range(0, nx, _SLAB):
        x1 = min(x0 + _SLAB, nx)
        lo = hi = None
        for bx in _to_bernstein(c[x0:x1 + 3], 0):
            for by in _to_bernstein(bx, 1):
                for bz in _to_bernstein(by, 2):
                    # np.fmin would drop NaN: a cell with a NaN coefficient must stay unbounded
                    lo = bz if lo is None else np.minimum(lo, bz)
                    hi = bz if hi is None else np.maximum(hi, bz)
        out[x0:x1, ..., 0] = lo
        out[x0:x1, ..., 1] = hi
    return out
