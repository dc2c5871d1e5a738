"""The main window: docks the 3-D view, the panels, the menus and the status bar.

It owns one :class:`splineviz.model.Scene`; the view (:mod:`splineviz.gui.view`) and every
panel (:mod:`splineviz.gui.panels`) are views of it, file operations live in
:mod:`splineviz.gui.commands` (opening files from the window: :mod:`splineviz.gui.opening`),
menus in :mod:`splineviz.gui.actions`, the status bar in :mod:`splineviz.gui.status`, crash
recovery in :mod:`splineviz.gui.recovery` and background work in :mod:`splineviz.gui.jobs`.
The window fits the screen it opens on, asks before closing with unsaved changes and shows
every error as one non-blocking message (also in the log panel).
"""

from __future__ import annotations

import time
from pathlib import Path

from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QAction
from PySide6.QtWidgets import QApplication, QDockWidget, QMainWindow, QMessageBox

from splineviz.core.errors import SplinevizError
from splineviz.gui import animation_dock, opening, window_state
from splineviz.gui.actions import build_actions, icon
from splineviz.gui.commands import Commands
from splineviz.gui.jobs import JobRunner, error_message, start_process_server
from splineviz.gui.layout import ViewLayout
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
    VolumeRenderingPanel,
)
from splineviz.gui.quantities_dock import QuantitiesPanel
from splineviz.gui.split import LinkedViews
from splineviz.gui.status import StatusBar
from splineviz.gui.time_toolbar import TimeToolbar
from splineviz.gui.view import View3D
from splineviz.model import Scene


def _preload() -> None:
    """Import now what the first volume needs: a module imported later by a worker thread
    holds the GIL while it executes (pyopencl's import alone is ~0.3 s), stalling the
    window; before the window is shown nobody waits."""
    from importlib import import_module

    import scipy.ndimage  # noqa: F401  (the B-spline plugin's prefilter, the readout)

    import splineviz.compute.raycast  # noqa: F401
    import splineviz.compute.raycast.to_program  # noqa: F401  (truncated octahedra)
    import splineviz.compute.smoothing  # noqa: F401
    import splineviz.core.testfunctions  # noqa: F401
    import splineviz.model.opening  # noqa: F401
    from splineviz.core.splines import MODELS

    # every model's module: the first switch to a model imported it (and scipy.ndimage for
    # the plugin's B-spline) in the worker that builds its caster, holding the GIL
    for name in MODELS.names():
        import_module(MODELS[name].target.split(":")[0])


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
        animation_dock.install(self)
        self.actions_by_name = build_actions(self)
        self.time_toolbar = TimeToolbar(self)
        self.addToolBar(Qt.ToolBarArea.BottomToolBarArea, self.time_toolbar)
        self.status = StatusBar(self)
        self._view_busy = self.status.view_busy  # each view of a split reports to it
        self._add_panel_toggles()
        # after the status bar: a split restored with the scene connects to its labels
        self.linked_views = LinkedViews(self)
        self.view_layout = ViewLayout(self)  # View > Layout: the 3-D view and the slices
        self.view_layout.add_menu(self.menuBar())
        self.setCentralWidget(self.view_layout.widget)
        self.jobs.error.connect(self.show_error)
        self.jobs.message.connect(lambda m: self.statusBar().showMessage(m, 4000))
        self.view._refiner.error.connect(self.show_error)
        # the first view tells a second one of the drag (LinkedViews)
        self.iso_panel.histogram.pressed.connect(self.view.begin_interaction)
        self.iso_panel.histogram.released.connect(self.view.end_interaction)
        self.volume_panel.drag_started.connect(self.view.begin_interaction)
        self.volume_panel.drag_ended.connect(self.view.end_interaction)
        self.commands.opened.connect(lambda p: opening.opened(self, p))
        self.commands.saved.connect(lambda p: self.statusBar().showMessage(f"saved {p}", 6000))
        self.commands.saved.connect(lambda p: self.log.add(f"saved {p}"))
        self.commands.warned.connect(self.show_warning)
        #: autosaves the scene for crash recovery (the app turns it on: :meth:`enable_autosave`)
        self.autosaver = None
        self.scene.changed.connect(self.update_title)
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
        self.volume_panel = VolumeRenderingPanel(self.scene, error=self.show_error,
                                                 jobs=self.jobs)
        self.remesh_panel = RemeshPanel(self.scene, self.jobs)
        self.analysis_panel = AnalysisPanel(self.scene)
        self.quantities_panel = QuantitiesPanel(self.scene, self.jobs)
        self.log = LogPanel()
        left, right = Qt.DockWidgetArea.LeftDockWidgetArea, Qt.DockWidgetArea.RightDockWidgetArea
        self.docks = {
            "Data": self._dock("Data", self.data_panel, left),
            "Isosurface": self._dock("Isosurface", self.iso_panel, left),
            "Clipping": self._dock("Clipping", self.clip_panel, right),
            "Smoothing": self._dock("Smoothing", self.smooth_panel, right),
            # beside the isosurface: the two ways the volume is shown (ParaView's
            # representations)
            "Volume rendering": self._dock("Volume rendering", self.volume_panel, left),
            "Remeshing": self._dock("Remeshing", self.remesh_panel, right),
            "Analysis": self._dock("Analysis", self.analysis_panel, right),
            "Quantities": self._dock("Quantities", self.quantities_panel,
                                     Qt.DockWidgetArea.BottomDockWidgetArea),
            "Log": self._dock("Log", self.log, Qt.DockWidgetArea.BottomDockWidgetArea),
        }
        # the right column as tabs: narrower, so the 3-D view keeps its room
        self.tabifyDockWidget(self.docks["Clipping"], self.docks["Smoothing"])
        self.tabifyDockWidget(self.docks["Smoothing"], self.docks["Remeshing"])
        self.tabifyDockWidget(self.docks["Remeshing"], self.docks["Analysis"])
        self.tabifyDockWidget(self.docks["Isosurface"], self.docks["Volume rendering"])
        self.docks["Isosurface"].raise_()
        self.docks["Clipping"].raise_()
        # the plots over time and the log under the view (ParaView's bottom row), shown from
        # View > Panels: seven tabs in one column no longer fit a 1280x800 screen
        self.docks["Log"].hide()
        self.docks["Quantities"].hide()
        # the minimum size of the window was fixed while the docks were still stacked (each
        # added dock is placed below the last until tabified); work it out for the tabs
        self.layout().activate()

    def _add_panel_toggles(self):
        for name, dock in self.docks.items():
            a: QAction = dock.toggleViewAction()
            a.setToolTip(f"Show or hide the {name} panel")
            self.panels_menu.addAction(a)

    def fit_to_screen(self) -> None:
        """Size the window to the screen it opens on (:func:`.window_state.fit_to_screen`)."""
        window_state.fit_to_screen(self)
        self._size_docks()

    def _size_docks(self) -> None:
        """The 3-D view gets most of the width: each dock column about a fifth."""
        side = max(250, int(0.2 * self.width()))
        self.resizeDocks([self.docks["Data"], self.docks["Clipping"]],
                         [side, window_state.column_width(self, side)],
                         Qt.Orientation.Horizontal)

    def showEvent(self, event):  # noqa: N802 (Qt naming)
        super().showEvent(event)
        if not getattr(self, "_docks_sized", False):
            # dock sizes only take once the window is laid out on screen
            self._docks_sized = True
            QTimer.singleShot(0, self._size_docks)

    # -- title, messages--------------------------------------------------------------------

    def cancel_all(self) -> None:
        """Esc: cancel the running jobs and the exact frames every view is computing."""
        self.jobs.cancel_all()
        for view in self.linked_views.views:
            view.cancel_refine()

    def update_title(self) -> None:
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
        """Open a file or session (:func:`splineviz.gui.opening.open_path`)."""
        return opening.open_path(self, path, mode, block, **iso)

    def recent_files(self) -> list[str]:
        return self.recent.files()

    def save_session(self, path) -> Path | None:
        p = self.guard(self.commands.save_session, path)
        if p is not None:
            self.session_file = Path(p)
            self.update_title()
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
        from splineviz.gui.recovery import offer_recovery

        return offer_recovery(self, folder)

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
        opening.accepts_drop(event)

    def dropEvent(self, event):  # noqa: N802
        opening.drop(self, event)

    def confirm_discard(self) -> bool:
        """Ask what to do with unsaved changes; False: the user wants to stay."""
        return self.commands.confirm_unsaved("Quitting")

    def closeEvent(self, event):  # noqa: N802
        if self._closed:
            super().closeEvent(event)
            return
        if not self.confirm_discard():
            event.ignore()
            return
        self._closed = True
        self.time_toolbar.pause()
        if self.autosaver is not None:
            self.autosaver.close()  # a clean quit: nothing to recover
        self.jobs.close()
        for box in list(self._message_boxes):
            box.close()
        self.plane_widgets.close()
        self.log.close_log()
        self.view_layout.close()
        self.linked_views.close()
        self.view.close()
        super().closeEvent(event)
