"""The 3-D view: a pyvistaqt interactor showing the scene model, refined in a worker.

:class:`View3D` puts a :class:`~splineviz.render.scene_view.SceneView` (progressive mode)
on a ``QtInteractor``. While the camera moves, frames are reduced-resolution previews made
in the GUI thread within a time budget; the exact frames are made by a background thread
and shown when they still match the view. The camera is written back to the scene model
after every render, so sessions and standard views see where the user looks. Under the
cursor the view reports the world position and data value of the first isosurface hit.

The GUI thread never waits on that work (issue 26): a preview it cannot make at once (the
caster is busy or not built) leaves the last frame on screen, as does a resize of the view
(a layout change, a split: :meth:`SplineScene.view_resized`); a change of view or state
gives up the exact frame under way (its thread is left to end by itself) and starts the new
one; the worker shows what it makes on the way (a preview of a new model or data, coarser
images of a slow model). While an exact frame takes longer than :data:`OVERLAY_DELAY_MS`
the view says what it computes and what it shows meanwhile
(:class:`~splineviz.gui.overlay.ViewOverlay`, and the ``busy`` signal for the status
bar); :meth:`View3D.cancel_refine` (Esc) gives it up until the next change.
"""

from __future__ import annotations

import functools
import time

import numpy as np
from PySide6.QtCore import QEvent, QObject, QTimer, Signal

from splineviz.core.renderers import CELL_PROJECTION
from splineviz.gui.jobs import JobRunner
from splineviz.gui.overlay import ViewOverlay
from splineviz.model import Scene
from splineviz.render.overlay import describe
from splineviz.render.scene_view import SceneView

#: delay before exact frames are computed after the last change (debounce)
REFINE_DELAY_MS = 120
#: the single keys that act in the view (the help's "Keys in the 3-D view"): key ->
#: :meth:`View3D.standard_view` argument (None: all data from the current direction)
VIEW_KEYS = {"r": None, "v": "isometric"}
#: delay before the value under the cursor is looked up after the mouse stops
READOUT_DELAY_MS = 40
#: an exact frame under way for longer than this shows the overlay (shorter ones would
#: only flash it)
OVERLAY_DELAY_MS = 400
#: a coarser image of the exact surface replaces a finer preview of a cheaper model from
#: this resolution factor on (below it the preview shows more)
PARTIAL_OVER_PREVIEW = 0.5
#: OpenGL's GL_NEAREST (see :func:`_render_window`)
_GL_NEAREST = 0x2600


@functools.cache
def _interactor_class():
    """pyvistaqt's ``QtInteractor`` that draws a frame VTK has just rendered without
    rendering it again.

    pyvistaqt renders the whole scene in every paint, also in the paint that a finished
    render schedules to show itself (it cannot know whether pyvista changed the scene
    since). This app renders only through :meth:`View3D.request_render` (and VTK's own
    interactor and widgets, which render themselves), so that second render of each frame
    is the same picture again: 10-25 ms of every drag step of each view. A paint that no
    render scheduled (an expose, a resize) still renders.
    """
    from pyvistaqt import QtInteractor

    class Interactor(QtInteractor):
        _frame_ready = False

        def _cb_frame(self, obj, evt):
            # pyvistaqt schedules a paint unless the render ran inside one
            if not self._in_paint:
                self._frame_ready = True
            super()._cb_frame(obj, evt)

        def resizeGL(self, w, h):  # noqa: N802 (Qt naming)
            self._frame_ready = False  # the frame is of the old size
            super().resizeGL(w, h)

        def paintGL(self):  # noqa: N802
            ready, self._frame_ready = self._frame_ready, False
            if not ready or self._in_paint:
                super().paintGL()
                return
            self._in_paint = True  # pyvistaqt's paint then blits without rendering
            try:
                super().paintGL()
            finally:
                self._in_paint = False

    return Interactor


def _render_window():
    """The VTK render window of a view: pyvistaqt's, whose copy of each frame to the Qt
    widget is a plain copy.

    pyvistaqt blits VTK's frame into the widget's framebuffer with linear filtering. The
    two are always the same size, so nearest filtering gives the same pixels; but Mesa's
    software GL (llvmpipe) copies a same-size nearest blit directly, while a linear one
    goes through a shader it compiles for every new OpenGL context: the first paint of a
    new view (a split view's second one) took 74-206 ms for that compile alone, 0.1 ms
    with nearest filtering.
    """
    from vtkmodules.vtkRenderingOpenGL2 import vtkGenericOpenGLRenderWindow

    class RenderWindow(vtkGenericOpenGLRenderWindow):
        def BlitDisplayFramebuffer(self, *args):  # noqa: N802 (VTK naming)
            # (read index, source x, y, w, h, destination x, y, w, h, mask, filter)
            if len(args) == 11 and tuple(args[3:5]) == tuple(args[7:9]):
                args = (*args[:10], _GL_NEAREST)
            return super().BlitDisplayFramebuffer(*args)

    return RenderWindow()


class View3D(QObject):
    """The interactor widget and the refinement loop of one scene (see module docstring).

    Signals
    -------
    frame_rendered(float)
        Seconds the last render took.
    readout(str)
        What is under the cursor ("" when nothing).
    busy(str)
        A message while exact frames are computed ("" when done).
    interacting(bool)
        A camera drag (or an isovalue drag) began (True) or ended (False): a linked view
        shows previews meanwhile (:meth:`follow_interaction`).
    activated()
        A mouse button was pressed in the view (the user turned to it).

    Parameters
    ----------
    scene : Scene
    parent_widget : QWidget
    device : str or None
        OpenCL device preference.
    min_size : (width, height) or None
    side : {None, "left", "right"}
        The side of a split view this view is (see :class:`SceneView`).
    attach : bool
        Show the scene at once. False makes only the widget (cheap, nothing drawn yet);
        :meth:`attach` shows the scene later — a split view opens in steps this way, so
        that no step holds the GUI thread long (:class:`splineviz.gui.split.LinkedViews`).
    """

    frame_rendered = Signal(float)
    #: a frame made on the way by the refining worker (serial number of the job, layer,
    #: RenderedFrame), queued to the GUI thread
    _partial_frame = Signal(int, object, object)
    readout = Signal(str)
    busy = Signal(str)
    interacting = Signal(bool)
    activated = Signal()

    def __init__(self, scene: Scene, parent_widget, device=None, min_size=None,
                 side: str | None = None, attach: bool = True):
        super().__init__(parent_widget)
        self.scene = scene
        self.side = side
        self._device = device
        # no multisampling: on software GL (llvmpipe) 4x MSAA cost ~80 ms of a 1024x768
        # frame (113 -> 33 ms measured); the ray-cast image is one sample per pixel anyway
        self.plotter = _interactor_class()(parent_widget, auto_update=False,
                                           multi_samples=0, rw=_render_window())
        self.plotter.enable_anti_aliasing = None
        if min_size is not None:
            self.plotter.setMinimumSize(*min_size)
        # the scene's background from the first paint on, also before :meth:`attach`
        self.plotter.set_background(scene.view.background)
        #: the scene shown (None until :meth:`attach`)
        self.scene_view: SceneView | None = None
        self.spline_scene = None
        self._axes = None
        self._refiner = JobRunner(self)
        self._refiner.changed.connect(self._refine_ended)
        self._render_timer = QTimer(self)
        self._render_timer.setSingleShot(True)
        self._render_timer.setInterval(0)
        self._render_timer.timeout.connect(self._render_now)
        self._camera_timer = QTimer(self)
        self._camera_timer.setSingleShot(True)
        self._camera_timer.setInterval(0)
        self._camera_timer.timeout.connect(self._camera_to_model)
        # the view's shape reaches the model after the resize event: a camera framed again
        # (see Scene.aspect) is then drawn by an ordinary render, not by the render software
        # OpenGL makes inside the resize
        self._aspect = None
        self._aspect_timer = QTimer(self)
        self._aspect_timer.setSingleShot(True)
        self._aspect_timer.setInterval(0)
        self._aspect_timer.timeout.connect(self._aspect_to_model)
        self._syncing_camera = False
        self._refine_job = None
        #: counts the refine jobs started: frames on the way of an older one are dropped
        self._refine_serial = 0
        #: (view key, layer states) the running exact frames are for
        self._refine_key = None
        #: the key whose exact frames the user cancelled (Esc): not started again for it
        self._cancelled_key = None
        self._refine_again = False
        self._refine_held = False
        self._closed = False
        self._t_frame = None
        self.frame_times: list[float] = []
        self._refine_timer = QTimer(self)
        self._refine_timer.setSingleShot(True)
        self._refine_timer.setInterval(REFINE_DELAY_MS)
        self._refine_timer.timeout.connect(self._start_refine)
        self._readout_timer = QTimer(self)
        self._readout_timer.setSingleShot(True)
        self._readout_timer.setInterval(READOUT_DELAY_MS)
        self._readout_timer.timeout.connect(self._update_readout)
        self._overlay_timer = QTimer(self)
        self._overlay_timer.setSingleShot(True)
        self._overlay_timer.setInterval(OVERLAY_DELAY_MS)
        self._overlay_timer.timeout.connect(self._update_overlay)
        self._partial_frame.connect(self._show_partial)
        #: what is being computed, written over the view (see module docstring)
        self.overlay = ViewOverlay(self.plotter)
        self._cursor = None
        iren = self.plotter.iren.interactor
        iren.AddObserver("StartInteractionEvent", self._interaction_started)
        iren.AddObserver("EndInteractionEvent", self._interaction_ended)
        rw = self.plotter.render_window
        rw.AddObserver("StartEvent", self._frame_start)
        rw.AddObserver("EndEvent", self._frame_end)
        self._documented_keys_only()
        self.plotter.installEventFilter(self)
        self.plotter.setMouseTracking(True)
        if attach:
            self.attach()
            self.add_axes()

    def _documented_keys_only(self) -> None:
        """Only the keys the help lists (:data:`VIEW_KEYS`) act in the view.

        VTK's interactor style acts on single letters typed over the view (w: wireframe,
        s: surface, r: its own camera reset, 3: stereo, e/q: exit, f: fly to, p: pick, j/t:
        joystick) and pyvista adds its own (q, b, v, C, +, -): a user typing into the wrong
        place changed the picture or closed the view. Character events are stopped before
        the style sees them; pyvista's key table holds only the documented keys."""
        iren = self.plotter.iren
        iren.clear_key_event_callbacks()
        for key, view in VIEW_KEYS.items():
            iren.add_key_event(key, lambda view=view: self.standard_view(view))
        vtk_iren = iren.interactor

        def swallow(_obj, _event):
            vtk_iren.GetCommand(tag).SetAbortFlag(1)

        tag = vtk_iren.AddObserver("CharEvent", swallow, 1.0)

    def attach(self, grid: bool = True) -> None:
        """Show the scene: its objects become VTK props of this view (nothing is rendered
        here) and the view renders on every change of the scene. ``grid=False``: the axes
        grid follows with :meth:`add_grid` (see :class:`SceneView`)."""
        if self.scene_view is not None or self._closed:
            return
        self.scene_view = SceneView(self.scene, self.plotter, progressive=True,
                                    device=self._device, side=self.side, grid=grid)
        self.spline_scene = self.scene_view.spline_scene
        self.spline_scene.request_refine = self._schedule_refine
        self.spline_scene.request_render = self.request_render  # a linked colour range
        self.scene.changed.connect(self.request_render)

    def add_grid(self) -> None:
        """The axes grid of a view attached without it."""
        if self.scene_view is not None and not self._closed:
            self.scene_view.enable_grid()

    def add_axes(self) -> None:
        """The orientation axes in the corner (their first frame compiles their shaders:
        a split view adds them after its first picture)."""
        if self._axes is None and not self._closed:
            self._axes = self.plotter.add_axes()

    @property
    def attached(self) -> bool:
        return self.scene_view is not None

    @property
    def widget(self):
        return self.plotter

    # -- rendering -----------------------------------------------------------------------

    def request_render(self) -> None:
        """Render once control is back in the event loop: the changes made meanwhile (a
        camera's position, focal point and view up are set one after the other) are all
        in, and many changes cost one render."""
        # the camera written back after a frame changes the model: that needs no new render
        if not self._closed and not self._syncing_camera:
            self._render_timer.start()

    def _render_now(self) -> None:
        if not self._closed:
            self.plotter.render()

    def _camera_to_model(self) -> None:
        if self._closed or self.scene_view is None:
            return
        self._syncing_camera = True
        try:
            self.scene_view.camera_from_vtk()
        finally:
            self._syncing_camera = False

    def _aspect_to_model(self) -> None:
        if not self._closed and self._aspect is not None:
            self.scene.aspect = self._aspect

    def _frame_start(self, *_):
        self._t_frame = time.perf_counter()

    def _frame_end(self, *_):
        if self._t_frame is None or self._closed:
            return
        dt = time.perf_counter() - self._t_frame
        self.frame_times.append(dt)
        del self.frame_times[:-100]
        # the mouse moves VTK's camera: tell the model, but after this event is handled —
        # a render can happen while the model is in the middle of moving the camera itself
        self._camera_timer.start()
        self.frame_rendered.emit(dt)

    def _interaction_started(self, *_):
        if self.spline_scene is None:
            return
        self.spline_scene.set_interacting(True)
        self.interacting.emit(True)

    def _interaction_ended(self, *_):
        if self.spline_scene is None:
            return
        self.spline_scene.set_interacting(False)
        self._render_now()  # schedules the exact frames
        self.interacting.emit(False)

    def follow_interaction(self, on: bool) -> None:
        """A linked view's drag began or ended: previews only meanwhile (an exact frame
        started here would compete for the device with the previews of both views), the
        exact frames once it ended — after the camera it last showed reached this view."""
        if self._closed or self.spline_scene is None:
            return
        self.spline_scene.set_interacting(on)
        if not on:
            self.request_render()

    def begin_interaction(self) -> None:
        """A drag outside the view started (the isovalue slider): previews only, no exact
        frame is started — it would hold the ray caster the next preview needs."""
        self._interaction_started()

    def end_interaction(self) -> None:
        """The drag ended: the exact frames follow."""
        self._interaction_ended()

    def hold_refine(self, on: bool) -> None:
        """Hold the exact frames back (True) or let them be made (False). A view that opens
        in steps holds them until its last step: the worker that makes them builds the ray
        casters in Python, and its hold on the GIL lengthened the steps in the GUI thread."""
        self._refine_held = bool(on)
        if not on and not self._closed and self.spline_scene is not None \
                and self.spline_scene.needs_refine():
            self._refine_timer.start()

    def _schedule_refine(self) -> None:
        if self._closed or self._refine_held:
            return
        if self._cancelled_key is not None and self._key() == self._cancelled_key:
            return  # cancelled (Esc) until something changes
        self._refine_timer.start()

    def _key(self) -> tuple:
        """What the exact frames are for: the view and every layer's state."""
        return (self.spline_scene.view_state().key(),
                tuple(layer.state for layer in self.spline_scene.layers))

    def _start_refine(self) -> None:
        if self._closed or self.spline_scene is None or self._refine_held:
            return
        key = self._key()
        if key == self._cancelled_key:
            return
        self._cancelled_key = None
        if self._refine_job is not None:
            if key == self._refine_key:
                self._refine_again = True
                return
            # the frames under way are of another view or state: give them up without
            # waiting (their thread stops at its next step or is left to end by itself)
            self._refine_job.cancel()
            self._refine_job = None
        if not self.spline_scene.needs_refine():
            self._update_overlay()
            return
        view = self.spline_scene.view_state()
        self._refine_key = key
        self._refine_serial += 1
        self._refine_job = self._refiner.run(
            "rendering", self.spline_scene.refine, view,
            partial=functools.partial(self._partial_frame.emit, self._refine_serial),
            on_done=self._refined, on_error=self._failed)
        self._overlay_timer.start()
        self._update_overlay()

    def cancel_refine(self) -> None:
        """Give up the exact frames under way (Esc): the shown frames stay, marked in the
        overlay, and no exact frame is started until the view or a layer changes."""
        if self._closed or self.spline_scene is None:
            return
        job = self._refine_job
        if job is None and not self.spline_scene.needs_refine():
            return
        self._cancelled_key = self._key()
        self._refine_timer.stop()
        self._refine_again = False
        if job is not None:
            job.cancel()
            self._refine_job = None
        self._overlay_timer.stop()
        self._update_overlay()

    def _show_partial(self, serial: int, layer, rf) -> None:
        """A frame the worker made on the way: shown unless the view already shows a finer
        one of the same state (a cheaper model's, though, gives way to the exact model's
        from :data:`PARTIAL_OVER_PREVIEW` of the full resolution)."""
        if self._closed or self.spline_scene is None or self._refine_job is None \
                or serial != self._refine_serial:
            return
        if layer not in self.spline_scene.layers and layer not in \
                self.spline_scene.volume_layers:
            # removed (another file opened) while the signal was queued
            return
        shown = self.spline_scene.shown_frame(layer)
        if shown is not None and shown.state == rf.state and shown.view.key() == rf.view.key() \
                and shown.scale > rf.scale and not (shown.path == "preview" != rf.path
                                                    and rf.scale >= PARTIAL_OVER_PREVIEW):
            return
        if self.spline_scene.apply([(layer, rf)]):
            self._update_overlay()
            self._render_now()

    def _update_overlay(self) -> None:
        """The overlay and the status message: what the exact frames under way are of, and
        what is shown meanwhile (see :func:`splineviz.render.overlay.describe`)."""
        if self._closed or self.spline_scene is None:
            return
        job = self._refine_job
        cancelled = self._cancelled_key is not None
        lines = []
        if cancelled or (job is not None and not self._overlay_timer.isActive()):
            fraction = None if job is None else job.fraction
            for layer in self.spline_scene.layers:
                rf = self.spline_scene.shown_frame(layer)
                exact = rf is not None and rf.final and rf.state == layer.state
                stand_in = self.spline_scene.shows_stand_in(layer)
                if not layer.visible or (not stand_in and (
                        self.spline_scene.drawn_by_cells(layer) or (exact and (
                            not cancelled or rf.view.key() == self._cancelled_key[0])))):
                    continue
                lines.append(describe(layer, rf, fraction, cancelled, stand_in))
        if lines:
            status = lines[0].replace("\n", " - ")
        else:
            ss = self.spline_scene
            cells = any(layer.visible and ss.renderer_of(layer, probe=False) == CELL_PROJECTION
                        for layer in ss.layers)
            status = "" if job is None else (
                "drawing by cell projection..." if cells else "ray casting...")
        self.busy.emit(status)
        self.overlay.set_text("\n".join(lines))

    def _refined(self, results) -> None:
        if not self._closed and self.spline_scene.apply(results):
            self._render_now()

    def _failed(self, exc) -> None:
        from splineviz.gui.jobs import error_message

        self._refiner.error.emit(f"rendering failed: {error_message(exc)}")

    def _refine_ended(self) -> None:
        job = self._refine_job
        if self._closed:
            return
        if job is not None and job.active:
            self._update_overlay()  # its progress
            return
        self._refine_job = None
        self._overlay_timer.stop()
        self._update_overlay()
        if self._refine_again or self.spline_scene.needs_refine():
            self._refine_again = False
            self._schedule_refine()

    @property
    def computing(self) -> bool:
        """Whether exact frames are being computed (what :meth:`cancel_refine` stops)."""
        return self._refine_job is not None

    @property
    def refining(self) -> bool:
        return (self._refine_job is not None or self._refine_timer.isActive()
                or self._render_timer.isActive())

    def wait_for_refine(self, timeout_s: float = 120.0) -> None:
        """Process events until exact frames are shown (tests, scripted screenshots)."""
        from PySide6.QtWidgets import QApplication

        end = time.perf_counter() + timeout_s
        while time.perf_counter() < end:
            QApplication.processEvents()
            if self.spline_scene is None:
                time.sleep(0.005)
                continue
            if not self.refining and not self.spline_scene.needs_refine():
                return
            if not self.refining:
                self._start_refine()
            time.sleep(0.005)
        raise TimeoutError("exact frames did not arrive in time")

    # -- camera --------------------------------------------------------------------------

    def standard_view(self, name: str | None) -> None:
        """Look at all data from a standard direction (None: keep the direction)."""
        self.scene.frame(view=name)
        self.request_render()

    # -- value under the cursor ----------------------------------------------------------

    def eventFilter(self, obj, event):  # noqa: N802 (Qt naming)
        if obj is self.plotter:
            if event.type() == QEvent.Type.MouseButtonPress:
                self.activated.emit()
            elif event.type() == QEvent.Type.MouseMove and not event.buttons():
                p = event.position()
                self._cursor = (p.x(), p.y())
                self._readout_timer.start()
            elif event.type() == QEvent.Type.Resize:
                size = event.size()
                self._aspect = size.width() / max(size.height(), 1)
                self._aspect_timer.start()
                if self.spline_scene is not None:
                    self.spline_scene.view_resized()
            elif event.type() == QEvent.Type.Leave:
                self._cursor = None
                self.readout.emit("")
        return False

    def pick(self, x: float, y: float) -> dict | None:
        """The nearest isosurface hit at widget pixel (x, y): ``{"name", "position",
        "isovalue", "value"}`` (``value``: the data interpolated there), or None."""
        w, h = self.plotter.width(), self.plotter.height()
        if w < 1 or h < 1 or self.scene_view is None:
            return None
        best = None
        for node_id, layer in self.scene_view.layers.items():
            rf = self.spline_scene.shown_frame(layer)
            if rf is None or not layer.visible:
                continue
            fh, fw = rf.frame.hit.shape
            r, c = int(y / h * fh), int(x / w * fw)
            if not (0 <= r < fh and 0 <= c < fw) or not rf.frame.hit[r, c]:
                continue
            depth = float(rf.frame.depth[r, c])
            if best is None or depth < best[0]:
                # the colour-by value at the hit, when the surface is coloured by one
                colour = None if rf.scalars is None else float(rf.scalars[r, c])
                best = (depth, node_id, rf.frame.position[r, c], layer, colour)
        if best is None:
            return None
        _, node_id, pos, layer, colour = best
        if colour is not None and not np.isfinite(colour):
            colour = None
        return {"name": self.scene.get(node_id).name, "position": np.asarray(pos),
                "isovalue": layer.isovalue, "value": _trilinear(layer.volume, pos),
                "color_by": layer.color_by, "color_value": colour}

    def _update_readout(self) -> None:
        if self._cursor is None or self._closed:
            return
        hit = self.pick(*self._cursor)
        if hit is None:
            self.readout.emit("")
            return
        x, y, z = hit["position"]
        colour = "" if hit["color_value"] is None else \
            f"  {hit['color_by']} {hit['color_value']:.5g}"
        self.readout.emit(f"{hit['name']}: ({x:.4g}, {y:.4g}, {z:.4g})  "
                          f"data {hit['value']:.5g}  (iso {hit['isovalue']:.5g}){colour}")

    def close(self, widget: bool = True) -> None:
        """Stop following the scene and rendering; ``widget=False`` leaves the VTK widget
        open (its OpenGL resources are released when the caller closes it later)."""
        if not self._closed:
            self._closed = True
            self._refine_timer.stop()
            self._readout_timer.stop()
            self._camera_timer.stop()
            self._render_timer.stop()
            self._overlay_timer.stop()
            self._aspect_timer.stop()
            self._refiner.close()
            if self.scene_view is not None:
                self.scene.changed.disconnect(self.request_render)
                self.scene_view.close()
        if widget:
            self.plotter.close()

    def join(self, timeout_s: float) -> bool:
        """After :meth:`close`: wait for a frame still being ray cast (see
        :meth:`splineviz.gui.jobs.JobRunner.join`)."""
        return self._refiner.join(timeout_s)


def _trilinear(volume, point) -> float:
    """The samples of ``volume`` interpolated trilinearly at a world point."""
    from scipy.ndimage import map_coordinates

    from splineviz.core.frame import from_world

    idx = volume.world_to_index(from_world(volume, np.asarray(point, dtype=np.float64)[None]))
    # float32 output: the samples may be integers (map_coordinates returns their type)
    return float(map_coordinates(volume.data, idx.T, order=1, mode="nearest",
                                 output=np.float32)[0])
