"""Quasi-interpolating splines on the type-6 partition, evaluated on demand (thesis §4.4).

Shared machinery of :mod:`~splineviz.core.splines.cubic_c1` and
:mod:`~splineviz.core.splines.super_quadratic`. Nothing per tetrahedron is stored for the
volume: for each query point the cube and generic tetrahedron are located
(:func:`splineviz.core.partitions.type6.locate`), the 27 data values around the cube centre are
gathered and the tetrahedron's B-coefficients are the mask products of eq. (4.3). A full
per-tetrahedron array for 256^3 (24 tets x 20 coefficients x 8 bytes per cube, ~12 GB) is never
built; memory is the padded volume plus one evaluation chunk.

Boundary: like the truncated-octahedral spline, the data get one ghost layer of linear
extrapolation (:func:`~splineviz.core.splines.boundary.pad_linear`, thesis Remark 1), so the
cubes centred at every data point -- which cover the whole data box -- have full stencils and
linear functions are reproduced up to the boundary.
"""

from __future__ import annotations

import numpy as np

from splineviz.core import bform
from splineviz.core.partitions import type6
from splineviz.core.splines import type6_rules
from splineviz.core.splines.base import TetSpline
from splineviz.core.splines.boundary import pad_linear

#: ghost layers needed by the 3x3x3 stencil around each cube centre
GHOST_LAYERS = 1


def _compact_masks(masks: np.ndarray):
    """Drop the data offsets a tetrahedron never uses.

    Parameters
    ----------
    masks : (24, n_d, 27)

    Returns
    -------
    used : (24, k) int64 stencil rows used by each tetrahedron (k equal for all by symmetry)
    compact : (24, n_d, k) the masks restricted to them
    """
    nonzero = (masks != 0).any(axis=1)  # (24, 27)
    used = np.array([np.flatnonzero(row) for row in nonzero])
    compact = np.take_along_axis(masks, used[:, None, :], axis=2)
    return used, np.ascontiguousarray(compact)


class Type6Spline(TetSpline):
    """A quasi-interpolating spline on Delta_6 given by a :class:`type6_rules.Type6Scheme`.

    Parameters
    ----------
    volume : Volume or (nx, ny, nz) array
    """

    #: scheme name in :func:`type6_rules.scheme`
    scheme_name: str = ""

    def __init__(self, volume):
        super().__init__(volume)
        self.scheme = type6_rules.scheme(self.scheme_name)
        self.degree = self.scheme.degree
        self._padded = None
        shape = np.asarray(self.volume.shape) + 2 * GHOST_LAYERS
        strides = np.array([shape[1] * shape[2], shape[2], 1], dtype=np.int64)
        self._pad_strides = strides
        self._stencil = type6_rules.OFFSETS @ strides  # (27,) flat offsets of the stencil
        self._compact = _compact_masks(self.scheme.tet_masks)

    @property
    def padded(self) -> np.ndarray:
        """(nx + 2, ny + 2, nz + 2) float64 data with one linear ghost layer (built once)."""
        if self._padded is None:
            self._padded = pad_linear(self.volume.data, GHOST_LAYERS)
        return self._padded

    def neighbourhoods(self, cube: np.ndarray) -> np.ndarray:
        """The 27 data values around each cube centre.

        Parameters
        ----------
        cube : (N, 3) int data-point indices in [0, n - 1] per axis

        Returns
        -------
        (N, 27) float64 in the order of :data:`type6_rules.OFFSETS`
        """
        base = (np.asarray(cube, dtype=np.int64) + GHOST_LAYERS) @ self._pad_strides
        return self.padded.ravel()[base[:, None] + self._stencil]

    def all_cubes(self) -> np.ndarray:
        """(n_cubes, 3) int64 indices of every cube (= every data point), C order."""
        idx = np.indices(self.volume.shape).reshape(3, -1).T
        return np.ascontiguousarray(idx, dtype=np.int64)

    def tet_coefficients(self, cube: np.ndarray, tet: np.ndarray) -> np.ndarray:
        """B-coefficients of generic tetrahedra ``tet`` in cubes ``cube`` (eq. 4.3).

        Parameters
        ----------
        cube : (N, 3) int
        tet : (N,) int in [0, 24)

        Returns
        -------
        (N, n_d) float64 in the multi-index order of :func:`bform.multi_indices`
        """
        tet = np.asarray(tet, dtype=np.int64)
        order = np.argsort(tet, kind="stable")
        out = np.empty((len(tet), self.scheme.tet_masks.shape[1]))
        out[order] = self._sorted_coefficients(np.asarray(cube)[order], tet[order])
        return out

    def _sorted_coefficients(self, cube: np.ndarray, tet: np.ndarray) -> np.ndarray:
        """Like :meth:`tet_coefficients` for ``tet`` sorted ascending (contiguous groups)."""
        base = (np.asarray(cube, dtype=np.int64) + GHOST_LAYERS) @ self._pad_strides
        flat = self.padded.ravel()
        used, compact = self._compact
        out = np.empty((len(tet), compact.shape[1]))
        # per generic tetrahedron: gather only the data its masks use (23 of 27 values for
        # cubics, 15 for quadratics) and do one small matrix product on a contiguous slice
        edges = np.searchsorted(tet, np.arange(type6.N_TETS + 1))
        for t in range(type6.N_TETS):
            lo, hi = edges[t], edges[t + 1]
            if hi > lo:
                vals = flat[base[lo:hi, None] + self._stencil[used[t]]]
                # einsum, not matmul: BLAS threading costs more than it gains on these
                # thin (n, 23) x (23, 20) products, erratically so on a loaded machine
                np.einsum("nk,ck->nc", vals, compact[t], out=out[lo:hi])
        return out

    def determining_values(self, cube: np.ndarray) -> np.ndarray:
        """Coefficients of the determining set M_Q of each cube (§4.4, §6.1.1).

        Parameters
        ----------
        cube : (N, 3) int

        Returns
        -------
        (N, |M|) float64: 56 values per cube for cubic-c1, 24 for super-quadratic, in the order
        of ``self.scheme.determining``
        """
        return self.neighbourhoods(cube) @ self.scheme.determining_masks.T

    def cube_coefficients(self, cube: np.ndarray) -> np.ndarray:
        """All coefficients of each cube from its determining set by repeated averaging.

        Returns
        -------
        (N, P) float64 on ``self.scheme.cube_points`` (P = 175 or 65)
        """
        return type6_rules.apply_rules(self.determining_values(cube), self.scheme)

    def local_bform(self, upoints):
        cube, tet, local = type6.locate(upoints)
        coeffs = self.tet_coefficients(cube, tet)
        matrix = type6.barycentric_matrices()[tet]
        lam = np.einsum("nij,nj->ni", matrix[:, :, :3], local) + matrix[:, :, 3]
        return coeffs, lam, matrix

    def index_derivatives(self, upoints, order):
        # evaluate in the order of the generic tetrahedra (contiguous groups, no scatter of
        # the coefficient arrays), then put the few output columns back in input order
        cube, tet, local = type6.locate(upoints)
        perm = np.argsort(tet, kind="stable")
        tet_s = tet[perm]
        coeffs = self._sorted_coefficients(cube[perm], tet_s)
        matrix = type6.barycentric_matrices()[tet_s]
        lam = np.einsum("nij,nj->ni", matrix[:, :, :3], local[perm]) + matrix[:, :, 3]
        if order == 0:
            res = bform.evaluate(coeffs, lam)[:, None]
        else:
            value, grad = bform.value_gradient(coeffs, lam, matrix)
            parts = [value[:, None], grad]
            if order >= 2:
                parts.append(bform.hessian(coeffs, lam, matrix).reshape(-1, 9))
            res = np.concatenate(parts, axis=1)
        out = np.empty_like(res)
        out[perm] = res
        return out
