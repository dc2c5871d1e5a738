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
