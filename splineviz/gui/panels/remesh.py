"""The remeshing panel: point cloud to triangle mesh (thesis ch. 7), in a worker.

Parameters, a Remesh button for the current point cloud, the point size of that cloud, and
the quality statistics of the current mesh (read from its :class:`~splineviz.model.MeshNode`,
so they always belong to the mesh selected, never to an older or removed one). A remeshed
mesh and a new point size are steps of the scene's undo stack (:mod:`splineviz.gui.undo`).
"""

from __future__ import annotations

# imported with the window, not on the first point cloud: importing scipy.spatial takes
# ~0.6 s and holds the GIL, which would stall the window even from a worker thread
import scipy.spatial  # noqa: F401
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QWidget,
)

from splineviz.gui.jobs import call_named
from splineviz.gui.undo import undo_stack
from splineviz.model import MeshNode, PointsNode, Scene
from splineviz.model.summaries import cached_spacing, known_spacing


def quality_text(q: dict) -> str:
    keys = [("n_vertices", "vertices", "{:,}"), ("n_faces", "triangles", "{:,}"),
            ("radius_ratio_mean", "radius ratio mean", "{:.3f}"),
            ("radius_ratio_min", "radius ratio min", "{:.3f}"),
            ("valence6_fraction", "valence 6", "{:.1%}"),
            ("hausdorff", "Hausdorff", "{:.3g}"), ("rms_distance", "RMS distance", "{:.3g}"),
            ("boundary_edges", "boundary edges", "{:,}")]
    return "\n".join(f"{label}: {fmt.format(q[k])}" for k, label, fmt in keys if k in q)


class RemeshPanel(QWidget):
    """Remeshing parameters, the Remesh button and the current mesh's statistics."""

    def __init__(self, scene: Scene, jobs, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.jobs = jobs
        self.points: PointsNode | None = None
        self.mode = QComboBox()
        self.mode.addItems(["curvature adaptive (rho)", "uniform edge length"])
        self.mode.setToolTip("Adaptive: shorter edges where the surface bends; uniform: one "
                             "target edge length")
        self.rho = QDoubleSpinBox()
        self.rho.setRange(0.05, 1.5)
        self.rho.setSingleStep(0.05)
        self.rho.setValue(0.35)
        self.rho.setToolTip("Angle (radians) one edge may turn on the osculating circle")
        self.edge = QDoubleSpinBox()
        self.edge.setDecimals(5)
        self.edge.setRange(1e-6, 1e6)
        self.edge.setValue(1.0)
        self.edge.setToolTip("Target edge length in world units (uniform mode)")
        self.sharp_creases = QCheckBox("Sharp creases")
        self.sharp_creases.setChecked(True)
        self.sharp_creases.setToolTip("Keep the sharp edges of scanned parts (two flat sides "
                                      "meeting): vertices on the edge, mesh edges along it; "
                                      "off: the surface is rounded there")
        self.point_size = QSpinBox()
        self.point_size.setRange(1, 20)
        self.point_size.setValue(3)
        self.point_size.setToolTip("Size of the points of the current point cloud, pixels")
        self.run_button = QPushButton("Remesh")
        self.run_button.setToolTip("Triangulate the current point cloud in the background "
                                   "(progress and Cancel in the status bar)")
        self.stats = QLabel("")
        self.stats.setWordWrap(True)
        self.stats.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        form = QFormLayout(self)
        form.addRow("Mode", self.mode)
        form.addRow("rho (rad)", self.rho)
        form.addRow("Edge length", self.edge)
        form.addRow(self.sharp_creases)
        form.addRow("Point size", self.point_size)
        form.addRow(self.run_button)
        form.addRow(self.stats)
        self.run_button.clicked.connect(lambda: self.run())
        self.point_size.valueChanged.connect(self._point_size)
        scene.selection.connect(self._selection_changed)
        scene.inserted.connect(self._inserted)
        scene.removed.connect(self._removed)
        self._set_points(None)
        # a scene given to the window (the app reads the file named on its command line
        # before the window opens) has its clouds already: they were inserted unseen
        for node in scene.of_kind(PointsNode):
            self._inserted(node)

    def _inserted(self, node) -> None:
        if isinstance(node, PointsNode):
            self._set_points(node)
            spacing = known_spacing(node.data)  # the reading process measured it
            if spacing is not None:
                self.edge.setValue(2.0 * spacing)
            else:  # a k-d tree of the cloud: not in the GUI thread
                self.jobs.run("Point spacing", cached_spacing, node.data, cancellable=False,
                              on_done=lambda h: self.edge.setValue(2.0 * h))

    def _removed(self, node) -> None:
        if node is self.points:
            pts = self.scene.of_kind(PointsNode)
            self._set_points(pts[-1] if pts else None)
        self._show_stats(self.scene.selected)

    def _selection_changed(self, node) -> None:
        if isinstance(node, PointsNode):
            self._set_points(node)
        self._show_stats(node)

    def _set_points(self, node: PointsNode | None) -> None:
        self.points = node
        self.run_button.setEnabled(node is not None)
        self.point_size.setEnabled(node is not None)
        if node is not None:
            self.point_size.blockSignals(True)
            self.point_size.setValue(int(round(node.point_size)))
            self.point_size.blockSignals(False)

    def _show_stats(self, node) -> None:
        if isinstance(node, MeshNode) and node.stats:
            self.stats.setText(f"{node.name}\n{quality_text(node.stats)}")
        elif not any(isinstance(n, MeshNode) for n in self.scene):
            self.stats.setText("")

    def _point_size(self, size: int) -> None:
        if self.points is not None:
            undo_stack(self.scene).set(self.points, f"Point size of {self.points.name}",
                                       point_size=float(size))

    def run(self, points: PointsNode | None = None):
        """Remesh ``points`` (default: the current cloud) in a job; returns the job."""
        node = points or self.points
        if node is None:
            return None
        adaptive = self.mode.currentIndex() == 0
        edge = None if adaptive else float(self.edge.value())
        rho = float(self.rho.value()) if adaptive else None
        sharp = self.sharp_creases.isChecked()

        def done(out, node=node):
            def add():
                mesh = self.scene.add_mesh(
                    out["vertices"], out["faces"], name=f"mesh of {node.name}",
                    normals=out["normals"], points_id=node.id if node.id in self.scene else None,
                    edge_length=edge, rho=rho, sharp_creases=sharp, stats=out["quality"])
                self.scene.select(mesh)

            undo_stack(self.scene).change(f"Remesh {node.name}", add)

        # a process, not a thread: the front is Python that would hold the GIL for
        # hundreds of milliseconds at a time, and Cancel can stop a process at once; the
        # remesher is named, not imported here (its imports would freeze the window)
        return self.jobs.run(f"Remeshing {node.name}", call_named,
                             "splineviz.pointcloud.remesh:remesh_with_quality", node.data,
                             edge_length=edge, rho=rho, sharp_creases=sharp, on_done=done,
                             process=True)
