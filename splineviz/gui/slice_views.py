"""The 2-D slice views: axial, coronal and sagittal views of a volume through its spline
model, with the exact isosurface contour, a linked crosshair, a probe and a ruler.

:class:`SliceViews` keeps the three :class:`SliceView` widgets and the 3-D view in step with
one :class:`~splineviz.model.slices.SliceViewNode`: a change of its crosshair moves every
slice and the slice planes' outline in the 3-D view; a change of the scene (isovalue,
model, colour, visibility, smoothing) redraws the slices. Slices are computed in one worker
thread (the spline is built there, which takes up to a second for the smooth models); the
GUI thread only shows the results, and only the newest request of each view is computed
(:mod:`splineviz.gui.slice_worker`). The slices run along the volume's own axes: for an
oblique scan (a volume with a direction) that is its own frame, where the crosshair, probe
and ruler live too; the 3-D view's picks are taken into it and the slice planes' outline
turned out of it (:mod:`splineviz.core.frame`). A chunked volume (OME-Zarr, bricked
stores) is sliced too: the worker reads the slab of samples around each slice, never the
whole volume; the window / level comes from the histogram the volume already has.

The layout and the crosshair are also kept in the scene's view
(:attr:`~splineviz.model.nodes.ViewNode.slice_layout`, ``slice_single``, ``crosshair``), so
sessions save and restore them: a change of either side is copied to the other. The
crosshair goes into the scene only once the slices were shown or it was placed there (a
scene that never used the slice views saves no crosshair); a crosshair from a session is
kept when its volume appears (moved into its box), a new volume otherwise centres it.

Mouse and keyboard in a slice view (the documented bindings, nothing else of VTK's):

* wheel: the next / previous slice (one grid step); Ctrl + wheel: zoom;
* left click or drag: move the crosshair there (the other views follow);
* Shift + left drag: a ruler (its length in world units, in the view and the status bar);
* right drag: window (left / right) and level (up / down); View > Layout resets them and
  chooses the colour map;
* moving the mouse: the probe (position, spline value and gradient) in the status bar;
* double click in the 3-D view: the crosshair moves to the isosurface point clicked;
  Shift + double click: one end of a ruler, then the other (shown in the 3-D view).
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QEvent, QObject, Qt, QTimer, Signal
from vtkmodules.vtkInteractionStyle import vtkInteractorStyleUser

from splineviz.core import slice_sampling
from splineviz.core.frame import from_world
from splineviz.core.units import format_quantity
from splineviz.core.volume import Volume
from splineviz.gui.slice_worker import SliceRequest, SliceResult, SliceWorker
from splineviz.gui.view import _interactor_class, _render_window
from splineviz.model import IsosurfaceNode, Scene, VolumeNode
from splineviz.model.slices import AXES, SliceViewNode
from splineviz.render.slice_view import SlicePlanesMarker, SliceScene

#: window change per pixel of a right drag, as a share of the window
WINDOW_PER_PIXEL = 0.005
#: zoom per wheel notch with Ctrl held
ZOOM_STEP = 1.15
#: background of the slice views
BACKGROUND = (0.0, 0.0, 0.0)


def fit(state: SliceViewNode, volume) -> None:
    """Crosshair at the volume's centre sample, window on its 2-98 % values: the node's
    :meth:`~splineviz.model.slices.SliceViewNode.fit` for samples in memory; for a chunked
    volume (not read here, in the GUI thread) the percentiles of its cached histogram
    (:func:`splineviz.model.summaries.cached_histogram`, made when it was opened)."""
    if isinstance(volume, Volume):
        state.fit(volume)
        return
    from splineviz.model.summaries import cached_histogram

    log_counts, edges = cached_histogram(volume)
    below = np.concatenate([[0.0], np.cumsum(np.expm1(log_counts))])
    lo, hi = np.interp([0.02 * below[-1], 0.98 * below[-1]], below, edges)
    if not hi > lo:
        lo, hi = volume.finite_range
    if not hi > lo:
        hi = lo + 1.0
    centre = np.asarray(volume.origin) + (np.asarray(volume.shape) // 2) * \
        np.asarray(volume.spacing)
    state.update(crosshair=tuple(map(float, centre)), window=float(hi - lo),
                 level=float(0.5 * (lo + hi)))


class SliceView(QObject):
    """One slice view: a VTK interactor widget showing a :class:`SliceScene`.

    Parameters
    ----------
    owner : SliceViews
    name : "axial", "coronal" or "sagittal"
    parent_widget : QWidget
    """

    def __init__(self, owner: SliceViews, name: str, parent_widget=None):
        super().__init__(parent_widget)
        self.owner = owner
        self.name = name
        self.plotter = _interactor_class()(parent_widget, auto_update=False,
                                           multi_samples=0, rw=_render_window())
        self.plotter.enable_anti_aliasing = None
        self.plotter.setObjectName(f"slice-{name}")
        self.plotter.setMinimumSize(120, 120)
        self.plotter.set_background(BACKGROUND)
        self.scene = SliceScene(self.plotter.renderer, name)
        #: the result shown (None until the first one arrives)
        self.result: SliceResult | None = None
        self._drag: str | None = None
        self._drag_from = None
        self._window_from = (1.0, 0.0)
        self._ruler_start = None
        self._framed = False
        self._closed = False
        self._wheel_ctrl = False
        # VTK's and pyvista's bindings (camera rotation; single letters: w wireframe, r a
        # perspective camera reset, e/q exit, ...) mean nothing here: a plain style, no
        # pyvista key table and character events stopped before the style sees them
        self.plotter.iren.clear_key_event_callbacks()
        iren = self.plotter.iren.interactor
        iren.SetInteractorStyle(vtkInteractorStyleUser())

        def swallow(_obj, _event):
            iren.GetCommand(tag).SetAbortFlag(1)

        tag = iren.AddObserver("CharEvent", swallow, 1.0)
        for event, slot in (("MouseWheelForwardEvent", lambda *_: self._wheel(1)),
                            ("MouseWheelBackwardEvent", lambda *_: self._wheel(-1)),
                            ("LeftButtonPressEvent", self._left_press),
                            ("LeftButtonReleaseEvent", self._release),
                            ("RightButtonPressEvent", self._right_press),
                            ("RightButtonReleaseEvent", self._release),
                            ("MouseMoveEvent", self._move)):
            iren.AddObserver(event, slot)
        self.plotter.installEventFilter(self)
        self.plotter.setMouseTracking(True)

    @property
    def widget(self):
        return self.plotter

    @property
    def position(self) -> float:
        return self.owner.state.position(self.name)

    def request_render(self) -> None:
        """Render in a later turn of the event loop (:meth:`SliceViews.queue_render`)."""
        if not self._closed:
            self.owner.queue_render(self)

    def _render_now(self) -> None:
        if not self._closed and self.plotter.isVisible():
            self.plotter.render()

    def reset_camera(self) -> None:
        w, h = self.plotter.width(), self.plotter.height()
        self.scene.reset_camera(w / max(h, 1))
        self.request_render()

    def show_result(self, result: SliceResult) -> None:
        self.result = result
        self.scene.set_image(result.grid, result.values)
        self.scene.set_contours(result.curves, result.colors)
        if not self._framed:
            self._framed = True
            self.reset_camera()
        self.request_render()

    # -- the mouse (VTK interactor observers) -------------------------------------------

    def _event_plane(self) -> np.ndarray:
        x, y = self.plotter.iren.interactor.GetEventPosition()
        return self.scene.display_to_plane(x, y)

    def _event_world(self) -> np.ndarray:
        return self.scene.to_world(self._event_plane(), self.position)

    def _wheel(self, steps: int) -> None:
        # (VTK's Qt interactor passes no modifiers with a wheel event: the Qt event's, kept
        # by :meth:`eventFilter`, tell a zoom)
        if self._wheel_ctrl:
            self.scene.zoom(ZOOM_STEP ** steps)
            self.request_render()
            return
        self.owner.scroll(self.name, steps)

    def _left_press(self, *_):
        if self.plotter.iren.interactor.GetShiftKey():
            self._drag = "ruler"
            self._ruler_start = self._event_world()
            self.owner.set_ruler(self._ruler_start, self._ruler_start, self.name)
            return
        self._drag = "crosshair"
        self.owner.move_crosshair(self._event_world())

    def _right_press(self, *_):
        self._drag = "window"
        self._drag_from = np.asarray(self.plotter.iren.interactor.GetEventPosition(), float)
        st = self.owner.state
        self._window_from = (st.window, st.level)

    def _release(self, *_):
        self._drag = None

    def _move(self, *_):
        if self._drag == "crosshair":
            self.owner.move_crosshair(self._event_world())
        elif self._drag == "ruler":
            self.owner.set_ruler(self._ruler_start, self._event_world(), self.name)
        elif self._drag == "window":
            d = np.asarray(self.plotter.iren.interactor.GetEventPosition(), float) \
                - self._drag_from
            window, level = self._window_from
            self.owner.state.update(window=window * float(np.exp(WINDOW_PER_PIXEL * d[0])),
                                    level=level + window * WINDOW_PER_PIXEL * d[1])
        else:
            self.owner.probe(self._event_world())

    def eventFilter(self, obj, event):  # noqa: N802 (Qt naming)
        if obj is self.plotter:
            if event.type() == QEvent.Type.Wheel:
                self._wheel_ctrl = bool(event.modifiers() & Qt.KeyboardModifier.ControlModifier)
            elif event.type() == QEvent.Type.Resize:
                self.reset_camera()
            elif event.type() == QEvent.Type.Leave:
                self.owner.readout.emit("")
        return False

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.plotter.close()


class SliceViews(QObject):
    """The slice views of a scene and their link to the 3-D view (see module docstring).

    Parameters
    ----------
    scene : Scene
    view3d : splineviz.gui.view.View3D or None
        The 3-D view that shows the slice planes and takes double clicks.
    parent : QObject, optional

    Signals
    -------
    readout(str)
        The probe's or the ruler's line for the status bar ("" when none).
    error(str)
    """

    readout = Signal(str)
    error = Signal(str)

    def __init__(self, scene: Scene, view3d=None, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.view3d = view3d
        #: the 3-D views the slice planes are drawn in (the first, and a split's second)
        self._views3d = [view3d] if view3d is not None else []
        self.state = SliceViewNode(id="slices")
        self.views: dict[str, SliceView] = {}
        self.worker = SliceWorker(self)
        self.worker.computed.connect(self._computed)
        self.worker.failed.connect(self.error.emit)
        self._volume: VolumeNode | None = None
        self._signature = None
        self._requested: dict[str, tuple] = {}
        self._closed = False
        #: the ruler's ends (world) while one is shown, and the view it was drawn in
        self.ruler: tuple | None = None
        self._ruler_start = None
        self._marker_key = None
        self.marker = SlicePlanesMarker(view3d.plotter.renderer) if view3d is not None \
            else None
        if view3d is not None:
            view3d.plotter.installEventFilter(self)
        self._refresh_timer = QTimer(self)
        self._refresh_timer.setSingleShot(True)
        self._refresh_timer.setInterval(0)
        self._refresh_timer.timeout.connect(self.refresh)
        #: views waiting to be rendered, one per turn of the event loop
        self._to_render: list[SliceView] = []
        self._render_timer = QTimer(self)
        self._render_timer.setSingleShot(True)
        self._render_timer.setInterval(0)
        self._render_timer.timeout.connect(self._render_next)
        self.state.events.crosshair.connect(self._crosshair_changed)
        self.state.events.layout.connect(self._layout_changed)
        self.state.events.single.connect(self._layout_changed)
        for name in ("window", "level", "color_map"):
            getattr(self.state.events, name).connect(self._window_changed)
        self.state.events.volume_id.connect(lambda *_: self._schedule())
        scene.changed.connect(self._schedule)
        scene.selection.connect(self._schedule)
        #: True while the state and the scene's view are copied into each other
        self._syncing = False
        self.state.events.layout.connect(self._to_scene)
        self.state.events.single.connect(self._to_scene)
        for name in ("slice_layout", "slice_single", "crosshair"):
            getattr(scene.view.events, name).connect(self._from_scene)
        scene.removed.connect(self._node_removed)
        self._from_scene()

    # -- views ---------------------------------------------------------------------------

    def queue_render(self, view: SliceView) -> None:
        """Render ``view`` soon. A crosshair move changes every view: rendered one per turn
        of the event loop, not all in one (10-40 ms each on software GL, under load up to
        90), so input and the other views' frames get in between."""
        if view not in self._to_render:
            self._to_render.append(view)
        if not self._closed and not self._render_timer.isActive():
            self._render_timer.start()

    def _render_next(self) -> None:
        if self._to_render and not self._closed:
            self._to_render.pop(0)._render_now()
        if self._to_render and not self._closed:
            self._render_timer.start()

    @property
    def rendering(self) -> bool:
        """Whether views are waiting to be rendered."""
        return bool(self._to_render)

    def make_view(self, name: str, parent_widget=None) -> SliceView:
        """The view of slice ``name`` (made on first use)."""
        if name not in self.views:
            view = SliceView(self, name, parent_widget)
            self.views[name] = view
            if self._volume is not None:
                view.scene.set_extent(self._volume.active.bounds)
                view.scene.set_crosshair(self.state.crosshair)
            self._window_changed()
            self._schedule()
        return self.views[name]

    @property
    def volume(self) -> VolumeNode | None:
        """The volume the slices show."""
        return self._volume

    def _pick_volume(self) -> VolumeNode | None:
        vid = self.state.volume_id
        if vid is not None and vid in self.scene:
            node = self.scene.get(vid)
            if isinstance(node, VolumeNode) and node.active is not None:
                return node
        sel = self.scene.selected
        if isinstance(sel, IsosurfaceNode):
            sel = self.scene.volume_of(sel)
        if isinstance(sel, VolumeNode) and sel.active is not None:
            return sel
        for node in self.scene.volumes:
            if node.active is not None:
                return node
        return None

    def _isosurfaces(self, volume: VolumeNode) -> list[IsosurfaceNode]:
        return [n for n in self.scene.isosurfaces_of(volume) if n.visible]

    # -- following the scene -------------------------------------------------------------

    def _schedule(self, *_):
        if not self._closed:
            self._refresh_timer.start()

    def refresh(self) -> None:
        """Recompute the slices when what they show changed (volume, models, isovalues,
        colours); move the crosshair into a new volume."""
        if self._closed:
            return
        volume = self._pick_volume()
        if volume is not self._volume:
            self._volume = volume
            self._signature = None
            self.ruler = self._ruler_start = None
            if self.marker is not None:
                self.marker.set_ruler(None, None)
            if volume is not None:
                # the new box first: the crosshair's lines span it (drawn with the old
                # box, they were short ticks after a file or session of another size)
                for view in self.views.values():
                    view.scene.set_extent(volume.active.bounds)
                    view.scene.set_ruler(None, None)
                    view._framed = False
                saved = self.scene.view.crosshair
                self._syncing = True
                try:
                    fit(self.state, volume.active)
                    if saved is not None:  # restored with a session
                        self.state.move_to(saved, volume.active)
                finally:
                    self._syncing = False
                for view in self.views.values():  # also when the point stayed the same
                    view.scene.set_crosshair(self.state.crosshair)
                    view.request_render()
                # placed by the app, not an edit: no "unsaved changes" after a session load
                modified = self.scene.modified
                self._to_scene()
                self.scene.modified = modified
        if volume is None:
            self._update_marker()
            return
        isos = self._isosurfaces(volume)
        signature = (id(volume.active),
                     tuple((n.model, tuple(sorted(n.model_options().items())),
                            float(n.isovalue), tuple(n.color)) for n in isos))
        if signature != self._signature:
            self._signature = signature
            self._requested.clear()
        self._request_all()
        self._update_marker()

    def _model(self) -> tuple[str, tuple]:
        """The spline model of the image: the first visible isosurface's (else the one a
        first isosurface would get, :meth:`~splineviz.model.Scene.first_model`)."""
        isos = self._isosurfaces(self._volume) if self._volume is not None else []
        if isos:
            return isos[0].model, tuple(sorted(isos[0].model_options().items()))
        return self.scene.first_model(), ()

    def _request_all(self) -> None:
        if self._volume is None:
            return
        model, options = self._model()
        isos = tuple((n.model, tuple(sorted(n.model_options().items())), float(n.isovalue),
                      tuple(n.color)) for n in self._isosurfaces(self._volume))
        for name in self.state.shown:
            view = self.views.get(name)
            if view is None:
                continue
            pos = self.state.position(name)
            key = (self._signature, pos)
            if self._requested.get(name) == key:
                continue
            self._requested[name] = key
            self.worker.request(name, SliceRequest(self._volume.active, model, options,
                                                   AXES[name], pos, isos))

    def _computed(self, name: str, result: SliceResult) -> None:
        view = self.views.get(name)
        if view is not None and not self._closed:
            view.show_result(result)

    # -- the state's events --------------------------------------------------------------

    def _crosshair_changed(self, point) -> None:
        self._to_scene()
        for view in self.views.values():
            view.scene.set_crosshair(point)
            view.request_render()
        if self.ruler is not None:
            self._show_ruler()
        self._request_all()
        self._update_marker()

    def _layout_changed(self, *_):
        self._request_all()
        self._update_marker()

    def _window_changed(self, *_):
        st = self.state
        for view in self.views.values():
            view.scene.set_window_level(st.window, st.level, st.color_map)
            view.request_render()

    def _update_marker(self) -> None:
        """The slice planes in the 3-D view; it renders again only when they changed (the
        scene's changes that reach :meth:`refresh` include every camera move)."""
        if self.marker is None:
            return
        shown = self.state.shown if self._volume is not None else ()
        bounds = self._volume.active.bounds if self._volume is not None else None
        frame = self._volume.active if self._volume is not None else None
        key = (bounds, self.state.crosshair, shown, id(frame))
        if key == self._marker_key:
            return
        self._marker_key = key
        # the slices work in the volume's own frame; an oblique scan's are drawn turned
        self.marker.frame = frame
        self.marker.update(bounds if bounds is not None else ((0, 0),) * 3,
                           self.state.crosshair, shown)
        self._render_3d()

    def add_view3d(self, view) -> None:
        """Show the slice planes and the ruler in another 3-D view too (the right half of
        a split view, :class:`splineviz.gui.split.LinkedViews`)."""
        if self.marker is not None and view not in self._views3d:
            self._views3d.append(view)
            self.marker.add_renderer(view.plotter.renderer)
            view.request_render()

    def remove_view3d(self, view) -> None:
        """Stop drawing in a 3-D view that closes."""
        if view in self._views3d and view is not self.view3d:
            self._views3d.remove(view)
            self.marker.remove_renderer(view.plotter.renderer)

    def _render_3d(self) -> None:
        for view in self._views3d:
            view.request_render()

    # -- the scene's view: what sessions keep ---------------------------------------------

    def _to_scene(self, *_):
        """Copy the layout and the crosshair into the scene's view (see module docstring)."""
        if self._syncing or self._closed:
            return
        st, view = self.state, self.scene.view
        values = {"slice_layout": st.layout, "slice_single": st.single}
        if self._volume is not None and (st.layout != "3d" or view.crosshair is not None):
            values["crosshair"] = tuple(st.crosshair)
        changed = {k: v for k, v in values.items() if getattr(view, k) != v}
        if changed:
            self._syncing = True
            try:
                view.update(changed)
            finally:
                self._syncing = False

    def _from_scene(self, *_):
        """The scene's view changed (a session was loaded): the layout and the crosshair
        follow it (a crosshair for a volume not shown yet waits for :meth:`refresh`)."""
        if self._syncing or self._closed:
            return
        view = self.scene.view
        self._syncing = True
        try:
            self.state.update(layout=view.slice_layout, single=view.slice_single)
            if (view.crosshair is not None and self._volume is not None
                    and self._volume.id in self.scene
                    and self.scene.get(self._volume.id) is self._volume):
                self.state.move_to(view.crosshair, self._volume.active)
        finally:
            self._syncing = False

    def _node_removed(self, node) -> None:
        """The volume shown left the scene: its crosshair means nothing for the next one."""
        if node is self._volume and self.scene.view.crosshair is not None \
                and not self._closed:
            self._syncing = True
            try:
                self.scene.view.crosshair = None
            finally:
                self._syncing = False

    # -- what the views do ---------------------------------------------------------------

    def scroll(self, name: str, steps: int) -> None:
        """Move slice ``name`` by ``steps`` grid steps."""
        if self._volume is not None:
            self.state.scroll(name, steps, self._volume.active)

    def reset_window(self) -> None:
        """Window / level from the shown volume's samples (the crosshair stays)."""
        if self._volume is not None:
            point = self.state.crosshair
            fit(self.state, self._volume.active)
            self.state.crosshair = point

    def move_crosshair(self, point) -> None:
        """Move the crosshair to a world point (kept in the volume's box)."""
        if self._volume is not None:
            self.state.move_to(point, self._volume.active)

    def probe(self, point) -> slice_sampling.Probe | None:
        """Read the spline at a world point into the status bar (None before the image's
        spline is built: the probe never builds one in the GUI thread)."""
        if self._volume is None:
            return None
        model, options = self._model()
        spline = self.worker.spline(self._volume.active, model, options, point)
        if spline is None:
            return None
        lo, hi = np.asarray(spline.bounds, dtype=np.float64).T
        if np.any(point < lo) or np.any(point > hi):
            self.readout.emit("")
            return None
        result = slice_sampling.probe(spline, point)
        self.readout.emit(f"{model}: {result.describe(self.unit)}")
        return result

    def set_ruler(self, a, b, name: str) -> float:
        """Show a ruler from ``a`` to ``b`` (world) in the view ``name`` (a slice, or
        ``"3d"``) and in the 3-D view; returns its length (world units, :attr:`unit`)."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        self.ruler = (a, b, name)
        self._show_ruler()
        if self.marker is not None:
            self.marker.set_ruler(a, b, self.unit)
            self._render_3d()
        length = float(np.linalg.norm(b - a))
        unit = f" {self.unit}" if self.unit else ""
        self.readout.emit(f"ruler {format_quantity(length, self.unit, digits=5)} from "
                          f"({', '.join(f'{c:.4g}' for c in a)}) to "
                          f"({', '.join(f'{c:.4g}' for c in b)}){unit}")
        return length

    @property
    def unit(self) -> str:
        """The unit of the shown volume's world coordinates, ``""`` when its file did not
        say (see :mod:`splineviz.core.units`)."""
        return self._volume.data.unit if self._volume is not None else ""

    def _show_ruler(self) -> None:
        """The ruler in the slice view it was drawn in, while that view shows its plane."""
        a, b, name = self.ruler if self.ruler is not None else (None, None, None)
        for other, view in self.views.items():
            here = other == name and abs(self.state.position(other) - a[AXES[other]]) <= \
                1e-9 * max(1.0, abs(a[AXES[other]]))
            view.scene.set_ruler(*((a, b) if here else (None, None)), self.unit)
            view.request_render()

    def _ruler_point_3d(self, point) -> None:
        """Shift + double click in the 3-D view: the first end of a new ruler, then its
        second end."""
        if self._ruler_start is None:
            self._ruler_start = np.asarray(point, float)
            self.set_ruler(self._ruler_start, self._ruler_start, "3d")
            self.readout.emit("ruler from ({}); Shift + double click its other end".format(
                ", ".join(f"{c:.4g}" for c in self._ruler_start)))
        else:
            start, self._ruler_start = self._ruler_start, None
            self.set_ruler(start, point, "3d")

    def eventFilter(self, obj, event):  # noqa: N802 (Qt naming)
        # a double click on an isosurface in the 3-D view moves the crosshair there; with
        # Shift it places an end of the ruler
        if (self.view3d is not None and obj is self.view3d.plotter
                and event.type() == QEvent.Type.MouseButtonDblClick
                and event.button() == Qt.MouseButton.LeftButton):
            p = event.position()
            hit = self.view3d.pick(p.x(), p.y())
            if hit is None or self._volume is None:
                return False
            # the hit is in world, the slices in the volume's own frame (an oblique scan)
            point = from_world(self._volume.active, hit["position"])
            if event.modifiers() & Qt.KeyboardModifier.ShiftModifier:
                self._ruler_point_3d(point)
            else:
                self.move_crosshair(point)
        return False

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._refresh_timer.stop()
        self._render_timer.stop()
        self._to_render.clear()
        self.scene.changed.disconnect(self._schedule)
        self.scene.selection.disconnect(self._schedule)
        self.scene.removed.disconnect(self._node_removed)
        for name in ("slice_layout", "slice_single", "crosshair"):
            getattr(self.scene.view.events, name).disconnect(self._from_scene)
        if self.view3d is not None:
            self.view3d.plotter.removeEventFilter(self)
        self.worker.close()
        for view in self.views.values():
            view.close()
