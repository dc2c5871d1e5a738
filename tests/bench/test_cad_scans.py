"""The pieces of ``splineviz bench cad-scans`` (issue 31, part 3): the surface measures on
surfaces whose answers are known, the range-scan simulation, and (``-m bench``) a tiny run."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

pytest.importorskip("open3d")
pytest.importorskip("pymeshlab")

from splineviz.bench.cad_scans import (  # noqa: E402
    _box,
    cad_shape,
    fine_truth,
    range_scans,
    run_bench,
    seen_samples,
)
from splineviz.pointcloud.quality import (  # noqa: E402
    distance_to_mesh,
    mesh_quality,
    point_to_triangle_distance,
    surface_agreement,
)


def _unit_box():
    return fine_truth(*_box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]), 0.1)


def test_identical_surfaces_agree_perfectly():
    v, f = _unit_box()
    m = surface_agreement(v, f, v, f, threshold=0.01, n_samples=5000)
    assert m["chamfer"] < 1e-12 and m["hausdorff"] < 1e-12
    assert m["fscore"] == 1.0 and m["normal_consistency"] == pytest.approx(1.0)


def test_shifted_surface_is_measured_by_its_shift():
    v, f = _unit_box()
    shifted = v + [0.0, 0.0, 0.02]
    m = surface_agreement(shifted, f, v, f, threshold=0.01, n_samples=20000)
    # the top and bottom faces, a third of each surface, are 0.02 from the truth's; the side
    # faces overlap the truth but for a strip 0.02 wide; the farthest point is 0.02 away
    assert m["hausdorff"] == pytest.approx(0.02, rel=1e-6)
    assert 0.2 * 0.02 < m["chamfer"] < 0.45 * 0.02
    # the top and bottom faces (a third of the area) are farther than the threshold
    assert m["precision"] == pytest.approx(2 / 3, abs=0.02)
    assert m["fscore"] < 0.7
    # the faces stay parallel to the truth's but for the strips, where the nearest true face
    # is the perpendicular top or bottom (a few % of the area)
    assert 0.95 < m["normal_consistency"] < 0.995


def test_a_missing_face_costs_recall_not_precision():
    v, f = _unit_box()
    n = (np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]))
    top = (n[:, 2] > 0) & (v[f].mean(axis=1)[:, 2] > 1 - 1e-9)
    m = surface_agreement(v, f[~top], v, f, threshold=0.01, n_samples=20000)
    assert m["precision"] == 1.0
    assert m["recall"] == pytest.approx(5 / 6, abs=0.02)
    assert m["hausdorff"] == pytest.approx(0.5, abs=0.02)  # the top face's middle


def test_distance_to_mesh_names_the_nearest_triangle():
    v, f = _unit_box()
    rng = np.random.default_rng(4)
    pts = rng.uniform(-0.5, 1.5, size=(2000, 3))
    d, near = distance_to_mesh(pts, v, f, return_faces=True)
    np.testing.assert_allclose(point_to_triangle_distance(pts, v[f[near]]), d, atol=1e-12)
    # outside the box the distance to the box is known in closed form
    outside = np.linalg.norm(np.maximum(np.maximum(-pts, pts - 1), 0), axis=1)
    out = outside > 0
    np.testing.assert_allclose(d[out], outside[out], atol=1e-9)


def _stacked_boxes():
    """Box [0, 1]^3 with a smaller box through its top face, as two closed meshes: the top
    face's middle and the small box's bottom are inside the part."""
    a = fine_truth(*_box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]), 0.1)
    b = fine_truth(*_box([0.25, 0.25, 0.8], [0.75, 0.75, 1.5]), 0.1)
    return np.vstack([a[0], b[0]]), np.vstack([a[1], b[1] + len(a[0])])


def test_scans_see_only_the_visible_surface():
    v, f = _stacked_boxes()
    pts, eyes = range_scans(v, f, 6000, 0.0)
    assert 4000 < len(pts) < 8000
    # noise-free scans lie on the surface, and no ray reached the buried faces
    assert distance_to_mesh(pts, v, f).max() < 1e-5
    assert cKDTree(pts).query([0.5, 0.5, 1.0])[0] > 0.19
    # every scanner saw its points in front of it
    assert len(np.unique(eyes, axis=0)) == 4
    # the same rule for samples: the buried middle of the top face is not seen, its rim is
    samples = np.array([[0.5, 0.5, 1.0], [0.1, 0.1, 1.0], [0.5, 0.5, 0.8]])
    _, tri = distance_to_mesh(samples, v, f, return_faces=True)
    assert seen_samples(v, f, samples, tri).tolist() == [False, True, False]


def test_csg_shapes_are_closed():
    for name in ("box-cylinder", "bracket"):
        q = mesh_quality(cad_shape(name))
        assert q["boundary_edges"] == 0 and q["non_manifold_edges"] == 0, name


def test_noise_moves_points_off_the_surface_by_its_level():
    v, f = _unit_box()
    diag = np.sqrt(3.0)
    pts, _ = range_scans(v, f, 6000, 0.005)
    d = distance_to_mesh(pts, v, f)
    # along the ray, so at most the sigma off the surface on average, about 0.8 sigma
    assert 0.3 * 0.005 * diag < np.sqrt(np.mean(d**2)) < 1.5 * 0.005 * diag


@pytest.mark.bench
def test_bench_cad_scans_tiny():
    lines = []

    class Out:
        def write(self, s):
            lines.append(s)

    rows = run_bench(shapes=("box-cylinder",), noises=(0.0025,), n_points=8000, out=Out())
    table = "".join(lines)
    print(table)
    assert [r["method"] for r in rows] == ["ours", "poisson8"]
    assert all("error" not in r for r in rows), rows
    for r in rows:
        assert 0 < r["chamfer_pct"] < 1 and 0.5 < r["fscore"] <= 1
        assert 0.8 < r["normal_consistency"] <= 1 and r["time_s"] > 0 and r["peak_rss"] > 0
    assert "targets held" in table and f"{rows[0]['chamfer_pct']:.4f}" in table
