"""Sessions keep the window's layout (3-D only / four-up / one slice) and the crosshair of
the slice views (issue 26): saved from the real window after View > Layout and a wheel turn
over a slice, restored by loading the session; a scene that never showed the slices saves
the document it saved before these fields existed."""

import json

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import close_window, open_window, pump, wheel  # noqa: E402

from splineviz.core.volume import Volume  # noqa: E402
from splineviz.model.slices import IN_PLANE  # noqa: E402


@pytest.fixture
def window(qapp, tmp_path):
    w = open_window(tmp_path / "settings")
    yield w
    close_window(w)
    assert w.join_workers(30)


def _view_entry(path) -> dict:
    return json.loads(path.read_text())["views"][0]


def _settled(w) -> bool:
    slices = w.view_layout.slices
    return (w.view_layout.ready and not slices.rendering and not slices.worker.busy
            and not w.jobs.jobs)


def test_layout_and_crosshair_are_saved_and_restored(window, tmp_path):
    w = window
    lay = w.view_layout
    w.open_default()
    assert pump(120, lambda: bool(w.scene.isosurfaces) and not w.jobs.jobs)
    assert pump(10, lambda: lay.slices.volume is not None)

    plain = tmp_path / "plain.svs"
    assert w.save_session(plain) is not None
    entry = _view_entry(plain)
    assert not {"slice_layout", "slice_single", "crosshair"} & set(entry)

    lay.actions[("four-up", None)].trigger()
    assert pump(60, lambda: _settled(w))
    axial = lay.views["axial"].widget
    centre = lay.state.crosshair
    wheel(axial, (axial.width() / 2, axial.height() / 2), clicks=2)
    assert pump(10, lambda: lay.state.crosshair != centre)
    moved = lay.state.crosshair
    assert w.scene.view.crosshair == pytest.approx(moved)

    four_up = tmp_path / "four-up.svs"
    assert w.save_session(four_up) is not None
    entry = _view_entry(four_up)
    assert entry["slice_layout"] == "four-up"
    assert entry["crosshair"] == pytest.approx(list(moved))

    # elsewhere (one slice of a volume 100 times as big), then the session brings the
    # layout and the crosshair back
    lay.actions[("one-slice", "sagittal")].trigger()
    big = Volume(np.random.default_rng(0).random((20, 20, 20)), spacing=(10.0,) * 3)
    w.scene.clear()
    w.scene.add_volume(big, name="big", isovalue=0.5)
    assert pump(30, lambda: lay.slices.volume is not None
                and lay.slices.volume.active is big and not lay.slices._refresh_timer.isActive())
    lay.slices.scroll("sagittal", 3)
    assert lay.state.crosshair != moved
    w.scene.mark_saved()
    w.open_path(four_up, mode="replace", block=True)
    assert pump(60, lambda: lay.state.layout == "four-up" and _settled(w)
                and lay.slices.volume is not None and lay.slices.volume.active is not big
                and lay.state.crosshair == pytest.approx(moved))
    assert lay.actions[("four-up", None)].isChecked()
    assert set(lay.views) == {"axial", "coronal", "sagittal"}
    assert all(lay.views[n].widget.isVisible() for n in ("axial", "coronal", "sagittal"))
    # the crosshair's lines span the restored volume's box, not the big one's or a tick
    bounds = np.asarray(lay.slices.volume.active.bounds)
    for name, view in lay.views.items():
        u, v = IN_PLANE[name]
        lines = np.asarray(view.scene._cross_mapper.GetInput().GetBounds()).reshape(3, 2)
        assert lines[0] == pytest.approx(bounds[u]) and lines[1] == pytest.approx(bounds[v])
    pump(0.3)
    assert not w.scene.modified, "loading the session left unsaved changes"

    # a session without a layout shows the 3-D view alone
    w.open_path(plain, mode="replace", block=True)
    assert pump(60, lambda: lay.state.layout == "3d" and not w.jobs.jobs)
    assert not any(v.widget.isVisible() for v in lay.views.values())
