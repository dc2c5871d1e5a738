"""The File and Help menus' dialogs, recent files and the menus filled on demand. Each
function takes the main window and calls its commands; none keeps state of its own."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QSettings
from PySide6.QtGui import QAction
from PySide6.QtWidgets import (
    QCheckBox,
    QDialog,
    QDialogButtonBox,
    QFileDialog,
    QFormLayout,
    QMessageBox,
    QSpinBox,
)

import splineviz
from splineviz.gui.open_dialogs import open_chosen

#: entries kept in File > Open Recent
MAX_RECENT = 8

#: shown by Help > Keyboard and mouse
HELP_TEXT = """<b>Mouse in the 3-D view</b><br>
left drag: rotate &nbsp; right drag or wheel: zoom &nbsp; middle drag or Shift+left: pan<br>
hover over a surface: position and data value in the status bar<br><br>
<b>Keys in the 3-D view</b><br>
r: reset the camera to all data &nbsp; v: isometric view<br><br>
<b>Shortcuts</b><br>
Ctrl+N new scene, Ctrl+O open, Ctrl+S save session, Ctrl+Shift+S save session as,
Ctrl+E export screenshot, Ctrl+Z undo, Ctrl+Shift+Z redo (a slider drag is one step),
Ctrl+1/2/3 look down +X/+Y/+Z (with Shift: -X/-Y/-Z), Ctrl+0 isometric, F7 split view
(two linked views), Esc cancel jobs and the exact frames being computed"""


def size_boxes(size, tip: str, even: bool = False) -> tuple[QSpinBox, QSpinBox]:
    """Width and height fields of an exported picture (16 to 16384 pixels), set to ``size``
    (rounded up to even numbers with ``even``: H.264 frames)."""
    boxes = (QSpinBox(), QSpinBox())
    for box, v in zip(boxes, size, strict=True):
        box.setRange(16, 16384)
        box.setValue(v + v % 2 if even else v)
        box.setToolTip(tip)
    return boxes


def ok_cancel(dialog: QDialog) -> QDialogButtonBox:
    """OK and Cancel buttons that accept and reject ``dialog``."""
    buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok
                               | QDialogButtonBox.StandardButton.Cancel)
    buttons.accepted.connect(dialog.accept)
    buttons.rejected.connect(dialog.reject)
    return buttons


class ScreenshotDialog(QDialog):
    """Size and transparency of an exported screenshot."""

    def __init__(self, parent, size):
        super().__init__(parent)
        self.setWindowTitle("Export screenshot")
        self.width, self.height = size_boxes(size, "Pixels; the view is rendered again at "
                                                   "this size")
        self.transparent = QCheckBox("Transparent background")
        self.transparent.setToolTip("Alpha 0 where nothing was drawn")
        form = QFormLayout(self)
        form.addRow("Width", self.width)
        form.addRow("Height", self.height)
        form.addRow(self.transparent)
        form.addRow(ok_cancel(self))


def load_session(window) -> None:
    path, _ = QFileDialog.getOpenFileName(window, "Load session", "",
                                          "splineviz sessions (*.svs)")
    if path:
        window.open_path(path)


def save_session(window) -> None:
    """Save to the session's file, or ask for one."""
    if window.session_file is not None:
        window.save_session(window.session_file)
    else:
        save_session_as(window)


def save_session_as(window) -> bool:
    path, _ = QFileDialog.getSaveFileName(window, "Save session", "session.svs",
                                          "splineviz sessions (*.svs)")
    return bool(path) and window.save_session(path) is not None


def export_screenshot(window) -> None:
    dlg = ScreenshotDialog(window, window.spline_scene.window_size())
    if dlg.exec() != QDialog.DialogCode.Accepted:
        return
    path, _ = QFileDialog.getSaveFileName(window, "Export screenshot", "screenshot.png",
                                          "PNG images (*.png)")
    if path:  # rendered in the background (the window stays responsive)
        from splineviz.gui.screenshot import export_screenshot as export

        window.guard(export, window, path, (dlg.width.value(), dlg.height.value()),
                     dlg.transparent.isChecked())


def export_mesh(window, method: str = "flying-edges") -> None:
    """Save the selected mesh or isosurface; asks whether to cut it by its clip planes when
    it has some (ParaView's Clip filter before Save Data). ``method="front"``: mesh an
    isosurface with the advancing front on the spline."""
    path, _ = QFileDialog.getSaveFileName(window, "Export mesh", "mesh.ply",
                                          "Meshes (*.ply *.stl *.vtp *.obj)")
    if not path:
        return
    clip = True
    if window.scene.planes_cutting(window.scene.selected):
        answer = QMessageBox.question(
            window, "Export mesh", "Cut the mesh by its clip planes, as the view shows it?",
            QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No
            | QMessageBox.StandardButton.Cancel, QMessageBox.StandardButton.Yes)
        if answer == QMessageBox.StandardButton.Cancel:
            return
        clip = answer == QMessageBox.StandardButton.Yes
    window.guard(window.commands.export_mesh, path, clip=clip, method=method)


def fill_sources(window, menu) -> None:
    """The plugins' synthetic sources (and the plugins that failed, greyed out)."""
    from splineviz.plugins import failures, sources

    menu.clear()
    for name, src in sorted(sources().items()):
        a = QAction(src.title or name, window)
        a.setToolTip(src.description or src.title or name)
        a.triggered.connect(lambda _=False, n=name: window.guard(
            window.commands.open_source, n, mode="ask"))
        menu.addAction(a)
    for rec in failures():
        a = QAction(f"plugin {rec.name} failed: {rec.error}", window)
        a.setEnabled(False)
        menu.addAction(a)


def fill_examples(window, menu) -> None:
    """The example sessions shipped in ``resources/sessions``."""
    menu.clear()
    try:
        from splineviz.resources import example_sessions

        examples = example_sessions()
    except Exception:  # noqa: BLE001  (no resources folder: an empty menu)
        examples = {}
    for name, path in sorted(examples.items()):
        a = QAction(name, window)
        a.triggered.connect(lambda _=False, p=path: window.open_path(p))
        menu.addAction(a)
    menu.setEnabled(bool(examples))


class RecentFiles:
    """File > Open Recent, kept in the user's Qt settings."""

    def __init__(self, window, menu):
        self.window = window
        self.menu = menu
        self.fill()

    @staticmethod
    def _settings() -> QSettings:
        return QSettings("splineviz", "splineviz")

    def files(self) -> list[str]:
        v = self._settings().value("recent", [])
        return [v] if isinstance(v, str) else list(v or [])

    def add(self, path: str) -> None:
        p = str(Path(path).absolute())
        files = [p] + [f for f in self.files() if f != p]
        self._settings().setValue("recent", files[:MAX_RECENT])
        self.fill()

    def fill(self) -> None:
        self.menu.clear()
        for f in self.files():
            a = QAction(f, self.window)
            a.triggered.connect(lambda _=False, f=f: open_chosen(self.window, f))
            self.menu.addAction(a)
        self.menu.setEnabled(bool(self.files()))


def show_help(window) -> None:
    QMessageBox.information(window, "Keyboard and mouse", HELP_TEXT)


def about(window) -> None:
    QMessageBox.about(window, "About splineviz",
                      f"splineviz {splineviz.__version__}\n\nSmooth trivariate spline "
                      "isosurfaces by exact ray casting, and point-cloud meshing.")
