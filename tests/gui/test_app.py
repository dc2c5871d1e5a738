"""The desktop app under Xvfb (pytest-xvfb): window, panels, workers, export, robustness."""

import os
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pv = pytest.importorskip("pyvista")

import splineviz as sv  # noqa: E402
from splineviz.gui.main_window import MainWindow  # noqa: E402
from splineviz.render.isosurface import MODEL_LABELS  # noqa: E402

SIZE = (160, 120)


def sphere_volume(n=15):
    x = np.linspace(-1, 1, n)
    return sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2), spacing=2 / (n - 1),
                     origin=(-1, -1, -1))


@pytest.fixture
def window(qtbot, tmp_path, monkeypatch):
    # recent files go to a private settings folder, not the user's
    from PySide6.QtCore import QSettings

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope, str(tmp_path))
    w = MainWindow(size=SIZE)
    qtbot.addWidget(w)
    w.resize(900, 560)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.wait_idle()
    w.close()


def view_image(w):
    w.plotter.render()
    return np.asarray(w.plotter.screenshot(return_img=True)).astype(int)


def shown(w, layer):
    return w.scene.shown_frame(layer)


def test_window_opens_on_default_data_and_isovalue_changes_picture(window):
    item = window.open_default()
    layer = item.layers[0]
    window.wait_for_refine()
    f = shown(window, layer)
    assert f.final and f.frame.hit.mean() > 0.05
    assert window.iso_panel.layer is layer
    a = view_image(window)
    lo, hi = window.iso_panel.histogram.range()
    window.iso_panel.spin.setValue(layer.isovalue + 0.15 * (hi - lo))
    assert layer.isovalue == pytest.approx(window.iso_panel.spin.value())
    window.wait_for_refine()
    b = view_image(window)
    assert shown(window, layer).state == layer.state
    assert np.abs(a - b).sum(axis=2).astype(bool).mean() > 0.02
    # the status bar reports frame time and active cells
    assert "ms" in window.fps_label.text() and "active" in window.cells_label.text()


def test_each_model_renders(window):
    item = window.add_volume(sphere_volume(), "sphere", iso=0.64, model="trilinear")
    layer = item.layers[0]
    for index, model in enumerate(MODEL_LABELS):
        window.iso_panel.model.setCurrentIndex(index)
        assert layer.model == model
        window.wait_for_refine()
        f = shown(window, layer)
        assert f.final and f.state == layer.state
        r = np.linalg.norm(f.frame.position[f.frame.hit], axis=1)
        assert f.frame.hit.mean() > 0.1 and np.abs(r - 0.8).max() < 0.05, model


def test_clip_plane_removes_surface_on_cut_side_and_shows_mesh_inside(window):
    item = window.add_volume(sphere_volume(), "sphere", iso=0.64, model="trilinear")
    layer = item.layers[0]
    cam = window.plotter.camera
    cam.position, cam.focal_point, cam.up = (0.2, -5, 0.3), (0, 0, 0), (0, 0, 1)
    window.add_mesh_item(pv.Sphere(radius=0.5, theta_resolution=30, phi_resolution=30),
                         "ball")
    rec = window.scene.props[window.items[-1].prop_name]
    rec.actor.GetProperty().SetColor(1, 0, 0)
    rec.actor.GetProperty().LightingOff()
    rec.actor.GetProperty().EdgeVisibilityOff()
    window.wait_for_refine()
    img = view_image(window)
    red = (img[..., 0] > 200) & (img[..., 1] < 60) & (img[..., 2] < 60)
    assert red.sum() == 0  # the ball is inside the surface
    plane = window.clip_panel.add_plane(origin=(0, 0, 0), normal=(-1, 0, 0))
    assert len(window.clip_panel.planes) == 1 and plane["widget"].GetEnabled()
    window.clip_panel.show_widgets.setChecked(False)  # its red outline is not the ball
    window.wait_for_refine()
    f = shown(window, layer).frame
    assert np.nanmax(f.position[..., 0]) <= 1e-6  # nothing on the cut side x > 0
    img = view_image(window)
    red = (img[..., 0] > 200) & (img[..., 1] < 60) & (img[..., 2] < 60)
    assert red.sum() > 50
    # the ball shows through the cut, never over the near wall of the kept half
    near_wall = f.hit & (np.nan_to_num(f.position[..., 1]) < 0)
    assert near_wall.sum() > 500 and not np.any(red & near_wall)
    window.clip_panel.list.setCurrentRow(0)
    window.clip_panel.flip_plane()
    window.wait_for_refine()
    f = shown(window, layer).frame
    assert np.nanmin(f.position[..., 0]) >= -1e-6
    window.clip_panel.remove_plane()
    assert window.scene.clip_planes == ()


def test_screenshot_export_has_requested_size(window, tmp_path):
    window.add_volume(sphere_volume(), "sphere", iso=0.64, model="trilinear")
    window.wait_for_refine()
    img = window.export_screenshot(tmp_path / "a.png", size=(211, 97), transparent=True)
    assert img.shape == (97, 211, 4)
    from PIL import Image

    with Image.open(tmp_path / "a.png") as im:
        assert im.size == (211, 97)
    assert img[0, 0, 3] == 0 and (img[..., 3] == 255).mean() > 0.01


def test_corrupt_file_gives_message_and_window_stays_usable(window, tmp_path):
    item = window.add_volume(sphere_volume(), "sphere", iso=0.64, model="trilinear")
    bad = tmp_path / "broken.vti"
    bad.write_bytes(b"<?xml version='1.0'?>\n<VTKFile type='ImageData'>garbage" + os.urandom(64))
    window.open_path(bad)
    window.wait_idle()
    assert window.last_error and "broken.vti" in window.last_error
    assert len(window.items) == 1 and window.isVisible()
    # still usable: the isovalue still drives the picture
    window.iso_panel.spin.setValue(0.3)
    window.wait_for_refine()
    f = shown(window, item.layers[0])
    assert f.state == item.layers[0].state and f.frame.hit.any()


def test_point_cloud_loads_and_session_round_trip(window, tmp_path, shared_data):
    window.open_path(shared_data / "points" / "kitten.xyz", block=True)
    pts = window.items[-1]
    assert pts.kind == "points" and len(pts.points.points) > 5000
    window.add_volume(sphere_volume(), "sphere", iso=0.64, model="trilinear")
    vol = tmp_path / "sphere.npy"
    np.save(vol, sphere_volume().data)
    window.clear()
    window.open_path(vol, block=True, iso=0.5)
    window.clip_panel.add_plane(origin=(7, 7, 7), normal=(0, 0, 1))
    window.items[0].layers[0].set_opacity(0.5)
    path = tmp_path / "s.svs"
    window.save_session(path)
    window.clear()
    assert not window.items
    window.open_path(path, block=True)
    assert window.last_error is None
    layer = window.items[0].layers[0]
    assert layer.isovalue == 0.5 and layer.opacity == 0.5
    assert window.scene.clip_planes[0][1] == (0.0, 0.0, 1.0)
    assert str(path.absolute()) in window.recent_files()


def test_smoothing_panel_feeds_the_spline_and_keeps_original(window):
    item = window.add_volume(sphere_volume(), "sphere", iso=0.64, model="trilinear")
    original = item.volume.data.copy()
    window.smooth_panel.sigma.setValue(1.5)   # live: runs after a short delay in a worker
    window.smooth_panel.apply()
    window.wait_idle()
    assert item.sigma == 1.5 and item.smoothed is not None
    assert np.array_equal(item.volume.data, original)
    assert item.layers[0].volume is item.smoothed
    window.smooth_panel.reset_button.click()
    window.wait_idle()
    assert item.smoothed is None and item.layers[0].volume is item.volume


def test_200_isovalue_changes_leave_memory_flat(window):
    window.resize(400, 300)  # the view shrinks to its minimum size: a fast loop
    item = window.add_volume(sphere_volume(21), "sphere", iso=0.5, model="trilinear")
    spin = window.iso_panel.spin

    def rss_mb():
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20

    values = 0.3 + 0.5 * (np.arange(220) % 20) / 20
    for v in values[:20]:  # warm up: kernels built, buffers allocated
        spin.setValue(float(v))
    before = rss_mb()
    for v in values[20:]:
        spin.setValue(float(v))
    after = rss_mb()
    assert item.layers[0].isovalue == pytest.approx(values[-1])
    print(f"RSS {before:.1f} -> {after:.1f} MiB over 200 isovalue changes")
    assert after - before < 25, f"RSS grew {after - before:.1f} MiB over 200 changes"


def test_cli_screenshot_opens_gui_and_saves(qapp, tmp_path):
    from PIL import Image

    from splineviz.cli import main

    out = tmp_path / "default.png"
    assert main(["--screenshot", str(out), "--size", "200x150"]) == 0
    with Image.open(out) as im:
        img = np.asarray(im.convert("RGB")).astype(int)
    assert img.shape == (150, 200, 3)
    bg = img[0, 0]
    surface = np.any(np.abs(img - bg) > 40, axis=2)
    assert 0.05 < surface.mean() < 0.9


def test_cli_corrupt_file_is_one_line_error(qapp, tmp_path, capsys):
    from splineviz.cli import main

    bad = tmp_path / "bad.nrrd"
    bad.write_bytes(b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4\n\n")
    assert main([str(bad), "--screenshot", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("splineviz: error:")
    assert not Path(tmp_path / "x.png").exists()


def test_remesh_panel_runs_remesh_in_a_worker(window, shared_data):
    window.open_path(shared_data / "points" / "kitten.xyz", block=True)
    cloud = window.items[-1]
    window.remesh_panel.mode.setCurrentIndex(0)
    window.remesh_panel.rho.setValue(0.6)  # coarse: a quick run
    window.remesh_panel.run()
    assert window.busy() and window.cancel_button.isVisibleTo(window)
    window.wait_idle(300)
    assert window.last_error is None
    mesh_item = window.items[-1]
    assert mesh_item.kind == "mesh" and mesh_item.mesh.n_cells > 500
    assert mesh_item.stats["boundary_edges"] == 0 and mesh_item.stats["radius_ratio_mean"] > 0.8
    assert "radius ratio mean" in window.remesh_panel.stats.text()
    assert cloud.name in mesh_item.name


@pytest.mark.slow
def test_bonsai_opens_in_a_worker_and_renders(window, shared_data):
    window.open_path(shared_data / "volumes" / "bonsai.vti", iso=40.0)
    assert window.busy()
    window.wait_idle(300)
    window.wait_for_refine(300)
    layer = window.items[-1].layers[0]
    f = shown(window, layer)
    assert f.final and f.frame.hit.mean() > 0.05 and f.stats["active_cells"] > 100_000


def test_export_mesh_of_an_isosurface_and_drop_to_open(window, tmp_path, qtbot):
    from PySide6.QtCore import QMimeData, QPointF, Qt, QUrl
    from PySide6.QtGui import QDropEvent

    item = window.add_volume(sphere_volume(), "sphere", iso=0.64, model="cubic-c1")
    out = tmp_path / "iso.ply"
    window.export_mesh(out, item.layers[0])
    mesh = sv.read_mesh(out)
    r = np.linalg.norm(np.asarray(mesh.points), axis=1)
    assert mesh.n_cells > 500 and np.abs(r - 0.8).max() < 0.02
    # dropping the file onto the window opens it (as a point cloud of its vertices)
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(out))])
    event = QDropEvent(QPointF(10, 10), Qt.DropAction.CopyAction, mime,
                       Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier)
    window.dropEvent(event)
    window.wait_idle()
    assert window.items[-1].kind == "points" and window.items[-1].name == "iso.ply"


def test_synthetic_sources_from_plugins_and_default_session(window, tmp_path):
    from splineviz.plugins import sources

    names = sorted(sources())
    if not names:
        pytest.skip("no source plugin installed")
    window._fill_sources()
    assert len(window.sources_menu.actions()) >= len(names)
    item = window.open_source(names[0], shape=(12, 13, 14))
    assert item.volume.shape == (12, 13, 14) and item.source == names[0]
    path = tmp_path / "src.svs"
    window.save_session(path)
    window.clear()
    window.open_path(path, block=True)
    assert window.last_error is None and window.items[0].volume.shape == (12, 13, 14)


def test_cli_screenshot_without_display_renders_offscreen(tmp_path):
    import subprocess
    import sys

    from PIL import Image

    out = tmp_path / "headless.png"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"
    result = subprocess.run([sys.executable, "-m", "splineviz.cli", "--screenshot", str(out),
                             "--size", "120x90", "--model", "trilinear"],
                            env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    with Image.open(out) as im:
        img = np.asarray(im.convert("RGB")).astype(int)
    assert img.shape == (90, 120, 3)
    assert 0.05 < np.any(np.abs(img - img[0, 0]) > 40, axis=2).mean() < 0.9


def test_session_with_a_moved_data_file_is_repointed(window, tmp_path, monkeypatch):
    vol = tmp_path / "a.npy"
    np.save(vol, sphere_volume().data)
    window.open_path(vol, block=True, iso=0.5)
    path = tmp_path / "s.svs"
    window.save_session(path)
    window.clear()
    moved = tmp_path / "elsewhere.npy"
    vol.rename(moved)
    asked = []

    def fake_dialog(obj_id, missing):
        asked.append(Path(missing).name)
        return str(moved)

    monkeypatch.setattr(window, "_ask_repoint", fake_dialog)
    window.open_path(path)   # parsed here, data read in a worker
    window.wait_idle()
    assert asked == ["a.npy"] and window.last_error is None
    assert window.items[0].path == str(moved) and window.items[0].layers[0].isovalue == 0.5
