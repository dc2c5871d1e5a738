"""The main window's status bar: the readout under the cursor, the last frame's time, the
cells the ray casters visit, the running job's progress with its Cancel button, and the
view's "ray casting..." while exact frames are made.

Cancel does what Esc does (:meth:`~splineviz.gui.main_window.MainWindow.cancel_all`): it
stops the running jobs and the exact frames every view is computing; it shows while either
runs."""

from __future__ import annotations

from PySide6.QtWidgets import QLabel, QProgressBar, QPushButton


class StatusBar:
    """Fills ``window.statusBar()`` and keeps it up to date from the window's view, job
    runner and spline scene.

    The widgets are also the window's attributes (``readout_label``, ``fps_label``,
    ``cells_label``, ``progress``, ``cancel_button``): scripts and tests read them there.
    """

    def __init__(self, window):
        self.window = window
        sb = window.statusBar()
        self.readout_label = QLabel("")
        self.readout_label.setToolTip("Position and data value under the cursor")
        self.fps_label = QLabel("")
        self.fps_label.setToolTip("Time of the last frame")
        self.cells_label = QLabel("")
        self.cells_label.setToolTip("Cells and tetrahedra the ray caster visits")
        self.progress = QProgressBar()
        self.progress.setMaximumWidth(200)
        self.progress.setVisible(False)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setToolTip("Stop the running jobs and the exact frames being "
                                      "computed (Esc)")
        self.cancel_button.setVisible(False)
        self.cancel_button.clicked.connect(window.cancel_all)
        sb.addWidget(self.readout_label, 1)
        for w in (self.progress, self.cancel_button, self.fps_label, self.cells_label):
            sb.addPermanentWidget(w)
        for name in ("readout_label", "fps_label", "cells_label", "progress", "cancel_button"):
            setattr(window, name, getattr(self, name))
        window.view.readout.connect(self.readout_label.setText)
        window.view.frame_rendered.connect(self.frame_rendered)
        window.view.busy.connect(self.view_busy)
        window.jobs.changed.connect(self.jobs_changed)

    def frame_rendered(self, dt: float) -> None:
        """The last frame took ``dt`` seconds; list each layer's active cells and devices."""
        if self.window._closed:
            return
        self.fps_label.setText(f"frame {dt * 1000:.0f} ms")
        active, devices = [], set()
        for layer in self.window.spline_scene.layers:
            s = layer.last_stats
            n = s.get("active_tets") or s.get("active_cells")
            if n is not None:
                active.append(f"{n:,} active {'tets' if s.get('active_tets') else 'cells'}")
            if s.get("device"):
                devices.add(str(s["device"]).split(":")[0])
        self.cells_label.setText("; ".join(active + sorted(devices)))

    def jobs_changed(self) -> None:
        """Progress and Cancel of the newest job; hidden when none runs."""
        if self.window._closed:
            return
        jobs = self.window.jobs.jobs
        self.progress.setVisible(bool(jobs))
        self._update_cancel()
        if not jobs:
            self.window.statusBar().clearMessage()
            return
        job = jobs[-1]
        cancelling = job.state == "cancelling"
        if job.fraction is None or cancelling:
            self.progress.setRange(0, 0)
        else:
            self.progress.setRange(0, 100)
            self.progress.setValue(int(100 * job.fraction))
        text = f"cancelling {job.label}..." if cancelling else (
            job.label + (f": {job.message}" if job.message else "..."))
        self.progress.setFormat(job.label)
        self.window.statusBar().showMessage(text)

    def view_busy(self, message: str) -> None:
        """"ray casting..." while exact frames are made; cleared when they are shown (unless
        a job's message is up)."""
        if self.window._closed:
            return
        self._update_cancel()
        if message:
            self.window.statusBar().showMessage(message)
        elif not self.window.jobs.jobs:
            self.window.statusBar().clearMessage()

    def _views_computing(self) -> bool:
        """Whether a view of the window computes exact frames (the views of a split too)."""
        linked = getattr(self.window, "linked_views", None)  # made after the status bar
        views = linked.views if linked is not None else [self.window.view]
        return any(view.computing for view in views)

    def _update_cancel(self) -> None:
        """Cancel shows while a cancellable job runs or a view computes exact frames; it is
        disabled while the only thing left is a job being cancelled."""
        jobs = self.window.jobs.jobs
        running = any(j.cancellable and j.state == "running" for j in jobs)
        computing = self._views_computing()
        self.cancel_button.setVisible(computing or any(j.cancellable for j in jobs))
        self.cancel_button.setEnabled(computing or running)
