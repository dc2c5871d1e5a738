"""The relevant tetrahedra of a type-6 spline for an isovalue (thesis §6.1.1).

A tetrahedron is *relevant* when its B-net spans the isovalue: ``min(c) <= iso <= max(c)``
over its B-coefficients. By the convex-hull property of the Bernstein-Bezier form a tet
whose coefficients all lie on one side cannot hold the isosurface, so these tets (with
their coefficients) are all a cell-projection renderer has to draw.

Classification in two steps, as the ray caster's: cubes are first culled by a bound of
all their coefficients from the 27 data values around the cube centre (every coefficient
is an affine combination of them with weights summing to 1, so it lies in
``[lo - m (hi - lo), hi + m (hi - lo)]`` with ``m`` the largest negative weight mass); the
surviving cubes' 24 tets are then tested on their exact coefficients (stream compaction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from splineviz.core.errors import SplinevizError
from splineviz.core.partitions import type6
from splineviz.core.splines.type6_spline import GHOST_LAYERS, Type6Spline

#: cubes whose tets are classified together (bounds the memory of the coefficient arrays:
#: 24 tets x 20 float64 coefficients x 4096 cubes ~ 16 MB)
CUBE_CHUNK = 4096


class RelevantTetsError(SplinevizError, ValueError):
    """A spline that is not on the type-6 partition."""


@dataclass(frozen=True)
class RelevantTets:
    """The relevant tetrahedra of one isosurface of a type-6 spline.

    Attributes
    ----------
    cube : (N, 3) int64 data-point index of each tet's cube centre
    tet : (N,) int64 generic tetrahedron in [0, 24) (its orientation, §4.4)
    coeffs : (N, n_d) float64 B-coefficients in the order of :func:`bform.multi_indices`
    degree : int polynomial degree (2 super-quadratic, 3 cubic-c1)
    """

    cube: np.ndarray
    tet: np.ndarray
    coeffs: np.ndarray
    degree: int

    def __len__(self) -> int:
        return len(self.tet)

    def vertices(self) -> np.ndarray:
        """(N, 4, 3) float64 index-space vertices [v0, v1, v2, v3] of each tet."""
        return type6.world_vertices(self.cube, self.tet)

    def per_orientation(self) -> np.ndarray:
        """(24,) int64 number of relevant tets of each generic orientation."""
        return np.bincount(self.tet, minlength=type6.N_TETS)


def _candidate_cubes(spline: Type6Spline, isovalue: float) -> np.ndarray:
    """(M,) flat indices of the cubes whose coefficient bound spans ``isovalue``."""
    padded = spline.padded
    lo = ndimage.minimum_filter(padded, size=3, mode="nearest")
    hi = ndimage.maximum_filter(padded, size=3, mode="nearest")
    g = GHOST_LAYERS
    inner = tuple(slice(g, g + n) for n in spline.volume.shape)
    lo, hi = lo[inner], hi[inner]
    negmass = float(np.max(np.sum(np.clip(-spline.scheme.cube_masks, 0, None), axis=1)))
    # the float64 products of the masks round; widen by a relative epsilon so that the
    # bound never excludes a cube whose exact test would keep it
    slack = negmass * (hi - lo) + 1e-9 * (np.abs(lo) + np.abs(hi) + 1.0)
    keep = (lo - slack <= isovalue) & (isovalue <= hi + slack)
    return np.flatnonzero(keep)


def relevant_tets(spline, isovalue: float) -> RelevantTets:
    """The tetrahedra of ``spline`` whose B-net spans ``isovalue``, with their coefficients.

    Parameters
    ----------
    spline : Type6Spline (``"super-quadratic"`` or ``"cubic-c1"``)
    isovalue : float

    Returns
    -------
    RelevantTets, tets in C order of their cubes, then by generic tet.
    """
    if not isinstance(spline, Type6Spline):
        raise RelevantTetsError(
            f"relevant tetrahedra need a type-6 spline (super-quadratic or cubic-c1), "
            f"not {getattr(spline, 'model', type(spline).__name__)!r}")
    iso = float(isovalue)
    cand = _candidate_cubes(spline, iso)
    shape = spline.volume.shape
    n_d = spline.scheme.tet_masks.shape[1]
    cubes, tets, coeffs = [], [], []
    tet_ids = np.arange(type6.N_TETS)
    for start in range(0, len(cand), CUBE_CHUNK):
        flat = cand[start:start + CUBE_CHUNK]
        cube = np.stack(np.unravel_index(flat, shape), axis=1).astype(np.int64)
        rep_cube = np.repeat(cube, type6.N_TETS, axis=0)
        rep_tet = np.tile(tet_ids, len(cube))
        c = spline.tet_coefficients(rep_cube, rep_tet)
        keep = (c.min(axis=1) <= iso) & (iso <= c.max(axis=1))
        cubes.append(rep_cube[keep])
        tets.append(rep_tet[keep])
        coeffs.append(c[keep])
    if not cubes:
        return RelevantTets(np.zeros((0, 3), np.int64), np.zeros(0, np.int64),
                            np.zeros((0, n_d)), spline.degree)
    return RelevantTets(np.concatenate(cubes), np.concatenate(tets), np.concatenate(coeffs),
                        spline.degree)


__all__ = ["RelevantTets", "RelevantTetsError", "relevant_tets"]
