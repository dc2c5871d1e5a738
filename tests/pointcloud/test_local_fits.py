"""The compiled fits of the noise-aware projection (pointcloud/local_fits.py) and the
k-nearest connectivity the standalone projector builds."""

import numpy as np
import pc_surfaces as S
from scipy import sparse
from scipy.spatial import cKDTree

from splineviz.pointcloud.cocone import _pca_rings, knn_connectivity
from splineviz.pointcloud.local_fits import (
    nearest_in_rows,
    neighbour_median,
    project_median,
    project_on_polynomials,
    sheet_mask,
    smoothing_fits,
    variable_degree_fits,
)
from splineviz.pointcloud.projection import fit_polynomials, frames_from_normals

SCALES = ((1.6, 3), (2.6, 2), (4.2, 2))


def _grid_patch(f, noise=0.0, seed=0, n=25):
    """One neighbourhood: a jittered grid of unit spacing around the origin, heights ``f``."""
    rng = np.random.default_rng(seed)
    g = np.arange(n) - n // 2
    xy = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2) + 0.2 * rng.uniform(-1, 1, (n * n, 2))
    xy[0] = 0.0
    pts = np.c_[xy, f(xy[:, 0], xy[:, 1]) + noise * rng.normal(size=n * n)]
    index = np.argsort(np.linalg.norm(pts[:, :2], axis=1))[None, :200]
    index[0, 0] = 0
    return pts, index


def _fit(pts, index, scales=SCALES, noise=False):
    return smoothing_fits(pts, index, np.ones(index.shape, dtype=bool),
                          np.eye(3)[None], np.ones(len(pts)), np.array([0]), scales, 1e4,
                          noise=noise)


def test_quadratic_is_reproduced_at_every_width():
    true = np.array([0.3, 0.1, -0.2, 0.05, -0.02, 0.04])
    f = lambda x, y: true[0] + true[1] * x + true[2] * y + true[3] * x * x \
        + true[4] * x * y + true[5] * y * y  # noqa: E731
    pts, index = _grid_patch(f)
    coeffs, degree, _, _, _, sigma, rss, _ = _fit(pts, index, noise=True)
    true[0] = 0.0  # local heights are relative to the point itself, which is on the surface
    for s in range(3):
        assert np.allclose(coeffs[s, 0, :6], true, atol=1e-9)
        assert np.allclose(coeffs[s, 0, 6:], 0.0, atol=1e-9)
    assert degree[:, 0].tolist() == [3, 2, 2]
    assert sigma[0] < 1e-9 and np.all(rss < 1e-15)


def test_quartic_is_reproduced_by_the_degree_4_fit():
    # the degree test's alternative (projection.DETAIL_SCALE): exact on a quartic graph, whose
    # quartic part a quadratic at the same width misses
    rng = np.random.default_rng(3)
    true = np.r_[0.0, 0.1 * rng.normal(size=14)]
    e = np.array([(t - b, b) for t in range(5) for b in range(t + 1)])
    f = lambda x, y: sum(c * x**a * y**b for c, (a, b) in zip(true, e, strict=True))  # noqa: E731
    pts, index = _grid_patch(f)
    coeffs, degree, _, _, _, _, rss, _ = _fit(pts, index, ((3.4, 4), (3.4, 2)), noise=True)
    assert degree[:, 0].tolist() == [4, 2]
    assert np.allclose(coeffs[0, 0], true, atol=1e-8)
    assert rss[0, 0] < 1e-15 < rss[1, 0]


def test_noise_estimate_and_variance_factor():
    """On a noisy plane: the residual estimate recovers sigma, and ``spread`` predicts the
    variance of the fitted height at the origin over repeated noise (local heights are
    relative to the noisy point itself: its own height is added back)."""
    values, sigmas, ratios = [], [], []
    for seed in range(60):
        pts, index = _grid_patch(lambda x, y: 0.0 * x, noise=0.1, seed=seed)
        coeffs, _, _, spread, _, sigma, rss, dof = _fit(pts, index, SCALES + ((3.4, 4),),
                                                        noise=True)
        values.append(coeffs[:, 0, 0] + pts[0, 2])
        sigmas.append(sigma[0])
        ratios.append(rss[:, 0] / dof[:, 0])
    assert abs(np.mean(sigmas) / 0.1 - 1.0) < 0.1
    # every fit's residual sum has the expectation dof * sigma^2 (the degree test's premise)
    assert np.all(np.abs(np.mean(ratios, axis=0) / 0.1**2 - 1.0) < 0.1)
    predicted = 0.1 * np.sqrt(spread[:, 0])
    measured = np.std(values, axis=0)
    assert np.all(np.abs(measured / predicted - 1.0) < 0.3)
    # wider fits average more points: smaller variance
    assert predicted[0] > predicted[1] > predicted[2]


def test_scan_lines_fall_back_to_the_plane_and_borders_lean():
    """Points on two lines leave degree 2 undetermined across them: the plane is fitted.  A
    half-plane neighbourhood (a border of the cloud) has its centroid about 0.56 widths off."""
    x = np.linspace(-6, 6, 61)
    pts = np.c_[np.r_[x, x], np.r_[np.zeros(61), np.ones(61)], 0.1 * np.r_[x, x]]
    pts = np.r_[[[0.0, 0.0, 0.0]], pts[pts[:, 0] ** 2 + pts[:, 1] ** 2 > 0]]
    index = np.arange(len(pts))[None]
    coeffs, degree = _fit(pts, index)[:2]
    assert degree[:, 0].tolist() == [1, 1, 1]
    assert np.allclose(coeffs[:, 0, 1], 0.1, atol=1e-6)
    pts, index = _grid_patch(lambda x, y: 0.0 * x, n=41)
    half = index[:, pts[index[0], 0] >= 0]
    balance = _fit(pts, half)[4]
    assert np.all((balance[:, 0] > 0.4) & (balance[:, 0] < 0.65))
    assert np.all(_fit(pts, index)[4][:, 0] < 0.05)


def test_projection_onto_a_polynomial_graph():
    """Gauss-Newton lands on z = x^2 / 4 at the orthogonal foot (normal through the query)."""
    coeffs = np.zeros((1, 21))
    coeffs[0, 3] = 0.25
    queries = np.array([[0.5, 0.2, 1.0], [-1.0, 0.3, -0.5], [0.0, 0.0, 0.4]])
    pos, nrm = project_on_polynomials(np.zeros((1, 3)), np.eye(3)[None], np.ones(1), coeffs,
                                      np.array([2]), np.array([3.0]), np.zeros(3, dtype=int),
                                      queries, 30)
    assert np.allclose(pos[:, 2], 0.25 * pos[:, 0] ** 2, atol=1e-12)
    assert np.allclose(np.linalg.norm(nrm, axis=1), 1.0)
    off = queries - pos
    assert np.allclose(np.linalg.norm(np.cross(off, nrm), axis=1), 0.0, atol=1e-8)


def test_knn_connectivity_normals_and_ring_graph():
    pts = S.sphere(3000, seed=3)
    conn = knn_connectivity(pts)
    assert np.min(np.einsum("ij,ij->i", conn.normals, conn.points)) > 0.99  # outward
    g = conn.graph
    assert (g != g.T).nnz == 0
    # every point has neighbours on all sides (a ring), not only the nearest cluster
    counts = np.diff(g.indptr)
    assert counts.min() >= 3 and np.median(counts) >= 6
    d = conn.points[g.indices] - np.repeat(conn.points, counts, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pull = np.add.reduceat(d, g.indptr[:-1], axis=0) / counts[:, None]
    assert np.percentile(np.linalg.norm(pull, axis=1), 99) < 0.5
    assert len(conn.triangles) == 0


def test_pca_rings_match_the_numpy_formulation():
    rng = np.random.default_rng(4)
    pts = S.sphere(2000, seed=5) + 0.003 * rng.normal(size=(2000, 3))
    dist, idx = cKDTree(pts).query(pts, 13)
    normals, ring, ring_dist, flat = _pca_rings(pts, idx, dist, 6, np.array([12]), 0.5)
    # reference: batched covariance eigenvectors, then the nearest point per angular sector
    nb = pts[idx]
    d = nb - nb.mean(axis=1, keepdims=True)
    w, vec = np.linalg.eigh(np.einsum("nki,nkj->nij", d, d))
    want = vec[:, :, 0]
    assert np.allclose(np.abs(np.einsum("ij,ij->i", normals, want)), 1.0, atol=1e-12)
    assert np.allclose(flat, w[:, 0] / w[:, 1], rtol=1e-9)
    for i in rng.choice(len(pts), 200, replace=False):
        n = normals[i]
        t1 = np.cross(np.eye(3)[np.argmin(np.abs(n))], n)
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        rel = pts[idx[i, 1:]] - pts[i]
        sector = np.minimum(((np.arctan2(rel @ t2, rel @ t1) + np.pi) / (2 * np.pi) * 6)
                            .astype(int), 5)
        for s in range(6):
            hit = np.flatnonzero(sector == s)
            assert ring[i, s] == (idx[i, 1 + hit[0]] if len(hit) else -1)
            if len(hit):
                assert ring_dist[i, s] == dist[i, 1 + hit[0]]


def test_pca_normals_take_more_neighbours_where_noise_hides_the_plane():
    # a plane with noise of about the spacing: the 12 nearest points are not flat enough, the
    # normal comes from the first count whose least variance is at most half the middle one
    rng = np.random.default_rng(7)
    xy = rng.random((3000, 2))
    pts = np.column_stack([xy, 0.02 * rng.normal(size=3000)])
    idx = cKDTree(pts).query(pts, 49)[1]
    dist = cKDTree(pts).query(pts, 13)[0]
    counts = np.array([12, 24, 48])
    normals, _, _, flat = _pca_rings(pts, idx, dist, 6, counts, 0.5)
    want = np.empty((len(pts), 3))
    for i in range(len(pts)):
        for c in counts:
            d = pts[idx[i, :c + 1]] - pts[idx[i, :c + 1]].mean(axis=0)
            w, vec = np.linalg.eigh(d.T @ d)
            want[i] = vec[:, 0]
            if w[0] <= 0.5 * w[1]:
                break
    assert np.allclose(np.abs(np.einsum("ij,ij->i", normals, want)), 1.0, atol=1e-9)
    assert np.median(flat) > 0.25  # a noise-dominated cloud by knn_connectivity's gate
    # and the larger neighbourhoods do find the plane: the normals of 12 points do not
    twelve = _pca_rings(pts, idx, dist, 6, counts[:1], 0.5)[0]
    assert np.median(np.abs(normals[:, 2])) > 0.93  # 0.955: 17 degrees
    assert np.median(np.abs(twelve[:, 2])) < 0.9  # 0.87: 30 degrees off


def test_neighbour_median_and_nearest_in_rows_match_numpy():
    rng = np.random.default_rng(6)
    values = rng.normal(size=500)
    for k in (7, 8):  # odd and even counts
        index = rng.integers(0, 500, size=(300, k))
        assert np.array_equal(neighbour_median(values, index), np.median(values[index], axis=1))
    # a graph with tied lengths and rows shorter than k
    rows = rng.integers(0, 60, 400)
    cols = rng.integers(0, 60, 400)
    keep = rows != cols
    g = sparse.coo_matrix((rng.integers(1, 4, keep.sum()).astype(float),
                           (rows[keep], cols[keep])), shape=(70, 70)).tocsr()
    got = nearest_in_rows(g, 7)
    for i in range(70):
        lo, hi = g.indptr[i], g.indptr[i + 1]
        order = np.argsort(g.data[lo:hi], kind="stable")[:6]
        want = np.r_[i, g.indices[lo:hi][order], np.full(6 - len(order), i)]
        assert np.array_equal(got[i], want)


def _eigen_fits(pts, index, valid, frames, scale, k, q_max, cond_max):
    """The NumPy reference: :func:`fit_polynomials` (eigenvalue condition numbers)."""
    rel = pts[index[:, :k]] - pts[:, None, :]
    loc = np.einsum("pij,pkj->pki", frames, rel) / scale[:, None, None]
    w = np.where(valid[:, :k], np.exp(-np.einsum("pkc,pkc->pk", loc, loc)), 0.0)
    return fit_polynomials(loc, w, q_max, cond_max)


def test_compiled_variable_degree_fits_choose_the_eigenvalue_degrees():
    """The shifted-Cholesky condition test picks the degrees the extreme eigenvalues pick
    (scattered points on a sphere give degrees 3-5, points near a scan-line circle force
    lower ones) with the same coefficients; at each cut ``cond_max`` is moved to just
    below and just above the eigenvalue condition number of one point's degree-5 matrix, so a
    test that decided on the wrong side of it fails."""
    rng = np.random.default_rng(5)
    pts = S.sphere(4000, seed=8)
    pts[:400] = np.c_[np.cos(t := rng.uniform(0, 2 * np.pi, 400)), np.sin(t),
                      0.01 * rng.normal(size=400)]  # a ring: near a curve in the LCS
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    conn = knn_connectivity(pts, 40)
    index = conn.nearest
    valid = sheet_mask(conn.normals, index, 0.0)
    frames = frames_from_normals(conn.normals)
    ids = np.arange(len(pts))
    c0, d0, _ = _eigen_fits(conn.points, index, valid, frames, conn.spacing, 40, 5, 1e4)
    c1, d1, _ = variable_degree_fits(conn.points, index, valid, frames, conn.spacing, ids, 40,
                                     5, 1e4)
    assert set(np.unique(d0)) >= {3, 4, 5}
    assert np.array_equal(d0, d1)
    assert np.allclose(c0, c1, rtol=0, atol=1e-9)
    # the eigenvalue condition number of one point's degree-5 matrix, then cuts around it
    rel = conn.points[index[:1, :40]] - conn.points[:1, None, :]
    loc = np.einsum("pij,pkj->pki", frames[:1], rel) / conn.spacing[:1, None, None]
    w = np.where(valid[:1, :40], np.exp(-np.einsum("pkc,pkc->pk", loc, loc)), 0.0)
    b = np.stack([loc[..., 0] ** (t - j) * loc[..., 1] ** j for t in range(6)
                  for j in range(t + 1)], -1)
    ev = np.linalg.eigvalsh(np.einsum("pk,pki,pkj->pij", w, b, b))[0]
    cond = ev[-1] / ev[0]
    for cut, want in ((cond * (1 - 1e-6), False), (cond * (1 + 1e-6), True)):
        _, d, _ = variable_degree_fits(conn.points, index, valid, frames, conn.spacing,
                                       ids[:1], 40, 5, cut)
        assert (d[0] == 5) == want, (cut, cond, d)


def test_median_projection_is_the_median_of_the_projections():
    """The compiled medians equal NumPy's medians of the single projections, for odd and even
    numbers of polynomials (random graphs of degree 2 around scattered origins)."""
    rng = np.random.default_rng(3)
    n = 30
    points = rng.normal(size=(n, 3))
    frames = np.stack([np.linalg.qr(rng.normal(size=(3, 3)))[0].T for _ in range(n)])
    scale = rng.uniform(0.5, 1.5, n)
    coeffs = np.zeros((n, 21))
    coeffs[:, :6] = 0.2 * rng.normal(size=(n, 6))
    degree, reach = np.full(n, 2), np.full(n, 3.0)
    r = rng.normal(size=(50, 3))
    for k in (7, 4):
        sets = rng.integers(0, n, size=(50, k))
        pos, nrm = project_median(points, frames, scale, coeffs, degree, reach, sets, r, 3)
        each = project_on_polynomials(points, frames, scale, coeffs, degree, reach,
                                      sets.ravel(), np.repeat(r, k, axis=0), 3)
        assert np.array_equal(pos, np.median(each[0].reshape(50, k, 3), axis=1))
        assert np.array_equal(nrm, np.median(each[1].reshape(50, k, 3), axis=1))
