"""End to end under Xvfb: the four-up layout (View > Layout) on the shared tooth CT, driven
through the real interactors by Qt mouse and wheel events.

* each slice view shows the spline sampled on its slice and the exact isosurface contour:
  every contour vertex on the isosurface (within 1e-6 of the data range), on the slice, and
  drawn where the picture shows it in the isosurface's colour;
* the wheel moves a slice by one grid step (the picture changes), Ctrl + wheel zooms;
* a click in one view moves the crosshair: the other views' slices and the 3-D view's slice
  outlines follow; the probe and the ruler read the spline and world distances;
* the layouts show and hide the views.

The window stays open across the tests of this module.
"""

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import (  # noqa: E402  (tests/gui helper, on sys.path via pytest)
    LEFT,
    NO_BUTTON,
    drag_steps,
    mouse,
    pump,
    run_steps,
    wheel_step,
)
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt  # noqa: E402
from PySide6.QtGui import QWheelEvent  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

from splineviz.model.slices import AXES  # noqa: E402

ISO = 150.0


@pytest.fixture(scope="module")
def window(qapp, tmp_path_factory, shared_data):
    from PySide6.QtCore import QSettings

    from splineviz.gui.main_window import MainWindow

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope,
                      str(tmp_path_factory.mktemp("settings")))
    w = MainWindow()
    w.show()
    for dock in w.docks.values():
        dock.hide()
    w.resize(900, 700)
    w.open_path(shared_data / "volumes" / "tooth.nrrd", block=True)
    w.scene.isosurfaces[0].isovalue = ISO
    pump(0.3)
    # through the menu, as a user
    w.view_layout.actions[("four-up", None)].trigger()
    assert pump(30, lambda: w.view_layout.ready)
    settle(w)
    yield w
    w.wait_idle()
    w.close()
    pump(0.1)
    assert w.join_workers(30)


def settle(w) -> None:
    """Until every slice shows the newest result and has been drawn."""
    assert w.view_layout.slices.worker.wait(120)
    assert pump(10, lambda: not w.view_layout.slices.rendering)


def picture(view) -> np.ndarray:
    """The view's last frame, (H, W, 3) uint8, row 0 at the top."""
    view.plotter.render()
    return np.asarray(view.plotter.screenshot(None, return_img=True))[..., :3]


def qt_pos(view, display):
    """Widget pixel of a VTK display pixel (y up)."""
    return float(display[0]), float(view.plotter.height() - 1 - display[1])


def centre(view):
    return view.plotter.width() / 2.0, view.plotter.height() / 2.0


def test_four_up_shows_the_three_slices_beside_the_3d_view(window):
    lay = window.view_layout
    assert set(lay.views) == {"axial", "coronal", "sagittal"}
    assert window.view.plotter.isVisible()
    for view in lay.views.values():
        assert view.widget.isVisible() and view.result is not None
        assert view.widget.width() > 150 and view.widget.height() > 150
    # four quarters: the 3-D view and each slice about as large as the others
    sizes = [window.linked_views.splitter.size().toTuple()] + [
        v.widget.size().toTuple() for v in lay.views.values()]
    widths, heights = np.array(sizes).T
    assert widths.max() - widths.min() <= 0.1 * widths.max()
    assert heights.max() - heights.min() <= 0.1 * heights.max()
    # the 3-D view outlines the three slice planes through the crosshair
    marker = lay.slices.marker
    assert set(marker.outlines) == {"axial", "coronal", "sagittal"}
    for name, outline in marker.outlines.items():
        np.testing.assert_allclose(outline[:, AXES[name]], lay.state.crosshair[AXES[name]])


def test_the_contour_lies_on_the_isosurface_and_in_the_picture(window):
    lay = window.view_layout
    iso = window.scene.isosurfaces[0]
    vol = window.scene.volume_of(iso).active
    lo, hi = vol.finite_range
    spline = lay.slices.worker.spline(vol, iso.model,
                                      tuple(sorted(iso.model_options().items())))
    want = np.round(np.asarray(iso.color) * 255)
    for name, view in lay.views.items():
        result = view.result
        assert result.curves, f"the {name} slice through the tooth cuts its surface"
        pts = np.concatenate([c.points for c in result.curves])
        assert np.max(np.abs(spline.evaluate(pts) - ISO)) <= 1e-6 * (hi - lo)
        np.testing.assert_allclose(pts[:, AXES[name]], lay.state.position(name))
        # the image is the spline on the slice
        g = result.grid
        j, i = len(g.vs) // 2, len(g.us) // 3
        p = g.points()[j, i]
        assert result.values[j, i] == pytest.approx(spline.evaluate(p[None])[0])
        # drawn: near most vertices the picture has a pixel of the isosurface's colour
        img = picture(view)
        h, w = img.shape[:2]
        ua, va = g.axes
        seen = 0
        sample = pts[:: max(1, len(pts) // 200)]
        for q in sample:
            x, y = view.scene.plane_to_display(q[[ua, va]])
            r, c = int(round(h - 1 - y)), int(round(x))
            patch = img[max(r - 2, 0):r + 3, max(c - 2, 0):c + 3].reshape(-1, 3)
            seen += bool(np.any(np.abs(patch.astype(int) - want).max(axis=1) <= 40))
        assert seen >= 0.9 * len(sample), f"{name}: contour drawn at {seen}/{len(sample)}"



def test_each_contour_is_the_3d_clip_plane_cross_section(window):
    """A clip plane at each slice and its cross section (the curves the 3-D view draws for
    it): the same curves as the slice's contour, by length and vertex by vertex."""
    from splineviz.model import ClipPlaneNode
    from splineviz.model.analysis import section_curves

    lay = window.view_layout
    scene = window.scene
    iso = scene.isosurfaces[0]
    vol = scene.volume_of(iso)
    for name, view in lay.views.items():
        axis = AXES[name]
        origin = np.asarray(lay.state.crosshair, dtype=float)
        normal = np.zeros(3)
        normal[axis] = 1.0
        plane = scene.add(ClipPlaneNode(volume_id=vol.id, origin=tuple(origin),
                                        normal=tuple(normal), show_widget=False))
        section = scene.add_section(iso, plane)
        try:
            curves = section_curves(scene, section)
        finally:
            scene.remove(plane)
        mine = view.result.curves
        assert len(curves) == len(mine)
        assert sum(c.length for c in curves) == pytest.approx(sum(c.length for c in mine),
                                                              rel=1e-6)
        a = np.concatenate([c.points for c in curves])
        b = np.concatenate([c.points for c in mine])
        # the same seeding grid (the plane's origin differs only within the plane): the
        # same vertices
        assert len(a) == len(b)
        np.testing.assert_allclose(np.sort(a, axis=0), np.sort(b, axis=0), atol=1e-6)
    settle(window)

def test_wheel_scrolls_one_grid_step(window):
    lay = window.view_layout
    view = lay.views["axial"]
    vol = lay.slices.volume.active
    before = lay.state.crosshair
    img0 = picture(view)
    run_steps([lambda: wheel_step(view.widget, centre(view), 1)] * 3, 30)
    settle(window)
    after = lay.state.crosshair
    assert after[2] == pytest.approx(before[2] + 3 * vol.spacing[2])
    assert after[:2] == before[:2]
    assert view.result.grid.position == pytest.approx(after[2])
    # the coronal and sagittal views' crosshair (the axial trace) moved up with it
    assert lay.views["coronal"].scene.crosshair[1] == pytest.approx(after[2])
    assert np.abs(picture(view).astype(int) - img0).max() > 0
    run_steps([lambda: wheel_step(view.widget, centre(view), -1)], 30)
    settle(window)
    assert lay.state.crosshair[2] == pytest.approx(before[2] + 2 * vol.spacing[2])


def test_ctrl_wheel_zooms_and_leaves_the_slice(window):
    lay = window.view_layout
    view = lay.views["sagittal"]
    cam = view.plotter.renderer.GetActiveCamera()
    scale, point = cam.GetParallelScale(), lay.state.crosshair
    local = QPointF(*centre(view))
    event = QWheelEvent(local, view.widget.mapToGlobal(local), QPoint(0, 0), QPoint(0, 120),
                        NO_BUTTON, Qt.KeyboardModifier.ControlModifier,
                        Qt.ScrollPhase.NoScrollPhase, False)
    QApplication.sendEvent(view.widget, event)
    pump(0.1)
    assert cam.GetParallelScale() < scale
    assert lay.state.crosshair == point
    view.reset_camera()


def test_click_moves_the_crosshair_in_every_view(window):
    lay = window.view_layout
    axial = lay.views["axial"]
    z = lay.state.crosshair[2]
    target = axial.scene.plane_to_display((30.0, 60.0))
    pos = qt_pos(axial, target)
    run_steps([lambda: mouse(axial.widget, QEvent.Type.MouseButtonPress, pos, LEFT, LEFT),
               lambda: mouse(axial.widget, QEvent.Type.MouseButtonRelease, pos, LEFT,
                              NO_BUTTON)], 30)
    settle(window)
    x, y, z2 = lay.state.crosshair
    # one pixel of the view in world units
    px = 2.0 * axial.plotter.renderer.GetActiveCamera().GetParallelScale() \
        / axial.plotter.height()
    assert abs(x - 30.0) <= 1.5 * px and abs(y - 60.0) <= 1.5 * px and z2 == z
    assert lay.views["coronal"].result.grid.position == pytest.approx(y)
    assert lay.views["sagittal"].result.grid.position == pytest.approx(x)
    np.testing.assert_allclose(lay.slices.marker.outlines["sagittal"][:, 0], x)
    np.testing.assert_allclose(lay.slices.marker.outlines["coronal"][:, 1], y)
    # a drag in the coronal view moves x and z, and y stays
    cor = lay.views["coronal"]
    a = qt_pos(cor, cor.scene.plane_to_display((40.0, 70.0)))
    b = qt_pos(cor, cor.scene.plane_to_display((55.0, 90.0)))
    run_steps(drag_steps(cor.widget, [a, b]), 30)
    settle(window)
    x3, y3, z3 = lay.state.crosshair
    px = 2.0 * cor.plotter.renderer.GetActiveCamera().GetParallelScale() / cor.plotter.height()
    assert abs(x3 - 55.0) <= 1.5 * px and abs(z3 - 90.0) <= 1.5 * px and y3 == y
    assert lay.views["axial"].result.grid.position == pytest.approx(z3)


def test_probe_reads_the_spline_under_the_mouse(window):
    lay = window.view_layout
    view = lay.views["axial"]
    iso = window.scene.isosurfaces[0]
    spline = lay.slices.worker.spline(lay.slices.volume.active, iso.model,
                                      tuple(sorted(iso.model_options().items())))
    pos = qt_pos(view, view.scene.plane_to_display((50.0, 45.0)))
    mouse(view.widget, QEvent.Type.MouseMove, pos, NO_BUTTON, NO_BUTTON)
    pump(0.05)
    text = window.readout_label.text()
    point = view.scene.to_world(view._event_plane(), lay.state.position("axial"))
    value = spline.evaluate(point[None])[0]
    assert f"value {value:.5g}" in text and "gradient" in text


def test_ruler_measures_world_distance(window):
    lay = window.view_layout
    view = lay.views["coronal"]
    a = qt_pos(view, view.scene.plane_to_display((20.0, 30.0)))
    b = qt_pos(view, view.scene.plane_to_display((60.0, 60.0)))
    steps = drag_steps(view.widget, [a, b], modifiers=Qt.KeyboardModifier.ShiftModifier)
    run_steps(steps, 30)
    pump(0.1)
    ends = view.scene.ruler
    assert ends is not None
    length = float(np.linalg.norm(ends[1] - ends[0]))
    assert length == pytest.approx(50.0, abs=1.0)  # a 30-40-50 triangle, to a pixel
    assert f"ruler {length:.5g}" in window.readout_label.text()
    # the crosshair did not move with a ruler drag
    assert view.owner.state.crosshair[1] == pytest.approx(view.result.grid.position)
    # another coronal slice hides the ruler there (the 3-D view keeps it); back, it shows
    point = lay.state.crosshair
    lay.slices.scroll("coronal", 1)
    assert view.scene.ruler is None and lay.slices.marker.ruler is not None
    lay.state.crosshair = point
    assert view.scene.ruler is not None


def test_layouts_show_and_hide_the_views(window):
    lay = window.view_layout
    lay.actions[("one-slice", "coronal")].trigger()
    pump(0.2)
    assert lay.views["coronal"].widget.isVisible()
    assert not lay.views["axial"].widget.isVisible()
    assert not window.view.plotter.isVisible()
    lay.actions[("3d", None)].trigger()
    pump(0.2)
    assert window.view.plotter.isVisible()
    assert not any(v.widget.isVisible() for v in lay.views.values())
    assert lay.slices.marker.outlines == {}
    lay.actions[("four-up", None)].trigger()
    pump(0.2)
    assert all(v.widget.isVisible() for v in lay.views.values())
    settle(window)


def test_window_level_by_right_drag(window):
    lay = window.view_layout
    view = lay.views["axial"]
    w0, l0 = lay.state.window, lay.state.level
    c = centre(view)
    run_steps(drag_steps(view.widget, [c, (c[0] + 40, c[1])], button=Qt.MouseButton.RightButton),
              30)
    assert lay.state.window > w0 and lay.state.level == pytest.approx(l0)
    assert view.scene.image_property.GetColorWindow() == pytest.approx(lay.state.window)
    point = lay.state.crosshair
    lay.actions[("reset_window", None)].trigger()
    assert (lay.state.window, lay.state.level) == pytest.approx((w0, l0))
    assert lay.state.crosshair == point
    # a colour map from the menu: the picture changes from grey to colour
    assert view.scene.color_map == "gray"
    lay.actions[("color_map", "viridis")].trigger()
    assert view.scene.color_map == "viridis"
    img = picture(view).astype(int)
    assert np.abs(img[..., 0] - img[..., 1]).max() > 40
    lay.actions[("color_map", "gray")].trigger()


def test_double_click_in_the_3d_view_moves_the_crosshair_to_the_surface(window):
    lay = window.view_layout
    window.wait_for_refine(120)
    pump(0.2)
    view = window.view
    w, h = view.plotter.width(), view.plotter.height()
    hit, pos = None, None
    for fx, fy in ((0.5, 0.5), (0.45, 0.4), (0.55, 0.6), (0.5, 0.3)):
        pos = (fx * w, fy * h)
        hit = view.pick(*pos)
        if hit is not None:
            break
    assert hit is not None, "the tooth fills the middle of the 3-D view"
    mouse(view.plotter, QEvent.Type.MouseButtonDblClick, pos, LEFT, LEFT)
    settle(window)
    np.testing.assert_allclose(lay.state.crosshair, hit["position"], atol=1e-9)
    for name, view2 in lay.views.items():
        assert view2.result.grid.position == pytest.approx(hit["position"][AXES[name]])


def test_ruler_in_the_3d_view_between_two_surface_points(window):
    lay = window.view_layout
    window.wait_for_refine(120)
    pump(0.2)
    view = window.view
    w, h = view.plotter.width(), view.plotter.height()
    hits = []
    for fx, fy in ((0.5, 0.35), (0.45, 0.3), (0.5, 0.6), (0.55, 0.65), (0.5, 0.5)):
        hit = view.pick(fx * w, fy * h)
        if hit is not None:
            hits.append(((fx * w, fy * h), hit["position"]))
    assert len(hits) >= 2
    (p0, a), (p1, b) = hits[0], hits[-1]
    shift = Qt.KeyboardModifier.ShiftModifier
    mouse(view.plotter, QEvent.Type.MouseButtonDblClick, p0, LEFT, LEFT, shift)
    pump(0.05)
    crosshair = lay.state.crosshair
    mouse(view.plotter, QEvent.Type.MouseButtonDblClick, p1, LEFT, LEFT, shift)
    pump(0.1)
    np.testing.assert_allclose(lay.slices.marker.ruler, [a, b])
    length = float(np.linalg.norm(b - a))
    assert f"ruler {length:.5g}" in window.readout_label.text()
    assert lay.state.crosshair == crosshair  # a ruler end does not move the crosshair
    # a ruler drawn in a slice shows in the 3-D view too
    sag = lay.views["sagittal"]
    c = centre(sag)
    run_steps(drag_steps(sag.widget, [c, (c[0] + 30, c[1] + 20)], modifiers=shift), 30)
    np.testing.assert_allclose(lay.slices.marker.ruler, sag.scene.ruler)


def test_single_letters_do_nothing_in_a_slice_view(window):
    from PySide6.QtGui import QKeyEvent

    lay = window.view_layout
    view = lay.views["axial"]
    cam = view.plotter.renderer.GetActiveCamera()
    before = (cam.GetParallelProjection(), cam.GetParallelScale(), cam.GetPosition())
    for key, text in ((Qt.Key.Key_W, "w"), (Qt.Key.Key_R, "r"), (Qt.Key.Key_E, "e"),
                      (Qt.Key.Key_Q, "q")):
        for kind in (QEvent.Type.KeyPress, QEvent.Type.KeyRelease):
            QApplication.sendEvent(view.widget, QKeyEvent(kind, key, Qt.KeyboardModifier.NoModifier,
                                                          text))
    pump(0.1)
    assert (cam.GetParallelProjection(), cam.GetParallelScale(), cam.GetPosition()) == before
    assert view.widget.isVisible() and window.isVisible()


def test_a_camera_move_does_not_redraw_the_slice_planes(window, monkeypatch):
    """Every camera move reaches the slice views (the scene's ``changed``): neither the
    3-D view's slice planes nor the slices are redone for it."""
    lay = window.view_layout
    settle(window)
    calls = []
    monkeypatch.setattr(lay.slices.marker, "update", lambda *a: calls.append(a))
    monkeypatch.setattr(lay.slices.worker, "request", lambda *a: calls.append(a))
    cam = window.scene.camera
    x, y, z = cam.position
    cam.position = (x * 1.01, y, z)
    pump(0.2)
    assert calls == []
