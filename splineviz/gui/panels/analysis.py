"""The analysis panel: colour the current isosurface by curvature, gradient magnitude or
another volume, and exact cross-section curves with their lengths and areas.

A view of one :class:`~splineviz.model.IsosurfaceNode` (the selection, or the first isosurface
of a selected volume) like the isosurface panel: widgets write the node's colour-by fields and
add :class:`~splineviz.model.SectionNode` objects; node events update the widgets.

The Minimum and Maximum fields always show the range in use: the manual one, or in the
automatic modes the range the views colour by (their shared
:func:`~splineviz.render.scene_view.colour_range_link`), so switching to manual starts from
what is on screen. A manual range belongs to the measure it was set for: another measure
starts automatic, and coming back brings the manual range back. "Same range in both views"
links or unlinks the two halves of a split view.
"""

from __future__ import annotations

import math
import weakref

from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QLabel,
    QListWidget,
    QPushButton,
    QWidget,
)

from splineviz.core.colour_by import COLORMAPS, FIELDS, RANGE_MODES
from splineviz.core.units import format_quantity
from splineviz.gui.undo import undo_stack
from splineviz.model import IsosurfaceNode, Scene, SectionNode, VolumeNode
from splineviz.render.scene_view import colour_range_link

#: labels of the colour-by fields
FIELD_LABELS = {"none": "Flat colour", "mean": "Mean curvature", "gaussian": "Gaussian curvature",
                "k1": "Principal curvature k1", "k2": "Principal curvature k2",
                "shape-index": "Shape index", "curvedness": "Curvedness",
                "gradient-magnitude": "Gradient magnitude", "volume": "Another volume",
                "distance": "Distance to another isosurface"}


def curve_summary(curves, unit: str = "") -> str:
    """One line per curve: closed or open, length and enclosed area, in ``unit`` (the
    world coordinates' unit, see :mod:`splineviz.core.units`; ``""``: bare numbers)."""
    lines = []
    for i, c in enumerate(curves or []):
        area = "" if math.isnan(c.area) else f", area {format_quantity(c.area, unit, 2, digits=6)}"
        lines.append(f"curve {i + 1}: {'closed' if c.closed else 'open'}, "
                     f"length {format_quantity(c.length, unit, digits=6)}{area}")
    return "\n".join(lines) or "no curve"


class AnalysisPanel(QWidget):
    """Colour-by and cross-section controls of the current isosurface (see module docstring);
    each edit is a step of the scene's undo stack (:mod:`splineviz.gui.undo`).

    Parameters
    ----------
    scene : Scene
    """

    def __init__(self, scene: Scene, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.node: IsosurfaceNode | None = None
        self._syncing = False
        self._watched: set[str] = set()
        self.title = QLabel("")
        self.field = QComboBox()
        for f in FIELDS:
            self.field.addItem(FIELD_LABELS[f], f)
        self.field.setToolTip("Colour the surface by a value computed from the spline at each "
                              "ray hit: curvatures from its exact gradient and Hessian")
        self.volume = QComboBox()
        self.volume.setToolTip("The volume whose values colour the surface")
        self.reference = QComboBox()
        self.reference.setToolTip("The isosurface (another model or isovalue) whose distance "
                                  "colours this one: the thesis' comparison figures")
        self.cmap = QComboBox()
        self.cmap.addItems(list(COLORMAPS))
        self.cmap.setToolTip("Colour map (matplotlib's tables)")
        self.range_mode = QComboBox()
        self.range_mode.addItems(list(RANGE_MODES))
        self.range_mode.setToolTip("auto: the values in view; symmetric: centred on 0 (signed "
                                   "curvatures); manual: the two numbers below")
        self.vmin = QDoubleSpinBox()
        self.vmax = QDoubleSpinBox()
        for box in (self.vmin, self.vmax):
            box.setDecimals(6)
            box.setRange(-1e12, 1e12)
            box.setKeyboardTracking(False)
        self.vmin.setToolTip("Value at the low end of the colour map: set in the manual "
                             "range, the range in use in the automatic ones")
        self.vmax.setToolTip("Value at the high end of the colour map: set in the manual "
                             "range, the range in use in the automatic ones")
        self.linked = QCheckBox("Same range in both views")
        self.linked.setToolTip("In a split view, colour a surface over one range in both "
                               "views (the span of what each shows); off: each view its own")
        #: (node id, colour-by field) -> the manual (min, max) set for that measure
        self._manual: dict[tuple[str, str], tuple[float, float]] = {}
        self.section_with = QComboBox()
        self.section_with.setToolTip("Cut the isosurface with a clip plane or another "
                                     "isosurface")
        self.add_section = QPushButton("Add cross section")
        self.add_section.setToolTip("Exact curves on the spline surface, drawn as lines")
        self.sections = QListWidget()
        self.sections.setMaximumHeight(90)
        self.summary = QLabel("")
        self.summary.setWordWrap(True)
        self.export = QPushButton("Export curves…")
        self.export.setToolTip("Write the selected section's curves as VTP or CSV, with their "
                               "lengths and areas")
        form = QFormLayout(self)
        form.addRow(self.title)
        form.addRow("Colour by", self.field)
        form.addRow("Volume", self.volume)
        form.addRow("Surface", self.reference)
        form.addRow("Colour map", self.cmap)
        form.addRow("Range", self.range_mode)
        form.addRow("Minimum", self.vmin)
        form.addRow("Maximum", self.vmax)
        form.addRow(self.linked)
        form.addRow("Section with", self.section_with)
        form.addRow(self.add_section)
        form.addRow(self.sections)
        form.addRow(self.summary)
        form.addRow(self.export)
        self.field.currentIndexChanged.connect(lambda _i: self._write_colour())
        self.volume.currentIndexChanged.connect(lambda _i: self._write_colour())
        self.reference.currentIndexChanged.connect(lambda _i: self._write_colour())
        self.cmap.currentTextChanged.connect(lambda _t: self._write_colour())
        self.range_mode.currentTextChanged.connect(lambda _t: self._write_colour())
        self.vmin.valueChanged.connect(lambda _v: self._write_colour())
        self.vmax.valueChanged.connect(lambda _v: self._write_colour())
        self.add_section.clicked.connect(self.add_cross_section)
        self.sections.currentRowChanged.connect(lambda _r: self._show_summary())
        self.export.clicked.connect(lambda: self.export_curves())
        scene.selection.connect(self._selection_changed)
        self._link = colour_range_link(scene)
        me = weakref.ref(self)

        def in_use(key, value):
            panel = me()
            if panel is not None:
                panel._range_in_use(key, value)

        self._link.listeners.append(in_use)
        self.linked.setChecked(self._link.enabled)
        self.linked.toggled.connect(self._link.set_enabled)
        self.destroyed.connect(lambda *_: self._link.listeners.remove(in_use)
                               if in_use in self._link.listeners else None)
        scene.inserted.connect(lambda _n: self._refresh_lists())
        scene.removed.connect(self._removed)
        self.set_node(None)

    # -- which node ----------------------------------------------------------------------

    def _selection_changed(self, node) -> None:
        if isinstance(node, IsosurfaceNode):
            self.set_node(node)
        elif isinstance(node, VolumeNode):
            isos = self.scene.isosurfaces_of(node)
            self.set_node(isos[0] if isos else None)
        elif isinstance(node, SectionNode):
            self.set_node(self.scene.get(node.isosurface_id))

    def _removed(self, node) -> None:
        if node is self.node:
            isos = self.scene.isosurfaces
            self.set_node(isos[-1] if isos else None)
        else:
            self._refresh_lists()

    def set_node(self, node: IsosurfaceNode | None) -> None:
        if self.node is not None:
            self.node.events.disconnect(self._node_changed)
        self.node = node
        for w in (self.field, self.volume, self.reference, self.cmap, self.range_mode,
                  self.vmin, self.vmax, self.section_with, self.add_section, self.sections,
                  self.export):
            w.setEnabled(node is not None)
        if node is None:
            self.title.setText("Select an isosurface")
            self._refresh_lists()
            return
        node.events.connect(self._node_changed)
        self.title.setText(node.name)
        self._refresh_lists()
        self._sync()

    def _node_changed(self, info) -> None:
        if not self._syncing:
            self._sync()

    # -- node -> widgets -----------------------------------------------------------------

    def _refresh_lists(self) -> None:
        self._syncing = True
        try:
            self.volume.clear()
            for v in self.scene.volumes:
                self.volume.addItem(v.name, v.id)
            self.section_with.clear()
            self.sections.clear()
            self.reference.clear()
            if self.node is None:
                return
            for iso in self.scene.isosurfaces:
                if iso is not self.node:
                    self.reference.addItem(f"{iso.name} ({iso.model} @ {iso.isovalue:g})",
                                           iso.id)
            for p in self.scene.clip_planes:
                self.section_with.addItem(f"plane {p.name}", p.id)
            for iso in self.scene.isosurfaces:
                if iso is not self.node:
                    self.section_with.addItem(f"isosurface {iso.name}", iso.id)
            for sec in self.sections_of_node():
                self.sections.addItem(sec.name)
                if sec.id not in self._watched:
                    # the view recomputes a section's curves when its inputs change
                    sec.events.curves.connect(lambda _c: self._show_summary())
                    self._watched.add(sec.id)
        finally:
            self._syncing = False
        if self.node is not None:
            self._sync()

    def sections_of_node(self) -> list[SectionNode]:
        return [s for s in self.scene.sections if self.node is not None and
                self.node.id in s.inputs]

    def _sync(self) -> None:
        n = self.node
        self._syncing = True
        try:
            self.field.setCurrentIndex(self.field.findData(n.color_by))
            if n.color_volume_id is not None:
                self.volume.setCurrentIndex(self.volume.findData(n.color_volume_id))
            self.volume.setEnabled(n.color_by == "volume")
            if n.color_isosurface_id is not None:
                self.reference.setCurrentIndex(self.reference.findData(n.color_isosurface_id))
            self.reference.setEnabled(n.color_by == "distance")
            self.cmap.setCurrentText(n.color_map)
            self.range_mode.setCurrentText(n.color_range)
            manual = n.color_range == "manual"
            shown = None if manual else self._link.range_of(n.id)
            lo, hi = (n.color_min, n.color_max) if shown is None else shown
            self.vmin.setValue(lo)
            self.vmax.setValue(hi)
            self.vmin.setEnabled(manual)
            self.vmax.setEnabled(manual)
        finally:
            self._syncing = False
        self._show_summary()

    def _range_in_use(self, key, value) -> None:
        """The views' shared range of surface ``key`` changed: show it while automatic."""
        n = self.node
        if n is None or key != n.id or n.color_range == "manual" or value is None:
            return
        self._syncing = True
        try:
            self.vmin.setValue(value[0])
            self.vmax.setValue(value[1])
        finally:
            self._syncing = False

    def _show_summary(self) -> None:
        secs = self.sections_of_node()
        row = self.sections.currentRow()
        sec = secs[row] if 0 <= row < len(secs) else (secs[-1] if secs else None)
        self.summary.setText("" if sec is None
                             else curve_summary(sec.curves, self.scene.length_unit()))
        self.export.setEnabled(sec is not None and bool(sec.curves))

    # -- widgets -> node -----------------------------------------------------------------

    def _write_colour(self) -> None:
        if self._syncing or self.node is None:
            return
        n = self.node
        values = {"color_by": self.field.currentData(), "color_map": self.cmap.currentText(),
                  "color_range": self.range_mode.currentText()}
        if values["color_range"] == "manual" and self.vmin.value() < self.vmax.value():
            # (in the automatic modes the fields show the range in use, not a setting)
            values.update(color_min=self.vmin.value(), color_max=self.vmax.value())
        if values["color_by"] != n.color_by:
            # a manual range is that measure's: keep it for a return, start the new
            # measure from its own (a curvature's range means nothing for a distance)
            if n.color_range == "manual":
                self._manual[(n.id, n.color_by)] = (n.color_min, n.color_max)
            kept = self._manual.get((n.id, values["color_by"]))
            values["color_range"] = "auto" if kept is None else "manual"
            if kept is not None:
                values.update(color_min=kept[0], color_max=kept[1])
        elif values["color_range"] == "manual" and "color_min" in values:
            self._manual[(n.id, n.color_by)] = (values["color_min"], values["color_max"])
        if values["color_by"] == "volume":
            values["color_volume_id"] = self.volume.currentData()
        if values["color_by"] == "distance":
            values["color_isosurface_id"] = self.reference.currentData()
        self._syncing = True
        try:
            undo_stack(self.scene).set(self.node, f"Colour of {self.node.name}", **values)
        finally:
            self._syncing = False
        self._sync()

    def add_cross_section(self) -> SectionNode | None:
        """A section of the current isosurface with the chosen plane or isosurface."""
        if self.node is None or self.section_with.currentData() is None:
            return None
        other = self.scene.get(self.section_with.currentData())
        node = self.node
        kind = "other" if isinstance(other, IsosurfaceNode) else "plane"
        sec = undo_stack(self.scene).change(
            "Add cross section", lambda: self.scene.add_section(node, **{kind: other}))
        self._refresh_lists()
        self.sections.setCurrentRow(self.sections.count() - 1)
        return sec

    def export_curves(self, path=None):
        """Write the selected section's curves (asks for a file when ``path`` is None)."""
        from splineviz.io.curves import write_curves
        from splineviz.model.analysis import section_curves

        secs = self.sections_of_node()
        row = self.sections.currentRow()
        sec = secs[row] if 0 <= row < len(secs) else (secs[-1] if secs else None)
        if sec is None:
            return None
        if path is None:
            path, _ = QFileDialog.getSaveFileName(self, "Export curves", f"{sec.name}.vtp",
                                                  "VTK PolyData (*.vtp);;CSV (*.csv)")
            if not path:
                return None
        curves = sec.curves if sec.curves is not None else section_curves(self.scene, sec)
        return write_curves(path, curves)
