"""The clipping panel and the plane widgets of the view.

Clip planes are :class:`~splineviz.model.ClipPlaneNode`\\ s: each cuts the isosurfaces of one
volume (the default when a volume is selected) or of the whole scene. The panel lists them;
:class:`PlaneWidgets` gives each a VTK plane widget in the view whose drags write the node,
and whose pose follows the node when it changes elsewhere (a session, the Flip button, undo).
Every edit is a step of the scene's undo stack (:mod:`splineviz.gui.undo`); a widget drag
is one step.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QHBoxLayout,
    QListWidget,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from splineviz.gui.undo import undo_stack
from splineviz.model import ClipPlaneNode, IsosurfaceNode, Scene, VolumeNode


class PlaneWidgets:
    """One ``vtkImplicitPlaneWidget`` per clip plane node, kept in step both ways."""

    def __init__(self, scene: Scene, plotter, request_render):
        self.scene = scene
        self.plotter = plotter
        self.request_render = request_render
        self.widgets: dict[str, object] = {}
        self._echo = False
        scene.inserted.connect(self._inserted)
        scene.removed.connect(self._removed)
        for node in scene.clip_planes:
            self._inserted(node)

    def _bounds(self, node: ClipPlaneNode):
        b = (self.scene.get(node.volume_id).bounds if node.volume_id
             else self.scene.bounds())
        return np.ravel(b if b is not None else ((-1, 1),) * 3)

    def _inserted(self, node) -> None:
        if not isinstance(node, ClipPlaneNode):
            return

        def moved(normal, origin, node=node):
            if self._echo or node.id not in self.scene:
                return
            self._echo = True
            try:
                undo_stack(self.scene).set(node, f"Move {node.name}",
                                           normal=tuple(map(float, normal)),
                                           origin=tuple(map(float, origin)))
            finally:
                self._echo = False

        widget = self.plotter.add_plane_widget(
            moved, normal=node.normal, origin=node.origin, bounds=self._bounds(node),
            normal_rotation=True, outline_translation=False, origin_translation=True,
            implicit=True, interaction_event="always", color="white", test_callback=False)
        undo = undo_stack(self.scene)
        widget.AddObserver("StartInteractionEvent", lambda *_: undo.begin_drag())
        widget.AddObserver("EndInteractionEvent", lambda *_: undo.end_drag())
        self.widgets[node.id] = widget
        self._apply(node)
        node.events.connect(self._changed)

    def _changed(self, info) -> None:
        node = info.signal.instance.instance  # the SignalGroup's owner
        if not self._echo and node.id in self.widgets:
            self._apply(node)
            self.request_render()

    def _apply(self, node: ClipPlaneNode) -> None:
        w = self.widgets[node.id]
        if not self._echo:
            w.SetNormal(node.normal)
            w.SetOrigin(node.origin)
        w.SetEnabled(int(node.show_widget and node.enabled))

    def _removed(self, node) -> None:
        w = self.widgets.pop(node.id, None)
        if w is None:
            return
        node.events.disconnect(self._changed)
        w.Off()
        widgets = self.plotter.widgets.plane_widgets
        if w in widgets:
            widgets.remove(w)

    def close(self) -> None:
        """Stop following the scene: the planes stay, their widgets go (a closed view's
        widgets must not hear of later moves)."""
        self.scene.inserted.disconnect(self._inserted)
        self.scene.removed.disconnect(self._removed)
        for node_id, w in list(self.widgets.items()):
            if node_id in self.scene:
                self.scene.get(node_id).events.disconnect(self._changed)
            w.Off()
        self.widgets.clear()


class ClippingPanel(QWidget):
    """List of clip planes with Add / Remove / Flip and widget visibility."""

    def __init__(self, scene: Scene, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.list = QListWidget()
        self.list.setToolTip("Clip planes: each keeps the side its normal points to")
        self.target = QComboBox()
        self.target.setToolTip("What a new plane cuts: the selected volume's isosurfaces or "
                               "every isosurface of the scene")
        self.target.addItems(["selected volume", "all isosurfaces"])
        self.add_button = QPushButton("Add")
        self.add_button.setToolTip("A plane through the centre of the data, normal +X")
        self.remove_button = QPushButton("Remove")
        self.remove_button.setToolTip("Remove the selected plane")
        self.flip_button = QPushButton("Flip")
        self.flip_button.setToolTip("Keep the other side of the selected plane")
        self.show_widgets = QCheckBox("Show plane widgets")
        self.show_widgets.setChecked(True)
        self.show_widgets.setToolTip("Drag a widget's plane to move it, its arrow to turn it")
        lay = QVBoxLayout(self)
        lay.addWidget(self.list)
        lay.addWidget(self.target)
        row = QHBoxLayout()
        for b in (self.add_button, self.remove_button, self.flip_button):
            row.addWidget(b)
        lay.addLayout(row)
        lay.addWidget(self.show_widgets)
        self._ids: list[str] = []
        self.add_button.clicked.connect(lambda: self.add_plane())
        self.remove_button.clicked.connect(self.remove_plane)
        self.flip_button.clicked.connect(self.flip_plane)
        self.show_widgets.toggled.connect(self._toggle_widgets)
        self.list.currentRowChanged.connect(self._row_selected)
        scene.inserted.connect(self._refill)
        scene.removed.connect(self._refill)
        self._refill()

    def _refill(self, *_args) -> None:
        row = self.list.currentRow()
        self.list.blockSignals(True)
        self.list.clear()
        self._ids = []
        for p in self.scene.clip_planes:
            owner = self.scene.get(p.volume_id).name if p.volume_id else "all"
            o = ", ".join(f"{v:.3g}" for v in p.origin)
            n = ", ".join(f"{v:.2f}" for v in p.normal)
            self.list.addItem(f"{p.name} [{owner}]  origin ({o})  normal ({n})")
            self._ids.append(p.id)
            p.events.connect(self._plane_changed, unique=True)
        self.list.setCurrentRow(min(max(row, 0), len(self._ids) - 1))
        self.list.blockSignals(False)
        for b in (self.remove_button, self.flip_button):
            b.setEnabled(bool(self._ids))

    def _plane_changed(self, info) -> None:
        if info.signal.name in ("origin", "normal", "name"):
            self._refill()

    def _row_selected(self, row: int) -> None:
        if 0 <= row < len(self._ids):
            self.scene.select(self._ids[row])

    def current(self) -> ClipPlaneNode | None:
        sel = self.scene.selected
        if isinstance(sel, ClipPlaneNode):
            return sel
        row = self.list.currentRow()
        return self.scene.get(self._ids[row]) if 0 <= row < len(self._ids) else None

    def _selected_volume(self) -> VolumeNode | None:
        sel = self.scene.selected
        if isinstance(sel, IsosurfaceNode):
            return self.scene.volume_of(sel)
        if isinstance(sel, VolumeNode):
            return sel
        if isinstance(sel, ClipPlaneNode) and sel.volume_id:
            return self.scene.get(sel.volume_id)
        vols = self.scene.volumes
        return vols[-1] if len(vols) == 1 else None

    def add_plane(self, origin=None, normal=(1.0, 0.0, 0.0)) -> ClipPlaneNode:
        volume = self._selected_volume() if self.target.currentIndex() == 0 else None
        show = self.show_widgets.isChecked()

        def add():
            node = self.scene.add_clip_plane(origin, normal, volume=volume, show_widget=show)
            self.scene.select(node)
            return node

        return undo_stack(self.scene).change("Add clip plane", add)

    def remove_plane(self) -> None:
        node = self.current()
        if node is not None:
            undo_stack(self.scene).remove(node)

    def flip_plane(self) -> None:
        node = self.current()
        if node is not None:
            undo_stack(self.scene).set(node, f"Flip {node.name}",
                                       normal=tuple(-v for v in node.normal))

    def _toggle_widgets(self, on: bool) -> None:
        def show():
            for p in self.scene.clip_planes:
                p.show_widget = on

        undo_stack(self.scene).change("Show plane widgets" if on else "Hide plane widgets",
                                      show)
