"""Inter-point connectivity and normals by the Cocone algorithm (thesis §7.2, Fig. 7.4).

Conventions: points are ``(N, 3)`` float64; the neighbour graph is a symmetric
``scipy.sparse.csr_matrix`` of shape ``(N, N)`` whose stored values are Euclidean edge lengths;
normals are ``(N, 3)`` unit vectors.

The algorithm [ACDL00]: build the 3-D Delaunay tetrahedralisation (Qhull); the Voronoi vertices
are the tetrahedra's circumcentres; the *pole* of a point is the farthest Voronoi vertex of its
cell (for cells on the convex hull, which are unbounded, the average outward hull normal); the
*co-cone* of a point is the set of directions within ``COCONE_ANGLE`` of the plane orthogonal to
the pole vector; a Delaunay triangle is kept when its dual Voronoi edge meets the co-cones of all
three of its vertices.  The edges of the kept triangles form the neighbour graph.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import Delaunay, QhullError, cKDTree

from splineviz.core.errors import SplinevizError
from splineviz.core.points import PointCloud
from splineviz.pointcloud.threads import allowed_cores, use_allowed_cores

#: half opening angle of the co-cone around the plane orthogonal to the pole (Cocone: pi/8)
COCONE_ANGLE = np.pi / 8
#: points closer than this fraction of the bounding-box diagonal are merged as duplicates
DUPLICATE_TOLERANCE = 1e-9
#: points left with fewer Cocone neighbours than this get their nearest neighbours added
MIN_NEIGHBOURS = 3
#: number of nearest neighbours whose mean distance defines the local sample spacing
SPACING_NEIGHBOURS = 6


class ConnectivityError(SplinevizError, ValueError):
    """A point set from which no connectivity can be built (too few or degenerate points)."""


@dataclass(frozen=True, eq=False)
class Connectivity:
    """Result of :func:`cocone_connectivity` on the de-duplicated points.

    Attributes
    ----------
    points : (N, 3) float64
        The distinct input points.
    inverse : (N0,) int
        For each original input point, its index in ``points``.
    graph : (N, N) scipy.sparse.csr_matrix
        Symmetric neighbour graph; values are edge lengths.
    normals : (N, 3) float64
        Unit normals from the pole vectors, oriented consistently along the graph (outward on
        closed surfaces: the point of largest x has a normal with positive x).
    spacing : (N,) float64
        Local sample spacing: mean distance to the ``SPACING_NEIGHBOURS`` nearest points.
    tree : scipy.spatial.cKDTree
        k-d tree over ``points``.
    triangles : (F, 3) int
        The Cocone triangles (a rough surface triangulation; unoriented).
    nearest : (N, k) int32 or None
        The ``k`` nearest points of each point, nearest first (column 0 the point itself),
        where the builder was asked for them (:func:`knn_connectivity`).
    """

    points: np.ndarray
    inverse: np.ndarray
    graph: sparse.csr_matrix
    normals: np.ndarray
    spacing: np.ndarray
    tree: cKDTree
    triangles: np.ndarray
    nearest: np.ndarray | None = None

    def void_ratio(self, quantile: float = 0.99) -> float:
        """How irregular the sampling is: a high quantile of the Cocone triangles' circumradii
        (the radii of the empty circles between samples) over the local spacing.

        About 0.7-1.0 for laser scans, about 1.4 for uniformly random samples; holes of the
        scan are too rare to move the quantile.  Without Cocone triangles (the k-nearest
        connectivity) the empty circles come from :func:`tangent_void_ratio`.
        """
        f, p = self.triangles, self.points
        if len(f) == 0:
            return tangent_void_ratio(p, self.normals, self.spacing, self.tree, quantile)
        a = np.linalg.norm(p[f[:, 1]] - p[f[:, 2]], axis=1)
        b = np.linalg.norm(p[f[:, 2]] - p[f[:, 0]], axis=1)
        c = np.linalg.norm(p[f[:, 0]] - p[f[:, 1]], axis=1)
        area = 0.5 * np.linalg.norm(np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]]),
                                    axis=1)
        radius = a * b * c / (4 * np.maximum(area, 1e-300))
        spacing = self.spacing[f].mean(axis=1)
        return float(np.quantile(radius / spacing, quantile))

    def neighbours(self, i: int) -> np.ndarray:
        """Indices of the graph neighbours of point ``i``."""
        return self.graph.indices[self.graph.indptr[i] : self.graph.indptr[i + 1]]


def deduplicate(points: np.ndarray, tolerance: float = DUPLICATE_TOLERANCE):
    """Merge points closer than ``tolerance`` times the bounding-box diagonal.

    Parameters
    ----------
    points : (N0, 3) float64

    Returns
    -------
    unique : (N, 3) float64
    inverse : (N0,) int
        ``unique[inverse]`` reproduces the input up to the tolerance.
    """
    diag = float(np.linalg.norm(np.ptp(points, axis=0))) if len(points) else 0.0
    step = max(diag * tolerance, np.finfo(float).tiny)
    keys = np.round((points - points.min(axis=0)) / step).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return points[first], inverse.ravel()


def circumcenters(vertices: np.ndarray) -> np.ndarray:
    """Circumcentres of tetrahedra.

    Parameters
    ----------
    vertices : (T, 4, 3) float64

    Returns
    -------
    (T, 3) float64; rows of flat tetrahedra are very large or non-finite.
    """
    a = vertices[:, 0]
    e = vertices[:, 1:] - a[:, None, :]  # (T, 3, 3) edge vectors
    rhs = 0.5 * np.einsum("tij,tij->ti", e, e)
    det = np.linalg.det(e)
    ok = np.abs(det) > 1e-300
    out = np.full(a.shape, np.inf)
    out[ok] = a[ok] + np.linalg.solve(e[ok], rhs[ok][..., None])[..., 0]
    return out


#: queries per k-d tree call from which :func:`tree_query` uses every core (threads cost
#: more than they save on the front's batches of a few dozen points)
PARALLEL_QUERIES = 2048


def tree_query(tree: cKDTree, x: np.ndarray, k: int = 1):
    """``tree.query(x, k)``: ``(distances, indices)``, on every allowed core for big batches
    (the result does not depend on the number of threads)."""
    return tree.query(x, k=k, workers=allowed_cores() if len(x) >= PARALLEL_QUERIES else 1)


#: points per block of :func:`nearest_points` and :func:`tangent_void_ratio`: their
#: temporaries (the k-d tree's (B, k) int64 and float64 answers, the void test's (B, 16)
#: fans) are bounded by the block, not the cloud (at 2 million points the unblocked ones
#: took gigabytes)
QUERY_BLOCK = 65536


def nearest_points(tree: cKDTree, points: np.ndarray, k: int, distances: int = 0):
    """The ``k`` nearest points of every point of ``points``, queried in blocks of
    ``QUERY_BLOCK`` rows so the k-d tree's int64 and float64 answers never exist for the
    whole cloud.

    Parameters
    ----------
    tree : cKDTree
    points : (N, 3) float64
    k : int
    distances : int
        Keep the distances of the first this many columns.

    Returns
    -------
    index : (N, k) int32, nearest first (the rows of ``tree.query``)
    dist : (N, distances) float64, the first columns of the distances
    """
    n = len(points)
    index = np.empty((n, k), dtype=np.int32)
    dist = np.empty((n, distances))
    for lo in range(0, n, QUERY_BLOCK):
        d, i = tree_query(tree, points[lo:lo + QUERY_BLOCK], k)
        d, i = np.reshape(d, (-1, k)), np.reshape(i, (-1, k))
        index[lo:lo + QUERY_BLOCK] = i
        dist[lo:lo + QUERY_BLOCK] = d[:, :distances]
    return index, dist


def local_spacing(tree: cKDTree, points: np.ndarray, k: int = SPACING_NEIGHBOURS) -> np.ndarray:
    """Mean distance of each point to its ``k`` nearest other points, shape ``(N,)``."""
    k = min(k, len(points) - 1)
    dist, _ = tree_query(tree, points, k + 1)
    return dist[:, 1:].mean(axis=1)


def _hull_pole_directions(dt: Delaunay, points: np.ndarray) -> np.ndarray:
    """Average outward normal of the convex-hull facets at each hull vertex; zero elsewhere."""
    hull = dt.convex_hull
    p = points[hull]
    nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    # orient outward: away from the centroid of the whole set
    out = np.sign(np.einsum("ij,ij->i", nrm, p.mean(axis=1) - points.mean(axis=0)))
    nrm *= np.where(out == 0, 1.0, out)[:, None]
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True) + 1e-300
    acc = np.zeros_like(points)
    for c in range(3):
        np.add.at(acc, hull[:, c], nrm)
    return acc


def poles(dt: Delaunay, points: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """Unit pole vectors (thesis Fig. 7.4: the farthest Voronoi vertex), shape ``(N, 3)``.

    Unbounded Voronoi cells (points on the convex hull) use the average outward normal of their
    hull facets, as the Cocone algorithm does.
    """
    n = len(points)
    simp = dt.simplices
    pid = simp.ravel()
    tid = np.repeat(np.arange(len(simp)), 4)
    vec = centers[tid] - points[pid]
    dist = np.einsum("ij,ij->i", vec, vec)
    dist[~np.isfinite(dist)] = -1.0  # flat tetrahedra carry no pole
    order = np.lexsort((dist, pid))  # per point, farthest last
    last = np.r_[pid[order][1:] != pid[order][:-1], True]
    pole = np.zeros((n, 3))
    pole[pid[order][last]] = vec[order][last]
    hull_dir = _hull_pole_directions(dt, points)
    on_hull = np.linalg.norm(hull_dir, axis=1) > 0
    pole[on_hull] = hull_dir[on_hull]
    pole[~np.isfinite(pole).all(axis=1)] = 0.0
    length = np.linalg.norm(pole, axis=1, keepdims=True)
    return np.divide(pole, length, out=np.zeros_like(pole), where=length > 0)


def _pole_cosine(points, pole, ids, x):
    """Cosine of the angle between ``x - p`` and the pole vector of ``p`` (p = points[ids])."""
    v = x - points[ids]
    cos = np.einsum("ij,ij->i", v, pole[ids]) / (np.linalg.norm(v, axis=1) + 1e-300)
    return cos


def cocone_triangles(dt: Delaunay, points: np.ndarray, pole: np.ndarray, centers: np.ndarray,
                     angle: float = COCONE_ANGLE) -> np.ndarray:
    """Delaunay triangles whose dual Voronoi edge meets the co-cones of all three vertices.

    Parameters
    ----------
    dt : scipy.spatial.Delaunay of ``points``
    points : (N, 3) float64
    pole : (N, 3) unit pole vectors
    centers : (T, 3) circumcentres of ``dt.simplices``

    Returns
    -------
    (F, 3) int triangles (vertex indices, unoriented).
    """
    simp, nb = dt.simplices, dt.neighbors
    t = np.repeat(np.arange(len(simp)), 4)
    k = np.tile(np.arange(4), len(simp))
    other = nb.ravel()
    keep = (other == -1) | (t < other)  # each interior face once
    t, k, other = t[keep], k[keep], other[keep]
    faces = np.stack([simp[t, (k + j) % 4] for j in (1, 2, 3)], axis=1)
    start = centers[t]
    end = np.empty_like(start)
    inner = other >= 0
    end[inner] = centers[other[inner]]
    # a hull face's dual Voronoi edge is a ray leaving the hull: end it far away
    p = points[faces[~inner]]
    nrm = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    away = np.einsum("ij,ij->i", nrm, p[:, 0] - points[simp[t[~inner], k[~inner]]])
    nrm *= np.sign(away + (away == 0))[:, None]
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True) + 1e-300
    far = 10.0 * float(np.linalg.norm(np.ptp(points, axis=0)))
    base = np.where(np.isfinite(start[~inner]), start[~inner], p.mean(axis=1))
    end[~inner] = base + far * nrm
    start = np.where(np.isfinite(start), start, end)
    end = np.where(np.isfinite(end), end, start)
    s = np.sin(angle)
    ok = np.ones(len(faces), dtype=bool)
    for j in range(3):
        c0 = _pole_cosine(points, pole, faces[:, j], start)
        c1 = _pole_cosine(points, pole, faces[:, j], end)
        # the angle is continuous along the edge: it meets the co-cone if an end lies inside
        # or the ends lie in opposite halves of the double cone around the pole
        ok &= (np.abs(c0) <= s) | (np.abs(c1) <= s) | (c0 * c1 < 0)
    return faces[ok]


#: nearest points whose empty circles in the tangent plane :func:`tangent_void_ratio` finds
VOID_NEIGHBOURS = 16
#: most threads of :func:`tangent_void_ratio` (each holds a quarter block's fans, ~40 MB)
VOID_THREADS = 8
#: most points whose empty circles :func:`tangent_void_ratio` measures: the quantile is a
#: statistic of the whole sampling, and evenly spread points give it (several empty circles
#: each) without asking the k-d tree about every point of a large cloud
VOID_SAMPLE = 16384


def tangent_void_ratio(points: np.ndarray, normals: np.ndarray, spacing: np.ndarray,
                       tree: cKDTree, quantile: float = 0.99) -> float:
    """:meth:`Connectivity.void_ratio` without a tetrahedralisation: empty circles of the
    Delaunay triangles at each point in its tangent plane.

    The ``VOID_NEIGHBOURS`` nearest points of a point, seen in its tangent plane and sorted by
    angle, form a fan of triangles with it; a fan triangle whose circumcircle holds none of
    them (and lies within them: its diameter at most the farthest one's distance) is a
    Delaunay triangle of the local sampling, and its circumradius over the point's spacing is
    one empty-circle ratio.

    Parameters
    ----------
    points, normals : (N, 3); spacing : (N,); tree : k-d tree of ``points``

    Returns
    -------
    float: the ``quantile`` of the ratios (1.0 when there are none), measured at up to
    ``VOID_SAMPLE`` points spread evenly over the cloud's order.
    """
    from concurrent.futures import ThreadPoolExecutor

    k = min(VOID_NEIGHBOURS, len(points) - 1)
    at = np.unique(np.linspace(0, len(points) - 1, min(len(points), VOID_SAMPLE)).astype(np.int64))
    n, block = len(at), max(1, QUERY_BLOCK // 4)
    # NumPy releases the GIL in its loops: blocks on threads (2 million points took 40 s on
    # one core); each thread's fans are a quarter block's, so memory stays bounded
    with ThreadPoolExecutor(max(1, min(allowed_cores(), VOID_THREADS))) as pool:
        ratios = np.concatenate(list(pool.map(
            lambda lo: _void_ratios(points, normals, spacing, tree, k, at[lo:lo + block]),
            range(0, n, block))))
    return float(np.quantile(ratios, quantile)) if len(ratios) else 1.0


def _void_ratios(points, normals, spacing, tree, k, at):
    """The empty-circle ratios of :func:`tangent_void_ratio` at the points ``at (B,)``:
    ``(R,)``."""
    _, idx = tree.query(points[at], k + 1)  # one worker: the blocks run on threads
    idx = idx[:, 1:]
    nrm, centre = normals[at], points[at]
    helper = np.zeros_like(nrm)
    helper[np.arange(len(nrm)), np.argmin(np.abs(nrm), axis=1)] = 1.0
    t1 = np.cross(helper, nrm)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(nrm, t1)
    rel = points[idx] - centre[:, None, :]
    u = np.einsum("nkc,nc->nk", rel, t1)
    v = np.einsum("nkc,nc->nk", rel, t2)
    order = np.argsort(np.arctan2(v, u), axis=1)
    u, v = np.take_along_axis(u, order, 1), np.take_along_axis(v, order, 1)
    bu, bv = np.roll(u, -1, axis=1), np.roll(v, -1, axis=1)
    cross = u * bv - v * bu
    na, nb = u * u + v * v, bu * bu + bv * bv
    with np.errstate(divide="ignore", invalid="ignore"):
        cx = (bv * na - v * nb) / (2 * cross)
        cy = (u * nb - bu * na) / (2 * cross)
    radius = np.hypot(cx, cy)  # the point itself is at the origin
    gap = radius.copy()
    for j in range(k):
        gap = np.minimum(gap, np.hypot(cx - u[:, j:j + 1], cy - v[:, j:j + 1]))
    reach = np.sqrt(np.max(na, axis=1, keepdims=True))
    empty = (cross > 0) & (gap >= radius * (1 - 1e-9)) & (2 * radius <= reach)
    return (radius / spacing[at, None])[empty]


def orient_normals(normals: np.ndarray, graph: sparse.csr_matrix, points: np.ndarray) -> np.ndarray:
    """Orient normals consistently by propagation along a minimum spanning tree [HDD*92].

    Edge weights ``1 - |n_i . n_j|`` make the propagation cross nearly parallel normals first.
    Per connected component, the sign is fixed so that the point of largest x has a normal with
    positive x (outward on a closed surface).

    Parameters
    ----------
    normals : (N, 3) unit vectors
    graph : (N, N) symmetric sparse neighbour graph
    points : (N, 3)

    Returns
    -------
    (N, 3) re-oriented copy.
    """
    g = sparse.triu(graph, k=1).tocoo()
    w = 1.0 - np.abs(np.einsum("ij,ij->i", normals[g.row], normals[g.col])) + 1e-6
    mst = csgraph.minimum_spanning_tree(sparse.csr_matrix((w, (g.row, g.col)), shape=graph.shape))
    mst = (mst + mst.T).tocsr()
    out = normals.copy()
    n = len(points)
    ncomp, labels = csgraph.connected_components(mst, directed=False)
    # each component's root: its point of largest x (the first such id)
    by_x = np.lexsort((np.arange(n), -points[:, 0], labels))
    roots = by_x[np.r_[True, labels[by_x[1:]] != labels[by_x[:-1]]]]
    out[roots[out[roots, 0] < 0]] *= -1
    # one breadth-first search from a node joined to every root: a forest has one path from
    # its root to each point, so each point's predecessor is the one a search of its own
    # component gives (a search per component cost O(N) each: noisy clouds of millions of
    # points have thousands of components)
    joined = sparse.vstack([sparse.hstack([mst, sparse.csr_matrix((n, 1))]),
                            sparse.csr_matrix((np.ones(ncomp), (np.zeros(ncomp, dtype=np.int64),
                                                                roots)), shape=(1, n + 1))])
    order, pred = csgraph.breadth_first_order(joined.tocsr(), n, directed=False)
    _flip_in_order(out, order, pred)
    return out


@numba.njit(cache=True)
def _flip_in_order(normals, order, pred):
    """Flip ``normals (N, 3)`` in place where they oppose their predecessor's, in breadth-first
    ``order`` (each parent is final before its children); nodes whose predecessor is no
    point (a root, or the search's own start) stay."""
    n = len(normals)
    for t in range(len(order)):
        v = order[t]
        u = pred[v] if v < n else -1
        if u < 0 or u >= n:
            continue
        if normals[v, 0] * normals[u, 0] + normals[v, 1] * normals[u, 1] \
                + normals[v, 2] * normals[u, 2] < 0:
            normals[v, 0] = -normals[v, 0]
            normals[v, 1] = -normals[v, 1]
            normals[v, 2] = -normals[v, 2]


def _planar_connectivity(points: np.ndarray):
    """Delaunay triangulation inside the best-fit plane of (almost) coplanar points."""
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    uv = (points - centre) @ vt[:2].T
    tri = Delaunay(uv).simplices
    normals = np.tile(vt[2], (len(points), 1))
    return tri, normals


def _distinct_points(cloud):
    """The distinct points of ``cloud``, the index of each input point among them and the
    singular values of the centred points (a sample of 20,000 at most).

    Returns
    -------
    points : (n, 3) float ndarray
    inverse : (N,) int ndarray
    sv : (3,) float ndarray

    Raises
    ------
    ConnectivityError
        Fewer than 4 distinct points, or all points on a line.
    """
    pts = cloud.points if isinstance(cloud, PointCloud) else PointCloud(cloud).points
    if len(pts) == 0:
        raise ConnectivityError("the point cloud is empty")
    points, inverse = deduplicate(pts)
    n = len(points)
    if n < 4:
        raise ConnectivityError(f"at least 4 distinct points are needed, got {n}")
    centred = points - points.mean(axis=0)
    sv = np.linalg.svd(centred[:: max(1, n // 20000)], compute_uv=False)
    if sv[1] <= 1e-9 * sv[0]:
        raise ConnectivityError("all points lie on a line; no surface can be built")
    return points, inverse, sv


def cocone_connectivity(cloud: PointCloud | np.ndarray,
                        angle: float = COCONE_ANGLE) -> Connectivity:
    """Cocone neighbour graph and oriented normals of a point cloud (thesis §7.2, Fig. 7.4).

    Duplicates are merged first; coplanar input is triangulated in its plane; points that Qhull
    leaves out or that end up with fewer than ``MIN_NEIGHBOURS`` Cocone neighbours are connected
    to their nearest neighbours so that every point has a neighbourhood.

    Parameters
    ----------
    cloud : PointCloud or (N0, 3) array_like
    angle : float
        Co-cone half opening angle in radians.

    Returns
    -------
    Connectivity

    Raises
    ------
    ConnectivityError
        Fewer than 4 distinct points, or all points on a line.
    """
    points, inverse, sv = _distinct_points(cloud)
    n = len(points)
    if sv[2] <= 1e-9 * sv[0]:
        faces, normals = _planar_connectivity(points)
    else:
        try:
            dt = Delaunay(points, qhull_options="Qbb Qc Q12 Qt")
        except QhullError:
            dt = Delaunay(points, qhull_options="QJ")
        centers = circumcenters(points[dt.simplices])
        pole = poles(dt, points, centers)
        faces = cocone_triangles(dt, points, pole, centers, angle)
        normals = pole
    tree = cKDTree(points)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    degree = np.bincount(edges.ravel(), minlength=n)
    lonely = np.flatnonzero(degree < 2 * MIN_NEIGHBOURS)  # each edge is counted twice per fan
    if len(lonely):
        k = min(SPACING_NEIGHBOURS, n - 1)
        _, idx = tree.query(points[lonely], k=k + 1)
        extra = np.stack([np.repeat(lonely, k), idx[:, 1:].ravel()], axis=1)
        edges = np.concatenate([edges, extra])
    edges = np.sort(edges, axis=1)
    edges = np.unique(edges[edges[:, 0] != edges[:, 1]], axis=0)
    length = np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1)
    graph = sparse.coo_matrix((length, (edges[:, 0], edges[:, 1])), shape=(n, n))
    graph = (graph + graph.T).tocsr()
    # points without a pole (isolated, degenerate cells) take a PCA normal of their neighbours
    bad = np.flatnonzero(np.linalg.norm(normals, axis=1) < 0.5)
    for i in bad:
        nb = np.r_[i, graph.indices[graph.indptr[i] : graph.indptr[i + 1]]]
        _, _, vt = np.linalg.svd(points[nb] - points[nb].mean(axis=0))
        normals[i] = vt[-1]
    normals = orient_normals(normals, graph, points)
    spacing = local_spacing(tree, points)
    return Connectivity(points, inverse, graph, normals, spacing, tree, faces)


@numba.njit(cache=True, parallel=True)
def _pca_rings(points, idx, dist, sectors, counts, flatness):
    """PCA normals and sector rings of :func:`knn_connectivity`.

    Parameters
    ----------
    points : (N, 3) float64
    idx : (N, M) int32 nearest points (column 0 the point itself), sorted by distance
    dist : (N, R) float64 the distances of the first R columns (the ring's candidates)
    sectors : int
    counts : (L,) int64 ascending neighbour counts, the last at most M - 1
    flatness : float
        The normal comes from the first count of neighbours whose least variance is at most
        ``flatness`` times the middle one, else from the last count.

    Returns
    -------
    normals : (N, 3) unit least-variance directions (unoriented)
    ring : (N, sectors) int64, the nearest point in each angular sector around the normal
        (-1 where a sector holds none)
    ring_dist : (N, sectors) its distance
    flat : (N,) the least over the middle variance of the first count's neighbours
    """
    n = idx.shape[0]
    k1 = dist.shape[1]
    normals = np.empty((n, 3))
    flat = np.empty(n)
    ring = np.full((n, sectors), -1, dtype=np.int64)
    ring_dist = np.zeros((n, sectors))
    for i in numba.prange(n):
        nrm = np.zeros(3)
        for level in range(len(counts)):
            m = counts[level] + 1
            mean = np.zeros(3)
            for c in range(m):
                mean += points[idx[i, c]]
            mean /= m
            cov = np.zeros((3, 3))
            for c in range(m):
                d = points[idx[i, c]] - mean
                for r in range(3):
                    for s in range(3):
                        cov[r, s] += d[r] * d[s]
            w, vec = np.linalg.eigh(cov)
            nrm = vec[:, 0].copy()
            if level == 0:
                flat[i] = w[0] / w[1] if w[1] > 0 else 1.0
            if w[0] <= flatness * w[1]:
                break
        normals[i] = nrm
        # tangent directions: a unit vector orthogonal to the normal, and their cross product
        axis = np.argmin(np.abs(nrm))
        helper = np.zeros(3)
        helper[axis] = 1.0
        t1 = np.cross(helper, nrm)
        t1 /= np.sqrt(t1[0] ** 2 + t1[1] ** 2 + t1[2] ** 2)
        t2 = np.cross(nrm, t1)
        # columns are sorted by distance: the first point met in a sector is its nearest
        for c in range(1, k1):
            rel = points[idx[i, c]] - points[i]
            angle = np.arctan2(rel[0] * t2[0] + rel[1] * t2[1] + rel[2] * t2[2],
                               rel[0] * t1[0] + rel[1] * t1[1] + rel[2] * t1[2])
            s = min(int((angle + np.pi) / (2 * np.pi) * sectors), sectors - 1)
            if ring[i, s] < 0:
                ring[i, s] = idx[i, c]
                ring_dist[i, s] = dist[i, c]
    return normals, ring, ring_dist, flat


#: nearest points whose covariance gives the normal of :func:`knn_connectivity`: the first of
#: these counts whose least variance is at most ``NORMAL_FLATNESS`` of the middle one, else the
#: last.  Where the noise is as large as the spacing the 12 nearest points of a dense scan
#: are a ball of noise, not a patch of the surface: Lucy sampled with 50,000 points and
#: Gaussian noise of 0.6 % of the diagonal (about three spacings), 12 points gave neighbouring
#: normals facing apart in 20 % of the pairs and the front 5,492 border edges; the first
#: count whose least variance is at most half the middle one, 10 % and 692 (at 0.2 % noise:
#: 737 -> 234 border edges, farthest clean point 1.13 -> 0.95 % of the diagonal)
NORMAL_NEIGHBOURS = (12, 24, 48)
NORMAL_FLATNESS = 0.5
#: ... in clouds whose median point's 12 nearest points have a least variance above this share
#: of the middle one (a scanner's noise covers the whole scan; a clean scan's nearest points
#: are not flat only where it bends, and there more points would blur the normal: Lucy's scan,
#: median 0.06, rms distance of its points to the mesh 0.069 -> 0.075 % of the diagonal with
#: more points there).  Medians: the clean bench clouds 0.005-0.06, the noisy bunny 0.15, Lucy
#: with 50,000 points and 0.2 / 0.6 % noise 0.34 / 0.52
NOISY_CLOUD_FLATNESS = 0.25
#: angular sectors around the normal in which :func:`knn_connectivity` joins the nearest point
GRAPH_SECTORS = 6


def knn_connectivity(cloud: PointCloud | np.ndarray, neighbours: int = 0) -> Connectivity:
    """Nearest-neighbour graph and oriented PCA normals: a fast stand-in for Cocone.

    For projecting a cloud (not meshing it) no Delaunay tetrahedralisation is needed: the
    normal of each point is the least-variance direction of its nearest points [HDD*92] (12,
    or more where noise hides the plane in them: ``NORMAL_NEIGHBOURS``), oriented like
    Cocone's by :func:`orient_normals`.  The graph joins each point to the nearest of its 12
    nearest points in each of ``GRAPH_SECTORS`` angular sectors around
    its normal (symmetrised): like Cocone's ring of neighbours it surrounds the point, where
    plain nearest neighbours may all lie to one side (the projector's median over the
    neighbours' polynomials then lands off the surface).  About five times faster than
    :func:`cocone_connectivity` on 20,000 points; the two sides of a part thinner than the
    spacing may share a graph edge, which Cocone's co-cone test avoids, so the mesher keeps
    Cocone.

    Parameters
    ----------
    cloud : PointCloud or (N0, 3) array_like
    neighbours : int
        Also keep this many nearest points of each point (itself included) as
        ``Connectivity.nearest``: one k-d tree query serves the normals and the caller.

    Returns
    -------
    Connectivity
        With no ``triangles`` (shape ``(0, 3)``).

    Raises
    ------
    ConnectivityError
        Fewer than 4 distinct points, or all points on a line.
    """
    points, inverse, sv = _distinct_points(cloud)
    n = len(points)
    tree = cKDTree(points)
    k = min(max(NORMAL_NEIGHBOURS[0], SPACING_NEIGHBOURS), n - 1)
    counts = np.array([min(c, n - 1) for c in NORMAL_NEIGHBOURS], dtype=np.int64)
    nearest, dist = nearest_points(tree, points, min(max(int(counts[-1]) + 1, int(neighbours)),
                                                     n), k + 1)
    use_allowed_cores()
    normals, ring, ring_dist, flat = _pca_rings(points, nearest, dist, GRAPH_SECTORS,
                                                counts[:1], NORMAL_FLATNESS)
    if len(counts) > 1 and np.median(flat) > NOISY_CLOUD_FLATNESS:
        normals, ring, ring_dist, _ = _pca_rings(points, nearest, dist, GRAPH_SECTORS, counts,
                                                 NORMAL_FLATNESS)
    has = ring >= 0
    graph = sparse.coo_matrix((ring_dist[has], (np.repeat(np.arange(n), has.sum(axis=1)),
                                                ring[has])), shape=(n, n)).tocsr()
    graph = graph.maximum(graph.T).tocsr()
    normals = orient_normals(normals, graph, points)
    spacing = dist[:, 1:min(SPACING_NEIGHBOURS, n - 1) + 1].mean(axis=1)
    nearest = np.ascontiguousarray(nearest[:, :neighbours]) if neighbours > 0 else None
    return Connectivity(points, inverse, graph, normals, spacing, tree,
                        np.empty((0, 3), dtype=np.int64), nearest)


def compile_kernels() -> None:
    """Compile the kernels into numba's on-disk cache (install.sh runs this once)."""
    _flip_in_order(np.ones((2, 3)), np.arange(2), np.zeros(2, dtype=np.int32))
    points = np.random.default_rng(0).normal(size=(12, 3))
    order = np.argsort(np.linalg.norm(points[:, None] - points[None], axis=-1), axis=1)[:, :5]
    _pca_rings(points, np.ascontiguousarray(order, dtype=np.int32), np.ones(order.shape), 6,
               np.array([2, 4]), NORMAL_FLATNESS)
