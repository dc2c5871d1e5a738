"""The volume rendering panel: direct volume rendering of the current volume (issue 30).

On/off, the transfer function (a preset placed on the data's range, or a ParaView JSON
colour-map preset file: import, and export of the one in use), the spline model the rays
sample and gradient shading. A view of the node's ``volume_rendering``,
``transfer_function``, ``rendering_model`` and ``rendering_shade``; every edit is a step of
the scene's undo stack (:mod:`splineviz.gui.undo`). The 3-D view shows the result
(:class:`splineviz.render.volume_layer.VolumeLayer`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QPushButton,
)

from splineviz.core.errors import SplinevizError
from splineviz.core.splines import MODELS
from splineviz.core.transfer_function import PRESETS, write_paraview_json
from splineviz.gui.panels.volume_panel import VolumePanel
from splineviz.gui.undo import undo_stack
from splineviz.model import Scene, VolumeNode

#: file filter of the transfer function dialogs
JSON_FILTER = "ParaView colour map preset (*.json)"


class VolumeRenderingPanel(VolumePanel):
    """Volume rendering settings of the current volume (see module docstring).

    Signals of errors go to ``error`` (a callable taking one sentence), the main window's
    message line; None raises nothing and shows the sentence in the panel.
    """

    def __init__(self, scene: Scene, parent=None, error=None):
        super().__init__(parent)
        self.scene = scene
        self.error = error
        self.node: VolumeNode | None = None
        self.enabled = QCheckBox("Volume rendering")
        self.enabled.setToolTip("Show the volume by emission-absorption ray marching through "
                                "its spline model, with its isosurfaces and meshes embedded")
        self.preset = QComboBox()
        self.preset.setToolTip("Transfer function: a preset placed on the data's value "
                               "range, or an imported ParaView JSON file")
        self.preset.addItems(PRESETS)
        self.model = QComboBox()
        self.model.setToolTip("Spline model the rays sample (trilinear and the type-6 "
                              "splines run on the OpenCL device, others are slow)")
        self.model.addItems(list(MODELS))
        self.shade = QCheckBox("Gradient shading")
        self.shade.setToolTip("Headlight Phong shading from the spline's exact gradient")
        self.import_button = QPushButton("Import...")
        self.import_button.setToolTip("Use a ParaView JSON colour map preset as the transfer "
                                      "function")
        self.export_button = QPushButton("Export...")
        self.export_button.setToolTip("Write the transfer function in use as a ParaView JSON "
                                      "colour map preset")
        self.info = QLabel("")
        self.info.setWordWrap(True)
        form = QFormLayout(self)
        form.addRow(self.enabled)
        form.addRow("Transfer function", self.preset)
        row = QHBoxLayout()
        row.addWidget(self.import_button)
        row.addWidget(self.export_button)
        form.addRow(row)
        form.addRow("Model", self.model)
        form.addRow(self.shade)
        form.addRow(self.info)
        self.enabled.toggled.connect(lambda on: self._set("Volume rendering",
                                                          volume_rendering=bool(on)))
        self.preset.activated.connect(
            lambda i: self._set("Transfer function", transfer_function=self.preset.itemText(i)))
        self.model.activated.connect(
            lambda i: self._set("Volume rendering model", rendering_model=self.model.itemText(i)))
        self.shade.toggled.connect(lambda on: self._set("Volume rendering shading",
                                                        rendering_shade=bool(on)))
        self.import_button.clicked.connect(lambda: self.import_json())
        self.export_button.clicked.connect(lambda: self.export_json())
        scene.selection.connect(self._selection_changed)
        scene.removed.connect(lambda n: n is self.node and self.set_node(None))
        self.set_node(next(iter(scene.volumes), None))

    def _show(self, *_args) -> None:
        node = self.node
        widgets = (self.enabled, self.preset, self.model, self.shade)
        for w in widgets:
            w.blockSignals(True)
        try:
            if node is None:
                self.info.setText("select a volume")
                return
            self.enabled.setChecked(node.volume_rendering)
            spec = node.transfer_function
            if self.preset.findText(spec) < 0:
                self.preset.addItem(spec)  # an imported file
            self.preset.setCurrentText(spec)
            self.model.setCurrentText(node.rendering_model)
            self.shade.setChecked(node.rendering_shade)
            state = "on" if node.volume_rendering else "off"
            self.info.setText(f"{node.name}: volume rendering {state}, "
                              f"{Path(spec).name}, {node.rendering_model}")
        finally:
            for w in widgets:
                w.blockSignals(False)

    def _set(self, text: str, **values) -> None:
        if self.node is None:
            return
        try:
            undo_stack(self.scene).set(self.node, f"{text} of {self.node.name}", **values)
        except SplinevizError as exc:
            self._error(str(exc))
            self._show()

    def _error(self, message: str) -> None:
        if self.error is not None:
            self.error(message)
        self.info.setText(message)

    def import_json(self, path=None) -> None:
        """Use the ParaView JSON preset ``path`` (asked for when None)."""
        if self.node is None:
            return
        if path is None:
            path, _ = QFileDialog.getOpenFileName(self, "Import transfer function", "",
                                                  JSON_FILTER)
            if not path:
                return
        from splineviz.core.transfer_function import read_paraview_json

        try:
            read_paraview_json(path)  # a bad file is one sentence here, not in the view
        except (SplinevizError, OSError) as exc:
            self._error(str(exc))
            return
        self._set("Transfer function", transfer_function=str(path))

    def export_json(self, path=None) -> None:
        """Write the transfer function in use to ``path`` (asked for when None)."""
        node = self.node
        if node is None or node.data is None:
            return
        if path is None:
            path, _ = QFileDialog.getSaveFileName(self, "Export transfer function",
                                                  "transfer_function.json", JSON_FILTER)
            if not path:
                return
        from splineviz.core.transfer_function import resolve

        data = node.active.data
        try:
            tf = resolve(node.transfer_function, (float(np.min(data)), float(np.max(data))))
            write_paraview_json(tf, path)
        except (SplinevizError, OSError) as exc:
            self._error(str(exc))
            return
        self.info.setText(f"transfer function written to {Path(path).name}")
