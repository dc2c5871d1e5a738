"""The isosurface panel: isovalue over the data's histogram, spline model, renderer, colour,
opacity, material of the current isosurface node.

A view of one :class:`~splineviz.model.IsosurfaceNode` (the scene's selection, or the first
isosurface of a selected volume): widgets write the node through the scene's undo stack
(:mod:`splineviz.gui.undo`; a drag of the isovalue or opacity slider is one step), node
events update the widgets.
The histogram of a big volume is computed in a worker and cached per volume.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QPaintEvent
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QStyle,
    QStyleOptionComboBox,
    QStylePainter,
    QWidget,
)
from superqt import QLabeledDoubleSlider

from splineviz.core.renderers import AUTO, RENDERERS, choose_renderer
from splineviz.core.splines import MODELS
from splineviz.gui.undo import undo_stack
from splineviz.gui.widgets import ColorButton, HistogramSlider
from splineviz.model import MATERIALS, SIDES, IsosurfaceNode, Scene, VolumeNode
from splineviz.model.summaries import HISTOGRAM_BINS, cached_histogram

#: volumes with at most this many samples get their histogram in the GUI thread
INLINE_HISTOGRAM_SAMPLES = 2_000_000
#: how soon the renderer note looks again whether OpenCL was probed (milliseconds), and
#: how many times
NOTE_RETRY_MS = 500
NOTE_RETRIES = 20

def model_label(name: str) -> str:
    spec = MODELS[name]
    degree = f", degree {spec.degree}" if spec.degree else ""
    path = "" if spec.family else " — NumPy reference, slow"
    return f"{spec.display_label}{degree}{path}"


class ElidedComboBox(QComboBox):
    """A combo box that shows a label too long for it cut with an ellipsis ("...") rather
    than clipped mid-letter; its list opens as wide as the longest label, and each item's
    tooltip is its whole label."""

    def displayed_text(self) -> str:
        """The current label as drawn: elided to the width of the box's text field."""
        opt = QStyleOptionComboBox()
        self.initStyleOption(opt)
        field = self.style().subControlRect(QStyle.ComplexControl.CC_ComboBox, opt,
                                            QStyle.SubControl.SC_ComboBoxEditField, self)
        return self.fontMetrics().elidedText(self.currentText(), Qt.TextElideMode.ElideRight,
                                             max(field.width() - 4, 0))

    def paintEvent(self, _event: QPaintEvent) -> None:  # noqa: N802 (Qt naming)
        painter = QStylePainter(self)
        opt = QStyleOptionComboBox()
        self.initStyleOption(opt)
        painter.drawComplexControl(QStyle.ComplexControl.CC_ComboBox, opt)
        opt.currentText = self.displayed_text()
        painter.drawControl(QStyle.ControlElement.CE_ComboBoxLabel, opt)

    def fit_popup(self) -> None:
        """The list as wide as its longest label (after the items changed)."""
        view = self.view()
        widest = 0
        for i in range(self.count()):
            self.setItemData(i, self.itemText(i), Qt.ItemDataRole.ToolTipRole)
            widest = max(widest, view.fontMetrics().horizontalAdvance(self.itemText(i)))
        # the item's margins and a scroll bar's width beside the text
        extra = 2 * view.frameWidth() + self.style().pixelMetric(
            QStyle.PixelMetric.PM_ScrollBarExtent) + 16
        view.setMinimumWidth(widest + extra)


class IsosurfacePanel(QWidget):
    """Controls of the current isosurface (see module docstring).

    Parameters
    ----------
    scene : Scene
    jobs : splineviz.gui.jobs.JobRunner
        Runs histogram computations of big volumes.
    """

    def __init__(self, scene: Scene, jobs, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.jobs = jobs
        self.node: IsosurfaceNode | None = None
        self._volume = None
        self.title = QLabel("")
        self.histogram = HistogramSlider()
        self.spin = QDoubleSpinBox()
        self.spin.setDecimals(5)
        self.spin.setKeyboardTracking(False)
        self.spin.setToolTip("Isovalue: type a value and press Enter")
        self.model = ElidedComboBox()
        # long model labels must not widen the dock: the box elides, the list shows them
        self.model.setSizeAdjustPolicy(
            QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.model.setMinimumContentsLength(12)
        self.model.setToolTip("Spline model the surface is the isosurface of (thesis ch. 4-5): "
                              "trilinear is the baseline; the smooth models have exact "
                              "normals and curvature")
        self.k = QSpinBox()
        self.k.setRange(1, 16)
        self.k.setToolTip("k of the truncated-octahedral operator Q_k (thesis eq. 5.9)")
        self.k_label = QLabel("Q_k order")
        self.renderer = ElidedComboBox()
        self.renderer.setSizeAdjustPolicy(
            QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.renderer.setMinimumContentsLength(12)
        for name, renderer in RENDERERS.items():
            self.renderer.addItem(renderer.label, name)
        self.renderer.fit_popup()
        #: what draws the surface when it is not what was chosen, in one sentence
        self.renderer_note = QLabel("")
        self.renderer_note.setWordWrap(True)
        self.renderer_note.setVisible(False)
        self.renderer.setToolTip("What draws the surface (thesis ch. 6): the ray caster in "
                                 "OpenCL, or cell projection in OpenGL (super-quadratic and "
                                 "cubic C1, one colour); automatic: ray casting where an "
                                 "OpenCL device works, else cell projection")
        self.color = ColorButton()
        self.color.setToolTip("Colour of the front side of the surface")
        self.opacity = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        self.opacity.setRange(0.05, 1.0)
        self.opacity.setToolTip("Opacity: below 1 the surface blends over what is behind it")
        self.material = QComboBox()
        self.material.addItems(list(MATERIALS))
        self.material.setToolTip("Shading: ambient, diffuse, specular and shininess constants")
        self.shown_in = QComboBox()
        for side in SIDES:
            self.shown_in.addItem({"both": "both views", "left": "left view",
                                   "right": "right view"}[side], side)
        self.shown_in.setToolTip("Which of the two linked views shows this isosurface while "
                                 "the view is split (View > Split view)")
        self.add_button = QPushButton("Add isosurface")
        self.add_button.setToolTip("Another isosurface of the same volume, at another value")
        form = QFormLayout(self)
        form.addRow(self.title)
        form.addRow(self.histogram)
        form.addRow("Isovalue", self.spin)
        form.addRow("Model", self.model)
        form.addRow(self.k_label, self.k)
        form.addRow("Renderer", self.renderer)
        form.addRow(self.renderer_note)
        form.addRow("Colour", self.color)
        form.addRow("Opacity", self.opacity)
        form.addRow("Material", self.material)
        form.addRow("Shown in", self.shown_in)
        form.addRow(self.add_button)
        self._syncing = False
        self._note_retries = 0
        self.fill_models()
        self.histogram.valueChanged.connect(lambda v: self._iso_changed(v, self.spin))
        self.spin.valueChanged.connect(lambda v: self._iso_changed(v, self.histogram))
        self.model.currentIndexChanged.connect(lambda _i: self._write(
            "model", self.model.currentData()))
        self.k.valueChanged.connect(lambda v: self._write("k", int(v)))
        self.renderer.currentIndexChanged.connect(lambda _i: self._write(
            "renderer", self.renderer.currentData()))
        self.color.colorChanged.connect(lambda c: self._write("color", tuple(c)))
        self.opacity.valueChanged.connect(lambda v: self._write("opacity", float(v)))
        self.material.currentTextChanged.connect(lambda m: self._write("material", m))
        self.shown_in.currentIndexChanged.connect(lambda _i: self._write(
            "shown_in", self.shown_in.currentData()))
        undo = undo_stack(scene)
        for press, release in ((self.histogram.pressed, self.histogram.released),
                               (self.opacity.sliderPressed, self.opacity.sliderReleased)):
            press.connect(undo.begin_drag)
            release.connect(undo.end_drag)
        scene.view.events.split.connect(self._split_changed)
        self.add_button.clicked.connect(self.add_isosurface)
        scene.selection.connect(self._selection_changed)
        scene.removed.connect(self._removed)
        scene.inserted.connect(self._inserted)
        self.set_node(None)

    def fill_models(self) -> None:
        """The registry's models (plugin models included) in the model box."""
        self.model.blockSignals(True)
        self.model.clear()
        for name in MODELS:
            self.model.addItem(model_label(name), name)
        self.model.fit_popup()
        self.model.blockSignals(False)

    # -- which node ----------------------------------------------------------------------

    def _selection_changed(self, node) -> None:
        if isinstance(node, IsosurfaceNode):
            self.set_node(node)
        elif isinstance(node, VolumeNode):
            isos = self.scene.isosurfaces_of(node)
            self.set_node(isos[0] if isos else None, volume=node)
        elif node is None and self.node is not None and self.node.id not in self.scene:
            self.set_node(None)

    def _inserted(self, node) -> None:
        # an empty panel shows the first isosurface that arrives (a loaded session selects
        # nothing; its first isosurface is what the user expects to edit)
        if self.node is None and isinstance(node, IsosurfaceNode):
            self.set_node(node)

    def _removed(self, node) -> None:
        if node is self.node or node is self._volume:
            isos = self.scene.isosurfaces
            self.set_node(isos[-1] if isos else None)

    def set_node(self, node: IsosurfaceNode | None, volume: VolumeNode | None = None) -> None:
        if self.node is not None:
            self.node.events.disconnect(self._node_changed)
        if self._volume is not None:
            self._volume.events.disconnect(self._volume_changed)
        self.node = node
        self._volume = self.scene.volume_of(node) if node is not None else volume
        for w in (self.histogram, self.spin, self.model, self.k, self.renderer, self.color,
                  self.opacity, self.material):
            w.setEnabled(node is not None)
        self._split_changed(self.scene.view.split)
        self.add_button.setEnabled(self._volume is not None)
        if self._volume is not None:
            self._volume.events.connect(self._volume_changed)
        if node is None:
            self.title.setText("Select an isosurface or a volume in the data panel")
            self.k.setVisible(False)
            self.k_label.setVisible(False)
            self.renderer_note.setVisible(False)
            self._clear_widgets()
            return
        self.spin.setSpecialValueText("")
        node.events.connect(self._node_changed)
        self.title.setText(f"{node.name} of {self._volume.name}")
        self._load_histogram()
        self._sync_all()

    def _clear_widgets(self) -> None:
        """No node: no histogram and no isovalue left over from the node shown before."""
        self._syncing = True
        try:
            self.histogram.set_histogram(np.zeros(HISTOGRAM_BINS),
                                         np.linspace(0.0, 1.0, HISTOGRAM_BINS + 1))
            self.histogram.setValue(0.0)
            # a blank box: the special text shows while the value is the minimum
            self.spin.setSpecialValueText(" ")
            self.spin.setRange(0.0, 0.0)
            self.spin.setValue(0.0)
        finally:
            self._syncing = False

    def _load_histogram(self) -> None:
        vol = self._volume.active
        lo, hi = vol.finite_range
        if vol.data.size <= INLINE_HISTOGRAM_SAMPLES:
            self.histogram.set_histogram(*cached_histogram(vol))
        else:
            # the range now, the counts when the worker has them
            self.histogram.set_histogram(np.zeros(1), np.array([lo, hi if hi > lo else lo + 1]))
            node = self.node
            self.jobs.run("Histogram", cached_histogram, vol, cancellable=False,
                          on_done=lambda h: self.node is node and
                          self.histogram.set_histogram(*h))
        lo, hi = self.histogram.range()
        self._syncing = True
        self.spin.setRange(lo, hi)
        self.spin.setSingleStep((hi - lo) / 200.0)
        self._syncing = False

    def _sync_all(self) -> None:
        n = self.node
        self._syncing = True
        try:
            self.spin.setValue(n.isovalue)
            self.histogram.setValue(n.isovalue)
            i = self.model.findData(n.model)
            if i < 0:  # a plugin model registered after the panel was built
                self.fill_models()
                i = self.model.findData(n.model)
            self.model.setCurrentIndex(i)
            has_k = "k" in MODELS[n.model].options
            self.k.setVisible(has_k)
            self.k_label.setVisible(has_k)
            self.k.setValue(n.k)
            self.renderer.setCurrentIndex(self.renderer.findData(n.renderer))
            self._show_renderer_note()
            self.color.setColor(n.color)
            self.opacity.setValue(n.opacity)
            self.material.setCurrentText(n.material)
            self.shown_in.setCurrentIndex(self.shown_in.findData(n.shown_in))
        finally:
            self._syncing = False

    def _show_renderer_note(self) -> None:
        """Say what draws the surface where the choice is automatic or cannot be followed
        (:func:`~splineviz.core.renderers.choose_renderer`; before the view has probed
        OpenCL, an automatic choice says nothing yet)."""
        from splineviz.compute.device import opencl_known
        from splineviz.render.isosurface import not_projectable

        n = self.node
        if n is None:
            return
        opencl = opencl_known()
        text = ""
        if opencl is None and n.renderer == AUTO:
            # the view's worker probes OpenCL for its first exact frame: look again then
            if self._note_retries < NOTE_RETRIES:
                self._note_retries += 1
                QTimer.singleShot(NOTE_RETRY_MS, self, self._show_renderer_note)
        else:
            choice = choose_renderer(n.renderer, n.model, n.color_by, opencl is not False,
                                     not_projectable(self._volume.active))
            text = choice.note
            if not text and n.renderer == AUTO:
                text = f"drawn by {RENDERERS[choice.renderer].label}"
        self.renderer_note.setText(text)
        self.renderer_note.setVisible(bool(text))

    def _node_changed(self, info) -> None:
        if not self._syncing and self.node is not None:
            if info.signal.name == "name":
                self.title.setText(f"{self.node.name} of {self._volume.name}")
            self._sync_all()

    def _split_changed(self, on: bool) -> None:
        """The side only matters while the view is split."""
        self.shown_in.setEnabled(self.node is not None and bool(on))

    def _volume_changed(self, info) -> None:
        if info.signal.name in ("smoothed", "sigma", "data") and self.node is not None:
            self._load_histogram()
            self._sync_all()

    # -- widgets -> node -----------------------------------------------------------------

    def _write(self, field: str, value) -> None:
        if self._syncing or self.node is None:
            return
        self._syncing = True
        try:
            undo_stack(self.scene).set(self.node, **{field: value})
        finally:
            self._syncing = False
        if field == "model":
            self._sync_all()  # shows or hides the Q_k order (and says what draws it)
        elif field == "renderer":
            self._show_renderer_note()

    def _iso_changed(self, v, mirror) -> None:
        """The slider or the spin box moved: show the value in the other one, write it."""
        if self._syncing:
            return
        self._syncing = True
        mirror.setValue(v)
        self._syncing = False
        self._write("isovalue", float(v))

    def add_isosurface(self) -> IsosurfaceNode | None:
        if self._volume is None:
            return None
        # while split, a new isosurface joins the side of the current one (a second
        # isovalue in the right view stays in the right view)
        side = self.node.shown_in if self.node is not None and self.scene.view.split \
            else "both"
        volume = self._volume

        def add():
            node = self.scene.add_isosurface(volume, shown_in=side)
            self.scene.select(node)
            return node

        return undo_stack(self.scene).change("Add isosurface", add)
