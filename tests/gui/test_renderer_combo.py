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
    iso.model = "to-quadratic"                                    # node -> note
    assert panel.renderer_note.isVisibleTo(panel)
    assert "'to-quadratic' is ray cast" in panel.renderer_note.text()
