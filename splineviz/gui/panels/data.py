"""The data panel: every object of the scene in a tree, with visibility check boxes (like
ParaView's pipeline browser). A view of the scene model: it rebuilds on insert/remove and
updates a row when its node changes; selecting a row selects the node in the scene. Ticks
and removals are steps of the scene's undo stack (:mod:`splineviz.gui.undo`)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QHBoxLayout,
    QPushButton,
    QTreeWidget,
    QTreeWidgetItem,
    QVBoxLayout,
    QWidget,
)

from splineviz.gui.undo import undo_stack
from splineviz.model import (
    ClipPlaneNode,
    IsosurfaceNode,
    MeshNode,
    Node,
    PointsNode,
    Scene,
    VolumeNode,
)

#: node fields shown in the tree (a change of another field needs no update)
_SHOWN = {"name", "visible", "enabled", "isovalue", "model", "sigma", "data", "origin",
          "normal", "vertices", "series", "time_index"}


def describe(node: Node) -> str:
    """The "Info" column of a node."""
    if isinstance(node, VolumeNode):
        text = "x".join(map(str, node.data.shape)) if node.data is not None else ""
        if node.series is not None:  # time-varying: which step of how many
            text += f", step {node.time_index + 1}/{len(node.series)}"
        return text + (f", smoothed {node.sigma:g}" if node.sigma else "")
    if isinstance(node, IsosurfaceNode):
        return f"{node.model} @ {node.isovalue:.4g}"
    if isinstance(node, PointsNode):
        return f"{len(node.data):,} points" if node.data is not None else ""
    if isinstance(node, MeshNode):
        return f"{len(node.faces):,} triangles" if node.faces is not None else ""
    if isinstance(node, ClipPlaneNode):
        n = ", ".join(f"{v:.2f}" for v in node.normal)
        return f"normal ({n})" + ("" if node.volume_id else ", all surfaces")
    return ""


class DataPanel(QWidget):
    """Tree of the scene's objects (see module docstring)."""

    def __init__(self, scene: Scene, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.tree = QTreeWidget()
        self.tree.setHeaderLabels(["Object", "Info"])
        self.tree.setColumnWidth(0, 170)
        self.tree.setToolTip("Loaded objects: tick to show or hide, select to edit in the "
                             "panels, Delete to remove")
        self.remove_button = QPushButton("Remove")
        self.remove_button.setToolTip("Remove the selected object (a volume takes its "
                                      "isosurfaces and clip planes with it)")
        lay = QVBoxLayout(self)
        lay.addWidget(self.tree)
        row = QHBoxLayout()
        row.addWidget(self.remove_button)
        row.addStretch(1)
        lay.addLayout(row)
        self._rows: dict[str, QTreeWidgetItem] = {}
        self._updating = False
        self.tree.itemChanged.connect(self._checked)
        self.tree.currentItemChanged.connect(self._current_changed)
        self.remove_button.clicked.connect(self.remove_selected)
        scene.inserted.connect(self._structure_changed)
        scene.removed.connect(self._structure_changed)
        scene.selection.connect(self._select_row)
        self.rebuild()

    def rebuild(self) -> None:
        self._updating = True
        try:
            self.tree.clear()
            self._rows.clear()
            for node in self.scene:
                parent_id = getattr(node, "volume_id", None)
                parent = self._rows.get(parent_id) if parent_id else None
                row = QTreeWidgetItem([node.name, describe(node)])
                row.setToolTip(0, node.name)
                row.setToolTip(1, describe(node))
                row.setFlags(row.flags() | Qt.ItemFlag.ItemIsUserCheckable)
                row.setData(0, Qt.ItemDataRole.UserRole, node.id)
                row.setCheckState(0, self._check_state(node))
                (parent.addChild(row) if parent is not None
                 else self.tree.addTopLevelItem(row))
                self._rows[node.id] = row
                node.events.connect(self._node_changed, unique=True)
            self.tree.expandAll()
            # the names whole (a fixed width cut them at 1280x800); the info gets the rest
            # and, where it is cut still, its tooltip
            self.tree.resizeColumnToContents(0)
            self.tree.setColumnWidth(0, min(self.tree.columnWidth(0) + 8,
                                            max(120, int(0.6 * self.tree.viewport().width()))))
            if self.scene.selected is not None and self.scene.selected.id in self._rows:
                self.tree.setCurrentItem(self._rows[self.scene.selected.id])
        finally:
            self._updating = False

    @staticmethod
    def _check_state(node: Node):
        on = node.enabled if isinstance(node, ClipPlaneNode) else node.visible
        return Qt.CheckState.Checked if on else Qt.CheckState.Unchecked

    def _structure_changed(self, node: Node) -> None:
        if node.id not in self.scene:
            node.events.disconnect(self._node_changed)
        self.rebuild()

    def _node_changed(self, info) -> None:
        if info.signal.name not in _SHOWN:
            return
        node = info.signal.instance.instance  # the SignalGroup's owner
        row = self._rows.get(node.id)
        if row is None:
            return
        self._updating = True
        try:
            row.setText(0, node.name)
            row.setText(1, describe(node))
            row.setToolTip(0, node.name)
            row.setToolTip(1, describe(node))
            row.setCheckState(0, self._check_state(node))
        finally:
            self._updating = False

    def _checked(self, row, column) -> None:
        if self._updating or column != 0:
            return
        node = self.scene.get(row.data(0, Qt.ItemDataRole.UserRole))
        on = row.checkState(0) == Qt.CheckState.Checked
        field = "enabled" if isinstance(node, ClipPlaneNode) else "visible"
        undo_stack(self.scene).set(node, f"{'Show' if on else 'Hide'} {node.name}",
                                   **{field: on})

    def _current_changed(self, row, _previous) -> None:
        if self._updating:
            return
        node_id = None if row is None else row.data(0, Qt.ItemDataRole.UserRole)
        self.scene.select(node_id if node_id in self.scene else None)

    def _select_row(self, node) -> None:
        row = None if node is None else self._rows.get(node.id)
        if row is not None and self.tree.currentItem() is not row:
            self._updating = True
            self.tree.setCurrentItem(row)
            self._updating = False

    def remove_selected(self) -> None:
        if self.scene.selected is not None:
            undo_stack(self.scene).remove(self.scene.selected)

    def keyPressEvent(self, event):  # noqa: N802 (Qt naming)
        if event.key() == Qt.Key.Key_Delete:
            self.remove_selected()
        else:
            super().keyPressEvent(event)
