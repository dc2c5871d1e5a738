"""The volume rendering panel: direct volume rendering of the current volume (issue 30).

On/off, the transfer function (a preset placed on the data's range, or a ParaView JSON
colour-map preset file: import, and export of the one in use) and its editor (opacity points
over the data's histogram, colour points on a bar:
:class:`~splineviz.gui.transfer_function_editor.TransferFunctionEditor`), the spline model the
rays sample and gradient shading. A view of the node's ``volume_rendering``,
``transfer_function``, ``transfer_function_points`` (the edited points; choosing a preset or
a file again drops them), ``rendering_model`` and ``rendering_shade``; every edit is a step of
the scene's undo stack (:mod:`splineviz.gui.undo`), a drag in the editor one step. The 3-D
view shows the result (:class:`splineviz.render.volume_layer.VolumeLayer`).

While a point is dragged the editor's points are written to the node at most once per
:data:`EDIT_INTERVAL_MS` (the view previews each write), and at the release.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pydantic import ValidationError
from PySide6.QtCore import QTimer, Signal
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
from splineviz.gui.panels.isosurface import INLINE_HISTOGRAM_SAMPLES
from splineviz.gui.panels.volume_panel import VolumePanel
from splineviz.gui.transfer_function_editor import TransferFunctionEditor
from splineviz.gui.undo import undo_stack
from splineviz.model import Scene, TransferFunctionPoints, VolumeNode
from splineviz.model.nodes import resolve_transfer_function
from splineviz.model.summaries import cached_histogram

#: file filter of the transfer function dialogs
JSON_FILTER = "ParaView colour map preset (*.json)"
#: least time between two writes of a dragged transfer function to the node (ms): each
#: write is a preview of the volume rendering, cast in the GUI thread within its budget
EDIT_INTERVAL_MS = 50


class VolumeRenderingPanel(VolumePanel):
    """Volume rendering settings of the current volume (see module docstring).

    Signals of errors go to ``error`` (a callable taking one sentence), the main window's
    message line; None raises nothing and shows the sentence in the panel.
    """

    #: a drag in the transfer function editor starts (the view previews only meanwhile)
    drag_started = Signal()
    #: ... and ended
    drag_ended = Signal()

    def __init__(self, scene: Scene, parent=None, error=None, jobs=None):
        super().__init__(parent)
        self.scene = scene
        self.error = error
        self.jobs = jobs
        self.node: VolumeNode | None = None
        #: ((node id, volume id, spec), TransferFunction) the editor shows
        self._shown_tf = None
        #: (node id, volume id) whose histogram the editor shows
        self._histogram_of = None
        self.editor = TransferFunctionEditor()
        self._write_timer = QTimer(self)
        self._write_timer.setSingleShot(True)
        self._write_timer.setInterval(EDIT_INTERVAL_MS)
        self._write_timer.timeout.connect(self._write_points)
        self._edit_pending = False
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
        form.addRow(self.editor)
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
            lambda i: self._set("Transfer function", transfer_function=self.preset.itemText(i),
                                transfer_function_points=None))
        self.editor.pressed.connect(self._drag_started)
        self.editor.edited.connect(self._edited)
        self.editor.released.connect(self._drag_ended)
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
            edited = " (edited)" if node.transfer_function_points is not None else ""
            self.info.setText(f"{node.name}: volume rendering {state}, "
                              f"{Path(spec).name}{edited}, {node.rendering_model}")
            self._show_editor()
        finally:
            for w in widgets:
                w.blockSignals(False)

    # -- the editor ----------------------------------------------------------------------

    def _data_range(self) -> tuple[float, float]:
        """The range presets are placed on (the renderers' own: the data's min and max)."""
        return self.node.active.finite_range

    def _show_editor(self) -> None:
        """The node's transfer function in the editor, over the data's histogram (not while
        the user's edit is still on its way to the node)."""
        node = self.node
        if node is None or node.data is None or self.editor.dragging or self._edit_pending:
            return
        vol = node.active
        key = (id(node), id(vol), node.transfer_function_spec)
        if self._shown_tf is not None and self._shown_tf[0] == key:
            return
        try:
            tf = resolve_transfer_function(node.transfer_function_spec, self._data_range())
        except SplinevizError as exc:
            self._error(str(exc))
            return
        if self._histogram_of != key[:2]:
            self._histogram_of = key[:2]
            self._load_histogram(vol)
        self._shown_tf = (key, tf)
        self.editor.set_points(tf.rgb_points, tf.opacity_points)

    def _load_histogram(self, vol) -> None:
        lo, hi = self._data_range()
        if vol.data.size <= INLINE_HISTOGRAM_SAMPLES or self.jobs is None:
            self.editor.set_histogram(*cached_histogram(vol))
            return
        # the range now, the counts when the worker has them
        self.editor.set_histogram(np.zeros(1), np.array([lo, hi if hi > lo else lo + 1.0]))
        node = self.node
        self.jobs.run("Histogram", cached_histogram, vol, cancellable=False,
                      on_done=lambda h: self.node is node and node.active is vol
                      and self.editor.set_histogram(*h))

    def _drag_started(self) -> None:
        undo_stack(self.scene).begin_drag()
        self.drag_started.emit()

    def _edited(self) -> None:
        self._edit_pending = True
        if not self.editor.dragging:
            self._write_points()  # a click (add, remove, colour): one step now
        elif not self._write_timer.isActive():
            self._write_timer.start()

    def _drag_ended(self) -> None:
        self._write_timer.stop()
        self._write_points()
        self._show_editor()  # the drag's last write may have changed nothing: no event
        undo_stack(self.scene).end_drag()
        self.drag_ended.emit()

    def _write_points(self) -> None:
        """The editor's points to the node's ``transfer_function_points``."""
        if not self._edit_pending:
            return
        self._edit_pending = False
        if self.node is None:
            return
        try:
            points = TransferFunctionPoints(
                rgb_points=tuple(map(tuple, self.editor.rgb_points().tolist())),
                opacity_points=tuple(map(tuple, self.editor.opacity_points().tolist())))
        except ValidationError as exc:
            self._error(f"transfer function not changed: {exc.errors()[0]['msg']}")
            points = None
        if points is not None:
            self._set("Transfer function edit", transfer_function_points=points)
        if not self.editor.dragging:
            self._shown_tf = None  # the node's, whatever the edit became
            self._show_editor()

    def set_node(self, node: VolumeNode | None) -> None:
        if node is not self.node:
            self._write_timer.stop()
            self._write_points()  # the edit of the node shown until now
            self._shown_tf = self._histogram_of = None
        super().set_node(node)

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
        self._set("Transfer function", transfer_function=str(path),
                  transfer_function_points=None)

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
        try:
            tf = resolve_transfer_function(node.transfer_function_spec, self._data_range())
            write_paraview_json(tf, path)
        except (SplinevizError, OSError) as exc:
            self._error(str(exc))
            return
        self.info.setText(f"transfer function written to {Path(path).name}")
