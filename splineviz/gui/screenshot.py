"""File > Export screenshot in the background: the exact frames of a picture of any size are
ray cast in a job (progress and Cancel in the status bar), the window stays responsive, and
the PNG is written when they are done.

The picture is what :func:`splineviz.render.scene_view.render_scene` draws (the command
line's ``--screenshot``): an off-screen view of the scene per side of a split, exact frames
only. Here the work is cut so that the GUI thread never holds on to it:

1. (GUI thread) the off-screen views are made; nothing is rendered yet;
2. (job thread) their exact frames are ray cast (:meth:`SplineScene.refine`; the casters
   are built there too) — cancellable;
3. (GUI thread, one view per turn of the event loop) the frames are shown and each view is
   rendered and read back (its colour, and for the volume rendering its camera, window depth
   and what its volumes cast); a frame the scene changed meanwhile is cast again (step 2);
4. (job thread) the volume rendering is cast and composited over the picture as
   :func:`~splineviz.render.volume_rendering.composite_volume_rendering` does for
   ``render_scene``; the PNG is written.

A cancel or an error closes the off-screen views once the job's thread has ended (its
casters are theirs).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal

from splineviz.core.errors import SplinevizError

#: times the frames are cast again when the scene changed while they were cast
MAX_ROUNDS = 4
#: interval of the check whether a cancelled job's thread has ended (ms)
_POLL_MS = 50


class ScreenshotExport(QObject):
    """One export of ``window``'s scene as a PNG (see module docstring); started by
    :func:`export_screenshot`.

    Signals
    -------
    finished(str)
        The file written (its path), or "" when cancelled or failed.
    """

    finished = Signal(str)

    def __init__(self, window, path, size, transparent: bool = False):
        super().__init__(window)
        self.window = window
        self.path = Path(path)
        self.size = (int(size[0]), int(size[1]))
        self.transparent = bool(transparent)
        #: (plotter, SceneView) per side of the picture
        self._views: list = []
        self._job = None
        self._round = 0
        self._step = 0
        self._images: list[np.ndarray] = []
        self.state = "running"  # running | done | cancelled | failed

    # -- the steps -------------------------------------------------------------------------

    def start(self) -> None:
        """Step 1, then the frames' job."""
        import pyvista as pv

        from splineviz.io._vtk import quiet_vtk_logger
        from splineviz.render.scene import SceneError
        from splineviz.render.scene_view import SceneView

        scene = self.window.scene
        w, h = self.size
        if w < 1 or h < 1 or w > 16384 or h > 16384:
            raise SceneError(f"a picture must be 1..16384 pixels per side, got {w}x{h}")
        if any(vol.smoothing_pending for vol in scene.volumes):
            raise SplinevizError("the smoothing is still being computed: export the "
                                 "screenshot once it is shown")
        if scene.view.split:
            if w < 2:
                raise SceneError("a picture of a split view needs 2 or more pixels across, "
                                 f"got {w}")
            parts = (("left", w // 2), ("right", w - w // 2))
        else:
            parts = ((None, w),)
        with quiet_vtk_logger():
            for side, width in parts:
                pl = pv.Plotter(off_screen=True, window_size=(width, h))
                self._views.append((pl, SceneView(scene, pl, progressive=False,
                                                  device=self.window.device, side=side)))
        self._cast()

    def _cast(self) -> None:
        """Step 2: the exact frames of every view, in a job."""
        self._round += 1
        requests = [(view.spline_scene, view.spline_scene.next_view_state())
                    for _pl, view in self._views]
        self._job = self.window.jobs.run(
            f"Screenshot {self.path.name}", _cast_frames, requests,
            on_done=self._frames_done, on_error=self._failed)
        self._job.on_end = self._ended

    def _frames_done(self, results) -> None:
        """The frames are cast: shown in their views; cast again what the scene changed."""
        if self._closing():
            return
        for (_pl, view), frames in zip(self._views, results, strict=True):
            view.spline_scene.apply(frames)
        if any(view.spline_scene.needs_refine() for _pl, view in self._views):
            if self._round >= MAX_ROUNDS:
                self._fail("the scene kept changing while the screenshot was made")
                return
            self._cast()
            return
        # twice for a split: the right half may widen a colour range both halves share
        self._step = 0
        self._steps = [("render", i) for _ in range(len(self._views))
                       for i in range(len(self._views))]
        self._steps += [("read", i) for i in range(len(self._views))]
        QTimer.singleShot(0, self, self._next_step)

    def _next_step(self) -> None:
        """Step 3: render or read back one view per turn of the event loop."""
        if self._closing():
            return
        if any(view.spline_scene.needs_refine() for _pl, view in self._views):
            self._cast()  # the scene changed: never ray cast in this thread
            return
        from splineviz.io._vtk import quiet_vtk_logger

        what, i = self._steps[self._step]
        pl, view = self._views[i]
        with quiet_vtk_logger():
            if what == "render":
                view.render_exact()
            else:
                self._images.append(_read_view(pl, view, self.transparent))
        self._step += 1
        if self._step < len(self._steps):
            QTimer.singleShot(0, self, self._next_step)
            return
        parts, self._images = self._images, []
        self._close_views()
        self._job = self.window.jobs.run(f"Writing {self.path.name}", _write, self.path, parts,
                                         self.window.device, on_done=self._written,
                                         on_error=self._failed)
        self._job.on_end = self._ended

    def _written(self, path) -> None:
        self.state = "done"
        self.window.commands.saved.emit(str(path))
        self.finished.emit(str(path))
        self.deleteLater()

    # -- endings ---------------------------------------------------------------------------

    def _closing(self) -> bool:
        """The window closed or the user cancelled: stop here (True)."""
        if self.window._closed or (self._job is not None and self._job.state == "cancelled"):
            self._end("cancelled")
            return True
        return False

    def _ended(self, job) -> None:
        """A job of this export ended; a cancelled one ends the export."""
        if job.state == "cancelled":
            self._end("cancelled")

    def _failed(self, exc) -> None:
        from splineviz.gui.jobs import error_message

        self._fail(f"screenshot not saved: {error_message(exc)}")

    def _fail(self, message: str) -> None:
        self._end("failed")
        self.window.show_error(message)

    def _end(self, state: str) -> None:
        if self.state != "running":
            return
        self.state = state
        self._close_views()
        self.finished.emit("")

    def _close_views(self) -> None:
        """Close the off-screen views, once no job thread casts with their casters."""
        job = self._job
        if self._views and job is not None and job._thread.is_alive():
            if not self.window._closed:
                QTimer.singleShot(_POLL_MS, self, self._close_views)
            # (a closing window leaves them to the process's exit: the thread still casts)
            return
        views, self._views = self._views, []
        for pl, view in views:
            view.close()
            pl.close()
        if self.state in ("cancelled", "failed"):
            self.deleteLater()


def _cast_frames(requests, job=None) -> list:
    """The exact frames of ``requests`` ((SplineScene, ViewState) pairs): one list of
    ``(layer, RenderedFrame)`` per view (job thread)."""
    out = []
    for i, (spline_scene, view) in enumerate(requests):
        if job is not None:
            job.progress(i / len(requests), "ray casting the exact frames")
        out.append(spline_scene.refine(view, job=job))
        if job is not None:
            job.check()
    return out


def _read_view(pl, view, transparent: bool) -> tuple:
    """(picture, camera, window depth, volume casts) of a rendered off-screen view (GUI
    thread); no camera or depth when no volume is volume rendered."""
    from splineviz.render.volume_rendering import volume_casts, vtk_camera, window_depth

    img = pl.screenshot(None, transparent_background=transparent, return_img=True)
    casts = volume_casts(view)
    if not casts:
        return img, None, None, casts
    h, w = img.shape[:2]
    return img, vtk_camera(pl), window_depth(pl, w, h), casts


def _write(path, parts, device, job=None):
    """Composite the volume rendering of each part (:func:`_read_view`), join the parts side
    by side and write the PNG (job thread)."""
    from splineviz.io.meshes import write_screenshot
    from splineviz.render.volume_rendering import composite_casts

    images = []
    for img, camera, depth, casts in parts:
        if casts:
            if job is not None:
                job.progress(len(images) / len(parts), "casting the volume rendering")
            img = composite_casts(img, camera, depth, casts, device)
            if job is not None:
                job.check()
        images.append(img)
    img = images[0] if len(images) == 1 else np.concatenate(images, axis=1)
    return write_screenshot(path, img)


def export_screenshot(window, path, size=None, transparent: bool = False) -> ScreenshotExport:
    """Start exporting ``window``'s scene as a PNG at ``size`` (default: the view's size) in
    the background; returns the export (its ``finished`` signal names the file). Bad input
    raises a :class:`SplinevizError` before anything starts."""
    size = size or window.view.spline_scene.window_size()
    export = ScreenshotExport(window, path, size, transparent)
    try:
        export.start()
    except BaseException:
        export._end("failed")
        raise
    return export
