"""Camera conventions against VTK's own camera (rays per pixel and OpenGL window depth)."""

import numpy as np
import pytest

from splineviz.core.camera import Camera, CameraError, parse_size


def _vtk_camera(cam, clip):
    vtk = pytest.importorskip("vtkmodules.vtkRenderingCore")
    c = vtk.vtkCamera()
    c.SetPosition(*cam.position)
    c.SetFocalPoint(*cam.focal_point)
    c.SetViewUp(*cam.view_up)
    c.SetViewAngle(cam.view_angle)
    c.SetClippingRange(*clip)
    return c


def _matrix(vtk_cam, aspect):
    m = vtk_cam.GetCompositeProjectionTransformMatrix(aspect, -1, 1)
    return np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])


@pytest.mark.parametrize("pos,up", [((3.0, -7.0, 5.0), (0, 0, 1)), ((-4, 2, -9), (0.3, 1, 0.2))])
def test_pixel_rays_and_depth_match_vtk(pos, up):
    cam = Camera(pos, (0.5, 0.2, -0.3), view_up=up, view_angle=37.0)
    w, h = 64, 48
    clip = (2.0, 30.0)
    m = _matrix(_vtk_camera(cam, clip), w / h)
    origin, dirs = cam.rays((w, h))
    rng = np.random.default_rng(1)
    rows, cols = rng.integers(0, h, 20), rng.integers(0, w, 20)
    dist = rng.uniform(3, 25, 20)
    pts = origin + dist[:, None] * dirs[rows, cols]
    ph = np.c_[pts, np.ones(len(pts))] @ m.T
    ndc = ph[:, :3] / ph[:, 3:]
    # the ray of pixel (r, c) passes through the pixel centre in VTK's NDC (y up, rows down)
    np.testing.assert_allclose(ndc[:, 0], 2 * (cols + 0.5) / w - 1, atol=1e-9)
    np.testing.assert_allclose(ndc[:, 1], 1 - 2 * (rows + 0.5) / h, atol=1e-9)
    np.testing.assert_allclose(cam.window_depth(pts, clip), (ndc[:, 2] + 1) / 2, atol=1e-9)
    a, b = cam.projection_constants(clip)
    ze = (pts - origin) @ cam.basis()[2]
    np.testing.assert_allclose(a - b / ze, (ndc[:, 2] + 1) / 2, atol=1e-9)


def test_depth_is_zero_at_near_and_one_at_far():
    cam = Camera((0, 0, 10), (0, 0, 0), view_up=(0, 1, 0))
    d = cam.window_depth([[0, 0, 8], [0, 0, -10]], (2, 20))
    np.testing.assert_allclose(d, [0, 1], atol=1e-12)


def test_fit_clipping_range_encloses_box():
    cam = Camera((10, 0, 0), (0, 0, 0))
    near, far = cam.fit_clipping_range(((-1, 1), (-2, 2), (-3, 3)))
    assert near < 9 and far > 11 and near > 8.9 and far < 11.1
    cam2 = Camera((10, 0, 0), (0, 0, 0), clipping_range=(1, 2))
    assert cam2.fit_clipping_range(((-1, 1),) * 3) == (1.0, 2.0)


def test_rays_are_unit_and_rows_go_down():
    cam = Camera((0, 0, 10), (0, 0, 0), view_up=(0, 1, 0), view_angle=60)
    _, d = cam.rays("5x4")
    assert d.shape == (4, 5, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0)
    assert d[0, 2, 1] > 0 > d[-1, 2, 1]  # top row looks up
    assert d[2, 0, 0] < 0 < d[2, -1, 0]  # left column looks left (right = dop x up = +x)


@pytest.mark.parametrize(
    "kwargs",
    [dict(position=(0, 0, 0), focal_point=(0, 0, 0)),
     dict(position=(0, 0, 1), focal_point=(0, 0, 0), view_up=(0, 0, 1)),
     dict(position=(0, 0, 1), view_angle=0),
     dict(position=(0, 0, 1), clipping_range=(2, 1))],
)
def test_degenerate_cameras_raise(kwargs):
    with pytest.raises(CameraError):
        Camera(**kwargs)


@pytest.mark.parametrize("bad", ["12", "0x4", "axb", (3,)])
def test_parse_size_errors(bad):
    with pytest.raises(CameraError):
        parse_size(bad)
