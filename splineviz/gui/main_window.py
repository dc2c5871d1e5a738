"""The main window: a 3-D view with docked panels, like ParaView / 3D Slicer / napari.

Model and view: the window keeps a list of :class:`DataItem` (volumes with their isosurface
layers, point clouds, meshes); the 3-D view is a :class:`~splineviz.render.scene.SplineScene`
in progressive mode on a pyvistaqt ``QtInteractor``. Panels edit the items and layers; the
scene re-renders. Long work (loading, smoothing, remeshing, exact ray casting of the smooth
models) runs in worker threads (:func:`superqt.utils.create_worker`) with a progress bar and
cancel; errors become a message box, never a dead window.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PySide6.QtCore import QSettings, Qt, QThreadPool, QTimer
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QDockWidget,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QMainWindow,
    QMessageBox,
    QProgressBar,
    QPushButton,
    QSpinBox,
    QTreeWidget,
    QTreeWidgetItem,
    QVBoxLayout,
    QWidget,
)
from superqt import QLabeledDoubleSlider
from superqt.utils import create_worker

import splineviz
from splineviz.core.errors import SplinevizError
from splineviz.core.volume import Volume
from splineviz.gui.widgets import ColorButton, HistogramSlider
from splineviz.render.isosurface import MATERIALS, MODEL_LABELS, PALETTE, IsosurfaceLayer
from splineviz.render.scene import SplineScene, offscreen_screenshot

#: delay before exact frames are computed after the last change (debounce)
REFINE_DELAY_MS = 150
#: delay before live smoothing runs after the last sigma change
SMOOTH_DELAY_MS = 300
#: entries kept in File > Open Recent
MAX_RECENT = 8
#: suffixes opened as point clouds (everything else is tried as a volume)
SESSION_SUFFIXES = (".svs",)
BACKGROUND = (0.10, 0.10, 0.14)


class Cancelled(Exception):
    """Raised inside a worker when the user pressed Cancel."""


@dataclass
class DataItem:
    """One loaded object of the data panel."""

    name: str
    kind: str                          # "volume" | "points" | "mesh"
    path: str | None = None
    volume: Volume | None = None       # the original samples (smoothing never replaces them)
    smoothed: Volume | None = None
    sigma: float = 0.0
    layers: list = field(default_factory=list)
    points: object = None              # PointCloud
    mesh: object = None                # pyvista.PolyData
    visible: bool = True
    source: str | None = None          # name of a synthetic source (session files)
    stats: dict = field(default_factory=dict)

    @property
    def prop_name(self) -> str:
        return f"{self.kind}:{self.name}:{id(self)}"

    @property
    def active_volume(self) -> Volume | None:
        return self.smoothed if self.smoothed is not None else self.volume


def load_path(path):
    """Read a file for the GUI (runs in a worker): ``("volume", Volume)``, ``("points",
    PointCloud)`` or ``("session", (Session, data))`` with the session's data read too.

    The kind comes from the format registry (a volume format claims the file, else a point
    format); session files by suffix.
    """
    from splineviz.io.errors import UnknownFormatError
    from splineviz.io.points import read_points  # noqa: F401  (registers point formats)
    from splineviz.io.registry import find_format
    from splineviz.io.volumes import read_volume

    p = Path(path)
    if p.suffix.lower() in SESSION_SUFFIXES:
        from splineviz.io.session import load_session

        session = load_session(p)
        return "session", (session, session_data(session))
    try:
        find_format(p, "volume")
    except UnknownFormatError:
        from splineviz.io.points import read_points

        return "points", read_points(p)
    return "volume", read_volume(p)


def session_data(session) -> dict:
    """Read the data of a session's volume and point objects (in a worker): id -> data."""
    data = {}
    for obj in session.objects:
        if obj.type in ("VolumeFile", "Source"):
            data[obj.id] = session.load_volume(obj.id)
        elif obj.type == "PointsFile":
            data[obj.id] = session.load_points(obj.id)
    return data


def default_model() -> str:
    """The model new isosurfaces start with: a smooth one if it has an OpenCL kernel (fast
    enough to drag), else trilinear; the model box switches to any of the four."""
    from splineviz.compute.raycast import KERNEL_MODELS

    for model in ("cubic-c1", "to-quadratic", "super-quadratic"):
        if model in KERNEL_MODELS:
            return model
    return "trilinear"


def default_data():
    """The embedded default data set (Marschner-Lobb 41^3, generated) and its isovalue."""
    from splineviz.render.extract import default_volume

    return default_volume()


# ------------------------------------------------------------------------------------------
# panels


class DataPanel(QWidget):
    """Loaded objects with visibility check boxes (like ParaView's pipeline browser)."""

    def __init__(self, window):
        super().__init__()
        self.window = window
        self.tree = QTreeWidget()
        self.tree.setHeaderLabels(["Object", "Info"])
        self.tree.setColumnWidth(0, 180)
        lay = QVBoxLayout(self)
        lay.addWidget(self.tree)
        row = QHBoxLayout()
        self.remove_button = QPushButton("Remove")
        row.addWidget(self.remove_button)
        row.addStretch(1)
        lay.addLayout(row)
        self.tree.itemChanged.connect(self._changed)
        self.tree.currentItemChanged.connect(lambda *_: window.selection_changed())
        self.remove_button.clicked.connect(self._remove)
        self._updating = False

    def rebuild(self, select=None) -> None:
        self._updating = True
        self.tree.clear()
        chosen = None
        for item in self.window.items:
            info = ""
            if item.kind == "volume":
                info = "x".join(str(n) for n in item.volume.shape)
                if item.sigma:
                    info += f", smoothed {item.sigma:g}"
            elif item.kind == "points":
                info = f"{len(item.points.points):,} points"
            elif item.kind == "mesh":
                info = f"{item.mesh.n_cells:,} triangles"
            node = QTreeWidgetItem([item.name, info])
            node.setFlags(node.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            node.setCheckState(0, Qt.CheckState.Checked if item.visible else
                               Qt.CheckState.Unchecked)
            node.setData(0, Qt.ItemDataRole.UserRole, item)
            self.tree.addTopLevelItem(node)
            if select is item:
                chosen = node
            for layer in item.layers:
                child = QTreeWidgetItem([layer.name, f"{layer.model} @ {layer.isovalue:.4g}"])
                child.setFlags(child.flags() | Qt.ItemFlag.ItemIsUserCheckable)
                child.setCheckState(0, Qt.CheckState.Checked if layer.visible else
                                    Qt.CheckState.Unchecked)
                child.setData(0, Qt.ItemDataRole.UserRole, layer)
                node.addChild(child)
                if select is layer:
                    chosen = child
            node.setExpanded(True)
        self._updating = False
        if chosen is not None:
            self.tree.setCurrentItem(chosen)
        elif self.tree.topLevelItemCount():
            self.tree.setCurrentItem(self.tree.topLevelItem(self.tree.topLevelItemCount() - 1))

    def current(self):
        node = self.tree.currentItem()
        return None if node is None else node.data(0, Qt.ItemDataRole.UserRole)

    def _changed(self, node, column):
        if self._updating or column != 0:
            return
        obj = node.data(0, Qt.ItemDataRole.UserRole)
        self.window.set_visible(obj, node.checkState(0) == Qt.CheckState.Checked)

    def _remove(self):
        obj = self.current()
        if obj is not None:
            self.window.remove_object(obj)


class IsosurfacePanel(QWidget):
    """Isovalue (histogram slider + spin box), model, colour, opacity, material."""

    def __init__(self, window):
        super().__init__()
        self.window = window
        self.layer: IsosurfaceLayer | None = None
        self.histogram = HistogramSlider()
        self.spin = QDoubleSpinBox()
        self.spin.setDecimals(5)
        self.spin.setKeyboardTracking(False)
        self.model = QComboBox()
        for key, label in MODEL_LABELS.items():
            self.model.addItem(label, key)
        self.color = ColorButton(PALETTE[0])
        self.opacity = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        self.opacity.setRange(0.05, 1.0)
        self.opacity.setValue(1.0)
        self.material = QComboBox()
        self.material.addItems(list(MATERIALS))
        self.add_button = QPushButton("Add isosurface")
        form = QFormLayout(self)
        form.addRow(self.histogram)
        form.addRow("Isovalue", self.spin)
        form.addRow("Model", self.model)
        form.addRow("Colour", self.color)
        form.addRow("Opacity", self.opacity)
        form.addRow("Material", self.material)
        form.addRow(self.add_button)
        self.histogram.valueChanged.connect(self._iso_from_slider)
        self.spin.valueChanged.connect(self._iso_from_spin)
        self.model.currentIndexChanged.connect(self._model)
        self.color.colorChanged.connect(lambda c: self._apply(lambda l: l.set_color(c)))
        self.opacity.valueChanged.connect(lambda v: self._apply(lambda l: l.set_opacity(v)))
        self.material.currentTextChanged.connect(
            lambda m: self._apply(lambda l: l.set_material(m)))
        self.add_button.clicked.connect(lambda: window.add_isosurface())
        self._syncing = False
        self.setEnabled(False)

    def set_layer(self, layer: IsosurfaceLayer | None, data=None) -> None:
        self.layer = layer
        self.setEnabled(layer is not None)
        if layer is None:
            return
        self._syncing = True
        try:
            self.histogram.set_data(layer.volume.data if data is None else data)
            lo, hi = self.histogram.range()
            self.spin.setRange(lo, hi)
            self.spin.setSingleStep((hi - lo) / 200.0)
            self.spin.setValue(layer.isovalue)
            self.histogram.setValue(layer.isovalue)
            self.model.setCurrentIndex(list(MODEL_LABELS).index(layer.model))
            self.color.setColor(layer.color)
            self.opacity.setValue(layer.opacity)
            self.material.setCurrentText(layer.material_name)
        finally:
            self._syncing = False

    def _apply(self, fn) -> None:
        if self._syncing or self.layer is None:
            return
        try:
            fn(self.layer)
        except SplinevizError as exc:
            self.window.show_error(str(exc))
            return
        self.window.request_render()

    def _iso_from_slider(self, v):
        if self._syncing:
            return
        self._syncing = True
        self.spin.setValue(v)
        self._syncing = False
        self._apply_iso(v)

    def _iso_from_spin(self, v):
        if self._syncing:
            return
        self._syncing = True
        self.histogram.setValue(v)
        self._syncing = False
        self._apply_iso(v)

    def _apply_iso(self, v):
        if self.layer is None:
            return
        self.layer.set_isovalue(v)
        self.window.layer_changed(self.layer)

    def _model(self, index):
        if self._syncing or self.layer is None:
            return
        self.layer.set_model(self.model.itemData(index))
        self.window.layer_changed(self.layer)


class ClippingPanel(QWidget):
    """Clip planes of the isosurfaces: add, remove, flip; each has a plane widget."""

    def __init__(self, window):
        super().__init__()
        self.window = window
        self.planes: list[dict] = []
        self.list = QListWidget()
        self.add_button = QPushButton("Add")
        self.remove_button = QPushButton("Remove")
        self.flip_button = QPushButton("Flip")
        self.show_widgets = QCheckBox("Show plane widgets")
        self.show_widgets.setChecked(True)
        lay = QVBoxLayout(self)
        lay.addWidget(self.list)
        row = QHBoxLayout()
        for b in (self.add_button, self.remove_button, self.flip_button):
            row.addWidget(b)
        lay.addLayout(row)
        lay.addWidget(self.show_widgets)
        self.add_button.clicked.connect(lambda: self.add_plane())
        self.remove_button.clicked.connect(self.remove_plane)
        self.flip_button.clicked.connect(self.flip_plane)
        self.show_widgets.toggled.connect(self._toggle_widgets)

    def add_plane(self, origin=None, normal=(1.0, 0.0, 0.0)) -> dict:
        bounds = self.window.scene_bounds()
        if origin is None:
            origin = tuple(0.5 * (lo + hi) for lo, hi in bounds)
        plane = {"origin": tuple(map(float, origin)), "normal": tuple(map(float, normal)),
                 "widget": None}
        self.planes.append(plane)
        self._make_widget(plane, bounds)
        self._sync()
        self.list.setCurrentRow(len(self.planes) - 1)
        return plane

    def _make_widget(self, plane, bounds):
        plotter = self.window.plotter

        def moved(normal, origin, plane=plane):
            plane["normal"] = tuple(map(float, normal))
            plane["origin"] = tuple(map(float, origin))
            self._sync(render=False)

        widget = plotter.add_plane_widget(
            moved, normal=plane["normal"], origin=plane["origin"],
            bounds=np.ravel(bounds), normal_rotation=True, outline_translation=False,
            origin_translation=True, implicit=True, interaction_event="always", color="white",
            test_callback=False)
        widget.SetEnabled(int(self.show_widgets.isChecked()))
        plane["widget"] = widget

    def current_index(self) -> int:
        i = self.list.currentRow()
        return i if 0 <= i < len(self.planes) else len(self.planes) - 1

    def remove_plane(self) -> None:
        i = self.current_index()
        if i < 0:
            return
        plane = self.planes.pop(i)
        w = plane["widget"]
        if w is not None:
            w.Off()
            widgets = self.window.plotter.widgets.plane_widgets
            if w in widgets:
                widgets.remove(w)
        self._sync()

    def flip_plane(self) -> None:
        i = self.current_index()
        if i < 0:
            return
        plane = self.planes[i]
        plane["normal"] = tuple(-v for v in plane["normal"])
        w = plane["widget"]
        if w is not None:
            w.SetNormal(plane["normal"])  # vtkImplicitPlaneWidget (pyvista, implicit=True)
        self._sync()

    def _toggle_widgets(self, on):
        for p in self.planes:
            if p["widget"] is not None:
                p["widget"].SetEnabled(int(on))
        self.window.request_render()

    def _sync(self, render=True) -> None:
        self.list.blockSignals(True)
        row = self.list.currentRow()
        self.list.clear()
        for p in self.planes:
            o = ", ".join(f"{v:.3g}" for v in p["origin"])
            n = ", ".join(f"{v:.2f}" for v in p["normal"])
            self.list.addItem(f"origin ({o})  normal ({n})")
        self.list.setCurrentRow(min(row, len(self.planes) - 1))
        self.list.blockSignals(False)
        self.window.scene.set_clip_planes([(p["origin"], p["normal"]) for p in self.planes])
        self.window.request_render()

    def clear(self) -> None:
        while self.planes:
            self.remove_plane()


class SmoothingPanel(QWidget):
    """Gaussian smoothing of the current volume on the OpenCL device, live; original kept."""

    def __init__(self, window):
        super().__init__()
        self.window = window
        self.sigma = QDoubleSpinBox()
        self.sigma.setRange(0.0, 8.0)
        self.sigma.setSingleStep(0.25)
        self.sigma.setSuffix(" voxels")
        self.sigma.setKeyboardTracking(False)
        self.live = QCheckBox("Apply live")
        self.live.setChecked(True)
        self.apply_button = QPushButton("Apply")
        self.reset_button = QPushButton("Original")
        self.info = QLabel("")
        form = QFormLayout(self)
        form.addRow("Sigma", self.sigma)
        form.addRow(self.live)
        row = QHBoxLayout()
        row.addWidget(self.apply_button)
        row.addWidget(self.reset_button)
        form.addRow(row)
        form.addRow(self.info)
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(SMOOTH_DELAY_MS)
        self._timer.timeout.connect(self.apply)
        self.sigma.valueChanged.connect(lambda _: self.live.isChecked() and self._timer.start())
        self.apply_button.clicked.connect(self.apply)
        self.reset_button.clicked.connect(lambda: (self.sigma.setValue(0.0), self.apply()))

    def apply(self) -> None:
        item = self.window.current_volume_item()
        if item is not None:
            self.window.smooth(item, self.sigma.value())


class RemeshPanel(QWidget):
    """Point-cloud remeshing (thesis ch. 7): parameters, run, progress, result statistics."""

    def __init__(self, window):
        super().__init__()
        self.window = window
        self.mode = QComboBox()
        self.mode.addItems(["curvature adaptive (rho)", "uniform edge length"])
        self.rho = QDoubleSpinBox()
        self.rho.setRange(0.05, 1.5)
        self.rho.setSingleStep(0.05)
        self.rho.setValue(0.35)
        self.edge = QDoubleSpinBox()
        self.edge.setDecimals(5)
        self.edge.setRange(1e-6, 1e6)
        self.edge.setValue(1.0)
        self.point_size = QSpinBox()
        self.point_size.setRange(1, 20)
        self.point_size.setValue(3)
        self.run_button = QPushButton("Remesh")
        self.stats = QLabel("")
        self.stats.setWordWrap(True)
        self.stats.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        form = QFormLayout(self)
        form.addRow("Mode", self.mode)
        form.addRow("rho (rad)", self.rho)
        form.addRow("Edge length", self.edge)
        form.addRow("Point size", self.point_size)
        form.addRow(self.run_button)
        form.addRow(self.stats)
        self.run_button.clicked.connect(self.run)
        self.point_size.valueChanged.connect(window.set_point_size)

    def run(self) -> None:
        item = self.window.current_points_item()
        if item is None:
            self.window.show_error("select a point cloud in the data panel first")
            return
        if self.mode.currentIndex() == 0:
            self.window.remesh(item, rho=self.rho.value())
        else:
            self.window.remesh(item, edge_length=self.edge.value())


class ScreenshotDialog(QDialog):
    """Size and transparency of an exported screenshot."""

    def __init__(self, parent, size):
        super().__init__(parent)
        self.setWindowTitle("Export screenshot")
        self.width = QSpinBox()
        self.height = QSpinBox()
        for s, v in ((self.width, size[0]), (self.height, size[1])):
            s.setRange(16, 16384)
            s.setValue(v)
        self.transparent = QCheckBox("Transparent background")
        form = QFormLayout(self)
        form.addRow("Width", self.width)
        form.addRow("Height", self.height)
        form.addRow(self.transparent)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok
                                   | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)


# ------------------------------------------------------------------------------------------
# the window


class MainWindow(QMainWindow):
    """The splineviz main window (see module docstring).

    Parameters
    ----------
    size : (width, height) of the 3-D view, optional
    device : OpenCL device preference for the ray casters
    """

    def __init__(self, size=None, device=None):
        super().__init__()
        from pyvistaqt import QtInteractor

        self.setWindowTitle("splineviz")
        # workers run on Qt's global pool; its default size (the core count, 2 here) would
        # let a long ray cast or remesh queue a load behind it
        pool = QThreadPool.globalInstance()
        pool.setMaxThreadCount(max(pool.maxThreadCount(), 6))
        self.setAcceptDrops(True)
        self.device = device
        self.items: list[DataItem] = []
        self.last_error: str | None = None
        self._message_boxes: list[QMessageBox] = []
        self._workers: list = []
        self._jobs = 0
        self._cancel_requested = False
        self._refine_worker = None
        self._refine_again = False
        self._closed = False
        # no multisampling: on software GL (llvmpipe) 4x MSAA cost ~80 ms of a 1024x768 frame
        # (113 -> 33 ms measured); the ray-cast image is one sample per pixel anyway
        self.plotter = QtInteractor(self, auto_update=False, multi_samples=0)
        self.plotter.set_background(BACKGROUND)
        self.plotter.enable_anti_aliasing = None
        self.setCentralWidget(self.plotter)
        if size is not None:
            # the docks must not squeeze the view below the requested size
            self.plotter.setMinimumSize(*size)
        self.scene = SplineScene(self.plotter, progressive=True)
        self.scene.request_refine = self._schedule_refine
        self._axes = self.plotter.add_axes()
        self._build_panels()
        self._build_menus()
        self._build_status()
        self._refine_timer = QTimer(self)
        self._refine_timer.setSingleShot(True)
        self._refine_timer.setInterval(REFINE_DELAY_MS)
        self._refine_timer.timeout.connect(self._start_refine)
        iren = self.plotter.iren.interactor
        iren.AddObserver("StartInteractionEvent", lambda *_: self.scene.set_interacting(True))
        iren.AddObserver("EndInteractionEvent", self._interaction_ended)
        rw = self.plotter.render_window
        rw.AddObserver("StartEvent", self._frame_start)
        rw.AddObserver("EndEvent", self._frame_end)
        self._t_frame = None
        self.frame_times: list[float] = []

    # -- construction --------------------------------------------------------------------

    def _dock(self, title, widget, area=Qt.DockWidgetArea.LeftDockWidgetArea) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(title)
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        return dock

    def _build_panels(self):
        self.data_panel = DataPanel(self)
        self.iso_panel = IsosurfacePanel(self)
        self.clip_panel = ClippingPanel(self)
        self.smooth_panel = SmoothingPanel(self)
        self.remesh_panel = RemeshPanel(self)
        self._dock("Data", self.data_panel)
        self._dock("Isosurface", self.iso_panel)
        right = Qt.DockWidgetArea.RightDockWidgetArea
        self._dock("Clipping", self.clip_panel, right)
        self._dock("Smoothing", self.smooth_panel, right)
        self._dock("Remeshing", self.remesh_panel, right)

    def _build_menus(self):
        m = self.menuBar().addMenu("&File")

        def act(menu, text, slot, shortcut=None):
            a = QAction(text, self)
            if shortcut:
                a.setShortcut(QKeySequence(shortcut))
            a.triggered.connect(slot)
            menu.addAction(a)
            return a

        act(m, "&Open...", self._open_dialog, QKeySequence.StandardKey.Open)
        self.recent_menu = m.addMenu("Open &Recent")
        self._fill_recent()
        act(m, "Open &default data", lambda: self.open_default())
        self.sources_menu = m.addMenu("Open s&ynthetic source")
        self.sources_menu.aboutToShow.connect(self._fill_sources)
        m.addSeparator()
        act(m, "&Load session...", self._open_session_dialog)
        act(m, "&Save session...", self._save_session_dialog, QKeySequence.StandardKey.Save)
        m.addSeparator()
        act(m, "Export &screenshot...", self._screenshot_dialog)
        act(m, "Export &mesh...", self._export_mesh_dialog)
        m.addSeparator()
        act(m, "&Quit", self.close, QKeySequence.StandardKey.Quit)
        v = self.menuBar().addMenu("&View")
        act(v, "&Reset camera", lambda: (self.plotter.reset_camera(), self.request_render()))
        h = self.menuBar().addMenu("&Help")
        act(h, "&About splineviz", self._about)

    def _build_status(self):
        sb = self.statusBar()
        self.fps_label = QLabel("")
        self.cells_label = QLabel("")
        self.device_label = QLabel("")
        self.progress = QProgressBar()
        self.progress.setMaximumWidth(180)
        self.progress.setVisible(False)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setVisible(False)
        self.cancel_button.clicked.connect(self.cancel_jobs)
        # permanent widgets: QStatusBar hides ordinary ones while a message shows
        for w in (self.progress, self.cancel_button, self.fps_label, self.cells_label,
                  self.device_label):
            sb.addPermanentWidget(w)

    # -- frame timing and status ---------------------------------------------------------

    def _frame_start(self, *_):
        self._t_frame = time.perf_counter()

    def _frame_end(self, *_):
        if self._t_frame is None or self._closed:
            return
        dt = time.perf_counter() - self._t_frame
        self.frame_times.append(dt)
        del self.frame_times[:-100]
        self.fps_label.setText(f"frame {dt * 1000:.0f} ms ({1.0 / max(dt, 1e-6):.0f} fps)")
        active, device = [], set()
        for layer in self.scene.layers:
            s = layer.last_stats
            n = s.get("active_tets") or s.get("active_cells")
            if n is not None:
                what = "tets" if s.get("active_tets") else "cells"
                active.append(f"{n:,} active {what}")
            if s.get("device"):
                device.add(str(s["device"]).split(":")[0])
        self.cells_label.setText("; ".join(active))
        self.device_label.setText(", ".join(sorted(device)) or "")

    # -- rendering -----------------------------------------------------------------------

    def request_render(self) -> None:
        if not self._closed:
            self.plotter.render()

    def _interaction_ended(self, *_):
        self.scene.set_interacting(False)
        self.request_render()  # schedules the exact frames

    def _schedule_refine(self) -> None:
        self._refine_timer.start()

    def _start_refine(self) -> None:
        if self._closed:
            return
        if self._refine_worker is not None:
            self._refine_again = True
            return
        if not self.scene.needs_refine():
            return
        view = self.scene.view_state()
        if any(layer.needs_classification() for layer in self.scene.layers):
            self.statusBar().showMessage("classifying cells and ray casting...")
        worker = create_worker(self.scene.refine, view, _start_thread=False, _ignore_errors=True)
        self._refine_worker = worker
        worker.returned.connect(self._refined)
        worker.errored.connect(lambda e: self.show_error(f"rendering failed: {e}"))
        worker.finished.connect(self._refine_finished)
        worker.start()

    def _refined(self, results) -> None:
        if not self._closed and self.scene.apply(results):
            self.plotter.render()

    def _refine_finished(self) -> None:
        self._refine_worker = None
        if not self._closed and not self._workers:
            self.statusBar().clearMessage()
        if self._refine_again:
            self._refine_again = False
            self._refine_timer.start()

    def wait_for_refine(self, timeout_s: float = 120.0) -> None:
        """Process events until exact frames are shown (tests, scripted screenshots)."""
        from PySide6.QtWidgets import QApplication

        end = time.perf_counter() + timeout_s
        while time.perf_counter() < end:
            QApplication.processEvents()
            if (self._refine_worker is None and not self._refine_timer.isActive()
                    and not self.scene.needs_refine()):
                return
            if (self._refine_worker is None and not self._refine_timer.isActive()):
                self._start_refine()
            time.sleep(0.01)
        raise TimeoutError("exact frames did not arrive in time")

    def measure_interaction(self, steps: int = 20, degrees: float = 3.0) -> dict:
        """Rotate the camera ``steps`` times as a drag would (previews) and time the frames.

        Returns
        -------
        dict with ``mean_ms``, ``median_ms``, ``fps`` and the window ``size``.
        """
        self.scene.set_interacting(True)
        times = []
        try:
            for _ in range(steps):
                self.plotter.camera.Azimuth(degrees)
                t = time.perf_counter()
                self.plotter.render()
                times.append(time.perf_counter() - t)
        finally:
            self.scene.set_interacting(False)
        t = np.asarray(times)
        return {"mean_ms": 1000 * t.mean(), "median_ms": 1000 * np.median(t),
                "fps": 1.0 / np.median(t), "size": self.scene.window_size()}

    # -- jobs ----------------------------------------------------------------------------

    def run_job(self, label, func, *args, on_done=None, progress=True, **kwargs):
        """Run ``func(*args, **kwargs)`` in a worker thread with progress and cancel.

        ``func`` may be a generator yielding fractions in [0, 1] (progress) and returning its
        result. Errors become a message; ``on_done(result)`` runs in the GUI thread.
        """
        self._cancel_requested = False
        worker = create_worker(func, *args, _start_thread=False, _ignore_errors=True, **kwargs)
        self._jobs += 1
        self.progress.setVisible(progress)
        self.progress.setRange(0, 0)
        self.progress.setFormat(label)
        self.cancel_button.setVisible(True)
        self.statusBar().showMessage(label + "...")
        if hasattr(worker, "yielded"):
            def step(v):
                self.progress.setRange(0, 100)
                self.progress.setValue(int(100 * float(v)))
            worker.yielded.connect(step)
        if on_done is not None:
            worker.returned.connect(on_done)
        worker.errored.connect(self._job_error)
        worker.finished.connect(lambda w=worker: self._job_finished(w))
        self._workers.append(worker)
        worker.start()
        return worker

    def _job_error(self, exc) -> None:
        if isinstance(exc, Cancelled) or type(exc).__name__ == "Cancelled":
            self.statusBar().showMessage("cancelled", 3000)
            return
        if isinstance(exc, (SplinevizError, OSError, ValueError)):
            self.show_error(str(exc))
        else:
            self.show_error("".join(traceback.format_exception_only(type(exc), exc)).strip())

    def _job_finished(self, worker) -> None:
        if self._closed:
            return
        if worker in self._workers:
            self._workers.remove(worker)
        self._jobs -= 1
        if self._jobs <= 0:
            self._jobs = 0
            self.progress.setVisible(False)
            self.cancel_button.setVisible(False)
            self.statusBar().clearMessage()

    def cancel_jobs(self) -> None:
        self._cancel_requested = True
        for w in list(self._workers):
            if hasattr(w, "quit"):
                w.quit()

    def busy(self) -> bool:
        return bool(self._workers)

    def wait_idle(self, timeout_s: float = 120.0) -> None:
        """Process events until no job runs (tests and scripted use)."""
        from PySide6.QtWidgets import QApplication

        end = time.perf_counter() + timeout_s
        while time.perf_counter() < end:
            QApplication.processEvents()
            # idle: no job, and no pending live-smoothing timer that would start one
            if not self._workers and not self.smooth_panel._timer.isActive():
                return
            time.sleep(0.01)
        if self._workers:
            raise TimeoutError(f"background work did not finish in {timeout_s:g} s: "
                               f"{len(self._workers)} job(s) running")

    def show_error(self, message: str) -> None:
        """A non-blocking message box; the window stays usable."""
        self.last_error = message
        self.statusBar().showMessage(message, 8000)
        box = QMessageBox(QMessageBox.Icon.Warning, "splineviz", message,
                          QMessageBox.StandardButton.Ok, self)
        box.setWindowModality(Qt.WindowModality.NonModal)
        box.finished.connect(lambda *_: self._message_boxes.remove(box)
                             if box in self._message_boxes else None)
        self._message_boxes.append(box)
        box.show()

    # -- data ----------------------------------------------------------------------------

    def open_default(self) -> DataItem:
        vol, iso = default_data()
        return self.add_volume(vol, "Marschner-Lobb 41^3", iso=iso, source="marschner-lobb")

    def open_source(self, name: str, shape=None) -> DataItem:
        """Sample a synthetic source offered by a plugin (see :mod:`splineviz.plugins`)."""
        from splineviz.plugins import sources

        src = sources().get(name)
        if src is None:
            raise SplinevizError(f"no synthetic source named {name!r}; plugins offer "
                                 f"{', '.join(sorted(sources())) or 'none'}")
        vol = src.volume(shape)
        return self.add_volume(vol, f"{src.title} {'x'.join(map(str, vol.shape))}",
                               iso=src.isovalue, source=name)

    def _fill_sources(self):
        from splineviz.plugins import failures, sources

        self.sources_menu.clear()
        for name, src in sorted(sources().items()):
            a = QAction(src.title or name, self)
            a.triggered.connect(lambda _=False, n=name: self.open_source(n))
            self.sources_menu.addAction(a)
        for rec in failures():
            a = QAction(f"plugin {rec.name} failed: {rec.error}", self)
            a.setEnabled(False)
            self.sources_menu.addAction(a)

    def open_path(self, path, block: bool = False, **iso_kwargs):
        """Open a volume, point cloud or session (in a worker unless ``block``)."""
        path = str(path)

        def done(result):
            kind, obj = result
            self._add_recent(path)
            if kind == "volume":
                self.add_volume(obj, Path(path).name, path=path, **iso_kwargs)
            elif kind == "points":
                self.add_points(obj, Path(path).name, path=path)
            else:
                self.apply_session(*obj)

        if block:
            try:
                done(load_path(path))
            except (SplinevizError, OSError, ValueError) as exc:
                self.show_error(str(exc))
            return None
        if Path(path).suffix.lower() in SESSION_SUFFIXES:
            # the document is parsed here (fast) so missing data files can be re-pointed in
            # a file dialog; the data are read in the worker
            from splineviz.io.session import load_session

            try:
                session = load_session(path, repoint=self._ask_repoint)
            except (SplinevizError, OSError) as exc:
                self.show_error(str(exc))
                return None
            return self.run_job(f"Loading {Path(path).name}", session_data, session,
                                on_done=lambda data: done(("session", (session, data))))
        return self.run_job(f"Loading {Path(path).name}", load_path, path, on_done=done)

    def _ask_repoint(self, obj_id: str, missing: Path):
        """File dialog for a session's missing data file; None gives up."""
        found, _ = QFileDialog.getOpenFileName(
            self, f"Where is {Path(missing).name}? (object {obj_id})", str(Path(missing).parent))
        return found or None

    def add_volume(self, volume: Volume, name: str, path=None, iso=None, model=None,
                   source=None) -> DataItem:
        item = DataItem(name, "volume", path=path, volume=volume, source=source)
        self.items.append(item)
        first = not any(i.kind != "volume" or i is not item for i in self.items)
        self.scene.add_mesh(f"outline:{id(item)}", _outline(volume), kind="outline",
                            color="gray", pickable=False)
        layer = self.add_isosurface(item, iso=iso, model=model, rebuild=False)
        if first or len(self.items) == 1:
            self.plotter.reset_camera(bounds=np.ravel(volume.bounds))
            self.plotter.camera.Azimuth(30)
            self.plotter.camera.Elevation(20)
            self.plotter.camera.Zoom(1.4)
        self.data_panel.rebuild(select=layer)
        self.request_render()
        return item

    def add_isosurface(self, item: DataItem | None = None, iso=None, model=None,
                       rebuild=True) -> IsosurfaceLayer | None:
        item = item or self.current_volume_item()
        if item is None:
            self.show_error("open a volume first")
            return None
        vol = item.active_volume
        if model is None:
            model = item.layers[-1].model if item.layers else default_model()
        n = len(item.layers)
        if iso is None and item.layers:
            lo, hi = vol.finite_range
            iso = lo + (hi - lo) * (0.3 + 0.4 * ((n * 0.618) % 1.0))
        layer = IsosurfaceLayer(vol, model=model, isovalue=iso, color=PALETTE[n % len(PALETTE)],
                                name=f"isosurface {n + 1}", device=self.device)
        item.layers.append(layer)
        self.scene.add_layer(layer)
        if rebuild:
            self.data_panel.rebuild(select=layer)
            self.request_render()
        return layer

    def add_points(self, pc, name: str, path=None) -> DataItem:
        import pyvista as pv

        item = DataItem(name, "points", path=path, points=pc)
        self.items.append(item)
        cloud = pv.PolyData(np.asarray(pc.points, dtype=np.float64))
        self.scene.add_mesh(item.prop_name, cloud, kind="points", color=(0.85, 0.85, 0.9),
                            point_size=self.remesh_panel.point_size.value(),
                            render_points_as_spheres=False, style="points")
        if len(self.items) == 1:
            self.plotter.reset_camera(bounds=cloud.bounds)
        spacing = _median_spacing(np.asarray(pc.points))
        self.remesh_panel.edge.setValue(2.0 * spacing)
        self.data_panel.rebuild(select=item)
        self.request_render()
        return item

    def add_mesh_item(self, mesh, name: str, stats=None) -> DataItem:
        item = DataItem(name, "mesh", mesh=mesh, stats=stats or {})
        self.items.append(item)
        self.scene.add_mesh(item.prop_name, mesh, kind="mesh", color=(0.75, 0.85, 0.95),
                            show_edges=True, edge_color=(0.2, 0.25, 0.35), smooth_shading=False)
        self.data_panel.rebuild(select=item)
        self.request_render()
        return item

    def set_point_size(self, size: int) -> None:
        for item in self.items:
            if item.kind == "points":
                rec = self.scene.props.get(item.prop_name)
                if rec is not None:
                    rec.actor.GetProperty().SetPointSize(size)
                    rec.options["point_size"] = size
        self.request_render()

    def set_visible(self, obj, visible: bool) -> None:
        if isinstance(obj, IsosurfaceLayer):
            obj.set_visible(visible)
        elif isinstance(obj, DataItem):
            obj.visible = visible
            if obj.kind == "volume":
                for layer in obj.layers:
                    layer.set_visible(visible)
                self.scene.set_prop_visible(f"outline:{id(obj)}", visible)
            else:
                self.scene.set_prop_visible(obj.prop_name, visible)
        self.request_render()

    def remove_object(self, obj) -> None:
        if isinstance(obj, IsosurfaceLayer):
            for item in self.items:
                if obj in item.layers:
                    item.layers.remove(obj)
            self.scene.remove_layer(obj)
        elif isinstance(obj, DataItem):
            for layer in obj.layers:
                self.scene.remove_layer(layer)
            if obj.kind == "volume":
                self.scene.remove_prop(f"outline:{id(obj)}")
            elif obj.prop_name in self.scene.props:
                self.scene.remove_prop(obj.prop_name)
            self.items.remove(obj)
        self.data_panel.rebuild()
        self.request_render()

    def clear(self) -> None:
        for item in list(self.items):
            self.remove_object(item)
        self.clip_panel.clear()

    def selection_changed(self) -> None:
        obj = self.data_panel.current()
        layer = None
        if isinstance(obj, IsosurfaceLayer):
            layer = obj
        elif isinstance(obj, DataItem) and obj.layers:
            layer = obj.layers[0]
        item = self._item_of(layer) if layer is not None else None
        self.iso_panel.set_layer(layer, None if item is None else item.active_volume.data)
        if item is not None:
            self.smooth_panel.sigma.blockSignals(True)
            self.smooth_panel.sigma.setValue(item.sigma)
            self.smooth_panel.sigma.blockSignals(False)

    def layer_changed(self, layer) -> None:
        """After the isovalue or model changed: label in the data panel, render."""
        node = self.data_panel.tree.currentItem()
        if node is not None and node.data(0, Qt.ItemDataRole.UserRole) is layer:
            node.setText(1, f"{layer.model} @ {layer.isovalue:.4g}")
        self.request_render()

    def _item_of(self, layer) -> DataItem | None:
        for item in self.items:
            if layer in item.layers:
                return item
        return None

    def current_volume_item(self) -> DataItem | None:
        obj = self.data_panel.current()
        if isinstance(obj, IsosurfaceLayer):
            return self._item_of(obj)
        if isinstance(obj, DataItem) and obj.kind == "volume":
            return obj
        vols = [i for i in self.items if i.kind == "volume"]
        return vols[-1] if vols else None

    def current_points_item(self) -> DataItem | None:
        obj = self.data_panel.current()
        if isinstance(obj, DataItem) and obj.kind == "points":
            return obj
        pts = [i for i in self.items if i.kind == "points"]
        return pts[-1] if pts else None

    def scene_bounds(self):
        vols = [i.volume for i in self.items if i.kind == "volume"]
        if vols:
            b = np.array([np.ravel(v.bounds) for v in vols])
            return tuple((b[:, 2 * a].min(), b[:, 2 * a + 1].max()) for a in range(3))
        bounds = self.plotter.renderer.ComputeVisiblePropBounds()
        if bounds[0] > bounds[1]:
            return ((-1.0, 1.0),) * 3
        return tuple((bounds[2 * a], bounds[2 * a + 1]) for a in range(3))

    # -- smoothing, remeshing ------------------------------------------------------------

    def smooth(self, item: DataItem, sigma: float, block: bool = False):
        """Smooth ``item``'s original volume (OpenCL) and feed it to its layers."""
        from splineviz.compute.smoothing import gaussian_smooth

        def done(vol):
            item.sigma = float(sigma)
            item.smoothed = None if sigma == 0 else vol
            for layer in item.layers:
                layer.set_volume(item.active_volume)
            self.smooth_panel.info.setText(
                "original data" if sigma == 0 else f"smoothed, sigma {sigma:g} voxels")
            self.data_panel.rebuild(select=self.data_panel.current())
            self.request_render()

        if sigma == 0:
            done(item.volume)
            return None
        if block:
            done(gaussian_smooth(item.volume, sigma, device=self.device))
            return None
        return self.run_job("Smoothing", gaussian_smooth, item.volume, sigma,
                            device=self.device, on_done=done)

    def remesh(self, item: DataItem, edge_length=None, rho=None):
        """Run ``sv.remesh`` on a point cloud in a worker; show the mesh and its quality."""
        try:
            remesh = splineviz.remesh
            quality = splineviz.mesh_quality
        except (AttributeError, ImportError) as exc:
            self.show_error(f"remeshing is not available: {exc}")
            return None
        pc = item.points

        def work():
            import threading
            from queue import Empty, Queue

            q: Queue = Queue()
            out = {}

            def progress(fraction, _message=""):
                q.put(float(fraction))
                return not self._cancel_requested

            def target():
                try:
                    mesh = remesh(pc, edge_length=edge_length, rho=rho, progress=progress)
                    out["mesh"] = mesh
                    out["quality"] = quality(mesh, reference=pc)
                except BaseException as exc:  # handed to the GUI thread below
                    out["error"] = exc

            t = threading.Thread(target=target, daemon=True)
            t.start()
            while t.is_alive() or not q.empty():
                try:
                    yield q.get(timeout=0.1)
                except Empty:
                    pass
            if "error" in out:
                err = out["error"]
                if type(err).__name__ == "Cancelled":
                    raise Cancelled("remeshing cancelled")
                raise err
            return out

        def done(out):
            q = out["quality"]
            item_mesh = self.add_mesh_item(out["mesh"], f"mesh of {item.name}", stats=q)
            self.remesh_panel.stats.setText(_quality_text(q))
            return item_mesh

        return self.run_job("Remeshing", work, on_done=done)

    # -- sessions, export ----------------------------------------------------------------

    def build_session(self):
        """A :class:`splineviz.io.session.Session` of what the window shows."""
        from splineviz.io.session import CameraState, Session

        s = Session()
        iso_ids = []
        for item in self.items:
            if item.kind == "volume":
                if item.path:
                    src = s.add("VolumeFile", {"path": item.path}, name=item.name)
                elif item.source:
                    src = s.add("Source", {"source": item.source,
                                           "shape": list(item.volume.shape)}, name=item.name)
                else:
                    continue
                for layer in item.layers:
                    props = {"isovalue": layer.isovalue, "model": layer.model,
                             "color": list(layer.color), "opacity": layer.opacity,
                             "visible": layer.visible}
                    iso_ids.append(s.add("Isosurface", props, inputs=[src.id],
                                         name=layer.name).id)
            elif item.kind == "points" and item.path:
                s.add("PointsFile", {"path": item.path, "visible": item.visible},
                      name=item.name)
        for plane in self.clip_panel.planes:
            if iso_ids:
                s.add("ClipPlane", {"origin": list(plane["origin"]),
                                    "normal": list(plane["normal"])}, inputs=iso_ids)
        cam = self.plotter.camera
        s.views[0].camera = CameraState(position=cam.position, focal_point=cam.focal_point,
                                        view_up=cam.up, view_angle=cam.view_angle)
        s.views[0].background = tuple(self.plotter.renderer.GetBackground())
        return s

    def save_session(self, path) -> None:
        from splineviz.io.session import save_session

        save_session(self.build_session(), path)
        self._add_recent(str(path))

    def apply_session(self, session, data=None) -> None:
        """Replace the scene by a loaded session (``data``: :func:`session_data`, read in a
        worker; read here when None)."""
        if data is None:
            data = session_data(session)
        self.clear()
        volumes = {}
        for obj in session.objects:
            if obj.type in ("VolumeFile", "Source"):
                volumes[obj.id] = (data[obj.id], obj)
        clip_planes = []
        for obj in session.objects:
            p = obj.properties
            if obj.type == "Isosurface":
                vol, src = volumes[obj.inputs[0]]
                item = next((i for i in self.items if i.name == (src.name or src.id)), None)
                if item is None:
                    item = DataItem(src.name or src.id, "volume", volume=vol,
                                    path=getattr(src.properties, "path", None),
                                    source=getattr(src.properties, "source", None))
                    self.items.append(item)
                    self.scene.add_mesh(f"outline:{id(item)}", _outline(vol), kind="outline",
                                        color="gray", pickable=False)
                model = p.model if p.model in MODEL_LABELS else "trilinear"
                layer = self.add_isosurface(item, iso=p.isovalue, model=model, rebuild=False)
                layer.name = obj.name or layer.name
                layer.set_color(p.color)
                layer.set_opacity(max(p.opacity, 0.05))
                layer.set_visible(p.visible)
            elif obj.type == "PointsFile":
                self.add_points(data[obj.id], obj.name or obj.id, path=p.path)
            elif obj.type == "ClipPlane" and p.enabled:
                clip_planes.append((p.origin, p.normal))
        for origin, normal in clip_planes:
            self.clip_panel.add_plane(origin, normal)
        cam = session.views[0].camera
        c = self.plotter.camera
        c.position, c.focal_point, c.up = cam.position, cam.focal_point, cam.view_up
        c.view_angle = cam.view_angle
        self.plotter.camera_set = True
        self.plotter.set_background(session.views[0].background)
        self.data_panel.rebuild()
        self.request_render()

    def export_screenshot(self, path, size=None, transparent: bool = False) -> np.ndarray:
        """Write the view as PNG at ``size`` (exact frames, off-screen); returns the image."""
        img = offscreen_screenshot(self.scene, str(path), size=size,
                                   transparent_background=transparent)
        self.statusBar().showMessage(f"saved {path}", 5000)
        return img

    def export_mesh(self, path, obj=None) -> str:
        """Write a mesh item, or an isosurface layer meshed on a refined grid (no GUI calls:
        the File menu runs it in a worker). Returns the path written."""
        import splineviz as sv
        from splineviz.render.extract import spline_isosurface

        obj = obj if obj is not None else self.data_panel.current()
        if isinstance(obj, DataItem) and obj.kind == "mesh":
            mesh = obj.mesh
        elif isinstance(obj, IsosurfaceLayer) or (isinstance(obj, DataItem) and obj.layers):
            layer = obj if isinstance(obj, IsosurfaceLayer) else obj.layers[0]
            mesh = spline_isosurface(sv.build_spline(layer.volume, layer.model), layer.isovalue)
        else:
            raise SplinevizError("select a mesh or an isosurface to export")
        return str(sv.write_mesh(path, mesh))

    # -- dialogs, recent files, drag and drop --------------------------------------------

    def _open_dialog(self):
        path, _ = QFileDialog.getOpenFileName(self, "Open volume, point cloud or session")
        if path:
            self.open_path(path)

    def _open_session_dialog(self):
        path, _ = QFileDialog.getOpenFileName(self, "Load session", "",
                                              "splineviz sessions (*.svs)")
        if path:
            self.open_path(path)

    def _save_session_dialog(self):
        path, _ = QFileDialog.getSaveFileName(self, "Save session", "session.svs",
                                              "splineviz sessions (*.svs)")
        if path:
            try:
                self.save_session(path)
            except (SplinevizError, OSError) as exc:
                self.show_error(str(exc))

    def _screenshot_dialog(self):
        dlg = ScreenshotDialog(self, self.scene.window_size())
        if dlg.exec() != QDialog.DialogCode.Accepted:
            return
        path, _ = QFileDialog.getSaveFileName(self, "Export screenshot", "screenshot.png",
                                              "PNG images (*.png)")
        if path:
            try:
                self.export_screenshot(path, (dlg.width.value(), dlg.height.value()),
                                       dlg.transparent.isChecked())
            except (SplinevizError, OSError) as exc:
                self.show_error(str(exc))

    def _export_mesh_dialog(self):
        path, _ = QFileDialog.getSaveFileName(self, "Export mesh", "mesh.ply",
                                              "Meshes (*.ply *.stl *.vtp *.obj *.vtk)")
        if path:
            self.run_job("Exporting mesh", self.export_mesh, path, self.data_panel.current(),
                         on_done=lambda p: self.statusBar().showMessage(f"saved {p}", 5000))

    def _about(self):
        QMessageBox.about(self, "About splineviz",
                          f"splineviz {splineviz.__version__}\n\nSmooth trivariate spline "
                          "isosurfaces (trilinear, quadratic super spline, cubic C1, "
                          "truncated-octahedral quadratic C1) by exact ray casting, and "
                          "point-cloud meshing.")

    def _settings(self) -> QSettings:
        return QSettings("splineviz", "splineviz")

    def recent_files(self) -> list[str]:
        v = self._settings().value("recent", [])
        return [v] if isinstance(v, str) else list(v or [])

    def _add_recent(self, path: str) -> None:
        p = str(Path(path).absolute())
        files = [p] + [f for f in self.recent_files() if f != p]
        self._settings().setValue("recent", files[:MAX_RECENT])
        self._fill_recent()

    def _fill_recent(self):
        self.recent_menu.clear()
        for f in self.recent_files():
            a = QAction(f, self)
            a.triggered.connect(lambda _=False, f=f: self.open_path(f))
            self.recent_menu.addAction(a)
        self.recent_menu.setEnabled(bool(self.recent_files()))

    def dragEnterEvent(self, event):  # noqa: N802
        if event.mimeData().hasUrls():
            event.acceptProposedAction()

    def dropEvent(self, event):  # noqa: N802
        for url in event.mimeData().urls():
            if url.isLocalFile():
                self.open_path(url.toLocalFile())

    def closeEvent(self, event):  # noqa: N802
        if self._closed:
            super().closeEvent(event)
            return
        self._refine_timer.stop()
        self.smooth_panel._timer.stop()
        self.cancel_jobs()
        try:
            self.wait_idle(timeout_s=10.0)
        except TimeoutError:
            pass  # a worker that ignores cancel: its result is dropped (window closed)
        if self._refine_worker is not None:
            self._refine_worker.finished.connect(lambda: None)
        self._closed = True
        for box in list(self._message_boxes):
            box.close()
        self.scene.close()
        self.plotter.close()
        super().closeEvent(event)


def _outline(volume: Volume):
    import pyvista as pv

    return pv.Box(bounds=np.ravel(volume.bounds)).outline()


def _median_spacing(points: np.ndarray) -> float:
    """Median nearest-neighbour distance of (up to 2000 sampled) points."""
    from scipy.spatial import cKDTree

    if len(points) < 2:
        return 1.0
    rng = np.random.default_rng(0)
    sample = points[rng.choice(len(points), size=min(2000, len(points)), replace=False)]
    d, _ = cKDTree(points).query(sample, k=2)
    return float(np.median(d[:, 1])) or 1.0


def _quality_text(q: dict) -> str:
    keys = [("n_vertices", "vertices", "{:,}"), ("n_faces", "triangles", "{:,}"),
            ("radius_ratio_mean", "radius ratio mean", "{:.3f}"),
            ("radius_ratio_min", "radius ratio min", "{:.3f}"),
            ("valence6_fraction", "valence 6", "{:.1%}"),
            ("hausdorff", "Hausdorff", "{:.3g}"), ("rms_distance", "RMS distance", "{:.3g}"),
            ("boundary_edges", "boundary edges", "{:,}")]
    return "\n".join(f"{label}: {fmt.format(q[k])}" for k, label, fmt in keys if k in q)
