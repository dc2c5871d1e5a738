"""``Scene._repr_png_`` and ``scene.show()``: the exact picture, as render_scene makes it."""

import io
import json
import urllib.request

import numpy as np
import pytest

from splineviz.core.camera import Camera
from splineviz.model import Scene
from splineviz.model.opening import default_scene
from splineviz.notebook import Picture, show
from splineviz.render.scene_view import render_scene


def _decode(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)))


def test_scene_repr_png_is_render_scene():
    scene = default_scene()
    png = scene._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert np.array_equal(_decode(png), render_scene(scene, (640, 480)))


def test_show_with_camera_leaves_the_scene_camera():
    scene = default_scene()
    pose = scene.camera.pose()
    cam = Camera((4.0, -1.0, 2.0), (0.0, 0.0, 0.0), view_up=(0, 0, 1), view_angle=30.0)
    pic = scene.show(size=(160, 120), camera=cam)
    assert isinstance(pic, Picture) and pic.size == (160, 120)
    assert scene.camera.pose() == pose
    other = default_scene()
    other.camera.update(position=cam.position, focal_point=cam.focal_point,
                        view_up=cam.view_up, view_angle=cam.view_angle)
    assert np.array_equal(pic.image, render_scene(other, (160, 120)))
    assert not np.array_equal(pic.image, render_scene(scene, (160, 120)))


def test_a_new_scene_is_framed_not_blank():
    from splineviz.model.opening import default_volume

    scene = Scene()
    vol, iso = default_volume()
    scene.add_volume(vol, "ML", isovalue=iso)
    pic = show(scene, size=(120, 90))
    background = pic.image[0, 0]
    assert (np.abs(pic.image.astype(int) - background).max(axis=2) > 30).mean() > 0.1


def test_show_interactive_serves_the_page_and_reports_the_camera():
    scene = default_scene()
    view = scene.show(size=(160, 120), interactive=True)
    try:
        assert view.url.startswith("http://127.0.0.1:")
        assert f'src="{view.url}"' in view._repr_html_()
        with urllib.request.urlopen(view.url, timeout=60) as page:
            assert b"splineviz" in page.read()
        with urllib.request.urlopen(view.url + "state", timeout=120) as reply:
            state = json.loads(reply.read())
        assert state["camera"]["position"] == pytest.approx(scene.camera.position)
        assert state["isovalue"] == scene.isosurfaces[0].isovalue
    finally:
        view.stop()
