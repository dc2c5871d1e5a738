"""The advancing front's compiled pieces: point grid, front-vertex grid, batched predictions,
valence flips."""

import numpy as np
import pc_surfaces as S
from scipy.spatial import cKDTree

import splineviz as sv
from splineviz.pointcloud import front_kernels as fk
from splineviz.pointcloud.quality import edge_face_counts
from splineviz.pointcloud.relaxation import flip_edges


def test_point_grid_finds_the_k_d_tree_neighbours():
    rng = np.random.default_rng(0)
    # uneven density: a dense cap on a sparse sphere
    pts = np.vstack([S.sphere(3000, seed=1), S.sphere(3000, seed=2) * [0.3, 0.3, 0.05]
                     + [0, 0, 1.0]])
    tree = cKDTree(pts)
    grid = fk.PointGrid(pts, 0.05)
    near = pts[rng.integers(0, len(pts), 400)] + rng.normal(scale=0.02, size=(400, 3))
    far = rng.normal(size=(20, 3)) * 3.0  # beyond MAX_SHELL cells: answered by the tree
    for q in (near, far, np.vstack([near, far])):
        for k in (1, 24):
            d0, i0 = tree.query(q, k=k)
            d1, i1 = grid.query(q, k, tree)
            np.testing.assert_array_equal(d1, np.reshape(d0, d1.shape))
            np.testing.assert_array_equal(i1, np.reshape(i0, i1.shape))


def test_front_vertex_grid_query_matches_brute_force():
    rng = np.random.default_rng(3)
    n = 500
    V = rng.uniform(-1, 1, (n, 3))
    N = rng.normal(size=(n, 3))
    head = np.full(1024, -1, dtype=np.int64)
    nxt, prv = np.full(n, -1, dtype=np.int64), np.full(n, -1, dtype=np.int64)
    cells = np.zeros((n, 3), dtype=np.int64)
    cell = 0.2
    for i in range(n):
        fk.grid_insert(head, nxt, prv, cells, i, *np.floor(V[i] / cell).astype(int))
    gone = rng.choice(n, 200, replace=False)
    for i in gone:
        fk.grid_remove(head, nxt, prv, cells, i)
    alive = np.setdiff1d(np.arange(n), gone)
    for _ in range(50):
        x, normal, radius = rng.uniform(-1, 1, 3), rng.normal(size=3), rng.uniform(0.05, 0.5)
        d = np.linalg.norm(V[alive] - x, axis=1)
        for use in (False, True):
            keep = (d <= radius) & ((N[alive] @ normal > 0) | (not use))
            expect = alive[keep][np.argsort(d[keep], kind="stable")]
            got = fk.vertices_near(head, nxt, cells, cell, V, N, x, radius, normal, use)
            np.testing.assert_array_equal(got, expect)


def test_batched_predictions_give_the_mesh_of_single_ones(monkeypatch):
    """Each batched prediction depends only on its own edge: the mesh is the one a front
    predicting one edge at a time builds."""
    from splineviz.pointcloud import advancing_front

    pts = S.torus(1500, seed=2)
    meshes = []
    for batch in (1, advancing_front.PREDICT_BATCH):
        monkeypatch.setattr(advancing_front, "PREDICT_BATCH", batch)
        m = sv.remesh(pts, edge_length=0.2, optimize_mesh=False)
        meshes.append((np.asarray(m.points), np.asarray(m.faces)))
    np.testing.assert_array_equal(meshes[0][0], meshes[1][0])
    np.testing.assert_array_equal(meshes[0][1], meshes[1][1])


def _union_jack(k):
    """A k x k grid of unit squares in z = 0 split along alternating diagonals: interior
    valences 4 and 8, faces counter-clockwise seen from +z."""
    x, y = np.meshgrid(np.arange(k + 1.0), np.arange(k + 1.0), indexing="ij")
    v = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]

    def vid(i, j):
        return i * (k + 1) + j

    faces = []
    for i in range(k):
        for j in range(k):
            a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            faces += [(a, b, c), (a, c, d)] if (i + j) % 2 == 0 else [(a, b, d), (b, c, d)]
    return v, np.array(faces)


def test_flips_bring_valences_towards_six_and_keep_the_mesh_valid():
    v, f = _union_jack(8)
    v[:, 2] = 0.01 * np.sin(v[:, 0]) * np.cos(v[:, 1])  # not exactly flat
    out, flips = flip_edges(v, f)
    assert flips > 0
    edges, counts = edge_face_counts(out)
    assert counts.max() == 2 and len(edges) == len(edge_face_counts(f)[0])
    p = v[out]
    assert np.all(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2] > 0)

    def deviation(faces):
        e, c = edge_face_counts(faces)
        val = np.bincount(e.ravel(), minlength=len(v))
        border = np.zeros(len(v), dtype=bool)
        border[e[c == 1].ravel()] = True
        return np.sum((val - np.where(border, 4, 6)) ** 2)

    assert deviation(out) < 0.5 * deviation(f)
    again, more = flip_edges(v, f)
    np.testing.assert_array_equal(again, out)  # deterministic
    assert more == flips


def test_border_test_far_from_the_cloud():
    """Points beyond the grid search (MAX_SHELL cells) are answered through the k-d tree."""
    from splineviz.pointcloud.advancing_front import AdvancingFront
    from splineviz.pointcloud.guidance import guidance_field
    from splineviz.pointcloud.projection import Projector

    rng = np.random.default_rng(9)
    pts = np.c_[rng.uniform(-2, 2, (1500, 2)), np.zeros(1500)]
    proj = Projector(pts)
    front = AdvancingFront(proj, guidance_field(proj, edge_length=0.2))
    xs = np.array([[0.0, 0.0, 0.0], [40.0, 0.0, 0.0], [0.0, 1.9, 0.0], [0.0, 2.6, 0.0]])
    up = np.array([[0.0, 0.0, 1.0]])
    n = up if proj.normals[0, 2] > 0 else -up
    np.testing.assert_array_equal(front._outside_flags(xs, n, False), [False, True, False, True])


def test_relaxation_makes_no_needles(monkeypatch):
    """A rough surface (here a projector that pulls points onto lines farther apart than
    the edges) folds relaxed triangles into needles unless those moves are undone."""
    from splineviz.pointcloud import relaxation
    from splineviz.pointcloud.quality import radius_ratios

    class Snap:
        def project_with_normals(self, points, normals=None):
            p = np.array(points, dtype=float)
            line = np.round(p[:, 0] / 0.25) * 0.25
            p[:, 0] = line + 0.05 * (p[:, 0] - line)  # pulled 95 % of the way to a line
            return p, np.tile([0.0, 0.0, 1.0], (len(p), 1))

    rng = np.random.default_rng(3)
    x, y = np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 1, 9))
    v = np.c_[x.ravel(), y.ravel(), np.zeros(81)]
    inner = (v[:, 0] > 0) & (v[:, 0] < 1) & (v[:, 1] > 0) & (v[:, 1] < 1)
    v[inner, :2] += rng.uniform(-0.03, 0.03, (inner.sum(), 2))
    q = np.arange(81).reshape(9, 9)[:-1, :-1].ravel()
    f = np.r_[np.c_[q, q + 1, q + 10], np.c_[q, q + 10, q + 9]]
    before = radius_ratios(v, f).min()
    after = radius_ratios(relaxation.relax(v, f, Snap()), f).min()
    assert after >= min(relaxation.RELAX_MIN_RATIO, before)
    monkeypatch.setattr(relaxation, "RELAX_MIN_RATIO", 0.0)
    assert radius_ratios(relaxation.relax(v, f, Snap()), f).min() < 0.05  # the guard's work
