"""Panels as views of a bare scene model (qtbot, no main window, no VTK view): widgets show
the selected node, write it, and follow its changes."""

import numpy as np
import pytest

pytest.importorskip("pytestqt")

import splineviz as sv  # noqa: E402
from splineviz.core.splines import MODELS  # noqa: E402
from splineviz.gui.jobs import JobRunner  # noqa: E402
from splineviz.gui.panels import (  # noqa: E402
    ClippingPanel,
    DataPanel,
    IsosurfacePanel,
    SmoothingPanel,
)
from splineviz.model import Scene  # noqa: E402


def sphere_scene():
    x = np.linspace(-1, 1, 11)
    scene = Scene()
    vol = scene.add_volume(sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2),
                                     spacing=0.2, origin=(-1, -1, -1)), "sphere", isovalue=0.5,
                           model="trilinear")
    return scene, vol, scene.isosurfaces[0]


def test_isosurface_panel_shows_writes_and_follows_its_node(qtbot):
    scene, vol, iso = sphere_scene()
    panel = IsosurfacePanel(scene, JobRunner())
    qtbot.addWidget(panel)
    assert not panel.spin.isEnabled()  # nothing selected yet
    scene.select(iso)
    assert panel.node is iso and panel.spin.value() == pytest.approx(0.5)
    assert [panel.model.itemData(i) for i in range(panel.model.count())] == list(MODELS)
    panel.spin.setValue(0.8)                       # widget -> node
    assert iso.isovalue == pytest.approx(0.8)
    iso.update(isovalue=0.3, model="cubic-c1", opacity=0.5, material="shiny")  # node -> widgets
    assert panel.spin.value() == pytest.approx(0.3)
    assert panel.histogram.value() == pytest.approx(0.3)
    assert panel.model.currentData() == "cubic-c1"
    assert panel.opacity.value() == pytest.approx(0.5) and panel.material.currentText() == "shiny"
    assert panel.k.isHidden()
    panel.model.setCurrentIndex(panel.model.findData("to-quadratic"))
    assert iso.model == "to-quadratic" and not panel.k.isHidden()
    panel.add_button.click()                       # a second isosurface, selected
    assert len(scene.isosurfaces) == 2 and panel.node is scene.isosurfaces[1]
    scene.remove(vol)                              # nothing stale is shown
    assert panel.node is None and not panel.spin.isEnabled()


def test_data_panel_tree_follows_the_scene(qtbot):
    scene, vol, iso = sphere_scene()
    panel = DataPanel(scene)
    qtbot.addWidget(panel)
    top = panel.tree.topLevelItem(0)
    assert top.text(0) == "sphere" and top.child(0).text(1) == "trilinear @ 0.5"
    iso.isovalue = 0.25
    assert top.child(0).text(1) == "trilinear @ 0.25"
    from PySide6.QtCore import Qt

    top.child(0).setCheckState(0, Qt.CheckState.Unchecked)   # tick box -> node
    assert iso.visible is False
    panel.tree.setCurrentItem(top.child(0))                  # selection -> scene
    assert scene.selected is iso
    plane = scene.add_clip_plane(volume=vol)
    assert panel.tree.topLevelItem(0).childCount() == 2
    scene.select(plane)
    panel.remove_selected()
    assert plane.id not in scene and panel.tree.topLevelItem(0).childCount() == 1


def test_clipping_and_smoothing_panels_edit_the_selected_volume(qtbot):
    scene, vol, iso = sphere_scene()
    clip, smooth = ClippingPanel(scene), SmoothingPanel(scene)
    qtbot.addWidget(clip)
    qtbot.addWidget(smooth)
    scene.select(iso)
    plane = clip.add_plane()
    assert plane.volume_id == vol.id and clip.list.count() == 1
    clip.flip_plane()
    assert plane.normal == (-1.0, 0.0, 0.0)
    clip.target.setCurrentIndex(1)                  # "all isosurfaces"
    assert clip.add_plane().volume_id is None
    scene.select(vol)
    smooth.sigma.setValue(1.25)
    smooth.apply()
    assert vol.sigma == 1.25 and vol.smoothing_pending  # the Smoother (not here) makes it
    smooth.reset()
    assert vol.sigma == 0.0
