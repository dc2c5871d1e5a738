"""The smoothing panel: Gaussian smoothing of the current volume (OpenCL), live.

It edits :attr:`VolumeNode.sigma`; :class:`Smoother` sees every sigma change (from the panel,
a session or the API) and makes the smoothed data in a worker, which the isosurfaces then
use. The original samples are never replaced: sigma 0 ("Original") shows them at once.
A new sigma from the panel is a step of the scene's undo stack (:mod:`splineviz.gui.undo`).
"""

from __future__ import annotations

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import (
    QCheckBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QPushButton,
)

from splineviz.gui.panels.volume_panel import VolumePanel
from splineviz.gui.undo import undo_stack
from splineviz.model import MAX_SIGMA, Scene, VolumeNode

#: delay before live smoothing runs after the last sigma change
SMOOTH_DELAY_MS = 300


class Smoother:
    """Makes the smoothed data of volumes whose ``sigma`` changed (one job per change;
    an older job's result is ignored by :meth:`VolumeNode.set_smoothed`)."""

    def __init__(self, scene: Scene, jobs, device=None):
        self.scene = scene
        self.jobs = jobs
        self.device = device
        #: volume id -> its sigma listener (dropped on removal: undo inserts it again)
        self._listeners: dict[str, object] = {}
        scene.inserted.connect(self._inserted)
        scene.removed.connect(self._removed)
        for v in scene.volumes:
            self._inserted(v)

    def _inserted(self, node) -> None:
        if isinstance(node, VolumeNode):
            listener = self._listeners[node.id] = lambda _s, node=node: self.update(node)
            node.events.sigma.connect(listener)
            node.events.data.connect(listener)  # a time-varying volume's new step
            self.update(node)

    def _removed(self, node) -> None:
        listener = self._listeners.pop(node.id, None)
        if listener is not None:
            node.events.sigma.disconnect(listener)
            node.events.data.disconnect(listener)

    def update(self, node: VolumeNode) -> None:
        if not node.smoothing_pending or node.id not in self.scene:
            return
        sigma, data = node.sigma, node.data
        # a result for data the node no longer shows (an earlier time step) is dropped
        self.jobs.run(f"Smoothing {node.name} (sigma {sigma:g})", smooth_volume, data,
                      sigma, device=self.device,
                      on_done=lambda vol: node.data is data and node.set_smoothed(vol, sigma))


def smooth_volume(volume, sigma: float, device=None):
    """Gaussian smoothing (worker thread), with the result's range and histogram computed
    here too: the panels showing them then cost the GUI thread nothing."""
    from splineviz.compute.smoothing import gaussian_smooth
    from splineviz.model.summaries import cached_histogram

    out = gaussian_smooth(volume, sigma, device=device)
    _ = out.finite_range
    cached_histogram(out)
    return out


class SmoothingPanel(VolumePanel):
    """Sigma of the current volume, live or on Apply; "Original" goes back to sigma 0."""

    def __init__(self, scene: Scene, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.node: VolumeNode | None = None
        self.sigma = QDoubleSpinBox()
        self.sigma.setRange(0.0, MAX_SIGMA)
        self.sigma.setSingleStep(0.25)
        self.sigma.setSuffix(" voxels")
        self.sigma.setKeyboardTracking(False)
        self.sigma.setToolTip("Standard deviation of the Gaussian, in voxels (0: the data "
                              "as read)")
        self.live = QCheckBox("Apply live")
        self.live.setChecked(True)
        self.live.setToolTip("Smooth as soon as sigma changes")
        self.apply_button = QPushButton("Apply")
        self.apply_button.setToolTip("Smooth the current volume with this sigma")
        self.reset_button = QPushButton("Original")
        self.reset_button.setToolTip("Show the data as read (the smoothing is kept aside)")
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
        self.sigma.valueChanged.connect(lambda _v: self.live.isChecked() and self._timer.start())
        self.apply_button.clicked.connect(self.apply)
        self.reset_button.clicked.connect(self.reset)
        scene.selection.connect(self._selection_changed)
        scene.removed.connect(lambda n: n is self.node and self.set_node(None))
        self.set_node(None)

    @property
    def pending(self) -> bool:
        return self._timer.isActive()

    def _show(self, *_args) -> None:
        node = self.node
        if node is None:
            self.info.setText("select a volume")
            return
        self.sigma.blockSignals(True)
        self.sigma.setValue(node.sigma)
        self.sigma.blockSignals(False)
        if node.sigma == 0:
            text = "original data"
        elif node.smoothing_pending:
            text = f"smoothing with sigma {node.sigma:g} voxels..."
        else:
            text = f"smoothed, sigma {node.sigma:g} voxels"
        self.info.setText(f"{node.name}: {text}")

    def apply(self) -> None:
        self._timer.stop()
        if self.node is not None:
            undo_stack(self.scene).set(self.node, f"Smooth {self.node.name}",
                                       sigma=float(self.sigma.value()))

    def reset(self) -> None:
        self.sigma.blockSignals(True)
        self.sigma.setValue(0.0)
        self.sigma.blockSignals(False)
        self.apply()
