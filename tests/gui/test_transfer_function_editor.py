"""The transfer function editor of the volume rendering panel (issue 30), driven through Qt's
mouse and key events: points added, dragged (kept in value order), removed and recoloured; in
the window a drag of an opacity point is one undo step of the node's transfer function, the
view previews it while the mouse moves without holding the GUI thread, the exact picture after
the release is brighter where the opacity rose and is the picture ``render_scene`` makes, and
a session keeps the edit (same points, same picture)."""

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import StallMeter, close_window, open_window, pump  # noqa: E402
from PySide6.QtCore import QPoint, Qt  # noqa: E402
from PySide6.QtGui import QColor  # noqa: E402
from PySide6.QtTest import QTest  # noqa: E402

#: as tests/gui/test_volume_rendering_view.py: the default suite's guard on one GUI-thread
#: stall (the budget is 100 ms), and the mean difference allowed against render_scene
STALL_GUARD_MS = 300.0
MEAN_TOL = 2.0

LEFT = Qt.MouseButton.LeftButton
NO_MOD = Qt.KeyboardModifier.NoModifier


def _pt(p) -> QPoint:
    return QPoint(int(round(p.x())), int(round(p.y())))


def _drag(widget, start: QPoint, end: QPoint, n: int = 10, between=None) -> None:
    """Press at ``start``, move in ``n`` steps to ``end`` (``between()`` after each), release."""
    QTest.mousePress(widget, LEFT, NO_MOD, start)
    for i in range(1, n + 1):
        f = i / n
        QTest.mouseMove(widget, QPoint(round(start.x() + f * (end.x() - start.x())),
                                       round(start.y() + f * (end.y() - start.y()))))
        if between is not None:
            between()
    QTest.mouseRelease(widget, LEFT, NO_MOD, end)


@pytest.fixture
def editor(qtbot):
    from splineviz.gui.transfer_function_editor import TransferFunctionEditor

    ed = TransferFunctionEditor()
    qtbot.addWidget(ed)
    ed.resize(400, 160)
    ed.set_histogram(np.log1p(np.arange(50.0)), np.linspace(0.0, 100.0, 51))
    ed.set_points([[0, 0, 0, 0], [100, 1, 1, 1]], [[0, 0], [40, 0.2], [60, 0.5], [100, 1]])
    ed.show()
    qtbot.waitExposed(ed)
    return ed


def test_editor_drags_adds_removes_and_recolours_points(editor, monkeypatch):
    ed = editor
    edits = []
    ed.edited.connect(lambda: edits.append(ed.opacity_points()))
    start = _pt(ed.point_position("opacity", 1))
    # dragged up and far to the right: the opacity rises, the value stops at its neighbour's
    far = QPoint(int(ed.point_position("opacity", 3).x()) + 40, start.y() - 60)
    _drag(ed, start, far)
    op = ed.opacity_points()
    assert len(edits) >= 5, "the drag told of its steps"
    assert op[1, 1] > 0.2 + 0.3
    assert op[1, 0] == pytest.approx(60.0)  # clamped at its right neighbour
    assert np.all(np.diff(op[:, 0]) >= 0), "the points left value order"

    # a click on empty space adds a point there, in order
    r = ed.plot_rect()
    QTest.mouseClick(ed, LEFT, NO_MOD, QPoint(int(r.left() + 0.2 * r.width()),
                                              int(r.bottom() - 0.7 * r.height())))
    op = ed.opacity_points()
    assert len(op) == 5 and op[1, 0] == pytest.approx(20.0, abs=1.0)
    assert op[1, 1] == pytest.approx(0.7, abs=0.05)

    # right-click removes it; Delete removes the selected one; two always stay
    QTest.mouseClick(ed, Qt.MouseButton.RightButton, NO_MOD, _pt(ed.point_position("opacity", 1)))
    assert len(ed.opacity_points()) == 4
    QTest.mouseClick(ed, LEFT, NO_MOD, _pt(ed.point_position("opacity", 3)))
    QTest.keyClick(ed, Qt.Key.Key_Delete)
    assert len(ed.opacity_points()) == 3
    for _ in range(3):
        QTest.mouseClick(ed, Qt.MouseButton.RightButton, NO_MOD,
                         _pt(ed.point_position("opacity", 0)))
    assert len(ed.opacity_points()) == 2

    # the colour bar: a double-click between markers adds one with the map's colour there,
    # a double-click on a marker asks for its colour
    bar = ed.bar_rect()
    QTest.mouseDClick(ed, LEFT, NO_MOD, QPoint(int(bar.center().x()), int(bar.center().y())))
    rgb = ed.rgb_points()
    assert len(rgb) == 3 and rgb[1, 0] == pytest.approx(50.0, abs=1.0)
    assert rgb[1, 1:] == pytest.approx([0.5, 0.5, 0.5], abs=0.02)
    monkeypatch.setattr(ed, "choose_color", lambda initial: QColor(255, 0, 0))
    QTest.mouseDClick(ed, LEFT, NO_MOD, _pt(ed.point_position("rgb", 1)))
    assert ed.rgb_points()[1, 1:] == pytest.approx([1.0, 0.0, 0.0])


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


def _show_panel(w):
    """The Volume rendering dock in front (it is tabbed with the Isosurface one)."""
    panel = w.volume_panel
    dock = panel.parentWidget()
    while dock is not None and not hasattr(dock, "toggleViewAction"):
        dock = dock.parentWidget()
    dock.show()
    dock.raise_()
    pump(5, lambda: panel.editor.isVisible() and panel.editor.width() > 100)
    return panel


def test_dragging_an_opacity_point_changes_the_picture(window, tmp_path):
    from splineviz.gui.undo import undo_stack
    from splineviz.model.session import load_scene, save_scene
    from splineviz.render.scene_view import render_scene

    w = window
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    vol = w.scene.volumes[0]
    for iso in w.scene.isosurfaces:
        iso.visible = False  # the volume rendering alone: its brightness is the opacity's
    panel = _show_panel(w)
    assert panel.node is vol
    panel.preset.setCurrentText("mri")
    panel.preset.activated.emit(panel.preset.currentIndex())
    panel.enabled.setChecked(True)
    assert pump(180, lambda: _settled(w) and w.spline_scene.volume_layers)
    before = _window_image(w)
    (layer,) = w.spline_scene.volume_layers
    alpha_before = w.spline_scene.shown_frame(layer).image[..., 3].astype(float)
    ed = panel.editor
    # mri's opacity: 0 up to 15 % of the range, 0.3 at 50 %, 0.8 at the top; the point of
    # the noise floor (15 %) is dragged to the top of the plot: the low values show too
    assert len(ed.opacity_points()) == 4
    start = _pt(ed.point_position("opacity", 1))
    end = QPoint(start.x(), int(ed.plot_rect().top()) + 1)
    steps_before = undo_stack(w.scene).stack.count()
    previews = []

    def previewed() -> bool:
        """The node holds the editor's points and the view shows a frame of them."""
        points, shown = vol.transfer_function_points, w.spline_scene.shown_frame(layer)
        return (points is not None and shown is not None and shown.state[2] == points
                and np.array_equal(np.array(points.opacity_points), ed.opacity_points()))

    def between():
        previews.append(pump(10, previewed) and ed.dragging)

    with StallMeter() as stall:
        _drag(ed, start, end, n=8, between=between)
        assert pump(180, lambda: _settled(w))
    assert stall.max_ms < STALL_GUARD_MS, f"the drag held the GUI thread {stall.max_ms:.0f} ms"
    points = vol.transfer_function_points
    assert points is not None, "the drag did not reach the model"
    assert np.array(points.opacity_points)[1, 1] > 0.95
    assert undo_stack(w.scene).stack.count() == steps_before + 1, "a drag is one undo step"
    assert previews and all(previews), "the view did not follow the dragged transfer " \
        f"function while the mouse moved (steps shown: {previews})"

    # the overlay the window shows over the scene: more opacity everywhere the rays meet
    # values above the noise floor, none where they met none
    after = _window_image(w)
    alpha_after = w.spline_scene.shown_frame(layer).image[..., 3].astype(float)
    covered_before, covered_after = (alpha_before > 25).mean(), (alpha_after > 25).mean()
    assert covered_after > covered_before + 0.02, \
        f"more opacity, no more covered picture ({covered_before:.1%} -> {covered_after:.1%})"
    assert alpha_after.mean() > alpha_before.mean() + 2.0
    assert np.all(alpha_after >= alpha_before - 2.0)
    assert _difference(after, before) > MEAN_TOL, "the picture did not change"
    size = w.spline_scene.window_size()
    diff = _difference(after, render_scene(w.scene, size)[..., :3])
    assert diff < MEAN_TOL, f"the window differs from render_scene by {diff:.2f} on average"

    # a session keeps the edit: the same points, the same picture
    path = save_scene(w.scene, tmp_path / "edited.svs")
    loaded = load_scene(path)
    assert loaded.volumes[0].transfer_function_points == points
    assert loaded.volumes[0].transfer_function == "mri"
    assert np.array_equal(render_scene(loaded, (160, 120)), render_scene(w.scene, (160, 120)))

    undo_stack(w.scene).undo()
    assert vol.transfer_function_points is None
    assert ed.opacity_points()[1, 1] == 0.0, "the editor kept the undone edit"


@pytest.mark.slow
def test_transfer_function_drag_on_bonsai_within_the_budget(window, shared_data):
    """Bonsai (256^3), volume rendered with ct-bone: each step of a drag of the opacity
    threshold is previewed, and the GUI thread's longest stall (the median of three drags)
    stays within the 100 ms budget."""
    from splineviz.bench.gui import MAX_STALL_MS

    w = window
    w.open_path(shared_data / "volumes" / "bonsai.vti", block=True)
    assert pump(300, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    vol = w.scene.volumes[0]
    for iso in w.scene.isosurfaces:
        iso.visible = False
    panel = _show_panel(w)
    panel.enabled.setChecked(True)
    assert pump(600, lambda: _settled(w) and w.spline_scene.volume_layers)
    (layer,) = w.spline_scene.volume_layers
    ed = panel.editor
    stalls = []
    for k in range(3):
        start = _pt(ed.point_position("opacity", 1))
        end = QPoint(start.x() + (-40 if k % 2 == 0 else 40), start.y())
        shown = []

        def between(shown=shown):
            shown.append(pump(30, lambda: (f := w.spline_scene.shown_frame(layer)) is not None
                              and f.state[2] == vol.transfer_function_points))

        with StallMeter() as stall:
            _drag(ed, start, end, n=10, between=between)
        stalls.append(stall.max_ms)
        assert all(shown), shown
        assert pump(600, lambda: _settled(w))
    print(f"transfer function drags on bonsai: longest stalls {stalls} ms")
    assert sorted(stalls)[1] < MAX_STALL_MS, stalls
