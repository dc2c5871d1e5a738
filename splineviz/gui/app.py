"""Start the application: ``splineviz [FILE|SESSION] [--screenshot PNG --size WxH ...]``.

With ``--screenshot`` the window opens, loads, renders exact frames, saves the view at
``--size`` and quits (for scripts and tests). Without a display (no ``$DISPLAY``), a
screenshot is rendered off-screen by the same scene code instead of a window.
"""

from __future__ import annotations

import os
import sys

from splineviz.core.camera import parse_size
from splineviz.core.errors import SplinevizError

DEFAULT_SIZE = (1024, 768)


def _iso_kwargs(args) -> dict:
    kw = {}
    if args.iso is not None:
        kw["iso"] = args.iso
    if args.model:
        kw["model"] = args.model
    return kw


def _apply_overrides(window, args) -> None:
    """--iso / --model for data that came from a session or the default set."""
    for item in window.items:
        for layer in item.layers:
            if args.iso is not None:
                layer.set_isovalue(args.iso)
            if args.model:
                layer.set_model(args.model)


def headless_screenshot(args, size) -> int:
    """``--screenshot`` without a display: the same scene, rendered off-screen."""
    import numpy as np
    import pyvista as pv

    from splineviz.gui.main_window import (
        BACKGROUND,
        _outline,
        default_data,
        default_model,
        load_path,
    )
    from splineviz.render.isosurface import IsosurfaceLayer
    from splineviz.render.scene import SplineScene, offscreen_screenshot

    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.set_background(BACKGROUND)
    scene = SplineScene(pl)
    try:
        if args.file:
            kind, obj = load_path(args.file)
            if kind != "volume":
                raise SplinevizError("without a display only volumes can be rendered; "
                                     "set DISPLAY or run under xvfb-run")
            vol, iso = obj, None
        else:
            vol, iso = default_data()
        iso = args.iso if args.iso is not None else iso
        scene.add_layer(IsosurfaceLayer(vol, model=args.model or default_model(), isovalue=iso))
        pl.add_mesh(_outline(vol), color="gray")
        pl.reset_camera(bounds=np.ravel(vol.bounds))
        pl.camera.Azimuth(30)
        pl.camera.Elevation(20)
        pl.camera.Zoom(1.4)
        pl.camera_set = True
        offscreen_screenshot(scene, args.screenshot, size=size)
    finally:
        scene.close()
        pl.close()
    return 0


def _install_excepthook(window) -> None:
    """Unexpected errors in Qt slots: traceback on stderr and a message in the window, which
    stays usable (Qt would otherwise only print them, or abort on some platforms)."""
    import traceback

    previous = sys.excepthook

    def hook(exc_type, exc, tb):
        traceback.print_exception(exc_type, exc, tb)
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
    from PySide6.QtWidgets import QApplication

    from splineviz.gui.main_window import MainWindow

    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("splineviz")
    window = MainWindow(size=size or DEFAULT_SIZE)
    window.resize(*(s + 420 for s in (size or DEFAULT_SIZE)))
    if not args.screenshot:
        _install_excepthook(window)
    window.show()
    if args.file:
        window.open_path(args.file, block=True, **_iso_kwargs(args))
        if window.last_error is not None and args.screenshot:
            window.close()
            raise SplinevizError(window.last_error)
        if args.file.lower().endswith(".svs"):
            _apply_overrides(window, args)
    else:
        window.open_default()
        _apply_overrides(window, args)
    if args.screenshot:
        app.processEvents()
        window.export_screenshot(args.screenshot, size=size or window.scene.window_size())
        window.close()
        return 0
    return app.exec()
