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
