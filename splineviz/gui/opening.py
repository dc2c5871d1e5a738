"""Opening files in the main window: a path from the File menu, the recent-files list, the
command line or a drop onto the window becomes a job of :class:`~splineviz.gui.commands.
Commands` (reading never blocks the GUI thread); what was opened goes to File > Open Recent,
and an opened session becomes the window's session file (its title).

The dialogs that ask for a path are in :mod:`splineviz.gui.dialogs`; each ends in
:func:`open_path`.
"""

from __future__ import annotations

from pathlib import Path


def open_path(window, path, mode: str = "ask", block: bool = False, **iso):
    """Open a volume, point cloud or session file as a job of ``window``'s commands.

    Parameters
    ----------
    window : MainWindow
    path : path-like
    mode : "ask", "replace" or "add"
        What happens to the objects already in the scene.
    block : bool
        Wait until the job has finished (scripts and tests).
    **iso
        ``isovalue``, ``model`` of the volume's isosurface.

    Returns
    -------
    The job, or None when the path was refused (the window shows why).
    """
    job = window.guard(window.commands.open_path, path, mode=mode, **iso)
    if block:
        window.wait_idle()
    return job


def opened(window, path: str) -> None:
    """``path`` was opened: into the recent files; a session becomes the session file."""
    window.recent.add(path)
    if path.lower().endswith(".svs"):
        window.session_file = Path(path)
        window.update_title()


def accepts_drop(event) -> bool:
    """Whether a drag entering the window carries files (then it is accepted)."""
    if event.mimeData().hasUrls():
        event.acceptProposedAction()
        return True
    return False


def drop(window, event) -> None:
    """Open every local file or folder dropped onto the window as File > Open would (a
    folder of several DICOM series asks which, a raw file asks for its layout)."""
    from splineviz.gui.open_dialogs import open_chosen

    for url in event.mimeData().urls():
        if url.isLocalFile():
            open_chosen(window, url.toLocalFile())
