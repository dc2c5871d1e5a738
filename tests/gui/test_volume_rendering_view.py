"""Volume rendering in the live view (issue 30): the panel turns it on, the exact frame the
refine worker casts shows the picture ``render_scene`` makes of the same scene and camera,
a preset change changes it, an edit is an undo step, and neither toggling nor orbiting holds
the GUI thread past the default suite's guard."""

import time

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import StallMeter, close_window, drag, open_window, pump  # noqa: E402

#: the default suite's limit on one GUI-thread stall (the budget is 100 ms; a busy
#: machine's tick does not reach three times that, a frame cast in the GUI thread does)
STALL_GUARD_MS = 300.0
#: mean per-pixel difference (largest channel, 0-255) allowed between the window and
#: render_scene: the overlay holds straight 8-bit colour, the export premultiplied floats
MEAN_TOL = 2.0


@pytest.fixture
def window(qapp, tmp_path):
    w = open_window(tmp_path / "settings")
    yield w
    close_window(w)


def _settled(w) -> bool:
    return (not w.view.refining and not w.spline_scene.needs_refine()
            and all(w.spline_scene.shown_frame(v).final
                    for v in w.spline_scene.volume_layers if v.visible))


def _window_image(w) -> np.ndarray:
    return np.asarray(w.plotter.screenshot(return_img=True))[..., :3].astype(int)


def _difference(a, b) -> float:
    return float(np.abs(a.astype(int) - b.astype(int)).max(axis=2).mean())


def test_panel_turns_volume_rendering_on_like_render_scene(window):
    from splineviz.gui.undo import undo_stack
    from splineviz.render.scene_view import render_scene

    w = window
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    assert pump(120, lambda: _settled(w))
    vol = w.scene.volumes[0]
    w.scene.select(vol)
    panel = w.volume_panel
    assert panel.node is vol
    plain = _window_image(w)

    with StallMeter() as stall:
        panel.preset.setCurrentText("mri")
        panel.preset.activated.emit(panel.preset.currentIndex())
        panel.enabled.setChecked(True)
        assert pump(180, lambda: _settled(w) and w.spline_scene.volume_layers)
    assert vol.volume_rendering and vol.transfer_function == "mri"
    assert stall.max_ms < STALL_GUARD_MS, f"toggling held the GUI thread {stall.max_ms:.0f} ms"
    shown = _window_image(w)
    size = w.spline_scene.window_size()
    expected = render_scene(w.scene, size)[..., :3]
    assert _difference(shown, plain) > 5 * MEAN_TOL, "volume rendering did not change the view"
    diff = _difference(shown, expected)
    assert diff < MEAN_TOL, f"the window differs from render_scene by {diff:.2f} on average"

    panel.preset.setCurrentText("ct-bone")
    panel.preset.activated.emit(panel.preset.currentIndex())
    assert pump(180, lambda: _settled(w))
    bone = _window_image(w)
    assert _difference(bone, shown) > MEAN_TOL, "the preset change did not change the view"
    diff = _difference(bone, render_scene(w.scene, size)[..., :3])
    assert diff < MEAN_TOL, f"ct-bone: the window differs from render_scene by {diff:.2f}"

    undo_stack(w.scene).undo()
    assert vol.transfer_function == "mri" and panel.preset.currentText() == "mri"

    # orbit with the volume rendering on: previews, then the exact frame, no stall. From a
    # settled view: an exact volume frame still cast by the worker when the drag starts
    # holds both cores of this machine, and Mesa's renderer then waits for them (up to
    # ~0.6 s measured; the exact volume frame is one kernel, not yet cut into tiles)
    assert pump(180, lambda: _settled(w))
    cx, cy = w.plotter.width() / 2.0, w.plotter.height() / 2.0
    with StallMeter() as stall:
        drag(w.plotter, (cx - 60, cy), (cx + 60, cy + 20), n=12)
        t0 = time.perf_counter()
        assert pump(180, lambda: _settled(w))
    print(f"orbit: longest stall {stall.max_ms:.0f} ms; exact after "
          f"{time.perf_counter() - t0:.1f} s")
    assert stall.max_ms < STALL_GUARD_MS, f"orbiting held the GUI thread {stall.max_ms:.0f} ms"
    diff = _difference(_window_image(w), render_scene(w.scene, size)[..., :3])
    assert diff < MEAN_TOL, f"after the orbit the window differs by {diff:.2f}"

    panel.enabled.setChecked(False)
    assert pump(60, lambda: not w.spline_scene.volume_layers and _settled(w))


def test_transfer_function_import_and_export(window, tmp_path):
    from splineviz.core.transfer_function import preset, read_paraview_json

    w = window
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    vol = w.scene.volumes[0]
    w.scene.select(vol)
    panel = w.volume_panel
    out = tmp_path / "tf.json"
    panel.export_json(out)
    data = vol.data.data
    expected = preset(vol.transfer_function, (float(data.min()), float(data.max())))
    tf = read_paraview_json(out)
    assert np.allclose(tf.opacity_points, expected.opacity_points)
    assert np.allclose(tf.rgb_points, expected.rgb_points)
    panel.import_json(out)
    assert vol.transfer_function == str(out)
    assert panel.preset.currentText() == str(out)
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    panel.import_json(bad)
    assert vol.transfer_function == str(out)  # unchanged, one sentence shown
    assert w.last_error and "\n" not in w.last_error
