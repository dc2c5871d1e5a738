"""What a drive of the real app found (issue 26), checked through the real window: the
isosurface panel after a session load, the slice-plane outlines in both halves of a split
view, the model box at 1280x800 and Open Recent for a file named on the command line."""

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import close_window, open_window, pump  # noqa: E402

from splineviz.core.volume import Volume  # noqa: E402


@pytest.fixture
def window(qapp, tmp_path):
    w = open_window(tmp_path / "settings")
    yield w
    close_window(w)
    assert w.join_workers(30)


def test_isosurface_panel_shows_the_loaded_sessions_isosurface(window, tmp_path):
    w = window
    panel = w.iso_panel
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    iso = w.scene.isosurfaces[0]
    iso.update(isovalue=float(np.mean(w.scene.volume_of(iso).active.finite_range)) * 0.9)
    saved = tmp_path / "s.svs"
    assert w.save_session(saved) is not None
    expected = iso.isovalue

    # another data set, selected, with a histogram of its own
    w.scene.clear()
    other = w.scene.add_volume(Volume(np.linspace(100.0, 200.0, 8**3).reshape(8, 8, 8)),
                               name="ramp", isovalue=150.0)
    w.scene.select(other)
    assert panel.histogram.range() == pytest.approx((100.0, 200.0))

    # with nothing selected: cleanly empty, nothing of the ramp left
    w.scene.select(None)
    w.scene.clear()
    assert panel.node is None and not panel.spin.isEnabled()
    assert panel.spin.text().strip() == ""
    assert not np.any(panel.histogram._counts)

    w.scene.mark_saved()
    w.open_path(saved, mode="replace", block=True)
    assert pump(60, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    assert w.scene.selected is None
    loaded = w.scene.isosurfaces[0]
    assert panel.node is loaded and panel.spin.isEnabled()
    assert panel.spin.value() == pytest.approx(expected, rel=1e-4)
    lo, hi = w.scene.volume_of(loaded).active.finite_range
    assert panel.histogram.range() == pytest.approx((lo, hi))


def _shown_labels(scene_view) -> list[list[str]]:
    grid = scene_view._grid
    out = []
    for i in range(3):
        arr = grid.GetAxisLabels(i)
        out.append([arr.GetValue(j) for j in range(arr.GetNumberOfValues())
                    if arr.GetValue(j)])
    return out


def test_tick_labels_thin_out_in_the_narrow_views_of_split_and_four_up(window):
    from splineviz.core.ticks import LABEL_CHAR_PX
    from splineviz.render.scene_view import grid_axis_px

    w = window
    w.resize(1280, 800)
    w.scene.add_volume(Volume(np.random.default_rng(1).random((11, 11, 11)),
                              spacing=(10.0,) * 3), name="box", isovalue=0.5)
    assert pump(60, lambda: not w.jobs.jobs)
    w.view.plotter.render()
    wide = _shown_labels(w.view.scene_view)
    w.scene.view.split = True
    w.view_layout.actions[("four-up", None)].trigger()
    assert pump(60, lambda: w.view2 is not None and not w.linked_views.opening
                and w.view_layout.ready)
    pump(0.5)
    for view in w.linked_views.views:
        view.plotter.render()
        sv = view.scene_view
        size = sv.plotter.renderer.GetSize()
        narrow = _shown_labels(sv)
        assert sum(map(len, narrow)) < sum(map(len, wide)), (size, narrow, wide)
        for labels in narrow:
            width = (max(map(len, labels)) + 2) * LABEL_CHAR_PX
            assert len(labels) <= max(2, grid_axis_px(*size) // width), (size, labels)


def test_slice_plane_outlines_show_in_both_halves_of_a_split_view(window):
    w = window
    lay = w.view_layout
    w.scene.add_volume(Volume(np.random.default_rng(2).random((12, 12, 12))), name="box",
                       isovalue=0.5)
    assert pump(60, lambda: not w.jobs.jobs)
    lay.actions[("four-up", None)].trigger()
    w.scene.view.split = True
    assert pump(60, lambda: w.view2 is not None and not w.linked_views.opening
                and lay.ready and bool(lay.slices.marker.outlines))
    marker = lay.slices.marker
    for view in w.linked_views.views:
        renderer = view.plotter.renderer
        assert renderer in marker.renderers
        actors = renderer.GetActors()
        lines = [actors.GetItemAsObject(i) for i in range(actors.GetNumberOfItems())]
        outline = [a for a in lines if a.GetVisibility() and a.GetMapper() is not None
                   and a.GetMapper().GetInput() is marker._lines]
        assert outline, "the slice planes are drawn in this half"
        assert outline[0].GetMapper().GetInput().GetNumberOfPoints() == 15
    # joined again: the right half's renderer is let go
    right = w.view2.plotter.renderer
    w.scene.view.split = False
    assert pump(30, lambda: w.view2 is None)
    assert right not in marker.renderers


def test_a_file_named_on_the_command_line_is_in_open_recent(qapp, tmp_path, monkeypatch):
    from PySide6.QtCore import QSettings
    from PySide6.QtWidgets import QApplication

    from splineviz.cli import main
    from splineviz.gui.main_window import MainWindow

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope,
                      str(tmp_path / "settings"))
    data = tmp_path / "cube.npy"
    x = np.linspace(-1, 1, 9)
    np.save(data, np.add.outer(np.add.outer(x**2, x**2), x**2))
    windows = []
    monkeypatch.setattr(MainWindow, "offer_recovery", lambda self: windows.append(self))

    def leave(_app):
        w = windows[-1]
        w.ask_before_closing = False
        pump(0.2)
        assert w.recent.menu.isEnabled()
        assert w.recent.files()[0] == str(data.absolute())
        w.close()
        return 0

    monkeypatch.setattr(QApplication, "exec", leave)
    assert main([str(data)]) == 0
    assert windows


def test_a_long_model_label_is_elided_in_the_box_and_whole_in_its_list(window):
    from PySide6.QtGui import QFontMetrics

    from splineviz.core.splines import MODELS
    from splineviz.gui.panels.isosurface import model_label

    w = window
    w.resize(1280, 800)
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    panel = w.iso_panel
    box = panel.model
    longest = max(MODELS, key=lambda n: len(model_label(n)))
    box.setItemText(box.findData(longest), model_label(longest) + " with a long name")
    box.fit_popup()
    box.setCurrentIndex(box.findData(longest))
    pump(0.2)
    whole = box.currentText()
    shown = box.displayed_text()
    metrics = QFontMetrics(box.font())
    assert metrics.horizontalAdvance(whole) > box.width() - 30, (box.width(), w.width())
    assert shown.endswith("…") and whole.startswith(shown[:-1])
    assert box.itemData(box.currentIndex(), 0x03) == whole  # tooltip: the whole label
    assert box.view().minimumWidth() >= metrics.horizontalAdvance(whole)


def test_labels_thinned_for_a_smaller_view_are_drawn_anew():
    """vtkCubeAxesActor keeps its label texts while the axis ranges stay: the labels of a
    view that narrowed over the same data must still be drawn thinned."""
    import pyvista as pv

    from splineviz.render.scene_view import label_grid

    pl = pv.Plotter(off_screen=True, window_size=(320, 320))
    pl.add_mesh(pv.Cube(center=(50, 50, 50), x_length=100, y_length=100, z_length=100))
    grid = pl.show_bounds(bounds=(0, 1, 0, 1, 0, 1), location="outer", ticks="outside",
                          font_size=10, minor_ticks=False, use_3d_text=False, render=False)
    bounds = ((0.0, 100.0),) * 3
    pictures = []
    for axis_px in (2000.0, 60.0, 2000.0):
        label_grid(grid, bounds, axis_px=axis_px)
        pl.render()
        pictures.append(pl.screenshot(return_img=True).astype(int))
    pl.close()
    assert np.abs(pictures[0] - pictures[1]).sum() > 0, "the thinned labels are drawn"
    assert np.abs(pictures[0] - pictures[2]).sum() == 0, "and the whole labels again"
