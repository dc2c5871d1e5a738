"""The renderer box of the isosurface panel (issue 32): it writes the node through the undo
stack, follows the node, and the view then draws the surface by cell projection."""

import numpy as np
import pytest

pytest.importorskip("pytestqt")

from splineviz.gui.jobs import JobRunner  # noqa: E402
from splineviz.gui.panels import IsosurfacePanel  # noqa: E402
from splineviz.gui.undo import undo_stack  # noqa: E402
from splineviz.model.opening import default_scene  # noqa: E402


def test_the_renderer_box_writes_the_node_undoably_and_the_scene_draws_it(qtbot):
    from splineviz.render.scene_view import OffscreenRenderer

    scene = default_scene()
    iso = scene.isosurfaces[0]
    panel = IsosurfacePanel(scene, JobRunner())
    qtbot.addWidget(panel)
    scene.select(iso)
    box = panel.renderer
    assert [box.itemData(i) for i in range(box.count())] == ["auto", "ray-casting",
                                                             "cell-projection"]
    assert box.itemText(2) == "cell projection (OpenGL)" and box.currentData() == "auto"
    undo = undo_stack(scene)
    steps = undo.stack.index()
    box.setCurrentIndex(box.findData("cell-projection"))          # widget -> node
    assert iso.renderer == "cell-projection" and undo.stack.index() == steps + 1
    assert not panel.renderer_note.isVisibleTo(panel)  # cubic C1: drawn as chosen
    with OffscreenRenderer(scene, (96, 72)) as r:
        (_pl, view), = r._views
        picture = r.render()
        assert view.spline_scene.drawn_by_cells(view.layers[iso.id])
    assert len(np.unique(picture.reshape(-1, 3), axis=0)) > 20  # a shaded surface
    undo.undo()                                                   # undo -> node -> widget
    assert iso.renderer == "auto" and box.currentData() == "auto"
    undo.redo()
    assert box.currentData() == "cell-projection"
    iso.model = "to-quadratic"                # drawn by cell projection too: no note
    assert not panel.renderer_note.isVisibleTo(panel)
    iso.model = "trilinear"                                       # node -> note
    assert panel.renderer_note.isVisibleTo(panel)
    assert "'trilinear' is ray cast" in panel.renderer_note.text()




def test_the_window_draws_the_surface_by_cell_projection_once_chosen(window, qtbot):
    # the whole window: the box in the panel, the refine worker that makes the tets, the
    # view that draws them, and the same picture as the ray caster's
    vol = window.open_default()
    iso = window.scene.isosurfaces_of(vol)[0]
    window.scene.select(iso)
    for v in window.scene.volumes:
        v.show_outline = False
    window.scene.view.show_scale = False
    window.scene.view.show_axes = False
    window.wait_for_refine()
    layer = window.view.scene_view.layers[iso.id]
    ss = window.spline_scene
    assert not ss.drawn_by_cells(layer) and ss.shown_frame(layer).final
    window.plotter.render()
    ray_cast = np.asarray(window.plotter.screenshot(return_img=True)).astype(int)
    box = window.iso_panel.renderer
    box.setCurrentIndex(box.findData("cell-projection"))
    window.wait_for_refine()
    window.plotter.render()
    assert ss.drawn_by_cells(layer) and not ss.needs_refine()
    cells = np.asarray(window.plotter.screenshot(return_img=True)).astype(int)
    qtbot.waitUntil(lambda: "cell projection" in window.cells_label.text(), timeout=10000)
    differ = np.abs(ray_cast - cells).max(axis=2) > 2
    assert (ray_cast != ray_cast[0, 0]).any(axis=2).mean() > 0.05  # the surface is there
    assert differ.mean() < 0.005, differ.mean()
    box.setCurrentIndex(box.findData("ray-casting"))                # and back
    window.wait_for_refine()
    assert not ss.drawn_by_cells(layer) and ss.shown_frame(layer).final
