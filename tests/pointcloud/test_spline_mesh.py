"""Meshes of spline isosurfaces by the advancing front on the spline: vertices on s = iso,
well-shaped triangles, a closed surface where the isosurface is closed, exact cuts by clip
planes, normals from the spline."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.pointcloud.quality import edge_face_counts, radius_ratios, valences
from splineviz.pointcloud.spline_mesh import SplineMeshError, spline_front_mesh

# cubic-c1 of x^2 + y^2 + z^2 is that field + 3/4 (h = 1): an exact sphere of radius 10
SPHERE = sv.Volume.from_function(lambda x, y, z: x * x + y * y + z * z, (32, 32, 32),
                                 ((-15.5, 15.5),) * 3)
ISO = 100.75


@pytest.fixture(scope="module")
def spline():
    return sv.build_spline(SPHERE, "cubic-c1")


def area(v, f):
    tri = v[f]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                axis=1).sum()


@pytest.fixture(scope="module")
def closed(spline):
    return spline_front_mesh(spline, ISO)


def test_closed_sphere(spline, closed):
    v, f, n = closed
    lo, hi = SPHERE.finite_range
    assert np.abs(spline.evaluate(v) - ISO).max() < 1e-6 * (hi - lo)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 10.0, rtol=1e-8)
    edges, counts = edge_face_counts(f)
    assert (counts == 2).all()  # closed, manifold
    assert len(v) - len(edges) + len(f) == 2  # a sphere
    assert radius_ratios(v, f).mean() > 0.9
    assert np.mean(valences(len(v), edges) == 6) > 0.6
    # outward triangles (CCW seen from the normals), normals to lower values: inwards here
    tri = v[f]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(np.einsum("fc,fc->f", fn, tri.mean(axis=1)) < 0)
    np.testing.assert_allclose(n, -v / 10.0, atol=1e-6)


def test_clip_plane_cut_is_exact(spline, closed):
    origin, normal = np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.3, 1.0])
    v, f, _n = spline_front_mesh(spline, ISO, planes=[(origin, normal)])
    d = (v - origin) @ (normal / np.linalg.norm(normal))
    assert d.min() > -1e-9
    edges, counts = edge_face_counts(f)
    rim = np.unique(edges[counts == 1])
    assert len(rim) > 20
    np.testing.assert_allclose(d[rim], 0.0, atol=1e-9)  # border vertices on the plane ...
    np.testing.assert_allclose(np.linalg.norm(v[rim], axis=1), 10.0, rtol=1e-8)  # and sphere
    # the cap is the part of the sphere on the kept side, area 2 pi R h; the triangles are
    # chords of the sphere, short of its area by the same fraction as the closed mesh's
    dist = float(origin @ normal / np.linalg.norm(normal))
    cap = area(v, f) / (2 * np.pi * 10.0 * (10.0 - dist))
    whole = area(*closed[:2]) / (4 * np.pi * 100.0)
    assert 0.95 < whole < 1 and abs(cap - whole) < 0.005


def test_refusals(spline):
    with pytest.raises(SplineMeshError):
        spline_front_mesh(spline, 5000.0)  # not crossed
    with pytest.raises(SplineMeshError):
        spline_front_mesh(spline, ISO, rho=4.0)
    with pytest.raises(SplineMeshError):
        spline_front_mesh(spline, ISO, planes=[((0, 0, 12.0), (0, 0, 1))])


def test_export_mesh_by_the_front(tmp_path):
    from splineviz.model import Scene
    from splineviz.render.extract import export_mesh

    scene = Scene()
    vol = scene.add_volume(SPHERE, "sphere", isosurface=False)
    iso = scene.add_isosurface(vol, isovalue=ISO, model="cubic-c1")
    scene.add_clip_plane((0, 0, 0), (1, 0, 0), volume=vol)
    mesh = sv.read_mesh(export_mesh(scene, iso, tmp_path / "front.vtp", method="front"))
    pts = np.asarray(mesh.points)
    assert pts[:, 0].min() > -1e-6 and mesh.point_data.active_normals is not None
    np.testing.assert_allclose(np.linalg.norm(pts, axis=1), 10.0, rtol=1e-6)


def test_holes_the_front_leaves_are_closed(spline, closed):
    from splineviz.pointcloud.spline_mesh import border_loops, fill_holes

    v, f, _n = closed
    # open two holes: the faces around one vertex, and a strip of faces near another
    around = np.flatnonzero((f == 0).any(axis=1))
    near = np.argsort(np.linalg.norm(v[f].mean(axis=1) - v[f[-1, 0]], axis=1))[:9]
    holed = np.delete(f, np.r_[around, near], axis=0)
    assert len(border_loops(holed)) == 2
    v2, f2, n = fill_holes(spline, ISO, v, holed, lambda p: False)
    assert n == 2
    edges, counts = edge_face_counts(f2)
    assert (counts == 2).all()
    np.testing.assert_allclose(np.linalg.norm(v2, axis=1), 10.0, rtol=1e-8)
    # a border marked as real stays open
    assert fill_holes(spline, ISO, v, holed, lambda p: True)[2] == 0
