"""A panel that edits the selected volume: selecting one of its isosurfaces selects it too."""

from __future__ import annotations

from PySide6.QtWidgets import QWidget

from splineviz.model import IsosurfaceNode, VolumeNode


class VolumePanel(QWidget):
    """Base of the panels that show one :class:`~splineviz.model.VolumeNode` (``self.node``);
    a panel defines ``_show(*args)``, its redraw whenever one of the node's properties
    changes."""

    node: VolumeNode | None = None

    def _selection_changed(self, node) -> None:
        if isinstance(node, IsosurfaceNode):
            node = self.scene.volume_of(node)
        if isinstance(node, VolumeNode):
            self.set_node(node)

    def set_node(self, node: VolumeNode | None) -> None:
        if self.node is not None:
            self.node.events.disconnect(self._show)
        self.node = node
        self.setEnabled(node is not None)
        if node is not None:
            node.events.connect(self._show)
        self._show()
