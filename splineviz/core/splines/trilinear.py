"""Trilinear interpolation: the baseline model (``model="trilinear"``).

The piece in each grid cell [i, i+1] x [j, j+1] x [k, k+1] (index space) is the tensor-product
interpolant of the cell's 8 samples: continuous, not C1. Derivatives are those of the piece
containing the point; on cell boundaries the cell with the larger index wins (points on the far
box faces use the last cell).
"""

from __future__ import annotations

import numpy as np

from splineviz.core.splines.base import Spline


class TrilinearSpline(Spline):
    """Trilinear interpolant of a :class:`~splineviz.core.volume.Volume`."""

    model = "trilinear"

    def cell_of(self, upoints: np.ndarray):
        """Cell index (N, 3) int and local coordinates (N, 3) in [0, 1] of index-space points."""
        shape = np.asarray(self.volume.shape)
        cell = np.clip(np.floor(upoints).astype(np.int64), 0, np.maximum(shape - 2, 0))
        return cell, upoints - cell

    def index_derivatives(self, upoints, order):
        data = self.volume.data
        shape = np.asarray(data.shape)
        cell, t = self.cell_of(upoints)
        # corner values c[a, b, c] of each cell; axes of length 1 repeat their only sample
        corners = np.empty((len(cell), 2, 2, 2))
        for a in range(2):
            for b in range(2):
                for c in range(2):
                    idx = np.minimum(cell + (a, b, c), shape - 1)
                    corners[:, a, b, c] = data[idx[:, 0], idx[:, 1], idx[:, 2]]
        w = [np.stack([1 - t[:, i], t[:, i]], axis=1) for i in range(3)]
        dw = np.array([-1.0, 1.0])
        value = np.einsum("nabc,na,nb,nc->n", corners, w[0], w[1], w[2])
        parts = [value[:, None]]
        if order >= 1:
            gx = np.einsum("nabc,a,nb,nc->n", corners, dw, w[1], w[2])
            gy = np.einsum("nabc,na,b,nc->n", corners, w[0], dw, w[2])
            gz = np.einsum("nabc,na,nb,c->n", corners, w[0], w[1], dw)
            parts.append(np.stack([gx, gy, gz], axis=1))
        if order >= 2:
            hxy = np.einsum("nabc,a,b,nc->n", corners, dw, dw, w[2])
            hxz = np.einsum("nabc,a,nb,c->n", corners, dw, w[1], dw)
            hyz = np.einsum("nabc,na,b,c->n", corners, w[0], dw, dw)
            zero = np.zeros_like(hxy)
            parts.append(np.stack([zero, hxy, hxz, hxy, zero, hyz, hxz, hyz, zero], axis=1))
        return np.concatenate(parts, axis=1)
