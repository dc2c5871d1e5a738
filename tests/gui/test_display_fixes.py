"""Display fixes of issue 26 part 6 through the real window (pytest-xvfb): only the
documented single keys act in the view; the window's first size and the remembered one."""

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvista")

import splineviz as sv  # noqa: E402
from splineviz.gui import window_state  # noqa: E402
from splineviz.gui.main_window import MainWindow  # noqa: E402


def _camera(w):
    c = w.scene.camera
    return np.array([*c.position, *c.focal_point, *c.view_up])


def test_vtk_letters_do_nothing_and_the_documented_keys_work(window, qtbot):
    vol = window.scene.add_volume(sv.Volume(np.random.default_rng(0).random((8, 8, 8))), "v",
                                  isovalue=0.5, model="trilinear")
    window.scene.select(vol)
    window.scene.frame(view="-Y")
    window.wait_for_refine()
    actors = list(window.plotter.renderer.GetActors())
    looks = [a.GetProperty().GetRepresentation() for a in actors]
    before = _camera(window)
    for letter in "wsfpjt3e":
        qtbot.keyClick(window.plotter, letter)
    window.wait_idle()
    assert [a.GetProperty().GetRepresentation() for a in actors] == looks  # no wireframe
    np.testing.assert_allclose(_camera(window), before)
    assert window.isVisible()
    qtbot.keyClick(window.plotter, "v")
    iso_view = _camera(window)
    window.scene.frame(view="isometric")
    np.testing.assert_allclose(iso_view, _camera(window))
    window.scene.camera.position = tuple(np.add(window.scene.camera.position, (3.0, 1.0, 0.0)))
    qtbot.keyClick(window.plotter, "r")
    reset = _camera(window)
    window.scene.frame()
    np.testing.assert_allclose(reset, _camera(window))


def test_the_first_opening_takes_85_percent_of_the_screen_at_most():
    from PySide6.QtCore import QRect

    rect = window_state.first_geometry(QRect(0, 0, 1600, 1000), 900, 600)
    assert (rect.width(), rect.height()) == (1360, 850)
    assert (rect.x(), rect.y()) == (120, 75)
    big = window_state.first_geometry(QRect(0, 0, 1280, 800), 1500, 900)
    assert (big.width(), big.height()) == (1280, 800)


def test_size_position_and_docks_are_remembered(window, qtbot, tmp_path):
    window.resize(window.minimumSizeHint().width() + 37, window.minimumSizeHint().height() + 23)
    window.docks["Isosurface"].hide()
    qtbot.wait(50)
    size = (window.width(), window.height())
    window_state.remember(window)
    again = MainWindow(size=(160, 120))
    qtbot.addWidget(again)
    assert window_state.restore_geometry(again)
    again.show()
    qtbot.waitExposed(again)
    window_state.restore_layout(again)
    qtbot.waitUntil(lambda: not again.docks["Isosurface"].isVisible())
    assert (again.width(), again.height()) == size
    again.wait_idle()
    again.close()


def test_dock_tabs_show_whole_titles_at_1280x800(window, qtbot):
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QTabBar

    window.resize(int(0.85 * 1280), int(0.85 * 800))  # the first opening on that screen
    qtbot.wait(50)
    window._size_docks()
    qtbot.wait(50)
    bars = [b for b in window.findChildren(QTabBar) if b.isVisible()]
    assert bars
    for bar in bars:
        assert bar.elideMode() == Qt.TextElideMode.ElideNone
        assert bar.width() >= bar.sizeHint().width(), [bar.tabText(i) for i in range(bar.count())]
    # a tab bar made later (a dock dragged onto another) gets the same settings
    window.tabifyDockWidget(window.docks["Data"], window.docks["Log"])
    window.docks["Log"].show()
    qtbot.wait(50)
    assert all(b.elideMode() == Qt.TextElideMode.ElideNone
               for b in window.findChildren(QTabBar))
