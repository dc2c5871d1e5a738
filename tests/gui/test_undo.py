"""Undo/redo through the real widgets, and no lost work (issue 26, part 2).

Every edit a user makes in the panels is undone and redone through the scene's undo stack
(state after undo equals the state before, compared through the scene model); a slider or
plane-widget drag is one step; Edit > Undo / Redo answer Ctrl+Z / Ctrl+Shift+Z; every path
that replaces a scene with unsaved changes asks first (Save / Discard / Cancel).
"""

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvista")

from PySide6.QtCore import QPoint, Qt, QTimer  # noqa: E402
from PySide6.QtGui import QColor  # noqa: E402
from PySide6.QtWidgets import QApplication, QColorDialog, QFileDialog, QMessageBox  # noqa: E402

import splineviz as sv  # noqa: E402
from splineviz.gui.jobs import JobRunner  # noqa: E402
from splineviz.gui.main_window import MainWindow  # noqa: E402
from splineviz.gui.panels import (  # noqa: E402
    AnalysisPanel,
    ClippingPanel,
    DataPanel,
    IsosurfacePanel,
    SmoothingPanel,
)
from splineviz.gui.undo import undo_stack  # noqa: E402
from splineviz.model import MeshNode, PointsNode, Scene  # noqa: E402

Button = QMessageBox.StandardButton


def sphere_volume(n=11):
    x = np.linspace(-1, 1, n)
    return sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2), spacing=2 / (n - 1),
                     origin=(-1, -1, -1))


def sphere_scene():
    scene = Scene()
    vol = scene.add_volume(sphere_volume(), "sphere", isovalue=0.5, model="trilinear")
    return scene, vol, scene.isosurfaces[0]


def state(scene: Scene) -> list:
    """The scene as the model holds it: per node its id, kind, saved properties and the
    identity of its data; then the selection."""
    rows = []
    for n in scene:
        data = [id(getattr(n, k)) for k in ("data", "vertices") if getattr(n, k, None)
                is not None]
        rows.append((n.id, n.kind, n.model_dump(mode="json", by_alias=True), data))
    return rows + [("selected", scene.selected and scene.selected.id)]


def check_step(scene, edit, steps: int = 1):
    """``edit()`` through a widget makes ``steps`` undo steps; undo gives back the state
    before, redo the state after. Returns (before, after)."""
    undo = undo_stack(scene)
    n = undo.stack.index()
    before = state(scene)
    edit()
    after = state(scene)
    assert after != before, "the edit changed nothing"
    assert undo.stack.index() == n + steps
    for _ in range(steps):
        undo.undo()
    assert state(scene) == before
    for _ in range(steps):
        undo.redo()
    assert state(scene) == after
    return before, after


def test_isosurface_panel_edits_are_undone_one_step_each(qtbot, monkeypatch):
    scene, vol, iso = sphere_scene()
    panel = IsosurfacePanel(scene, JobRunner())
    qtbot.addWidget(panel)
    scene.select(iso)
    check_step(scene, lambda: panel.spin.setValue(0.3))
    assert panel.spin.value() == pytest.approx(0.3)
    undo_stack(scene).undo()
    assert panel.spin.value() == pytest.approx(0.5)  # the widgets follow an undo
    undo_stack(scene).redo()
    check_step(scene, lambda: panel.model.setCurrentIndex(panel.model.findData("cubic-c1")))
    monkeypatch.setattr(QColorDialog, "getColor",
                        staticmethod(lambda *a, **k: QColor.fromRgbF(0.2, 0.4, 0.6)))
    check_step(scene, panel.color.click)
    check_step(scene, lambda: panel.material.setCurrentText("shiny"))
    assert undo_stack(scene).stack.undoText() == "Change material of isosurface"

    def drag_opacity():
        panel.opacity.setSliderDown(True)
        for v in (0.9, 0.7, 0.5):
            panel.opacity.setValue(v)
        panel.opacity.setSliderDown(False)

    check_step(scene, drag_opacity)  # one step for the drag
    assert iso.opacity == pytest.approx(0.5)
    check_step(scene, panel.add_button.click)
    assert len(scene.isosurfaces) == 2


def test_isovalue_slider_drag_is_one_step_and_two_drags_two(qtbot):
    scene, vol, iso = sphere_scene()
    panel = IsosurfacePanel(scene, JobRunner())
    qtbot.addWidget(panel)
    panel.resize(400, 300)
    panel.show()
    scene.select(iso)
    h = panel.histogram
    y = h.height() // 2

    def drag(x0, x1):
        qtbot.mousePress(h, Qt.MouseButton.LeftButton, pos=QPoint(x0, y))
        for x in np.linspace(x0, x1, 6).astype(int)[1:]:
            qtbot.mouseMove(h, QPoint(int(x), y))
        qtbot.mouseRelease(h, Qt.MouseButton.LeftButton, pos=QPoint(x1, y))

    undo = undo_stack(scene)
    start = iso.isovalue
    check_step(scene, lambda: drag(h.width() // 4, h.width() // 2))
    middle = iso.isovalue
    assert middle != start
    check_step(scene, lambda: drag(h.width() // 2, 3 * h.width() // 4))
    assert undo.stack.count() == 2 and iso.isovalue != middle
    undo.undo()
    assert iso.isovalue == middle and panel.spin.value() == pytest.approx(middle)
    undo.undo()
    assert iso.isovalue == start
    # arrow keys: one step per key press
    h.setFocus()
    check_step(scene, lambda: qtbot.keyClick(h, Qt.Key.Key_Right))


def test_data_clipping_analysis_and_smoothing_panels_edit_through_the_stack(qtbot):
    scene, vol, iso = sphere_scene()
    data, clip = DataPanel(scene), ClippingPanel(scene)
    analysis, smooth = AnalysisPanel(scene), SmoothingPanel(scene)
    for w in (data, clip, analysis, smooth):
        qtbot.addWidget(w)
    scene.select(iso)
    # clip planes: add, flip, hide the widgets, remove
    check_step(scene, clip.add_button.click)
    plane = scene.clip_planes[0]
    check_step(scene, clip.flip_button.click)
    check_step(scene, lambda: clip.show_widgets.setChecked(False))
    # colour-by, and a cross section with the plane
    scene.select(iso)
    check_step(scene, lambda: analysis.field.setCurrentIndex(analysis.field.findData("mean")))
    check_step(scene, lambda: analysis.range_mode.setCurrentText("symmetric"))
    analysis.section_with.setCurrentIndex(analysis.section_with.findData(plane.id))
    check_step(scene, analysis.add_section.click)
    assert len(scene.sections) == 1
    # visibility tick in the data tree
    row = data._rows[iso.id]
    check_step(scene, lambda: row.setCheckState(0, Qt.CheckState.Unchecked))
    # smoothing
    scene.select(vol)
    check_step(scene, lambda: (smooth.sigma.setValue(1.5), smooth.apply()))
    assert vol.sigma == 1.5
    scene.select(plane)
    check_step(scene, clip.remove_button.click)
    undo_stack(scene).undo()  # the plane (and its section) back
    assert clip.list.count() == 1 and len(scene.sections) == 1
    # removing the volume takes the isosurface, the plane and the section; undo puts them
    # back with their ids, data and order
    scene.select(vol)
    nodes = list(scene)
    check_step(scene, data.remove_button.click)
    undo_stack(scene).undo()
    assert list(scene) == nodes and all(a is b for a, b in zip(scene, nodes, strict=True))
    assert data.tree.topLevelItemCount() == 2 and clip.list.count() == 1  # volume, section
    assert [n.kind for n in scene] == ["volume", "isosurface", "clip_plane", "section"]


def test_an_object_added_or_removed_outside_the_stack_clears_the_history(qtbot):
    scene, vol, iso = sphere_scene()
    panel = IsosurfacePanel(scene, JobRunner())
    qtbot.addWidget(panel)
    scene.select(iso)
    panel.spin.setValue(0.3)
    undo = undo_stack(scene)
    assert undo.stack.canUndo()
    scene.add_volume(sphere_volume(7), "other")  # e.g. a session loaded
    assert not undo.stack.canUndo() and not undo.stack.canRedo()


# -- the window ------------------------------------------------------------------------


@pytest.fixture
def window(qtbot, tmp_path):
    from PySide6.QtCore import QSettings

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope, str(tmp_path))
    w = MainWindow(size=(160, 120))
    # pytest-qt closes the window before this fixture's teardown: no question then
    qtbot.addWidget(w, before_close_func=lambda w: setattr(w, "ask_before_closing", False))
    w.resize(900, 560)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.wait_idle()


def test_edit_menu_undo_redo_with_ctrl_z_and_ctrl_shift_z(window, qtbot):
    vol = window.scene.add_volume(sphere_volume(), "sphere", isovalue=0.5, model="trilinear")
    iso = window.scene.isosurfaces_of(vol)[0]
    window.scene.select(iso)
    menu = next(a.menu() for a in window.menuBar().actions() if a.text() == "&Edit")
    undo_action, redo_action = window.actions_by_name["undo"], window.actions_by_name["redo"]
    assert menu.actions()[:2] == [undo_action, redo_action]
    assert undo_action.shortcut().toString() == "Ctrl+Z"
    assert redo_action.shortcut().toString() == "Ctrl+Shift+Z"
    assert not undo_action.isEnabled()
    window.iso_panel.spin.setValue(0.3)
    assert undo_action.isEnabled() and undo_action.text() == "&Undo Change isovalue of isosurface"
    window.activateWindow()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is window)
    window.view.plotter.setFocus()
    qtbot.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert iso.isovalue == 0.5 and window.iso_panel.spin.value() == pytest.approx(0.5)
    qtbot.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier
                   | Qt.KeyboardModifier.ShiftModifier)
    assert iso.isovalue == pytest.approx(0.3)


def test_plane_widget_drag_is_one_step_and_the_widget_follows_undo(window):
    window.scene.add_volume(sphere_volume(), "sphere", isovalue=0.5, model="trilinear")
    plane = window.clip_panel.add_plane()
    widget = window.plane_widgets.widgets[plane.id]
    undo = undo_stack(window.scene)
    n = undo.stack.index()
    before = state(window.scene)
    widget.InvokeEvent("StartInteractionEvent")
    for x in (0.1, 0.2, 0.3):
        widget.SetOrigin(x, 0.0, 0.0)
        widget.InvokeEvent("InteractionEvent")
    widget.InvokeEvent("EndInteractionEvent")
    assert plane.origin == pytest.approx((0.3, 0.0, 0.0)) and undo.stack.index() == n + 1
    undo.undo()
    assert state(window.scene) == before
    assert widget.GetOrigin() == pytest.approx(plane.origin)  # the widget follows
    undo.redo()
    assert plane.origin == pytest.approx((0.3, 0.0, 0.0))


def test_remesh_result_and_opening_beside_are_steps(window, tmp_path):
    rng = np.random.default_rng(1)
    p = rng.normal(size=(600, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    window.scene.add_points(sv.PointCloud(p), "ball")
    cloud = window.scene.of_kind(PointsNode)[0]
    window.remesh_panel.rho.setValue(0.6)
    undo = undo_stack(window.scene)
    before = state(window.scene)
    window.remesh_panel.run(cloud)
    window.wait_idle(300)
    assert window.last_error is None
    mesh = window.scene.of_kind(MeshNode)[0]
    assert undo.stack.undoText() == "Remesh ball"
    undo.undo()
    assert state(window.scene) == before
    undo.redo()
    assert window.scene.get(mesh.id) is mesh and mesh.points_id == cloud.id
    # a file opened beside the objects: one step
    np.save(tmp_path / "a.npy", sphere_volume().data)
    before = state(window.scene)
    window.open_path(tmp_path / "a.npy", mode="add", block=True)
    assert [v.name for v in window.scene.volumes] == ["a.npy"]
    undo.undo()
    assert state(window.scene) == before


# -- replacing a scene with unsaved changes asks first ---------------------------------


@pytest.fixture
def answering(monkeypatch):
    """Answers the unsaved-changes question with ``answers`` (in order); ``asked`` lists
    the questions."""
    asked, answers = [], []

    def question(parent, title, text, buttons=None, default=None):
        asked.append((title, text))
        return answers.pop(0)

    monkeypatch.setattr(QMessageBox, "question", staticmethod(question))
    return asked, answers


def unsaved(window):
    """A scene holding a remeshed mesh: data with no file, never saved."""
    window.ask_before_closing = True
    window.scene.add_mesh(np.eye(3), [[0, 1, 2]], "mesh of points")
    assert window.scene.modified
    return state(window.scene)


def replace_paths(window, tmp_path):
    """name -> what the user does that replaces the scene."""
    from splineviz.model import Scene as _Scene
    from splineviz.model.session import save_scene
    from splineviz.plugins import sources
    from splineviz.resources import example_sessions

    np.save(tmp_path / "a.npy", sphere_volume().data)
    other = _Scene()
    other.add_volume(sphere_volume(7), "small", path=str(tmp_path / "a.npy"))
    session = save_scene(other, tmp_path / "other.svs")
    example = next(iter(example_sessions().values()))
    source = sorted(sources())[0]
    return {
        "new": lambda: window.commands.new_scene(),
        "open": lambda: window.open_path(tmp_path / "a.npy", mode="replace", block=True),
        "open default data": lambda: window.commands.open_default(),
        "synthetic source": lambda: window.commands.open_source(source, shape=(8, 8, 8),
                                                                mode="replace"),
        "example session": lambda: window.open_path(example, block=True),
        "load session": lambda: window.open_path(session, block=True),
    }


@pytest.mark.parametrize("path", ["new", "open", "open default data", "synthetic source",
                                  "example session", "load session"])
def test_replacing_an_unsaved_scene_asks_first(window, tmp_path, answering, path):
    asked, answers = answering
    do = replace_paths(window, tmp_path)[path]
    before = unsaved(window)
    old = window.session_file = tmp_path / "old.svs"  # the scene came from a session
    answers.append(Button.Cancel)
    do()
    window.wait_idle()
    assert len(asked) == 1 and asked[0][0] == "Unsaved changes"
    assert state(window.scene) == before  # cancelled: nothing lost
    answers.append(Button.Discard)
    do()
    window.wait_idle()
    assert len(asked) == 2 and window.last_error is None
    assert not window.scene.of_kind(MeshNode)  # replaced
    assert window.session_file != old  # Save must not overwrite the old scene's session
    assert not undo_stack(window.scene).stack.canUndo()
    # a saved scene is replaced without a question
    window.scene.mark_saved()
    do()
    window.wait_idle()
    assert len(asked) == 2


def test_save_answer_saves_before_replacing_and_a_cancelled_save_keeps_the_scene(
        window, tmp_path, answering, monkeypatch):
    asked, answers = answering
    before = unsaved(window)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: ("", "")))
    answers.append(Button.Save)
    assert not window.commands.new_scene()  # no file chosen: nothing replaced
    assert state(window.scene) == before
    target = tmp_path / "kept.svs"
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        staticmethod(lambda *a, **k: (str(target), "")))
    answers.append(Button.Save)
    assert window.commands.new_scene()
    assert target.exists() and len(window.scene) == 0 and window.session_file is None
    assert "untitled" in window.windowTitle()


def test_the_real_dialog_cancel_button_keeps_the_scene(window, qtbot):
    before = unsaved(window)
    clicked = []

    def click_cancel():
        box = QApplication.activeModalWidget()
        if isinstance(box, QMessageBox):
            clicked.append(box.text())
            box.button(Button.Cancel).click()
        else:
            QTimer.singleShot(20, click_cancel)

    QTimer.singleShot(20, click_cancel)
    assert window.commands.open_default() is None
    assert clicked and "unsaved changes" in clicked[0]
    assert state(window.scene) == before
