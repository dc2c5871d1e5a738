"""The spline isosurface in a VTK scene: depth compositing, clipping, translucency, export."""

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

import splineviz as sv  # noqa: E402
from splineviz.render.isosurface import IsosurfaceLayer, LayerError  # noqa: E402
from splineviz.render.quad import pack_depth, unpack_depth, view_normals  # noqa: E402
from splineviz.render.scene import SceneError, SplineScene, offscreen_screenshot  # noqa: E402

W, H = 160, 120
R = 0.8  # radius of the sphere isosurface


def sphere_volume(n=21):
    x = np.linspace(-1, 1, n)
    return sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2), spacing=2 / (n - 1),
                     origin=(-1, -1, -1))


def make_scene(opacity=1.0, model="trilinear", size=(W, H)):
    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.set_background("black")
    scene = SplineScene(pl)
    layer = IsosurfaceLayer(sphere_volume(), model=model, isovalue=R**2, color=(0.9, 0.9, 0.9),
                            opacity=opacity)
    scene.add_layer(layer)
    # looking along +y; image right = world +x, image up = world +z
    pl.camera_position = [(0.3, -5, 0.4), (0, 0, 0), (0, 0, 1)]
    pl.camera_set = True
    return pl, scene, layer


def shot(pl):
    pl.render_window.Render()  # pyvista's render() is a no-op before show()
    return np.asarray(pl.screenshot(return_img=True)).astype(int)


def test_depth_packing_round_trip():
    d = np.array([[0.0, 1.0, 0.5, 1e-7], [0.999999, 0.123456789, 0.75, 0.3]])
    back = unpack_depth(pack_depth(d))
    assert np.abs(back - d).max() <= 0.5 / (2**24 - 1) + 1e-12
    # 24 bits: neighbouring codes differ
    assert unpack_depth(pack_depth(np.array([0.5])))[0] != unpack_depth(
        pack_depth(np.array([0.5 + 1.5 / 2**24])))[0]


def test_view_normals_use_camera_basis():
    cam = sv.Camera((0, -5, 0), (0, 0, 0), view_up=(0, 0, 1))
    n = np.array([[[1.0, 0, 0], [0, -1.0, 0], [0, 0, 1.0]]])
    out = view_normals(n, np.ones((1, 3), bool), cam.basis())
    # right = +x, up = +z, towards the eye = -y
    assert out[0, 0, :3].tolist() == [255, 128, 128]
    assert out[0, 1, :3].tolist() == [128, 128, 255]
    assert out[0, 2, :3].tolist() == [128, 255, 128]
    assert out[0, :, 3].tolist() == [255, 255, 255]


def test_mesh_inside_surface_is_hidden_and_shows_through_a_cut():
    pl, scene, layer = make_scene()
    scene.add_mesh("ball", pv.Sphere(radius=0.5, theta_resolution=40, phi_resolution=40),
                   color="red", lighting=False)
    try:
        img = shot(pl)
        red = (img[..., 0] > 200) & (img[..., 1] < 60) & (img[..., 2] < 60)
        lit = img.sum(axis=2) > 60
        assert lit.mean() > 0.2            # the sphere surface is drawn
        assert red.sum() == 0              # and hides the ball inside it
        # keep x <= 0.1: the surface opens on the right, where the ball shows
        scene.set_clip_planes([((0.1, 0, 0), (-1, 0, 0))])
        img = shot(pl)
        frame = scene.shown_frame(layer).frame
        assert np.nanmax(frame.position[..., 0]) <= 0.1 + 1e-6
        red = (img[..., 0] > 200) & (img[..., 1] < 60) & (img[..., 2] < 60)
        assert red.sum() > 200
        cols = np.nonzero(red)[1]
        # red only right of the cut (the projection of x = 0.1 is near the centre column)
        assert cols.min() > W // 2 - 4
        # where the surface is hit behind a red pixel, the hit is on the far (inner back)
        # wall, behind the ball (y > 0.4); the near wall is cut away there
        both = red & frame.hit
        assert np.all(frame.position[both][:, 1] > 0.4)
    finally:
        pl.close()


def test_depth_compositing_with_a_tilted_plane_is_exact_per_pixel():
    pl, scene, layer = make_scene()
    # the plane x + y = 0 cuts through the sphere: in front of it where x + y > 0 on it
    plane = pv.Plane(center=(0, 0, 0), direction=(1, 1, 0), i_size=3, j_size=3,
                     i_resolution=1, j_resolution=1)
    scene.add_mesh("plane", plane, color="lime", lighting=False)
    try:
        img = shot(pl)
        frame = scene.shown_frame(layer).frame
        green = (img[..., 1] > 200) & (img[..., 0] < 60) & (img[..., 2] < 60)
        p = frame.position
        hit = frame.hit
        behind = hit & (p[..., 0] + p[..., 1] > 0)   # surface point behind the plane
        front = hit & (p[..., 0] + p[..., 1] < 0)
        assert behind.sum() > 300 and front.sum() > 300
        # per pixel: plane where the surface is behind it, surface where it is in front;
        # a band of one or two pixels along the intersection curve may differ
        assert (green & behind).sum() / behind.sum() > 0.97
        assert (green & front).sum() / front.sum() < 0.03
    finally:
        pl.close()


def test_translucent_surface_blends_over_a_mesh():
    pl, scene, layer = make_scene(opacity=0.4)
    scene.add_mesh("ball", pv.Sphere(radius=0.5, theta_resolution=40, phi_resolution=40),
                   color="red", lighting=False)
    try:
        img = shot(pl)
        frame = scene.shown_frame(layer).frame
        centre = img[H // 2 - 3:H // 2 + 3, W // 2 - 3:W // 2 + 3].reshape(-1, 3).mean(0)
        assert frame.hit[H // 2, W // 2]
        # red shows through (red channel well above the others) but is tinted by the surface
        assert centre[0] > 150 and 40 < centre[1] < 200 and 40 < centre[2] < 200
        # near the rim there is no ball behind: grey surface over a black background
        r, c = np.nonzero(frame.hit)
        rim = img[r[np.argmin(c)], c.min() + 2]
        assert abs(rim[0] - rim[1]) < 20
        layer.set_opacity(1.0)
        img = shot(pl)
        assert ((img[..., 0] > 200) & (img[..., 1] < 60)).sum() == 0
    finally:
        pl.close()


def test_isovalue_change_changes_picture_and_frame():
    pl, scene, layer = make_scene()
    try:
        a = shot(pl)
        layer.set_isovalue(0.3)
        b = shot(pl)
        f = scene.shown_frame(layer)
        assert f.state == layer.state and f.final
        radius = np.linalg.norm(f.frame.position[f.frame.hit], axis=1)
        assert np.abs(radius - np.sqrt(0.3)).max() < 0.05  # trilinear model error only
        assert np.abs(a - b).sum(axis=2).astype(bool).mean() > 0.05
    finally:
        pl.close()


@pytest.mark.parametrize("model", ["super-quadratic", "cubic-c1", "to-quadratic"])
def test_each_model_renders(model):
    pl, scene, layer = make_scene(model=model, size=(48, 36))
    try:
        img = shot(pl)
        f = scene.shown_frame(layer)
        assert f.frame.hit.mean() > 0.2 and (img.sum(axis=2) > 60).mean() > 0.2
        radius = np.linalg.norm(f.frame.position[f.frame.hit], axis=1)
        assert np.abs(radius - R).max() < 0.03
    finally:
        pl.close()


def test_progressive_mode_previews_then_refines(monkeypatch):
    import splineviz.render.scene as scene_module

    # a budget no frame can meet: the preview is at the smallest scale
    monkeypatch.setattr(scene_module, "PREVIEW_BUDGET_S", 1e-9)
    pl, scene, layer = make_scene()
    scene.progressive = True
    calls = []
    scene.request_refine = lambda: calls.append(1)
    try:
        # the casters are built by the refinement (a worker in the GUI), never by a preview
        shot(pl)
        assert calls and scene.shown_frame(layer) is None and scene.needs_refine()
        assert scene.apply(scene.refine())
        shot(pl)
        assert scene.shown_frame(layer).final and not scene.needs_refine()
        # a camera move shows a preview at the smallest scale, then refines
        pl.camera.Azimuth(10)
        calls.clear()
        shot(pl)
        assert calls and not scene.shown_frame(layer).final
        assert scene.shown_frame(layer).frame.hit.shape[1] < W // 2
        assert scene.needs_refine()
        results = scene.refine()
        assert scene.apply(results)
        shot(pl)
        assert scene.shown_frame(layer).final and not scene.needs_refine()
        # a stale result (layer changed meanwhile) is not shown
        layer.set_isovalue(0.5)
        assert not scene.apply(results)
    finally:
        pl.close()


def test_offscreen_screenshot_size_and_transparency(tmp_path):
    pl, scene, layer = make_scene()
    try:
        shot(pl)
        out = tmp_path / "shot.png"
        img = offscreen_screenshot(scene, out, size=(123, 77), transparent_background=True)
        assert img.shape == (77, 123, 4)
        assert img[0, 0, 3] == 0 and img[77 // 2, 123 // 2, 3] == 255
        from PIL import Image

        with Image.open(out) as im:
            assert im.size == (123, 77)
        with pytest.raises(SceneError):
            offscreen_screenshot(scene, size=(0, 10))
    finally:
        pl.close()


def test_layer_rejects_bad_settings():
    layer = IsosurfaceLayer(sphere_volume(5))
    with pytest.raises(LayerError):
        layer.set_opacity(0)
    with pytest.raises(LayerError):
        layer.set_model("quartic")
    with pytest.raises(LayerError):
        layer.set_isovalue(float("nan"))
    with pytest.raises(LayerError):
        layer.set_color((2, 0, 0))


def test_rerenders_on_window_size_and_data_change():
    pl, scene, layer = make_scene()
    try:
        shot(pl)
        assert scene.shown_frame(layer).frame.hit.shape == (H, W)
        pl.window_size = (100, 80)
        shot(pl)
        assert scene.shown_frame(layer).frame.hit.shape == (80, 100)
        # new data (as after smoothing): values halved, so the same isovalue lies further out
        vol = layer.volume
        layer.set_volume(sv.Volume(vol.data * 0.5, spacing=vol.spacing, origin=vol.origin))
        shot(pl)
        f = scene.shown_frame(layer)
        assert f.state == layer.state
        r = np.linalg.norm(f.frame.position[f.frame.hit], axis=1)
        assert np.abs(r - np.sqrt(2) * R).max() < 0.05
    finally:
        pl.close()


def test_depth_buffer_holds_the_frames_depth_exactly():
    import vtk
    from vtk.util import numpy_support

    pl, scene, layer = make_scene()
    try:
        shot(pl)
        f = scene.shown_frame(layer).frame
        z = vtk.vtkFloatArray()
        pl.render_window.GetZbufferData(0, 0, W - 1, H - 1, z)
        zbuf = numpy_support.vtk_to_numpy(z).reshape(H, W)[::-1]  # rows top-down
        assert f.hit.sum() > 1000
        # 24-bit packing: agreement to a few codes of 2^-24 (the depth buffer is 24 bits too)
        assert np.abs(zbuf[f.hit] - f.depth[f.hit]).max() < 4.0 / 2**24
        assert np.all(zbuf[~f.hit] == 1.0)
    finally:
        pl.close()
