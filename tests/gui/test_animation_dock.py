"""The Animation dock and File > Export animation: presets scrub the scene, keys come from
the view, an export runs in the background and a cancel leaves no file behind."""

import imageio
import numpy as np
import pytest

pytest.importorskip("pytestqt")

from interaction import StallMeter, close_window, open_window, pump  # noqa: E402
from PySide6.QtWidgets import QDialog, QFileDialog  # noqa: E402

from splineviz.gui import animation_dock  # noqa: E402
from splineviz.render.movie import staging_folder  # noqa: E402

#: generous on a busy 2-core machine (the 100 ms budget belongs to the benchmark)
MAX_STALL_MS = 300


@pytest.fixture
def window(qapp, tmp_path):
    w = open_window(tmp_path / "settings")
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    yield w
    close_window(w)


def _choose(monkeypatch, path, width, height, fmt):
    """The export dialog accepted with these choices and ``path`` picked as the file."""
    def exec_(dlg):
        dlg.width.setValue(width)
        dlg.height.setValue(height)
        dlg.format.setCurrentIndex(dlg.format.findData(fmt))
        return QDialog.DialogCode.Accepted

    monkeypatch.setattr(animation_dock.ExportAnimationDialog, "exec", exec_)
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        staticmethod(lambda *a, **k: (str(path), "")))


def test_presets_scrub_the_scene_and_keys_come_from_the_view(window):
    w = window
    panel = w.animation_panel
    assert "Animation" in w.docks
    panel.preset.setCurrentIndex(panel.preset.findData("orbit"))
    panel.frames.setValue(8)
    panel.make_preset()
    anim = w.scene.animation
    assert anim.frames == 8 and panel.tracks.count() == 1 and w.scene.modified
    cam = w.scene.camera
    before = np.subtract(cam.position, cam.focal_point)
    up = np.asarray(cam.view_up) / np.linalg.norm(cam.view_up)
    panel.slider.setValue(4)  # half a turn about the view up
    after = np.subtract(cam.position, cam.focal_point)
    along = np.dot(before, up) * up
    assert np.allclose(after - along, -(before - along), atol=1e-9)
    panel.key_iso.click()
    iso = w.scene.isosurfaces[0]
    assert w.scene.animation.track(iso.id, "isovalue").keys[0].frame == 4
    panel.preset.setCurrentIndex(panel.preset.findData("iso"))
    panel.combine.setChecked(True)
    panel.make_preset()
    assert {t.property for t in w.scene.animation.tracks} == {"camera", "isovalue"}
    panel.play_button.click()
    assert pump(2.0, lambda: panel.slider.value() != 0)
    panel.play_button.click()
    assert panel.play_button.text() == "Play"


def test_export_through_the_action_writes_the_movie(window, tmp_path, monkeypatch):
    w = window
    panel = w.animation_panel
    panel.frames.setValue(4)
    panel.make_preset()
    out = tmp_path / "turn.gif"
    _choose(monkeypatch, out, 64, 48, ".gif")
    w.actions_by_name["export animation"].trigger()
    assert pump(300, lambda: not w.jobs.jobs), "the export did not end"
    assert w.last_error is None
    assert imageio.v3.imread(out, index=None).shape[:3] == (4, 48, 64)
    assert not staging_folder(out).exists()


def test_cancelled_export_leaves_no_file_and_the_window_responsive(window, tmp_path,
                                                                   monkeypatch):
    w = window
    panel = w.animation_panel
    panel.frames.setValue(400)
    panel.make_preset()
    out = tmp_path / "long.mp4"
    _choose(monkeypatch, out, 320, 240, ".mp4")
    w.actions_by_name["export animation"].trigger()
    assert len(w.jobs.jobs) == 1
    job = w.jobs.jobs[0]
    with StallMeter() as meter:
        # frames are being written (the child process started and rendered some)
        assert pump(300, lambda: (job.fraction or 0) > 0 and staging_folder(out).exists()), \
            "the export made no progress"
        pump(1.0)
    assert meter.max_ms < MAX_STALL_MS, f"the window stalled {meter.max_ms:.0f} ms"
    assert job.message.startswith("frame ")
    w.actions_by_name["cancel"].trigger()
    assert job.wait(30.0)
    assert pump(5, lambda: not w.jobs.jobs)
    assert job.state == "cancelled"
    assert not out.exists() and not staging_folder(out).exists()
    assert list(tmp_path.glob("long*")) == []


def test_time_playback_preset_is_offered_for_a_time_varying_volume(window, tmp_path):
    nib = pytest.importorskip("nibabel")
    w = window
    panel = w.animation_panel
    assert panel.preset.findData("time") < 0  # the default volume does not vary
    g = np.linspace(-1, 1, 16)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    steps = [((1 - np.sqrt((x - 0.3 * t) ** 2 + y**2 + z**2)) * 200).clip(0, 255)
             for t in range(4)]
    img = nib.Nifti1Image(np.stack(steps, -1).astype(np.uint8), np.eye(4))
    img.header.set_xyzt_units("mm", "sec")
    path = tmp_path / "moving.nii.gz"
    nib.save(img, path)
    w.open_path(path, mode="replace", block=True)
    assert pump(60, lambda: bool(w.scene.time_varying) and not w.jobs.jobs)
    assert pump(5, lambda: panel.preset.findData("time") >= 0)
    panel.preset.setCurrentIndex(panel.preset.findData("time"))
    panel.step_from.setValue(1)
    panel.per_step.setValue(2)
    panel.make_preset()
    anim = w.scene.animation
    assert anim.frames == 6 and panel.frames.value() == 6
    assert pump(30, lambda: w.scene.step_index() == 1)  # frame 0, read by a job
    with StallMeter() as meter:
        panel.slider.setValue(5)  # its step read by a job when not read yet
        assert pump(30, lambda: w.scene.step_index() == 3)
        panel.play_button.click()
        assert pump(30, lambda: w.scene.step_index() == 1)  # looped round
        panel.play_button.click()
    assert meter.max_ms < MAX_STALL_MS, f"GUI thread stalled {meter.max_ms:.0f} ms"
