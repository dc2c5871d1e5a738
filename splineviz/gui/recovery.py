"""Crash safety: the scene is autosaved to a recovery session and offered back after a crash.

Every change of the scene (objects, properties, camera) restarts a :data:`DEBOUNCE_MS`
timer; when it runs out the scene is written as a session, ``recovery-<pid>-<start>.svs``,
into the recovery folder (:func:`recovery_dir`: ``$SPLINEVIZ_RECOVERY_DIR`` or the user's
data folder). Sessions refer to data files by path, so the file is small and is written in
the GUI thread (a few milliseconds). Data without a file (a volume made in Python, a
remeshed mesh) is copied once into ``recovery-<pid>-<start>_data/`` by a background thread
first, as ``.npy`` (volumes) or PLY (meshes, clouds): plain writes that release the GIL, so
the window is not stalled, whatever the size. The session is written through the atomic
writer, so a kill while saving leaves the previous recovery file whole.

A clean quit removes the files. A recovery file whose process is gone (the pid is not
running, or runs a program started at another time) is what a crash or a kill left behind:
:func:`offer_recovery` asks at start-up whether to restore it (``$SPLINEVIZ_RECOVER``
answers for tests and scripts: ``restore`` or ``discard``).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import shutil
import threading
import time
import weakref
from dataclasses import dataclass
from pathlib import Path

from PySide6.QtCore import QObject, QTimer, Signal

from splineviz.core.errors import SplinevizError

#: environment variable naming the recovery folder (tests; default: the user's data folder)
RECOVERY_ENV = "SPLINEVIZ_RECOVERY_DIR"
#: environment variable answering the start-up question: "restore" or "discard"
ANSWER_ENV = "SPLINEVIZ_RECOVER"
#: quiet time after the last change before the scene is written (milliseconds)
DEBOUNCE_MS = 2000
#: longest wait at a clean quit for a data copy being written (seconds)
CLOSE_WAIT_S = 10.0

_NAME = re.compile(r"^recovery-(\d+)-(\d+)\.svs$")
log = logging.getLogger("splineviz")


def recovery_dir() -> Path:
    """The folder of recovery files: ``$SPLINEVIZ_RECOVERY_DIR`` or
    ``<user data dir>/splineviz/recovery`` (platformdirs)."""
    env = os.environ.get(RECOVERY_ENV)
    if env:
        return Path(env).expanduser()
    import platformdirs

    return Path(platformdirs.user_data_dir("splineviz")) / "recovery"


def _start_stamp(pid: int) -> int | None:
    """Start time of process ``pid`` in centiseconds since the epoch (None: not running).
    With the pid it names a process unambiguously: pids are reused, start times are not."""
    import psutil

    try:
        return int(round(psutil.Process(pid).create_time() * 100))
    except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
        return None


@dataclass(frozen=True)
class RecoveryFile:
    """A recovery session left by a process that ended without a clean quit.

    Attributes
    ----------
    path : Path
        The ``.svs`` file.
    saved : float
        When it was written (seconds since the epoch).
    """

    path: Path
    saved: float

    @property
    def data_dir(self) -> Path:
        return self.path.with_name(f"{self.path.stem}_data")

    def discard(self) -> None:
        """Remove the session and its data folder (what cannot be removed stays: a
        quit must not fail over a recovery file)."""
        with contextlib.suppress(OSError):
            self.path.unlink(missing_ok=True)
        shutil.rmtree(self.data_dir, ignore_errors=True)


def orphaned(folder: Path | None = None) -> list[RecoveryFile]:
    """Recovery files in ``folder`` whose process no longer runs, newest first."""
    folder = recovery_dir() if folder is None else Path(folder)
    found = []
    try:
        entries = list(folder.iterdir())
    except OSError:  # no folder yet: nothing was ever autosaved
        return []
    for p in entries:
        m = _NAME.match(p.name)
        if m is None:
            continue
        pid, stamp = int(m.group(1)), int(m.group(2))
        now = _start_stamp(pid)
        if now is not None and abs(now - stamp) <= 1:
            continue  # that process still runs: its autosave, not a crash
        try:
            found.append(RecoveryFile(p, p.stat().st_mtime))
        except OSError:
            continue
    return sorted(found, key=lambda r: -r.saved)


class _Signals(QObject):
    """Carries the data writer's result from its thread to the GUI thread (queued)."""

    written = Signal(object)


class Autosaver(QObject):
    """Writes the scene to this process's recovery file after every change (debounced).

    Parameters
    ----------
    scene : Scene
    folder : path-like, optional
        The recovery folder (default :func:`recovery_dir`).
    debounce_ms : int
        Quiet time after the last change before writing.

    Signals
    -------
    saved(str)
        The recovery file was written (its path).
    failed(str)
        Autosaving failed (one sentence; autosaving goes on at the next change).
    """

    saved = Signal(str)
    failed = Signal(str)

    def __init__(self, scene, folder=None, debounce_ms: int = DEBOUNCE_MS, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.folder = recovery_dir() if folder is None else Path(folder)
        pid = os.getpid()
        stamp = _start_stamp(pid) or int(time.time() * 100)
        self.path = self.folder / f"recovery-{pid}-{stamp}.svs"
        self.data_dir = self.path.with_name(f"{self.path.stem}_data")
        #: node id -> (weak reference to the data written, path, read options)
        self._written: dict[str, tuple] = {}
        self._writing = False
        self._thread: threading.Thread | None = None
        self._closed = False
        self._signals = _Signals()
        self._signals.written.connect(self._data_written)
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(int(debounce_ms))
        self._timer.timeout.connect(self.save_now)
        scene.changed.connect(self._schedule)

    @property
    def pending(self) -> bool:
        """A write is scheduled or in progress."""
        return self._timer.isActive() or self._writing

    def _schedule(self) -> None:
        if not self._closed:
            self._timer.start()  # restarts: written once the changes pause

    def _data_of(self, node):
        return node.vertices if hasattr(node, "vertices") else node.data

    def _unwritten(self) -> list:
        """Nodes whose data has no file and no up-to-date copy in the recovery folder."""
        from splineviz.model.session import needs_data_file

        todo = []
        for node in self.scene:
            if not needs_data_file(node):
                continue
            done = self._written.get(node.id)
            if done is None or done[0]() is not self._data_of(node):
                todo.append(node)
        return todo

    def save_now(self) -> None:
        """Write the recovery file now (data without a file first, in a thread)."""
        if self._closed or self._writing:
            return
        todo = self._unwritten()
        if todo:
            self._writing = True
            self._thread = threading.Thread(target=self._write_data, args=(todo,),
                                            daemon=True, name="splineviz autosave")
            self._thread.start()
            return
        self._write_session()

    def _write_data(self, nodes) -> None:
        """Thread: copy the data of ``nodes`` into the recovery data folder."""
        from splineviz.model.session import write_node_data

        results = []
        try:
            self.data_dir.mkdir(parents=True, exist_ok=True)
            for node in nodes:
                data = self._data_of(node)
                path, options = write_node_data(node, self.data_dir, volume_suffix=".npy")
                results.append((node.id, weakref.ref(data), path, options))
        except (SplinevizError, OSError) as exc:
            results = exc
        try:
            self._signals.written.emit(results)
        except RuntimeError:  # the window (and the signals object) is gone
            pass

    def _data_written(self, results) -> None:
        self._writing = False
        if self._closed:
            return
        if isinstance(results, BaseException):
            self.failed.emit(f"autosave failed: {results}")
            return
        for node_id, ref, path, options in results:
            self._written[node_id] = (ref, path, options)
        if self._unwritten():  # the scene changed meanwhile: go again
            self._timer.start(0)
            return
        self._write_session()

    def _write_session(self) -> None:
        from splineviz.io.session import save_session
        from splineviz.model.session import needs_data_file, to_session

        written = {i: (p, o) for i, (_, p, o) in self._written.items() if i in self.scene}
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            save_session(to_session(self.scene, written), self.path)
        except (SplinevizError, OSError) as exc:
            self.failed.emit(f"autosave failed: {exc}")
            return
        # copies of removed objects, and of objects saved to files since, are not needed
        for node_id in [i for i in self._written
                        if i not in self.scene or not needs_data_file(self.scene.get(i))]:
            _, path, _ = self._written.pop(node_id)
            Path(path).unlink(missing_ok=True)
        self.saved.emit(str(self.path))

    def close(self) -> None:
        """A clean quit: stop autosaving and remove this process's recovery files."""
        self._closed = True
        self._timer.stop()
        self.scene.changed.disconnect(self._schedule)
        if self._thread is not None:
            # a copy being written would land in the folder removed next
            self._thread.join(CLOSE_WAIT_S)
        RecoveryFile(self.path, 0.0).discard()


def restored_data_paths(scene, data_dir: Path) -> None:
    """Nodes restored from a recovery file whose data lay in its data folder hold that data
    again without a file (as before the crash): the folder is removed after restoring, and
    saving the session writes such data beside it."""
    root = Path(data_dir).resolve()
    for node in scene:
        path = getattr(node, "path", None)
        if path is not None and Path(path).resolve().parent == root:
            node.path = None
            if hasattr(node, "read_options"):
                node.read_options = {}


def ask_restore(window, found: RecoveryFile) -> bool:
    """Whether to restore ``found``: ``$SPLINEVIZ_RECOVER`` or the user's answer."""
    answer = os.environ.get(ANSWER_ENV, "").strip().lower()
    if answer in ("restore", "discard"):
        return answer == "restore"
    from PySide6.QtWidgets import QMessageBox

    when = time.strftime("%Y-%m-%d %H:%M", time.localtime(found.saved))
    box = QMessageBox(QMessageBox.Icon.Question, "Restore the last scene?",
                      f"splineviz did not quit cleanly last time. Restore the scene autosaved "
                      f"at {when}?", parent=window)
    restore = box.addButton("Restore", QMessageBox.ButtonRole.AcceptRole)
    box.addButton("Discard", QMessageBox.ButtonRole.DestructiveRole)
    box.exec()
    return box.clickedButton() is restore


def offer_recovery(window, folder: Path | None = None):
    """If an earlier run left a recovery file in ``folder`` (default: the window's autosave
    folder, else :func:`recovery_dir`), ask whether to restore it and, if so, load it in a
    job of ``window`` (which replaces the scene); returns that job, or None. Files not
    restored are removed; older ones wait for the next start."""
    if folder is None and window.autosaver is not None:
        folder = window.autosaver.folder
    found = orphaned(folder)
    if not found:
        return None
    newest = found[0]
    if not ask_restore(window, newest):
        newest.discard()
        window.log.add(f"discarded the recovery file {newest.path}")
        return None

    def loaded():
        restored_data_paths(window.scene, newest.data_dir)
        newest.discard()
        window.scene.modified = True  # restored work is not saved anywhere yet
        window.session_file = None
        window.update_title()
        window.show_warning(f"restored the scene autosaved at "
                            f"{time.strftime('%H:%M:%S', time.localtime(newest.saved))}")

    # its data paths are relative to the recovery folder: outside it, and ours
    return window.commands.load_session(newest.path, allow_outside=True, on_loaded=loaded)
