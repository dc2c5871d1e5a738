"""The analysis panel on a bare scene model: colour-by widgets write and follow the node,
cross sections are added, summarised and exported."""

import numpy as np
import pytest

pytest.importorskip("pytestqt")

import splineviz as sv  # noqa: E402
from splineviz.gui.panels import AnalysisPanel  # noqa: E402
from splineviz.model import Scene  # noqa: E402
from splineviz.model.analysis import section_curves  # noqa: E402


def test_colour_by_and_sections(qtbot, tmp_path):
    scene = Scene()
    vol = scene.add_volume(sv.Volume.from_function(
        lambda x, y, z: x * x + y * y + z * z, (24, 24, 24), ((-11.5, 11.5),) * 3), "sphere",
        isosurface=False)
    other = scene.add_volume(sv.Volume.from_function(
        lambda x, y, z: x + 0 * y, (5, 5, 5), ((-12, 12),) * 3), "x", isosurface=False)
    iso = scene.add_isosurface(vol, isovalue=64.75, model="cubic-c1")
    plane = scene.add_clip_plane((0, 0, 1.0), (0, 0, 1), volume=vol)
    panel = AnalysisPanel(scene)
    qtbot.addWidget(panel)
    assert not panel.field.isEnabled()
    scene.select(iso)
    assert panel.node is iso and panel.field.currentData() == "none"
    assert not panel.volume.isEnabled() and not panel.vmin.isEnabled()
    # widgets -> node
    panel.volume.setCurrentIndex(panel.volume.findData(other.id))
    panel.field.setCurrentIndex(panel.field.findData("volume"))
    assert iso.color_by == "volume" and iso.color_volume_id == other.id
    panel.cmap.setCurrentText("coolwarm")
    panel.range_mode.setCurrentText("manual")
    assert panel.vmin.isEnabled()
    panel.vmax.setValue(5.0)
    panel.vmin.setValue(-5.0)
    assert (iso.color_map, iso.color_range, iso.color_min, iso.color_max) == \
        ("coolwarm", "manual", -5.0, 5.0)
    # node -> widgets
    iso.update(color_by="mean", color_range="symmetric")
    assert panel.field.currentData() == "mean" and not panel.vmin.isEnabled()
    # a section with the plane: listed, summarised, exported
    assert panel.section_with.findData(plane.id) >= 0
    panel.section_with.setCurrentIndex(panel.section_with.findData(plane.id))
    sec = panel.add_cross_section()
    assert sec.plane_id == plane.id and panel.sections.count() == 1
    section_curves(scene, sec)  # the view computes them; no view here
    assert "closed, length 49.8712, area 197.92" in panel.summary.text()  # 2 pi r, pi r^2
    path = panel.export_curves(tmp_path / "curves.csv")
    table = np.genfromtxt(path, delimiter=",", names=True)
    assert np.allclose(table["z"], 1.0)
    scene.remove(plane)
    assert panel.sections.count() == 0
