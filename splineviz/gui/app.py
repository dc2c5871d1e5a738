"""Start the application: ``splineviz [FILE|SESSION] [--screenshot PNG --size WxH ...]``.

The scene comes from :mod:`splineviz.model.opening` and a screenshot from
:func:`splineviz.render.scene_view.render_scene` on every path: with ``--screenshot`` and no
display the window is not even opened (off-screen rendering), with a display the window opens,
loads, saves and quits — the same scene and the same picture either way.
"""

from __future__ import annotations

import logging
import os
import sys

from splineviz.core.camera import parse_size
from splineviz.core.errors import SplinevizError

DEFAULT_SIZE = (1024, 768)


def _scene(args, preferred_model=None):
    """The scene of the command line: its file or the default data, with ``--iso``,
    ``--model`` and ``--renderer``; without ``--model`` the isosurfaces take
    ``preferred_model`` (a point cloud has none to take it)."""
    from splineviz.model.opening import default_scene, override, scene_from_path

    model = args.model or preferred_model
    if args.file:
        scene = scene_from_path(args.file, isovalue=args.iso, model=args.model,
                                renderer=args.renderer)
        if args.model is None and model is not None and scene.isosurfaces:
            override(scene, model=model)
            scene.mark_saved()
        return scene
    scene = default_scene()
    override(scene, isovalue=args.iso, model=model, renderer=args.renderer)
    return scene


def headless_screenshot(args, size) -> int:
    """``--screenshot`` without a display: the same scene, rendered off-screen."""
    from splineviz.render.scene_view import render_scene

    render_scene(_scene(args), size, args.screenshot)
    return 0


def _install_excepthook(window) -> None:
    """Unexpected errors in Qt slots: logged, and a message in the window, which stays usable
    (Qt would otherwise only print them, or abort on some platforms)."""
    previous = sys.excepthook
    log = logging.getLogger("splineviz")

    def hook(exc_type, exc, tb):
        log.error("unexpected error", exc_info=(exc_type, exc, tb))
        if issubclass(exc_type, KeyboardInterrupt):
            previous(exc_type, exc, tb)
            return
        try:
            window.show_error(f"{exc_type.__name__}: {exc}")
        except RuntimeError:  # the window is already gone
            pass

    sys.excepthook = hook


def run_gui(args) -> int:
    """Open the main window (see module docstring); returns the exit code."""
    size = parse_size(args.size) if args.size else None
    if args.file and not os.path.exists(args.file):
        # a typo on the command line is an error, not a window with a message box
        raise SplinevizError(f"file not found: {args.file}")
    if args.screenshot and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return headless_screenshot(args, size or DEFAULT_SIZE)
    session = bool(args.file) and args.file.lower().endswith(".svs") and not args.screenshot
    # data are read before the window opens, so a bad file is one line on stderr; a session
    # is opened by the window instead, which asks for data files that moved
    from PySide6.QtWidgets import QApplication

    from splineviz.gui import preferences

    # the preferred model, for the file named on the command line too (--model wins)
    scene = None if session else _scene(args, preferences.load().model)

    from splineviz.gui.main_window import MainWindow

    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("splineviz")
    window = MainWindow(scene=scene)
    if args.screenshot:
        window.show()
        app.processEvents()
        window.export_screenshot(args.screenshot, size=size or DEFAULT_SIZE)
        window.close()
        return 0
    from splineviz.gui import window_state

    # the last session's size, position and dock layout, unless --size asks for a view size
    if size is not None:
        window.resize(window.width() + size[0] - window.plotter.width(),
                      window.height() + size[1] - window.plotter.height())
    else:
        window_state.restore_geometry(window)
    window.ask_before_closing = True
    preferences.apply(window, preferences.load())
    _install_excepthook(window)
    window.show()
    if size is None:
        window_state.restore_layout(window)
    window.enable_autosave()
    # a restored scene (after a crash) replaces what the command line named
    restoring = window.offer_recovery() is not None
    if session and not restoring:
        window.open_path(args.file)
    elif window.scene.volumes and not restoring:
        window.scene.select(window.scene.volumes[0])
    if args.file and not session and not restoring:
        # read before the window, it goes to File > Open Recent as if opened from the menu
        from splineviz.gui import opening

        opening.opened(window, args.file)
    code = app.exec()
    window_state.remember(window)
    window.join_workers()
    return code
