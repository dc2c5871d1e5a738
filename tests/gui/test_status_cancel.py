"""The status bar's Cancel button stops what Esc stops: the running jobs and the exact frames
the views compute (issue 26). A plugin model whose evaluation sleeps keeps an exact frame
under way for as long as the test needs."""

import pytest

pytest.importorskip("pytestqt")

from interaction import close_window, open_window, pump  # noqa: E402
from sleeping_model import RELEASE, sleeping_model  # noqa: E402


@pytest.fixture
def window(qapp, tmp_path):
    with sleeping_model("Sleeping test model", 300.0) as name:
        w = open_window(tmp_path)
        w.slow_model = name
        yield w
        RELEASE.set()  # the stuck worker ends, so the window closes at once
        close_window(w)


def test_cancel_button_stops_the_exact_frames_under_way(window):
    w = window
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    assert pump(120, lambda: not w.view.refining and not w.spline_scene.needs_refine())
    assert not w.cancel_button.isVisible()  # nothing to cancel

    w.scene.isosurfaces[0].model = w.slow_model
    assert pump(10, lambda: w.view.computing)
    # no job runs: the button shows for the frames alone
    assert not w.jobs.jobs
    assert pump(2, lambda: w.cancel_button.isVisible() and w.cancel_button.isEnabled())

    w.cancel_button.click()
    assert pump(1.0, lambda: not w.view.refining)
    assert "cancelled" in w.view.overlay.text
    assert pump(1.0, lambda: not w.cancel_button.isVisible())
    pump(0.5)
    assert not w.view.computing, "a cancelled frame was started again by itself"


def test_a_cancelled_cell_projected_frame_says_the_stand_in_shows(qapp, tmp_path, monkeypatch):
    """Without a fast OpenGL, a cell-projected surface shows its trilinear stand-in until the
    exact frame is drawn off the GUI thread; cancelling that frame says so in the overlay."""
    import threading

    from splineviz.render.isosurface import IsosurfaceLayer

    release = threading.Event()
    original = IsosurfaceLayer.cell_frame

    def slow(self, view):
        release.wait(60)
        return original(self, view)

    w = open_window(tmp_path)
    try:
        w.open_default()
        w.scene.isosurfaces[0].renderer = "cell-projection"
        assert pump(120, lambda: not w.view.refining and not w.spline_scene.needs_refine())
        monkeypatch.setattr(IsosurfaceLayer, "cell_frame", slow)
        w.spline_scene.cells_seconds = 1.0  # a slow OpenGL, whatever this machine's
        w.plotter.camera.Azimuth(30)
        w.plotter.render()
        assert pump(10, lambda: w.view.computing)
        layer = w.spline_scene.layers[0]
        assert w.spline_scene.shows_stand_in(layer)
        w.cancel_button.click()
        assert pump(1.0, lambda: not w.view.refining)
        text = w.view.overlay.text
        assert "cancelled" in text and "trilinear stand-in" in text, text
    finally:
        release.set()
        close_window(w)
