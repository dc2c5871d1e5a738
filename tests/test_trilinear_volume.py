"""The data model and the trilinear baseline spline."""

import numpy as np
import pytest

import splineviz as sv

RNG = np.random.default_rng(11)


def test_volume_geometry_and_validation():
    v = sv.Volume(np.arange(24).reshape(2, 3, 4), spacing=(1, 2, 3), origin=(-1, 0, 1))
    assert v.data.dtype == np.float32 and v.shape == (2, 3, 4)
    assert v.bounds == ((-1, 0), (0, 4), (1, 10))
    p = v.index_to_world([[1, 2, 3]])
    assert np.allclose(p, [[0, 4, 10]]) and np.allclose(v.world_to_index(p), [[1, 2, 3]])
    for bad in (np.zeros((3, 3)), np.zeros((0, 2, 2)), np.array([[["a"]]])):
        with pytest.raises(sv.VolumeError):
            sv.Volume(bad)
    with pytest.raises(sv.VolumeError):
        sv.Volume(np.zeros((2, 2, 2)), spacing=(1, 0, 1))
    with pytest.raises(sv.VolumeError):
        _ = sv.Volume(np.full((2, 2, 2), np.nan)).finite_range


def test_pointcloud_validation():
    pc = sv.PointCloud(np.zeros((3, 3)), normals=np.ones((3, 3)))
    assert len(pc) == 3 and pc.diagonal == 0
    with pytest.raises(sv.PointCloudError):
        sv.PointCloud(np.zeros((3, 2)))
    with pytest.raises(sv.PointCloudError):
        sv.PointCloud([[0, 0, np.nan]])
    with pytest.raises(sv.PointCloudError):
        sv.PointCloud(np.zeros((3, 3)), normals=np.zeros((2, 3)))


def test_trilinear_reproduces_trilinear_functions():
    def f(x, y, z):
        return 1 + 2 * x - y + 0.5 * z + x * y - 2 * x * y * z

    vol = sv.Volume.from_function(f, (5, 6, 7), ((0, 1), (0, 2.5), (-1, 2)))
    s = sv.build_spline(vol, model="trilinear")
    p = RNG.uniform([0, 0, -1], [1, 2.5, 2], size=(500, 3))
    x, y, z = p.T
    assert np.allclose(s.evaluate(p), f(x, y, z), atol=1e-5)
    grad = np.stack([2 + y - 2 * y * z, -1 + x - 2 * x * z, 0.5 - 2 * x * y], axis=1)
    assert np.allclose(s.gradient(p), grad, atol=1e-4)
    h = s.hessian(p)
    assert np.allclose(h[:, 0, 1], 1 - 2 * z, atol=1e-4) and np.allclose(h[:, 0, 0], 0)
    # interpolates the samples
    g = np.stack(np.meshgrid(*[np.arange(n) for n in vol.shape], indexing="ij"), -1).reshape(-1, 3)
    assert np.allclose(s.evaluate(vol.index_to_world(g)), vol.data.ravel(), atol=1e-6)


def test_build_spline_rejects_unknown_model():
    with pytest.raises(ValueError, match="unknown spline model"):
        sv.build_spline(np.zeros((3, 3, 3)), model="nurbs")
