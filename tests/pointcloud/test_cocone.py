"""Cocone connectivity (thesis §7.2, Fig. 7.4): poles, co-cone filter, graph, normals."""

import numpy as np
import pc_surfaces as S
import pytest

from splineviz.core.points import PointCloud, PointCloudError
from splineviz.pointcloud.cocone import (
    ConnectivityError,
    circumcenters,
    cocone_connectivity,
    deduplicate,
    knn_connectivity,
)


def _ellipsoid(n, axes=(1.0, 0.6, 0.4), seed=0):
    return S.sphere(n, seed=seed) * np.array(axes)


def test_circumcenters_are_equidistant():
    rng = np.random.default_rng(0)
    tets = rng.normal(size=(100, 4, 3))
    c = circumcenters(tets)
    d = np.linalg.norm(tets - c[:, None], axis=2)
    assert np.allclose(d, d[:, :1])
    flat = np.zeros((1, 4, 3))
    flat[0, :, 0] = [0, 1, 2, 3]
    assert not np.isfinite(circumcenters(flat)).all()


def test_ellipsoid_normals_are_outward_and_accurate():
    axes = np.array([1.0, 0.6, 0.4])
    conn = cocone_connectivity(_ellipsoid(4000))
    p = conn.points
    true = p / axes**2
    true /= np.linalg.norm(true, axis=1, keepdims=True)
    cos = np.einsum("ij,ij->i", conn.normals, true)
    assert cos.min() > 0  # consistently outward
    assert np.median(cos) > np.cos(np.deg2rad(3))


def test_torus_normals_consistent_and_graph_local():
    pts = S.torus(6000, seed=1)
    conn = cocone_connectivity(pts)
    p = conn.points
    ring = np.stack([p[:, 0], p[:, 1], np.zeros(len(p))], 1)
    ring *= 1.0 / np.linalg.norm(ring, axis=1, keepdims=True)
    true = p - ring
    true /= np.linalg.norm(true, axis=1, keepdims=True)
    cos = np.einsum("ij,ij->i", conn.normals, true)
    assert cos.min() > 0.5
    g = conn.graph.tocoo()
    assert g.data.max() < 5 * np.median(conn.spacing)  # no long-range edges
    degree = np.diff(conn.graph.indptr)
    assert degree.min() >= 3 and 5 <= np.median(degree) <= 7


def test_close_parallel_sheets_are_not_connected():
    """Fig. 7.3 right: small Euclidean but large Riemannian distance -> no graph edge."""
    rng = np.random.default_rng(2)
    xy = rng.uniform(0, 1, (2500, 2))
    spacing = 1 / np.sqrt(2500)
    top = np.c_[xy, np.full(2500, 3 * spacing)]
    xy2 = rng.uniform(0, 1, (2500, 2))
    bottom = np.c_[xy2, np.zeros(2500)]
    conn = cocone_connectivity(np.vstack([top, bottom]))
    g = conn.graph.tocoo()
    z = conn.points[:, 2]
    sheet = z > 1.5 * spacing
    inner = (conn.points[:, :2].min(1) > 0.1) & (conn.points[:, :2].max(1) < 0.9)
    cross = (sheet[g.row] != sheet[g.col]) & inner[g.row] & inner[g.col]
    assert cross.sum() == 0


def test_duplicates_and_inverse():
    pts = _ellipsoid(800, seed=3)
    doubled = np.vstack([pts, pts[:100], pts[:5] + 1e-15])
    uniq, inverse = deduplicate(doubled)
    assert len(uniq) == 800
    assert np.allclose(uniq[inverse], doubled, atol=1e-12)
    conn = cocone_connectivity(PointCloud(doubled))
    assert len(conn.points) == 800 and len(conn.inverse) == len(doubled)


def test_planar_and_degenerate_input():
    rng = np.random.default_rng(4)
    plane = np.c_[rng.uniform(0, 1, (500, 2)), np.zeros(500)]
    conn = cocone_connectivity(plane)
    assert np.allclose(np.abs(conn.normals[:, 2]), 1.0)
    assert np.diff(conn.graph.indptr).min() >= 3
    with pytest.raises(ConnectivityError, match="line"):
        cocone_connectivity(np.c_[np.linspace(0, 1, 50), np.zeros((50, 2))])
    with pytest.raises(ConnectivityError, match="at least 4"):
        cocone_connectivity(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0]]))
    with pytest.raises(ConnectivityError, match="empty"):
        cocone_connectivity(np.zeros((0, 3)))
    with pytest.raises(PointCloudError):
        cocone_connectivity(np.array([[np.nan, 0, 0]] * 5))


def test_void_ratio_without_cocone_triangles():
    """The k-nearest connectivity's tangent-plane empty circles give about Cocone's void
    ratio: ~1.4 on a random sampling, below 1 on a jittered grid (a scan)."""
    pts = S.sphere(3000, seed=5)
    knn, cocone = knn_connectivity(pts).void_ratio(), cocone_connectivity(pts).void_ratio()
    assert abs(knn / cocone - 1.0) < 0.15 and knn > 1.2
    rng = np.random.default_rng(2)
    g = np.stack(np.meshgrid(np.arange(40.0), np.arange(40.0)), -1).reshape(-1, 2)
    grid = np.c_[g + 0.1 * rng.uniform(-1, 1, g.shape), 0.01 * rng.normal(size=len(g))]
    assert knn_connectivity(grid).void_ratio() < 0.9


def test_nearest_points_in_blocks_are_one_query_in_int32(monkeypatch):
    """The blocked k-NN query gives the k-d tree's own answer, ids as int32 (an (N, 80) int64
    index was 640 bytes a point of a large cloud)."""
    from scipy.spatial import cKDTree

    from splineviz.pointcloud import cocone

    pts = _ellipsoid(5000)
    tree = cKDTree(pts)
    d, i = tree.query(pts, 12)
    monkeypatch.setattr(cocone, "QUERY_BLOCK", 777)
    idx, dist = cocone.nearest_points(tree, pts, 12, 5)
    assert idx.dtype == np.int32 and dist.shape == (5000, 5)
    assert np.array_equal(idx, i) and np.array_equal(dist, d[:, :5])
    conn = knn_connectivity(pts, 40)
    assert conn.nearest.dtype == np.int32 and conn.nearest.shape == (5000, 40)
    assert np.array_equal(conn.nearest, cKDTree(conn.points).query(conn.points, 40)[1])


def test_void_ratio_in_blocks_is_the_whole_cloud_s(monkeypatch):
    """The tangent-plane void ratio computed block by block (bounded temporaries) is the
    quantile over the whole cloud, to the bit."""
    from splineviz.pointcloud import cocone

    conn = knn_connectivity(S.sphere(6000, seed=3))
    whole = conn.void_ratio()
    monkeypatch.setattr(cocone, "QUERY_BLOCK", 1000)
    assert conn.void_ratio() == whole


def test_void_ratio_of_a_sample_is_the_whole_cloud_s(monkeypatch):
    """Measured at evenly spread points (a large cloud's every point cost 32 s at 2
    million), the quantile is the whole cloud's within 3 %, both for a random sampling
    (~1.4) and for a jittered grid (a scan, below 1); every point is measured where the
    cloud has no more than the sample."""
    from splineviz.pointcloud import cocone

    rng = np.random.default_rng(2)
    g = np.stack(np.meshgrid(np.arange(100.0), np.arange(100.0)), -1).reshape(-1, 2)
    grid = np.c_[g + 0.1 * rng.uniform(-1, 1, g.shape), 0.01 * rng.normal(size=len(g))]
    for pts in (S.sphere(20000, seed=4), grid):
        conn = knn_connectivity(pts)
        monkeypatch.setattr(cocone, "VOID_SAMPLE", len(pts))
        whole = conn.void_ratio()
        monkeypatch.setattr(cocone, "VOID_SAMPLE", 2000)
        sampled = conn.void_ratio()
        assert sampled != whole and abs(sampled / whole - 1.0) < 0.03
    assert whole < 0.9


def test_orientation_of_many_components_is_one_search_per_component():
    """Normals oriented by one breadth-first search over all components (from a node joined
    to each component's root) are those of a search per component, which cost O(N) each."""
    from scipy import sparse
    from scipy.sparse import csgraph

    from splineviz.pointcloud.cocone import _flip_in_order, orient_normals

    base = S.sphere(3000, seed=4)
    pts = np.vstack([base, base[:1000] * 0.3 + 5, base[:50] * 0.01 - 7, base[50:80] * 0.01 + 9])
    conn = knn_connectivity(pts)
    rng = np.random.default_rng(5)
    normals = rng.normal(size=conn.normals.shape)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    g = sparse.triu(conn.graph, k=1).tocoo()
    w = 1.0 - np.abs(np.einsum("ij,ij->i", normals[g.row], normals[g.col])) + 1e-6
    mst = csgraph.minimum_spanning_tree(sparse.csr_matrix((w, (g.row, g.col)),
                                                          shape=conn.graph.shape))
    mst = (mst + mst.T).tocsr()
    want = normals.copy()
    ncomp, labels = csgraph.connected_components(mst, directed=False)
    assert ncomp == 4
    for c in range(ncomp):
        members = np.flatnonzero(labels == c)
        root = members[np.argmax(conn.points[members, 0])]
        if want[root, 0] < 0:
            want[root] *= -1
        order, pred = csgraph.breadth_first_order(mst, root, directed=False)
        _flip_in_order(want, order, pred)
    assert np.array_equal(orient_normals(normals, conn.graph, conn.points), want)
