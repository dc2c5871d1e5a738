"""The common interface of all spline models.

A model works in *index space* of its volume (sample ``data[i, j, k]`` at the point
``(i, j, k)``, grid spacing 1). The base class maps world points to index space, evaluates in
memory-bounded chunks and converts derivatives back to world space (chain rule with the
spacing). Models on tetrahedral partitions derive from :class:`TetSpline` and only report the
local B-form of the piece containing each point.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from splineviz.core import bform
from splineviz.core.volume import Volume

#: points per evaluation chunk; bounds the memory of gathered stencils
CHUNK = 65536


class Spline(ABC):
    """A piecewise polynomial approximating a :class:`~splineviz.core.volume.Volume`."""

    #: model name used by :func:`splineviz.build_spline`
    model: str = ""

    def __init__(self, volume: Volume):
        if not isinstance(volume, Volume):
            volume = Volume(volume)
        self.volume = volume
        self._spacing = np.asarray(volume.spacing, dtype=np.float64)
        self._origin = np.asarray(volume.origin, dtype=np.float64)

    @property
    def bounds(self):
        """((xmin, xmax), (ymin, ymax), (zmin, zmax)): the whole data box is covered."""
        return self.volume.bounds

    @abstractmethod
    def index_derivatives(self, upoints: np.ndarray, order: int) -> np.ndarray:
        """Value and index-space derivatives up to ``order`` (0, 1 or 2).

        Parameters
        ----------
        upoints : (N, 3) float64 points in index space inside the closed data box.
        order : int

        Returns
        -------
        (N, 1), (N, 4) or (N, 13) array: value, then gradient (3), then the Hessian (9, row
        major), as many as ``order`` asks for.
        """

    def _run(self, points, order: int) -> np.ndarray:
        p = np.asarray(points, dtype=np.float64)
        if p.ndim == 1 and p.shape[0] == 3:
            p = p[None]
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"points must have shape (N, 3), got {p.shape}")
        u = (p - self._origin) / self._spacing
        # points on the box boundary may be a rounding error outside; clamp them in
        u = np.clip(u, 0.0, np.asarray(self.volume.shape, dtype=np.float64) - 1)
        width = (1, 4, 13)[order]
        out = np.empty((len(u), width))
        for s in range(0, len(u), CHUNK):
            out[s:s + CHUNK] = self.index_derivatives(u[s:s + CHUNK], order)
        if order >= 1:
            out[:, 1:4] /= self._spacing
        if order >= 2:
            out[:, 4:] /= np.outer(self._spacing, self._spacing).ravel()
        return out

    def evaluate(self, points) -> np.ndarray:
        """Spline values: (N, 3) world points -> (N,) float64."""
        return self._run(points, 0)[:, 0]

    def gradient(self, points) -> np.ndarray:
        """Exact gradient of the piecewise polynomial: (N, 3) -> (N, 3)."""
        return self._run(points, 1)[:, 1:4]

    def value_gradient(self, points):
        """Values (N,) and gradients (N, 3) in one pass."""
        out = self._run(points, 1)
        return out[:, 0], out[:, 1:4]

    def hessian(self, points) -> np.ndarray:
        """Hessian of the piecewise polynomial: (N, 3) -> (N, 3, 3)."""
        return self._run(points, 2)[:, 4:].reshape(-1, 3, 3)


class TetSpline(Spline):
    """A spline whose pieces are B-forms on tetrahedra."""

    @abstractmethod
    def local_bform(self, upoints: np.ndarray):
        """B-form of the piece containing each index-space point.

        Parameters
        ----------
        upoints : (N, 3) float64

        Returns
        -------
        coeffs : (N, n_d)
        lam : (N, 4) barycentric coordinates of the points
        matrix : (N, 4, 4) index-space barycentric matrices M_T^{-1}
        """

    def index_derivatives(self, upoints, order):
        coeffs, lam, matrix = self.local_bform(upoints)
        if order == 0:
            return bform.evaluate(coeffs, lam)[:, None]
        value, grad = bform.value_gradient(coeffs, lam, matrix)
        parts = [value[:, None], grad]
        if order >= 2:
            parts.append(bform.hessian(coeffs, lam, matrix).reshape(-1, 9))
        return np.concatenate(parts, axis=1)
