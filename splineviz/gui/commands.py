"""What the File menu, drag and drop and the command line do to the scene: new, open, save,
export. Reading and writing run as jobs (progress, cancel); the scene model is changed in
the GUI thread when they finish. No method here blocks the GUI thread on data.

No work is lost: every path that replaces the scene (New, Open, Open default data, a
synthetic source or an example session opened in place of the objects, Load session) first
asks what to do with unsaved changes -- Save, Discard or Cancel (:meth:`Commands.
confirm_unsaved`) -- when the window asks about them (the app's windows; scripts and tests
that do not turn :attr:`MainWindow.ask_before_closing` on are never asked). Data opened
beside the objects already shown is a step of the undo stack (:mod:`splineviz.gui.undo`);
replacing the scene clears the history."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject, Signal
from PySide6.QtWidgets import QFileDialog, QMessageBox

from splineviz.core.errors import SplinevizError
from splineviz.gui.jobs import error_message
from splineviz.gui.undo import undo_stack
from splineviz.io.opening import data_name
from splineviz.model import IsosurfaceNode, MeshNode, Scene, VolumeNode
from splineviz.model.opening import OutsideFolder, noting_warnings, read_file
from splineviz.model.session import SESSION_SUFFIX, apply_session, read_session_data, session_path
from splineviz.model.summaries import remember

#: what to do with the current objects when a file is opened
OPEN_MODES = ("ask", "replace", "add")

log = logging.getLogger("splineviz")


class Commands(QObject):
    """File operations of the window (see module docstring).

    Signals
    -------
    opened(str)
        A file or session was opened (its path): for the recent-files list.
    saved(str)
        A file was written (its path).
    warned(str)
        Something was read with a change the user should know of, or not read at the
        user's wish (one sentence: the log panel and the status bar show it).
    """

    opened = Signal(str)
    saved = Signal(str)
    warned = Signal(str)

    def __init__(self, scene: Scene, jobs, window):
        super().__init__(window)
        self.scene = scene
        self.jobs = jobs
        self.window = window

    # -- unsaved changes -----------------------------------------------------------------

    def confirm_unsaved(self, action: str = "Replacing the scene") -> bool:
        """Ask what to do with unsaved changes before ``action`` loses them: Save (to the
        session file, or one asked for), Discard or Cancel. True: go on (saved, discarded,
        or nothing to lose); False: the user cancelled, or the save did not happen."""
        window = self.window
        if (not getattr(window, "ask_before_closing", False) or not self.scene.modified
                or not len(self.scene)):
            return True
        buttons = QMessageBox.StandardButton
        answer = QMessageBox.question(
            window, "Unsaved changes",
            f"The scene has unsaved changes. {action} discards them. Save them as a "
            "session first?", buttons.Save | buttons.Discard | buttons.Cancel, buttons.Save)
        if answer == buttons.Cancel:
            return False
        if answer == buttons.Save:
            if window.session_file is not None:
                return window.save_session(window.session_file) is not None
            from splineviz.gui.dialogs import save_session_as

            return save_session_as(window)
        return True

    # -- open ----------------------------------------------------------------------------

    def new_scene(self) -> bool:
        """Start an empty, untitled scene (asks about unsaved changes first); False: the
        user kept the scene."""
        if not self.confirm_unsaved("Starting a new scene"):
            return False
        self.scene.clear()
        self.scene.mark_saved()
        self._untitled()
        return True

    def _untitled(self) -> None:
        """The scene was replaced by one that no session file holds: Save asks for a file
        (it must not overwrite the session the old scene came from); the title follows."""
        self.window.session_file = None
        self.scene.changed.emit()

    def open_default(self) -> VolumeNode | None:
        """Replace the scene by the embedded default data (asks about unsaved changes
        first; None: the user kept the scene)."""
        from splineviz.model.opening import default_scene

        if not self.confirm_unsaved("Opening the default data"):
            return None
        default_scene(self.scene)
        self._untitled()
        node = self.scene.volumes[0]
        self.scene.select(node)
        return node

    def open_source(self, name: str, shape=None, mode: str = "add") -> VolumeNode | None:
        """Sample a synthetic source offered by a plugin (see :mod:`splineviz.plugins`)."""
        from splineviz.plugins import source_volume, sources

        src = sources().get(name)
        if src is None:
            raise SplinevizError(f"no synthetic source named {name!r}; plugins offer "
                                 f"{', '.join(sorted(sources())) or 'none'}")
        vol = source_volume(name, shape)
        return self._add_volume(vol, f"{src.title} {'x'.join(map(str, vol.shape))}", mode,
                                isovalue=src.isovalue, source=name)

    def open_path(self, path, mode: str = "ask", allow_outside: bool = False, raw=None,
                  **iso):
        """Open a volume, point cloud or session in a job; returns the job (None if the
        session could not even be parsed: the message is shown). ``allow_outside``: the
        user confirmed reading a data file outside the folder of the header naming it;
        ``raw``: a raw file's dims, dtype, byteorder and offset (the raw-file dialog's)."""
        from splineviz.io._util import regular_input

        path = str(path)
        if Path(path).suffix.lower() == SESSION_SUFFIX:
            return self.load_session(path, allow_outside=allow_outside)
        # a FIFO or device file would block the reader, and its job, for ever
        regular_input(path, allow_dir=True)

        def done(noted):
            result = self._noted(noted, Path(path).name)
            if isinstance(result, OutsideFolder):
                self._outside(result, allow_outside,
                              lambda: self.open_path(path, mode, allow_outside=True, raw=raw,
                                                     **iso))
                return
            kind, data, summaries = result
            for what, value in summaries.items():
                remember(what, data, value)
            self.opened.emit(path)
            if kind == "volume":
                self._add_volume(data, data_name(path), mode, path=path, read_options=raw,
                                 **iso)
            else:
                self._add(mode, lambda: self.scene.add_points(data, Path(path).name,
                                                              path=path), Path(path).name)

        # a process: readers (VTK's, NumPy's text parser) hold the GIL while they parse
        return self.jobs.run(f"Opening {Path(path).name}", noting_warnings, read_file, path,
                             allow_outside=allow_outside, on_done=done, process=True,
                             **(raw or {}))

    def _noted(self, noted, name: str):
        """Show the warnings a read raised (log panel and status bar); its value."""
        for text in noted.other_warnings:
            log.debug("reading %s: %s", name, text)
        for text in noted.warnings:
            self.warned.emit(f"{name}: {text}")
        return noted.value

    def _outside(self, refusal: OutsideFolder, confirmed: bool, retry):
        """A data file outside its folder was refused: ask, and ``retry()`` (its result is
        returned) if the user confirms; refused again after a confirmation, it is an error."""
        if confirmed:
            self.window.show_error(refusal.message)
            return None
        return retry() if self.confirm_outside(refusal) else None

    def confirm_outside(self, outside: OutsideFolder) -> bool:
        """Ask whether to read a data file outside the folder of the file naming it (as
        ParaView asks before loading state files that point elsewhere)."""
        answer = QMessageBox.question(
            self.window, "Data file outside its folder",
            f"{Path(outside.path).name or outside.path} names data file {outside.data_path} "
            "outside its folder. Read it anyway?",
            QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
            QMessageBox.StandardButton.No)
        if answer != QMessageBox.StandardButton.Yes:
            self.warned.emit(f"not read: {outside.data_path} lies outside the folder of "
                             f"{Path(outside.path).name or outside.path}")
            return False
        return True

    def _replace_or_add(self, mode: str) -> str | None:
        """"replace" or "add" (asked when the scene has objects and ``mode`` is "ask");
        None: the user cancelled."""
        if mode != "ask" or not len(self.scene):
            return "replace" if mode == "ask" else mode
        box = QMessageBox(QMessageBox.Icon.Question, "Open",
                          "Replace the objects shown now, or add the new data to them?",
                          parent=self.window)
        replace = box.addButton("Replace", QMessageBox.ButtonRole.AcceptRole)
        add = box.addButton("Add", QMessageBox.ButtonRole.ActionRole)
        box.addButton(QMessageBox.StandardButton.Cancel)
        box.exec()
        clicked = box.clickedButton()
        return "replace" if clicked is replace else "add" if clicked is add else None

    def _add(self, mode: str, make, name: str = "data"):
        """Put what ``make()`` makes in the scene, replacing the objects (unsaved changes
        are asked about) or beside them (one undo step)."""
        mode = self._replace_or_add(mode)
        if mode is None or (mode == "replace" and not self.confirm_unsaved(f"Opening {name}")):
            return None

        def put():
            if mode == "replace":
                self.scene.clear()
            node = make()
            # frame what is new when replacing, everything when adding
            self.scene.frame(node.bounds if mode == "replace" and isinstance(node, VolumeNode)
                             else None, view="isometric" if mode == "replace" else None)
            self.scene.select(node)
            return node

        if mode == "replace":
            node = put()
            self._untitled()
            return node
        return undo_stack(self.scene).change(f"Open {name}", put)

    def _add_volume(self, vol, name, mode, path=None, isovalue=None, model=None,
                    source=None, read_options=None) -> VolumeNode:
        return self._add(mode, lambda: self.scene.add_volume(
            vol, name, path=path, source=source, read_options=read_options,
            isovalue=isovalue, model=model), name)

    # -- sessions ------------------------------------------------------------------------

    def load_session(self, path, *, allow_outside: bool = False, on_loaded=None,
                     asked: bool = False):
        """Parse the session here (fast; missing data files are asked for), read its data
        in a job, then replace the scene (and call ``on_loaded()``). Returns the job, or
        None when the session was refused (the message is shown) or not confirmed.
        Unsaved changes are asked about first, unless ``asked``."""
        from splineviz.io.session import load_session

        if not asked and not self.confirm_unsaved(f"Opening {Path(path).name}"):
            return None
        try:
            noted = noting_warnings(load_session, path, repoint=self._ask_repoint,
                                    allow_outside=allow_outside)
        except Exception as exc:  # noqa: BLE001  (a hostile session is a message, not a crash)
            if not isinstance(exc, SplinevizError | OSError):
                log.debug("loading %s", path, exc_info=True)
            self.window.show_error(error_message(exc))
            return None
        session = self._noted(noted, Path(path).name)
        if isinstance(session, OutsideFolder):
            return self._outside(session, allow_outside, lambda: self.load_session(
                path, allow_outside=True, on_loaded=on_loaded, asked=True))
        return self._read_session(path, session, allow_outside, on_loaded)

    def _read_session(self, path, session, allow_outside: bool, on_loaded):
        def done(noted):
            data = self._noted(noted, Path(path).name)
            if isinstance(data, OutsideFolder):
                self._outside(data, allow_outside,
                              lambda: self._read_session(path, session, True, on_loaded))
                return
            apply_session(self.scene, session, data)
            self.opened.emit(str(path))
            if on_loaded is not None:
                on_loaded()

        # a process, as for single files: readers hold the GIL while they parse
        return self.jobs.run(f"Loading {Path(path).name}", noting_warnings, read_session_data,
                             session, allow_outside=allow_outside, on_done=done, process=True)

    def _ask_repoint(self, obj_id: str, missing: Path):
        found, _ = QFileDialog.getOpenFileName(
            self.window, f"Where is {Path(missing).name}? (object {obj_id})",
            str(Path(missing).parent))
        return found or None

    def save_session(self, path) -> Path:
        """Write the scene as a session (``.svs`` appended when missing); data without a
        file is written beside it. Small: done in the GUI thread."""
        from splineviz.model.session import save_scene

        p = save_scene(self.scene, session_path(path))
        self.saved.emit(str(p))
        self.opened.emit(str(p))
        return p

    # -- export --------------------------------------------------------------------------

    def export_screenshot(self, path, size=None, transparent: bool = False) -> np.ndarray:
        """Write the view as PNG at ``size`` (exact frames, off-screen, through the same
        :func:`~splineviz.render.scene_view.render_scene` as the command line)."""
        from splineviz.render.scene_view import render_scene

        size = size or self.window.view.spline_scene.window_size()
        img = render_scene(self.scene, size, str(path), transparent_background=transparent,
                           device=self.window.device)
        self.saved.emit(str(path))
        return img

    def export_mesh(self, path, node=None, clip: bool = True, method: str = "flying-edges"):
        """Write the selected mesh or isosurface as a mesh file in a job (``method``: how an
        isosurface is meshed, see :func:`splineviz.render.extract.export_mesh`)."""
        node = node if node is not None else self.scene.selected
        if isinstance(node, VolumeNode):
            isos = self.scene.isosurfaces_of(node)
            node = isos[0] if isos else None
        if not isinstance(node, MeshNode | IsosurfaceNode):
            raise SplinevizError("select a mesh or an isosurface to export")
        from splineviz.render.extract import export_mesh

        return self.jobs.run(f"Exporting {Path(path).name}", export_mesh, self.scene, node,
                             str(path), clip=clip, method=method,
                             on_done=lambda p: self.saved.emit(p))
