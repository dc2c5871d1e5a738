"""File > Export screenshot runs in the background (issue 26): through the real action (its
dialogs answered), the exact frames are cast in a job with progress and Cancel while the
window goes on, and the PNG written is the picture the command line's screenshot makes."""

import threading

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import close_window, open_window, pump  # noqa: E402
from PySide6.QtWidgets import QDialog  # noqa: E402
from sleeping_model import RELEASE, sleeping_model  # noqa: E402

from splineviz.gui import dialogs  # noqa: E402

SIZE = (320, 240)


@pytest.fixture
def window(qapp, tmp_path):
    w = open_window(tmp_path / "settings")
    yield w
    RELEASE.set()
    close_window(w)
    assert w.join_workers(30)


@pytest.fixture
def answers(monkeypatch):
    """The dialogs of the action answered: size :data:`SIZE`, then the file name."""
    chosen = {}

    def exec_(dlg):
        dlg.width.setValue(SIZE[0])
        dlg.height.setValue(SIZE[1])
        return QDialog.DialogCode.Accepted

    monkeypatch.setattr(dialogs.ScreenshotDialog, "exec", exec_)
    monkeypatch.setattr(dialogs.QFileDialog, "getSaveFileName",
                        lambda *a, **k: (str(chosen["path"]), ""))
    return chosen


def _exports(w):
    from splineviz.gui.screenshot import ScreenshotExport

    return w.findChildren(ScreenshotExport)


def test_the_screenshot_is_made_in_the_background(window, answers, tmp_path, monkeypatch):
    from splineviz.io.meshes import read_image
    from splineviz.render.isosurface import IsosurfaceLayer
    from splineviz.render.scene_view import render_scene

    w = window
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    w.scene.isosurfaces[0].model = "cubic-c1"  # a caster the export builds in its job
    assert pump(120, lambda: not w.view.refining and not w.spline_scene.needs_refine())
    answers["path"] = tmp_path / "shot.png"
    # every frame of the export is cast in a job's thread, none in the GUI thread (a
    # frame made for another near / far range than the render's was cast again there)
    compute, cast_in = IsosurfaceLayer.compute, []

    def recording(self, *args, **kwargs):
        cast_in.append(threading.current_thread() is threading.main_thread())
        return compute(self, *args, **kwargs)

    monkeypatch.setattr(IsosurfaceLayer, "compute", recording)

    w.actions_by_name["screenshot"].trigger()
    # the action returned at once: the frames are cast in a job the status bar shows
    assert not answers["path"].exists()
    assert any(j.label.startswith("Screenshot") for j in w.jobs.jobs)
    assert w.cancel_button.isVisible()
    (export,) = _exports(w)
    assert pump(120, lambda: export.state != "running")
    assert export.state == "done", w.last_error
    assert w.last_error is None
    assert cast_in and not any(cast_in), "a frame of the export was cast in the GUI thread"
    monkeypatch.undo()

    img = read_image(answers["path"])
    assert img.shape[:2] == (SIZE[1], SIZE[0])
    expected = render_scene(w.scene, SIZE)
    assert np.array_equal(img[..., :3], expected[..., :3])
    assert pump(5, lambda: not export._views)  # its off-screen views are closed


def test_cancel_stops_the_export(window, answers, tmp_path):
    w = window
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    answers["path"] = tmp_path / "never.png"
    with sleeping_model("Sleeping test model", 300.0) as slow:
        w.scene.isosurfaces[0].model = slow  # its exact frame never comes
        w.actions_by_name["screenshot"].trigger()
        (export,) = _exports(w)
        assert pump(5, lambda: any(j.label.startswith("Screenshot") for j in w.jobs.jobs))
        w.cancel_button.click()
        assert pump(5, lambda: export.state == "cancelled")
        assert not any(j.label.startswith("Screenshot") for j in w.jobs.jobs)
        RELEASE.set()  # the job's thread ends; then the export closes its views
        assert pump(30, lambda: not export._views)
    assert not answers["path"].exists()
    assert w.last_error is None


def test_the_screenshot_has_the_volume_rendering(window, answers, tmp_path, monkeypatch):
    """Issue 30: a volume-rendered volume is in the exported picture, cast in the job's
    thread, as render_scene composites it."""
    from splineviz.io.meshes import read_image
    from splineviz.render import volume_rendering
    from splineviz.render.scene_view import render_scene

    w = window
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    plain = render_scene(w.scene, SIZE)[..., :3]
    vol = w.scene.volumes[0]
    vol.update(volume_rendering=True, transfer_function="mri")
    assert pump(120, lambda: not w.view.refining and not w.spline_scene.needs_refine())
    composite, cast_in = volume_rendering.composite_casts, []

    def recording(*args, **kwargs):
        cast_in.append(threading.current_thread() is threading.main_thread())
        return composite(*args, **kwargs)

    monkeypatch.setattr(volume_rendering, "composite_casts", recording)
    answers["path"] = tmp_path / "volume.png"
    w.actions_by_name["screenshot"].trigger()
    (export,) = _exports(w)
    assert pump(120, lambda: export.state != "running")
    assert export.state == "done", w.last_error
    assert cast_in == [False], "the volume rendering was not cast in the export's job"
    monkeypatch.undo()

    img = read_image(answers["path"])[..., :3]
    expected = render_scene(w.scene, SIZE)[..., :3]
    assert np.array_equal(img, expected)
    changed = np.abs(img.astype(int) - plain.astype(int)).max(axis=2) > 8
    assert changed.mean() > 0.05, "the volume rendering is not in the screenshot"
