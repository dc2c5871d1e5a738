"""sv.mesh_quality: radius ratio, valences, border/non-manifold edges, distances."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.pointcloud.quality import (
    MeshQualityError,
    distance_to_mesh,
    point_to_triangle_distance,
    radius_ratios,
)


def _hex_patch(rings):
    """Regular triangulation of a hexagon with ``rings`` rings: equilateral, interior valence 6."""
    pts, index = [], {}
    for i in range(-rings, rings + 1):
        for j in range(-rings, rings + 1):
            if abs(i + j) <= rings:
                index[(i, j)] = len(pts)
                pts.append((i + 0.5 * j, np.sqrt(0.75) * j, 0.0))
    faces = []
    for (i, j), a in index.items():
        for b, c in (((i + 1, j), (i, j + 1)), ((i + 1, j), (i + 1, j - 1))):
            if b in index and c in index:
                tri = (a, index[b], index[c])
                faces.append(tri if c[1] > j or b[1] > j else (a, index[c], index[b]))
    return np.array(pts), np.array(faces)


def test_radius_ratio_values():
    eq = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(0.75), 0]])
    right = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    flat = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    f = np.array([[0, 1, 2]])
    assert radius_ratios(eq, f)[0] == pytest.approx(1.0)
    # right isosceles, legs 1: r_in = (2 - sqrt 2)/2, r_circ = sqrt(2)/2
    assert radius_ratios(right, f)[0] == pytest.approx(2 * (2 - np.sqrt(2)) / 2 / (np.sqrt(2) / 2))
    assert radius_ratios(flat, f)[0] == pytest.approx(0.0)


def test_regular_patch_counts():
    v, f = _hex_patch(3)
    q = sv.mesh_quality((v, f))
    assert q["radius_ratio_mean"] == pytest.approx(1.0)
    assert q["valence6_fraction"] == 1.0  # every interior vertex of the hexagon
    assert q["boundary_edges"] == 6 * 3  # hexagon perimeter
    assert q["non_manifold_edges"] == 0
    assert q["n_faces"] == 6 * 3 * 3 and q["n_vertices"] == 37
    # a third triangle on one edge makes it non-manifold
    extra = np.vstack([v, [[0.5, 0.3, 1.0]]])
    f2 = np.vstack([f, [[f[0, 0], f[0, 1], len(v)]]])
    assert sv.mesh_quality((extra, f2))["non_manifold_edges"] == 1


def test_point_triangle_distance_matches_brute_force():
    rng = np.random.default_rng(0)
    tri = rng.normal(size=(400, 3, 3))
    pts = rng.normal(size=(400, 3)) * 2
    d = point_to_triangle_distance(pts, tri)
    # brute force: minimum over a dense barycentric grid (upper bound, close to exact)
    s, t = np.meshgrid(np.linspace(0, 1, 121), np.linspace(0, 1, 121))
    keep = s + t <= 1
    w = np.stack([1 - s[keep] - t[keep], s[keep], t[keep]], 1)
    grid = np.einsum("gk,pkc->pgc", w, tri)
    brute = np.linalg.norm(grid - pts[:, None], axis=2).min(axis=1)
    assert np.all(d <= brute + 1e-12)
    assert np.allclose(d, brute, atol=2e-2 * np.ptp(tri))


def test_hausdorff_and_rms_of_offset_points():
    v, f = _hex_patch(4)
    rng = np.random.default_rng(1)
    xy = rng.uniform(-1.5, 1.5, (500, 2))
    pts = np.c_[xy, np.full(500, 0.05)]
    q = sv.mesh_quality((v, f), reference=pts)
    assert q["rms_distance"] == pytest.approx(0.05)
    # the mesh (radius 4) reaches far beyond the points: Hausdorff is mesh-to-points
    assert q["hausdorff"] > 2.0
    assert q["hausdorff"] == q["hausdorff_mesh_to_points"]
    assert q["hausdorff_points_to_mesh"] == pytest.approx(0.05)
    assert distance_to_mesh(pts, v, f).max() == pytest.approx(0.05)


def test_pyvista_input_and_errors():
    import pyvista as pv

    mesh = pv.Sphere(theta_resolution=24, phi_resolution=24)
    q = sv.mesh_quality(mesh)
    assert q["boundary_edges"] == 0 and q["non_manifold_edges"] == 0
    assert 0.5 < q["radius_ratio_mean"] < 1.0
    with pytest.raises(MeshQualityError):
        sv.mesh_quality((np.zeros((3, 3)), np.zeros((0, 3), dtype=int)))
    with pytest.raises(MeshQualityError):
        sv.mesh_quality((np.zeros((3, 3)), np.array([[0, 1, 5]])))
    with pytest.raises(MeshQualityError):
        sv.mesh_quality("not a mesh")


def test_edge_keys_give_the_unique_rows():
    """Edges found by one int64 key per edge (faster on millions of edges) are the sorted
    unique rows, with their counts; the surface fit's edge ids likewise."""
    from splineviz.pointcloud.quality import edge_face_counts
    from splineviz.pointcloud.surface_fit import _edges

    faces = np.random.default_rng(0).integers(0, 500, size=(3000, 3))
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    want, inverse, counts = np.unique(e, axis=0, return_inverse=True, return_counts=True)
    edges, got = edge_face_counts(faces)
    assert np.array_equal(edges, want) and np.array_equal(got, counts)
    edges, per_face = _edges(faces)
    assert np.array_equal(edges, want)
    assert np.array_equal(per_face, inverse.reshape(3, -1).T)
