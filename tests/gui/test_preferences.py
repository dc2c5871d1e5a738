"""Edit > Preferences... through the real dialog (issue 26, part 7): a value changed and
confirmed with OK is stored in QSettings and acts (the next volume opened gets the chosen
model; background, preview quality, lazy threshold and layout at once); "Restore defaults"
brings the built-in values back."""

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import pump  # noqa: E402  (tests/gui helper, on sys.path via pytest)
from PySide6.QtCore import QSettings  # noqa: E402
from PySide6.QtWidgets import QDialogButtonBox  # noqa: E402

from splineviz.gui import preferences  # noqa: E402
from splineviz.io._util import memory_budget  # noqa: E402
from splineviz.io.mapped import LAZY_SHARE_ENV, lazy_threshold  # noqa: E402


@pytest.fixture
def window(qapp, tmp_path, monkeypatch):
    from splineviz.gui.main_window import MainWindow

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope,
                      str(tmp_path / "settings"))
    # the dialog writes the environment variable: restored after the test
    monkeypatch.delenv(LAZY_SHARE_ENV, raising=False)
    monkeypatch.setattr(preferences, "_lazy_written", False)
    w = MainWindow()
    w.show()
    pump(0.1)
    yield w
    w.wait_idle()
    w.close()
    pump(0.1)
    assert w.join_workers(30)


def _open_dialog(window) -> preferences.PreferencesDialog:
    menu = window.actions_by_name["preferences"]
    assert menu.menuRole() == menu.MenuRole.PreferencesRole
    menu.trigger()
    assert pump(5, lambda: getattr(window, "_preferences_dialog", None) is not None
                and window._preferences_dialog.isVisible())
    return window._preferences_dialog


def _ok(dialog) -> None:
    dialog.buttons.button(QDialogButtonBox.StandardButton.Ok).click()
    assert pump(5, lambda: not dialog.isVisible())


def test_a_changed_preference_is_stored_and_acts(window, tmp_path):
    dialog = _open_dialog(window)
    assert dialog.model.currentData() == "cubic-c1"  # the built-in default
    dialog.model.setCurrentIndex(dialog.model.findData("trilinear"))
    dialog._set_background((1.0, 1.0, 1.0))
    dialog.preview.setCurrentIndex(dialog.preview.findData(0.5))
    dialog.lazy.setValue(40.0)
    dialog.layout_box.setCurrentIndex(dialog.layout_box.findData("one-slice:coronal"))
    _ok(dialog)

    s = QSettings("splineviz", "splineviz")
    assert s.value("preferences/model") == "trilinear"
    assert preferences.load() == preferences.Preferences(
        "trilinear", (1.0, 1.0, 1.0), 0.5, 0.4, "one-slice:coronal")
    # at once: background, preview quality, layout, the threshold the readers ask for
    assert tuple(window.scene.view.background) == (1.0, 1.0, 1.0)
    assert window.spline_scene.max_preview_scale == 0.5
    assert (window.view_layout.state.layout, window.view_layout.state.single) == \
        ("one-slice", "coronal")
    assert lazy_threshold() == int(0.4 * memory_budget())
    assert not window.scene.modified  # a preference is no edit of the scene
    # the next volume opened starts with the chosen model
    path = tmp_path / "blob.npy"
    x = np.linspace(-1, 1, 12)
    np.save(path, (x[:, None, None] ** 2 + x[None, :, None] ** 2
                   + x[None, None, :] ** 2).astype(np.float32))
    window.open_path(path, block=True)
    assert window.scene.isosurfaces[0].model == "trilinear"


def test_restore_defaults_and_cancel(window):
    preferences.save(preferences.Preferences("trilinear", (1.0, 0.0, 0.0), 0.25, 0.1, "3d"))
    dialog = _open_dialog(window)
    assert dialog.values() == preferences.load()  # the dialog shows what is stored
    # OK with only the preview quality changed: the scene's own background stays
    window.scene.view.background = (0.0, 0.5, 0.0)
    dialog.preview.setCurrentIndex(dialog.preview.findData(0.5))
    _ok(dialog)
    assert preferences.load().max_preview_scale == 0.5
    assert window.spline_scene.max_preview_scale == 0.5
    assert tuple(window.scene.view.background) == (0.0, 0.5, 0.0)
    dialog = _open_dialog(window)
    dialog.restore_button.click()
    assert dialog.values() == preferences.Preferences.defaults()
    dialog.reject()  # Cancel keeps what was stored
    assert preferences.load().model == "trilinear"
    dialog = _open_dialog(window)
    dialog.restore_button.click()
    _ok(dialog)
    assert preferences.load() == preferences.Preferences.defaults()
    assert window.spline_scene.max_preview_scale == 1.0


def test_the_command_line_file_takes_the_preferred_model_and_a_cloud_opens(tmp_path,
                                                                          shared_data):
    """``splineviz FILE``: a volume's isosurface takes the preferred model (``--model``
    wins), and a point cloud, which has no isosurface for it, opens (it was refused as if
    ``--model`` had been given)."""
    from argparse import Namespace

    from splineviz.gui.app import _scene
    from splineviz.model.scene import PointsNode

    cloud = tmp_path / "cloud.xyz"
    np.savetxt(cloud, np.random.default_rng(0).random((60, 3)))
    scene = _scene(Namespace(file=str(cloud), iso=None, model=None, renderer=None), "trilinear")
    assert len(scene.of_kind(PointsNode)) == 1 and not scene.isosurfaces
    args = Namespace(file=str(shared_data / "volumes" / "neghip.slc"), iso=None, model=None,
                     renderer=None)
    assert [i.model for i in _scene(args, "trilinear").isosurfaces] == ["trilinear"]
    assert not _scene(args, "trilinear").modified
    args.model = "super-quadratic"
    assert [i.model for i in _scene(args, "trilinear").isosurfaces] == ["super-quadratic"]
