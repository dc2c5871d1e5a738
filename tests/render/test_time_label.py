"""The time drawn in the view (issue 27): "t = 0.75 s (step 4/6)" in the upper-left corner
of pictures of a scene with a time-varying volume, off by the view's ``show_time`` (kept by
sessions only when off); scenes without one draw as before."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from splineviz.cli import main
from splineviz.io.time_series import open_time_series
from splineviz.model.scene import Scene
from splineviz.model.session import load_scene, save_scene
from splineviz.render.scene_view import SceneView, render_scene, time_label

nib = pytest.importorskip("nibabel")

SIZE = (160, 120)


@pytest.fixture
def nifti4d(tmp_path):
    shape = (20, 18, 16)
    x, y, z = np.meshgrid(*(np.linspace(-1, 1, k) for k in shape), indexing="ij")
    r = np.sqrt(x**2 + y**2 + z**2)
    data = np.stack([((1.0 + 0.25 * t) * (1 - r) * 120 + 40).clip(0, 255).astype(np.uint8)
                     for t in range(6)], -1)
    img = nib.Nifti1Image(data, np.eye(4))
    img.header.set_xyzt_units("mm", "sec")
    img.header["pixdim"][4] = 0.25
    path = tmp_path / "run.nii.gz"
    nib.save(img, path)
    return path, data


def _scene(path, step=3):
    scene = Scene()
    scene.add_time_series(open_time_series(path), step=step, path=str(path))
    scene.frame(view="isometric")
    scene.isosurfaces[0].update(model="trilinear")
    scene.view.show_scale = False
    return scene


def test_label_names_time_and_step(nifti4d):
    scene = _scene(nifti4d[0])
    assert time_label(scene) == "t = 0.75 s (step 4/6)"
    scene.set_step(-1)
    assert time_label(scene) == "t = 1.25 s (step 6/6)"


def test_label_drawn_in_the_corner_only_and_turned_off(nifti4d):
    path, data = nifti4d
    scene = _scene(path)
    shown = render_scene(scene, SIZE)
    scene.view.show_time = False
    bare = render_scene(scene, SIZE)
    diff = np.abs(shown.astype(int) - bare.astype(int)).max(axis=2) > 0
    rows, cols = np.nonzero(diff)
    assert len(rows) > 20  # the text is there
    # all of it at the top, starting at the left
    assert rows.max() < SIZE[1] // 4 and cols.min() < SIZE[0] // 10
    # without the label, the picture of the step alone (a 3-D volume) is the same
    alone = Scene()
    alone.add_volume(scene.volumes[0].series.step(3))
    alone.camera.update(scene.camera.model_dump())
    alone.isosurfaces[0].update(isovalue=scene.isosurfaces[0].isovalue, model="trilinear")
    alone.view.show_scale = False
    np.testing.assert_array_equal(bare, render_scene(alone, SIZE))


def test_label_follows_the_step_and_the_volume(nifti4d):
    scene = _scene(nifti4d[0])
    plotter = __import__("pyvista").Plotter(off_screen=True, window_size=SIZE)
    view = SceneView(scene, plotter)
    try:
        label = view._time_label
        assert label.GetText(label.UpperLeft) == "t = 0.75 s (step 4/6)"
        scene.set_step(1)
        assert label.GetText(label.UpperLeft) == "t = 0.25 s (step 2/6)"
        scene.remove(scene.volumes[0])
        assert not label.GetVisibility()
    finally:
        view.close()
        plotter.close()


def test_scene_without_time_makes_no_label(nifti4d):
    path, data = nifti4d
    scene = Scene()
    scene.add_volume(open_time_series(path).step(0))
    plotter = __import__("pyvista").Plotter(off_screen=True, window_size=SIZE)
    view = SceneView(scene, plotter)
    try:
        assert view._time_label is None
    finally:
        view.close()
        plotter.close()


def test_session_keeps_show_time_only_when_off(nifti4d, tmp_path):
    scene = _scene(nifti4d[0])
    on = save_scene(scene, tmp_path / "on.svs")
    assert "show_time" not in json.loads(on.read_text())["views"][0]
    scene.view.show_time = False
    off = save_scene(scene, tmp_path / "off.svs")
    assert json.loads(off.read_text())["views"][0]["show_time"] is False
    assert load_scene(off).view.show_time is False


def test_render_cli_draws_the_label_when_asked(nifti4d, tmp_path):
    path, _ = nifti4d
    args = ["render", str(path), "--time", "2", "--size", "96x72", "--model", "trilinear"]
    assert main([*args, "-o", str(tmp_path / "bare.png")]) == 0
    assert main([*args, "--time-label", "-o", str(tmp_path / "label.png")]) == 0
    bare, label = (np.asarray(Image.open(tmp_path / n)) for n in ("bare.png", "label.png"))
    assert not np.array_equal(bare, label)
