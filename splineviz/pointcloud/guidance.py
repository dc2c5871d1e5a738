"""Edge-length guidance field for the advancing front (thesis §7.3: "adapts to local surface
curvature by using a guidance field").

Conventions: one target edge length per input point, ``(N,)`` float64; queries return the value
of the nearest input point.  The ideal length at a point with largest absolute principal
curvature ``k`` is the chord that subtends the angle ``rho`` on the osculating circle,
``2 sin(rho / 2) / k`` (as in Afront [SSFS07]), clamped to ``[min_length, max_length]``, then
limited so that it grows by at most ``gradation`` per unit distance
(``L_i <= L_j + gradation * |p_i - p_j|``): neighbouring triangles then differ in size only
gradually, which the front needs to stay well shaped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from splineviz.core.errors import SplinevizError
from splineviz.pointcloud.local_fits import neighbour_median

#: default angle (radians) subtended by one edge on the osculating circle
DEFAULT_RHO = 0.35
#: default length bounds in multiples of the median sample spacing
DEFAULT_MIN_SPACINGS = 1.5
DEFAULT_MAX_SPACINGS = 5.0
#: edges are never shorter than this many local spacings (no vertex blow-up on sparse parts)
SAMPLING_FLOOR = 1.2
#: default growth of the edge length per unit distance
DEFAULT_GRADATION = 0.25


class GuidanceError(SplinevizError, ValueError):
    """Invalid guidance-field parameters."""


@dataclass(frozen=True, eq=False)
class GuidanceField:
    """Target edge lengths ``lengths (N,)`` at the projector's input points."""

    lengths: np.ndarray
    tree: object

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Target edge length at ``(M, 3)`` positions -> ``(M,)`` (nearest input point)."""
        _, idx = self.tree.query(np.atleast_2d(x))
        return self.lengths[idx]


def limit_gradation(lengths: np.ndarray, graph: sparse.csr_matrix, gradation: float) -> np.ndarray:
    """Largest field ``<= lengths`` with ``L_i <= L_j + gradation * |p_i - p_j|`` along graph
    paths.

    It equals ``min_j (L_j + gradation * d_graph(i, j))``: one Dijkstra run from a virtual
    source joined to every point ``j`` by an edge of weight ``L_j``.

    Parameters
    ----------
    lengths : (N,) positive
    graph : (N, N) symmetric sparse graph with edge lengths as values
    gradation : float > 0

    Returns
    -------
    (N,) float64
    """
    n = len(lengths)
    g = graph.tocoo()
    rows = np.r_[g.row, np.full(n, n)]
    cols = np.r_[g.col, np.arange(n)]
    vals = np.r_[gradation * g.data + 1e-300, lengths]
    big = sparse.csr_matrix((vals, (rows, cols)), shape=(n + 1, n + 1))
    dist = csgraph.dijkstra(big, directed=True, indices=n)
    return np.minimum(lengths, dist[:n])


def guidance_field(projector, edge_length: float | None = None, rho: float | None = None,
                   min_length: float | None = None, max_length: float | None = None,
                   gradation: float = DEFAULT_GRADATION) -> GuidanceField:
    """Build the target edge-length field.

    Parameters
    ----------
    projector : Projector
        Supplies points, spacing, curvature (of the local polynomials) and the neighbour graph.
    edge_length : float, optional
        Uniform target length; overrides ``rho``.
    rho : float, optional
        Curvature adaptation angle in radians (smaller = finer where curved);
        default ``DEFAULT_RHO``.
    min_length, max_length : float, optional
        Bounds; defaults ``DEFAULT_MIN_SPACINGS`` / ``DEFAULT_MAX_SPACINGS`` times the median
        spacing.
    gradation : float
        Largest growth of the length per unit distance.

    Returns
    -------
    GuidanceField
    """
    spacing = float(np.median(projector.scale))
    n = len(projector.points)
    if edge_length is not None:
        if not (np.isfinite(edge_length) and edge_length > 0):
            raise GuidanceError(f"edge_length must be a positive number, got {edge_length}")
        return GuidanceField(np.full(n, float(edge_length)), projector.conn.tree)
    rho = DEFAULT_RHO if rho is None else float(rho)
    if not (np.isfinite(rho) and 0 < rho < np.pi):
        raise GuidanceError(f"rho must be an angle in (0, pi) radians, got {rho}")
    lo = DEFAULT_MIN_SPACINGS * spacing if min_length is None else float(min_length)
    hi = DEFAULT_MAX_SPACINGS * spacing if max_length is None else float(max_length)
    if not (0 < lo <= hi and np.isfinite(hi)):
        raise GuidanceError(f"need 0 < min_length <= max_length, got {lo} and {hi}")
    if not (np.isfinite(gradation) and gradation > 0):
        raise GuidanceError(f"gradation must be positive, got {gradation}")
    kappa = np.abs(projector.principal_curvatures()).max(axis=1)
    # a median over each point's nearest neighbours removes single noisy curvature estimates
    kappa = neighbour_median(kappa, projector.median_sets)
    ideal = 2.0 * np.sin(rho / 2.0) / np.maximum(kappa, 1e-300)
    # never finer than the samples: where the cloud is sparse, the local spacing sets the floor
    floor = SAMPLING_FLOOR * projector.scale
    lengths = np.maximum(np.clip(ideal, lo, hi), floor)
    lengths = np.maximum(limit_gradation(lengths, projector.conn.graph, gradation), floor)
    return GuidanceField(lengths, projector.conn.tree)
