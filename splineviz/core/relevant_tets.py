"""The relevant tetrahedra of a tetrahedral spline for an isovalue (thesis §6.1.1).

A tetrahedron is *relevant* when its B-net spans the isovalue: ``min(c) <= iso <= max(c)``
over its B-coefficients. By the convex-hull property of the Bernstein-Bezier form a tet
whose coefficients all lie on one side cannot hold the isosurface, so these tets (with
their coefficients) are all a cell-projection renderer has to draw.

Classification in two steps, as the ray caster's: cubes are first culled by a bound of
all their coefficients from the 27 data values around the cube centre (every coefficient
is an affine combination of them with weights summing to 1, so it lies in
``[lo - m (hi - lo), hi + m (hi - lo)]`` with ``m`` the largest negative weight mass); the
surviving cubes' 24 tets are then tested on their exact coefficients (stream compaction).
The quadratic C1 spline on truncated octahedra (``to-quadratic``, thesis chapter 5) is
classified the same way: each TO is culled by the range of the data its 144 tets' stencils
read, then its tets are tested.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from splineviz.core.errors import SplinevizError
from splineviz.core.partitions import truncated_octahedra, type6
from splineviz.core.splines import to_quadratic
from splineviz.core.splines.to_quadratic import TOQuadraticSpline
from splineviz.core.splines.type6_spline import GHOST_LAYERS, Type6Spline

#: cubes whose tets are classified together (bounds the memory of the coefficient arrays:
#: 24 tets x 20 float64 coefficients x 4096 cubes ~ 16 MB)
CUBE_CHUNK = 4096


class RelevantTetsError(SplinevizError, ValueError):
    """A spline that is not on a tetrahedral partition (type-6 or truncated octahedra)."""


#: the partitions: name -> (generic tet vertices (T, 4, 3) relative to the cell centre,
#: barycentric matrices (T, 4, 4)) as functions
PARTITIONS = {
    "type6": (lambda: type6.VERTICES, type6.barycentric_matrices),
    "truncated-octahedra": (lambda: truncated_octahedra.generic_tetrahedra()[0],
                            truncated_octahedra.barycentric_matrices),
}


def partition_of(spline) -> str:
    """The :data:`PARTITIONS` key of ``spline``'s tets (``"type6"`` for super-quadratic and
    cubic-c1, ``"truncated-octahedra"`` for to-quadratic)."""
    return "truncated-octahedra" if isinstance(spline, TOQuadraticSpline) else "type6"


@dataclass(frozen=True)
class RelevantTets:
    """The relevant tetrahedra of one isosurface of a type-6 spline.

    Attributes
    ----------
    cube : (N, 3) index-space centre of each tet's cell: the data point at a type-6 cube's
        centre (int64), the (half-integer) centre of a truncated octahedron (float64)
    tet : (N,) int64 generic tetrahedron of the cell (its orientation: [0, 24) in a cube,
        §4.4; [0, 144) in a TO, §5.3)
    coeffs : (N, n_d) float64 B-coefficients in the order of :func:`bform.multi_indices`
    degree : int polynomial degree (2 super-quadratic and to-quadratic, 3 cubic-c1)
    partition : str key of :data:`PARTITIONS`
    """

    cube: np.ndarray
    tet: np.ndarray
    coeffs: np.ndarray
    degree: int
    partition: str = "type6"

    def __len__(self) -> int:
        return len(self.tet)

    def generic_vertices(self) -> np.ndarray:
        """(T, 4, 3) vertices of the partition's generic tets relative to the cell centre."""
        return PARTITIONS[self.partition][0]()

    def barycentric_matrices(self) -> np.ndarray:
        """(T, 4, 4) barycentric matrices of the generic tets (points relative to the cell
        centre)."""
        return PARTITIONS[self.partition][1]()

    def vertices(self) -> np.ndarray:
        """(N, 4, 3) float64 index-space vertices [v0, v1, v2, v3] of each tet."""
        return self.generic_vertices()[self.tet] + np.asarray(self.cube, np.float64)[:, None]

    def per_orientation(self) -> np.ndarray:
        """(T,) int64 number of relevant tets of each generic orientation."""
        return np.bincount(self.tet, minlength=len(self.generic_vertices()))


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
    spline : Type6Spline (``"super-quadratic"``, ``"cubic-c1"``) or TOQuadraticSpline
        (``"to-quadratic"``)
    isovalue : float

    Returns
    -------
    RelevantTets, tets in C order of their cubes (for TOs: in the order of
    :func:`~splineviz.core.partitions.truncated_octahedra.centres_covering`), then by generic
    tet.
    """
    if isinstance(spline, TOQuadraticSpline):
        return _relevant_to_tets(spline, float(isovalue))
    if not isinstance(spline, Type6Spline):
        raise RelevantTetsError(
            f"relevant tetrahedra need a type-6 or truncated-octahedral spline "
            f"(super-quadratic, cubic-c1 or to-quadratic), "
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


def _relevant_to_tets(spline: TOQuadraticSpline, iso: float) -> RelevantTets:
    """:func:`relevant_tets` of the quadratic C1 spline on truncated octahedra."""
    n_tets = len(truncated_octahedra.generic_tetrahedra()[0])
    table = to_quadratic.stencils(spline.k)
    # every data offset a TO's tets read (relative to its base data point), and the largest
    # negative weight mass of a coefficient (its bound's widening, as for cubes)
    offsets = np.unique(np.concatenate([o for o, _w in table]), axis=0)
    negmass = max(float(np.max(np.sum(np.clip(-w, 0, None), axis=1))) for _o, w in table)
    padded = spline._padded
    strides = np.array(padded.strides) // padded.itemsize
    flat = np.ravel(padded)
    centres = truncated_octahedra.centres_covering(np.zeros(3),
                                                   np.array(spline.volume.shape) - 1.0)
    base = np.rint(centres - 0.5).astype(np.int64) + to_quadratic.GHOST_LAYERS
    cells, tets, coeffs = [], [], []
    tet_ids = np.arange(n_tets)
    chunk = max(CUBE_CHUNK * 24 // n_tets, 1)
    for start in range(0, len(centres), chunk):
        b = base[start:start + chunk]
        vals = flat[(b @ strides)[:, None] + offsets @ strides]
        lo, hi = vals.min(axis=1), vals.max(axis=1)
        slack = negmass * (hi - lo) + 1e-9 * (np.abs(lo) + np.abs(hi) + 1.0)
        keep = (lo - slack <= iso) & (iso <= hi + slack)
        if not keep.any():
            continue
        rep_base = np.repeat(b[keep], n_tets, axis=0)
        rep_tet = np.tile(tet_ids, int(keep.sum()))
        c = to_quadratic.coefficients(padded, rep_base, rep_tet, spline.k)
        span = (c.min(axis=1) <= iso) & (iso <= c.max(axis=1))
        cells.append(np.repeat(centres[start:start + chunk][keep], n_tets, axis=0)[span])
        tets.append(rep_tet[span])
        coeffs.append(c[span])
    if not cells:
        return RelevantTets(np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros((0, 10)), 2,
                            "truncated-octahedra")
    return RelevantTets(np.concatenate(cells), np.concatenate(tets), np.concatenate(coeffs),
                        2, "truncated-octahedra")


__all__ = ["PARTITIONS", "RelevantTets", "RelevantTetsError", "relevant_tets"]
