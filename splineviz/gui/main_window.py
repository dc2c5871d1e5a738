"""The main window: docks the 3-D view, the panels, the menus and the status bar.

It owns one :class:`splineviz.model.Scene`; the view (:mod:`splineviz.gui.view`) and every
panel (:mod:`splineviz.gui.panels`) are views of it, file operations live in
:mod:`splineviz.gui.commands`, menus in :mod:`splineviz.gui.actions` and background work in
:mod:`splineviz.gui.jobs`. The window fits the screen it opens on, asks before closing with
unsaved changes and shows every error as one non-blocking message (also in the log panel).
"""

from __future__ import annotations

import time
from pathlib import Path

from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QAction, QGuiApplication
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QLabel,
    QMainWindow,
    QMessageBox,
    QProgressBar,
    QPushButton,
)

from splineviz.core.errors import SplinevizError
from splineviz.gui.actions import build_actions, icon
from splineviz.gui.commands import Commands
from splineviz.gui.dialogs import save_session_as
from splineviz.gui.jobs import JobRunner, error_message, start_process_server
from splineviz.gui.open_dialogs import open_chosen
from splineviz.gui.panels import (
    AnalysisPanel,
    ClippingPanel,
    DataPanel,
    IsosurfacePanel,
    LogPanel,
    PlaneWidgets,
    RemeshPanel,
    Smoother,
    SmoothingPanel,
)
from splineviz.gui.split import LinkedViews
from splineviz.gui.view import View3D
from splineviz.model import Scene

#: share of the screen's available area the window takes at most
SCREEN_SHARE = 0.92


def _preload() -> None:
    """Import now what the first volume needs: a module imported later by a worker thread
    holds the GIL while it executes (pyopencl's import alone is ~0.3 s), stalling the
    window; before the window is shown nobody waits."""
    import splineviz.compute.raycast  # noqa: F401
    import splineviz.compute.smoothing  # noqa: F401
    import splineviz.core.testfunctions  # noqa: F401
    import splineviz.model.opening  # noqa: F401


class MainWindow(QMainWindow):
    """The splineviz main window (see module docstring).

    Parameters
    ----------
    size : (width, height) of the 3-D view, optional (its minimum size)
    device : OpenCL device preference for the ray casters
    scene : Scene, optional
        The scene to show (a new, empty one by default).
    """

    def __init__(self, size=None, device=None, scene: Scene | None = None):
        super().__init__()
        from splineviz.plugins import load_plugins

        load_plugins()  # plugin models and sources appear in the panels and menus
        _preload()
        self.setWindowTitle("splineviz")
        self.setWindowIcon(icon("splineviz"))
        self.setAcceptDrops(True)
        self.setDockNestingEnabled(True)
        self.device = device
        self.scene = scene if scene is not None else Scene()
        self.last_error: str | None = None
        self.session_file: Path | None = None
        #: ask about unsaved changes on close (the app sets it; scripts and tests do not)
        self.ask_before_closing = False
        self._message_boxes: list[QMessageBox] = []
        self._closed = False
        self.jobs = JobRunner(self)
        start_process_server()  # remeshing forks from it later, not from this process
        self.view = View3D(self.scene, self, device=device, min_size=size, side="left")
        self.plotter = self.view.plotter
        self.spline_scene = self.view.spline_scene
        self.commands = Commands(self.scene, self.jobs, self)
        self.smoother = Smoother(self.scene, self.jobs, device)
        self.plane_widgets = PlaneWidgets(self.scene, self.plotter, self.view.request_render)
        self._build_panels()
        self.actions_by_name = build_actions(self)
        self._build_status()
        # after the status bar: a split restored with the scene connects to its labels
        self.linked_views = LinkedViews(self)
        self.setCentralWidget(self.linked_views.splitter)
        self.jobs.changed.connect(self._jobs_changed)
        self.jobs.error.connect(self.show_error)
        self.jobs.message.connect(lambda m: self.statusBar().showMessage(m, 4000))
        self.view._refiner.error.connect(self.show_error)
        # the first view tells a second one of the drag (LinkedViews)
        self.iso_panel.histogram.pressed.connect(self.view.begin_interaction)
        self.iso_panel.histogram.released.connect(self.view.end_interaction)
        self.commands.opened.connect(self._opened)
        self.commands.saved.connect(lambda p: self.statusBar().showMessage(f"saved {p}", 6000))
        self.commands.saved.connect(lambda p: self.log.add(f"saved {p}"))
        self.commands.warned.connect(self.show_warning)
        #: autosaves the scene for crash recovery (the app turns it on: :meth:`enable_autosave`)
        self.autosaver = None
        self.scene.changed.connect(self._update_title)
        self.fit_to_screen()

    # -- construction --------------------------------------------------------------------

    def _dock(self, title, widget, area) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(title)
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        return dock

    def _build_panels(self):
        self.data_panel = DataPanel(self.scene)
        self.iso_panel = IsosurfacePanel(self.scene, self.jobs)
        self.clip_panel = ClippingPanel(self.scene)
        self.smooth_panel = SmoothingPanel(self.scene)
        self.remesh_panel = RemeshPanel(self.scene, self.jobs)
        self.analysis_panel = AnalysisPanel(self.scene)
        self.log = LogPanel()
        left, right = Qt.DockWidgetArea.LeftDockWidgetArea, Qt.DockWidgetArea.RightDockWidgetArea
        self.docks = {
            "Data": self._dock("Data", self.data_panel, left),
            "Isosurface": self._dock("Isosurface", self.iso_panel, left),
            "Clipping": self._dock("Clipping", self.clip_panel, right),
            "Smoothing": self._dock("Smoothing", self.smooth_panel, right),
            "Remeshing": self._dock("Remeshing", self.remesh_panel, right),
            "Analysis": self._dock("Analysis", self.analysis_panel, right),
            "Log": self._dock("Log", self.log, Qt.DockWidgetArea.BottomDockWidgetArea),
        }
        # the right column as tabs: narrower, so the 3-D view keeps its room
        self.tabifyDockWidget(self.docks["Clipping"], self.docks["Smoothing"])
        self.tabifyDockWidget(self.docks["Smoothing"], self.docks["Remeshing"])
        self.tabifyDockWidget(self.docks["Remeshing"], self.docks["Analysis"])
        self.docks["Clipping"].raise_()
        self.docks["Log"].hide()

    def _build_status(self):
        sb = self.statusBar()
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
        self.cancel_button.setToolTip("Stop the running job (Esc)")
        self.cancel_button.setVisible(False)
        self.cancel_button.clicked.connect(self.jobs.cancel_all)
        sb.addWidget(self.readout_label, 1)
        for w in (self.progress, self.cancel_button, self.fps_label, self.cells_label):
            sb.addPermanentWidget(w)
        self.view.readout.connect(self.readout_label.setText)
        self.view.frame_rendered.connect(self._frame_rendered)
        self.view.busy.connect(self._view_busy)
        for name, dock in self.docks.items():
            a: QAction = dock.toggleViewAction()
            a.setToolTip(f"Show or hide the {name} panel")
            self.panels_menu.addAction(a)

    def fit_to_screen(self) -> None:
        """Size the window to the screen it opens on (status bar and docks visible)."""
        screen = self.screen() or QGuiApplication.primaryScreen()
        if screen is None:
            return
        avail = screen.availableGeometry()
        want = self.sizeHint().expandedTo(self.minimumSizeHint())
        w = min(max(want.width(), int(0.8 * avail.width())), int(SCREEN_SHARE * avail.width()))
        h = min(max(want.height(), int(0.8 * avail.height())),
                int(SCREEN_SHARE * avail.height()))
        self.resize(w, h)
        self.move(avail.x() + (avail.width() - w) // 2, avail.y() + (avail.height() - h) // 2)
        self._size_docks()

    def _size_docks(self) -> None:
        """The 3-D view gets most of the width: each dock column about a fifth."""
        side = max(250, int(0.2 * self.width()))
        self.resizeDocks([self.docks["Data"], self.docks["Clipping"]], [side, side],
                         Qt.Orientation.Horizontal)

    def showEvent(self, event):  # noqa: N802 (Qt naming)
        super().showEvent(event)
        if not getattr(self, "_docks_sized", False):
            # dock sizes only take once the window is laid out on screen
            self._docks_sized = True
            QTimer.singleShot(0, self._size_docks)

    # -- status --------------------------------------------------------------------------

    def _frame_rendered(self, dt: float) -> None:
        if self._closed:
            return
        self.fps_label.setText(f"frame {dt * 1000:.0f} ms")
        active, devices = [], set()
        for layer in self.spline_scene.layers:
            s = layer.last_stats
            n = s.get("active_tets") or s.get("active_cells")
            if n is not None:
                active.append(f"{n:,} active {'tets' if s.get('active_tets') else 'cells'}")
            if s.get("device"):
                devices.add(str(s["device"]).split(":")[0])
        self.cells_label.setText("; ".join(active + sorted(devices)))

    def _jobs_changed(self) -> None:
        if self._closed:
            return
        jobs = self.jobs.jobs
        self.progress.setVisible(bool(jobs))
        self.cancel_button.setVisible(any(j.cancellable for j in jobs))
        if not jobs:
            self.statusBar().clearMessage()
            return
        job = jobs[-1]
        cancelling = job.state == "cancelling"
        self.cancel_button.setEnabled(not cancelling)
        if job.fraction is None or cancelling:
            self.progress.setRange(0, 0)
        else:
            self.progress.setRange(0, 100)
            self.progress.setValue(int(100 * job.fraction))
        text = f"cancelling {job.label}..." if cancelling else (
            job.label + (f": {job.message}" if job.message else "..."))
        self.progress.setFormat(job.label)
        self.statusBar().showMessage(text)

    def cancel_all(self) -> None:
        """Esc: cancel the running jobs and the exact frames every view is computing."""
        self.jobs.cancel_all()
        for view in self.linked_views.views:
            view.cancel_refine()

    def _view_busy(self, message: str) -> None:
        """"ray casting..." while exact frames are made; cleared when they are shown (unless
        a job's message is up)."""
        if message:
            self.statusBar().showMessage(message)
        elif not self.jobs.jobs:
            self.statusBar().clearMessage()

    def _update_title(self) -> None:
        name = self.session_file.name if self.session_file else "untitled"
        self.setWindowTitle(f"{name}{' *' if self.scene.modified else ''} — splineviz")

    def show_error(self, message: str) -> None:
        """A non-blocking message box (one at a time); the window stays usable."""
        self.last_error = message
        self.log.add(f"error: {message}")
        if self._closed:
            return
        self.statusBar().showMessage(message, 8000)
        for box in self._message_boxes:
            box.close()
        box = QMessageBox(QMessageBox.Icon.Warning, "splineviz", message,
                          QMessageBox.StandardButton.Ok, self)
        box.setWindowModality(Qt.WindowModality.NonModal)
        box.finished.connect(lambda *_: box in self._message_boxes
                             and self._message_boxes.remove(box))
        self._message_boxes.append(box)
        box.show()

    def show_warning(self, message: str) -> None:
        """Something the user should know of, not an error: the log panel and the status
        bar (no message box to close)."""
        self.log.add(f"warning: {message}")
        if not self._closed:
            self.statusBar().showMessage(message, 8000)

    def guard(self, fn, *args, **kwargs):
        """Run a command; a user error becomes one message."""
        try:
            return fn(*args, **kwargs)
        except (SplinevizError, OSError) as exc:
            self.show_error(error_message(exc))
            return None

    # -- files ---------------------------------------------------------------------------

    def open_default(self):
        return self.commands.open_default()

    def open_path(self, path, mode: str = "ask", block: bool = False, **iso):
        """Open a file or session (a job; ``block`` waits for it: scripts and tests)."""
        job = self.guard(self.commands.open_path, path, mode=mode, **iso)
        if block:
            self.wait_idle()
        return job

    def recent_files(self) -> list[str]:
        return self.recent.files()

    def _opened(self, path: str) -> None:
        self.recent.add(path)
        if path.lower().endswith(".svs"):
            self.session_file = Path(path)
            self._update_title()

    def save_session(self, path) -> Path | None:
        p = self.guard(self.commands.save_session, path)
        if p is not None:
            self.session_file = Path(p)
            self._update_title()
        return p

    def export_screenshot(self, path, size=None, transparent: bool = False):
        return self.commands.export_screenshot(path, size, transparent)

    # -- crash recovery ------------------------------------------------------------------

    def enable_autosave(self, folder=None, debounce_ms: int | None = None) -> None:
        """Autosave the scene to a recovery file after every change (see
        :mod:`splineviz.gui.recovery`); a clean quit removes it."""
        from splineviz.gui.recovery import DEBOUNCE_MS, Autosaver

        if self.autosaver is None:
            self.autosaver = Autosaver(self.scene, folder, debounce_ms or DEBOUNCE_MS, self)
            self.autosaver.failed.connect(self.show_warning)

    def offer_recovery(self, folder=None):
        """If an earlier run left a recovery file (a crash or kill), ask whether to restore
        it and, if so, load it in a job (which replaces the scene); returns that job, or
        None. Files not restored are removed; older ones wait for the next start."""
        from splineviz.gui.recovery import ask_restore, orphaned, restored_data_paths

        if folder is None and self.autosaver is not None:
            folder = self.autosaver.folder
        found = orphaned(folder)
        if not found:
            return None
        newest = found[0]
        if not ask_restore(self, newest):
            newest.discard()
            self.log.add(f"discarded the recovery file {newest.path}")
            return None

        def loaded():
            restored_data_paths(self.scene, newest.data_dir)
            newest.discard()
            self.scene.modified = True  # restored work is not saved anywhere yet
            self.session_file = None
            self._update_title()
            self.show_warning(f"restored the scene autosaved at "
                              f"{time.strftime('%H:%M:%S', time.localtime(newest.saved))}")

        # its data paths are relative to the recovery folder: outside it, and ours
        return self.commands.load_session(newest.path, allow_outside=True, on_loaded=loaded)

    # -- tests and scripts ---------------------------------------------------------------

    def busy(self) -> bool:
        return bool(self.jobs.jobs)

    def wait_idle(self, timeout_s: float = 120.0) -> None:
        """Process events until no job runs (tests and scripted use)."""
        end = time.perf_counter() + timeout_s
        while time.perf_counter() < end:
            QApplication.processEvents()
            if not self.jobs.jobs and not self.smooth_panel.pending:
                return
            time.sleep(0.005)
        raise TimeoutError(f"background work did not finish in {timeout_s:g} s: "
                           f"{len(self.jobs.jobs)} job(s) running")

    @property
    def view2(self) -> View3D | None:
        """The right-hand view while the scene is split (View > Split view), else None."""
        return self.linked_views.second

    def wait_for_refine(self, timeout_s: float = 120.0) -> None:
        """Process events until every view shows exact frames (a second view still
        opening is waited for first)."""
        end = time.perf_counter() + timeout_s
        while self.linked_views.opening and time.perf_counter() < end:
            QApplication.processEvents()
            time.sleep(0.005)
        for view in self.linked_views.views:
            view.wait_for_refine(max(end - time.perf_counter(), 0.0))

    def request_render(self) -> None:
        self.view.request_render()

    def join_workers(self, timeout_s: float = 10.0) -> bool:
        """After the window closed: wait up to ``timeout_s`` for the background threads still
        running (a frame being ray cast, a job winding down, an autosave copy). Exiting the
        process while one is inside OpenCL aborted it ("terminate called without an active
        exception", from pocl's threads): the app calls this before it exits."""
        end = time.perf_counter() + timeout_s
        ok = self.view.join(timeout_s)
        ok = self.linked_views.join(max(end - time.perf_counter(), 0.0)) and ok
        ok = self.jobs.join(max(end - time.perf_counter(), 0.0)) and ok
        return ok

    # -- drag and drop, close ------------------------------------------------------------

    def dragEnterEvent(self, event):  # noqa: N802 (Qt naming)
        if event.mimeData().hasUrls():
            event.acceptProposedAction()

    def dropEvent(self, event):  # noqa: N802
        for url in event.mimeData().urls():
            if url.isLocalFile():
                open_chosen(self, url.toLocalFile())  # folders: series; raw: its layout

    def confirm_discard(self) -> bool:
        """Ask what to do with unsaved changes; False: the user wants to stay."""
        if not self.ask_before_closing or not self.scene.modified or not len(self.scene):
            return True
        answer = QMessageBox.question(
            self, "Unsaved changes", "The scene has unsaved changes. Save them as a session?",
            QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard
            | QMessageBox.StandardButton.Cancel, QMessageBox.StandardButton.Save)
        if answer == QMessageBox.StandardButton.Cancel:
            return False
        if answer == QMessageBox.StandardButton.Save:
            if self.session_file is not None:
                return self.save_session(self.session_file) is not None
            return save_session_as(self)
        return True

    def closeEvent(self, event):  # noqa: N802
        if self._closed:
            super().closeEvent(event)
            return
        if not self.confirm_discard():
            event.ignore()
            return
        self._closed = True
        if self.autosaver is not None:
            self.autosaver.close()  # a clean quit: nothing to recover
        self.jobs.close()
        for box in list(self._message_boxes):
            box.close()
        self.plane_widgets.close()
        self.log.close_log()
        self.linked_views.close()
        self.view.close()
        super().closeEvent(event)
