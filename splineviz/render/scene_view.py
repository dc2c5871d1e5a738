"""The one path from a scene model to a picture: :class:`SceneView` and :func:`render_scene`.

A :class:`SceneView` shows a :class:`splineviz.model.Scene` in a pyvista plotter (the GUI's
``QtInteractor`` or an off-screen ``pyvista.Plotter``). It subscribes to the scene's events
and keeps a :class:`~splineviz.render.scene.SplineScene` in step through one
:class:`NodeView` per node, of the class :data:`VIEW_CLASSES` names for the node's type: an
:class:`~splineviz.render.isosurface.IsosurfaceLayer` per isosurface node (reading the
node), an outline per volume, points and meshes as VTK props, clip planes per volume or
scene-wide, section curves; and the camera and the view settings (background or gradient,
axes grid with world units, the time of time-varying volumes in the upper-left corner). It
holds no state of its own that a session would need.

The window, ``splineviz FILE --screenshot``, ``splineviz render`` and session rendering all
draw through this class, so a session renders the same headless as in the window.
"""

from __future__ import annotations

import weakref

import numpy as np

from splineviz.core.frame import to_world
from splineviz.core.volume import Volume
from splineviz.model import (
    ClipPlaneNode,
    IsosurfaceNode,
    MeshNode,
    Node,
    PointsNode,
    Scene,
    SectionNode,
    VolumeNode,
)
from splineviz.render.colour_ranges import ColourRangeLink
from splineviz.render.isosurface import IsosurfaceLayer
from splineviz.render.scene import SplineScene
from splineviz.render.volume_layer import VolumeLayer

#: colour of volume outlines and of the axes grid labels
OUTLINE_COLOR = (0.6, 0.6, 0.65)
#: camera fields copied between the model and VTK
_CAMERA_FIELDS = ("position", "focal_point", "view_up", "view_angle")


_LINKS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def colour_range_link(scene: Scene) -> ColourRangeLink:
    """The :class:`~splineviz.render.colour_ranges.ColourRangeLink` of ``scene``'s views: the two
    halves of a split view colour a surface over one range (``link.set_enabled(False)``
    unlinks them)."""
    link = _LINKS.get(scene)
    if link is None:
        link = _LINKS[scene] = ColourRangeLink()
    return link


class SceneView:
    """Show ``scene`` in ``plotter`` and follow its changes (see module docstring).

    Parameters
    ----------
    scene : splineviz.model.Scene
    plotter : pyvista.Plotter or pyvistaqt.QtInteractor
    progressive : bool
        Previews while the camera moves, exact frames by :attr:`SplineScene.request_refine`
        (the GUI); False renders exact frames synchronously (scripts, screenshots).
    device : str or None
        OpenCL device preference of the ray casters.
    side : {None, "left", "right"}
        Which of the two views of a split scene this is (:attr:`splineviz.model.ViewNode.split`):
        it leaves out the objects shown only on the other side. None: every object.
    grid : bool
        Show the axes grid (the scene's ``show_scale``) from the start. False leaves it out
        until :meth:`enable_grid`: the first frame of its labels in a new OpenGL context
        takes 40-85 ms, and a view that opens while the window runs draws it one turn of
        the event loop after its first picture.
    """

    def __init__(self, scene: Scene, plotter, progressive: bool = False, device=None,
                 side: str | None = None, grid: bool = True,
                 live_volume_rendering: bool | None = None):
        self.scene = scene
        #: volume renderings as layers of the view (:class:`VolumeLayer`); off, they are
        #: composited over the finished picture (render_scene)
        self.live_volume_rendering = progressive if live_volume_rendering is None \
            else bool(live_volume_rendering)
        #: volume node id -> its volume rendering layer (while on)
        self.volume_layers: dict[str, VolumeLayer] = {}
        self.plotter = plotter
        self.device = device
        self.side = side
        self.spline_scene = SplineScene(plotter, progressive=progressive)
        self.spline_scene.range_link = colour_range_link(scene)
        #: node id -> what this view shows of it (a :data:`VIEW_CLASSES` object)
        self.views: dict[str, NodeView] = {}
        #: isosurface node id -> its layer
        self.layers: dict[str, IsosurfaceLayer] = {}
        self._props: dict[str, str] = {}  # node id -> prop name in the SplineScene
        self._handlers: dict[str, object] = {}
        self._grid = None
        self._grid_size: tuple[int, int] = (0, 0)
        self._resize_observer = None
        self._grid_enabled = bool(grid)
        self._time_label = None
        self._camera_lock = False
        scene.inserted.connect(self._inserted)
        scene.removed.connect(self._removed)
        scene.camera.events.connect(self._camera_changed)
        scene.view.events.connect(self._view_changed)
        scene.time_changed.connect(self._update_time_label)
        for node in scene:
            self._inserted(node)
        self._view_changed()
        self.camera_to_vtk()

    # -- nodes ---------------------------------------------------------------------------

    def _inserted(self, node: Node) -> None:
        self.views[node.id] = view_class(node)(self, node)

        def changed(info, node=node):
            self._node_changed(node, info.signal.name)

        self._handlers[node.id] = changed
        node.events.connect(changed)
        if isinstance(node, VolumeNode) and node.series is not None:
            self._update_time_label()

    def _removed(self, node: Node) -> None:
        handler = self._handlers.pop(node.id, None)
        if handler is not None:
            node.events.disconnect(handler)
        view = self.views.pop(node.id, None)
        if view is not None:
            view.remove()
        self._update_grid()
        if self._time_label is not None:
            self._update_time_label()

    def _node_changed(self, node: Node, what: str) -> None:
        view = self.views.get(node.id)
        if view is not None:
            view.changed(what)
        self._dependents_changed(node, what)
        if isinstance(node, VolumeNode) and what in ("series", "time_index", "time_offset"):
            self._update_time_label()

    def _dependents_changed(self, node: Node, what: str) -> None:
        """What shows other nodes through ``node``: a volume's isosurfaces, the surfaces
        coloured by their distance to an isosurface, the sections of either."""
        if isinstance(node, VolumeNode):
            for iso in self.scene.isosurfaces_of(node):
                layer = self.layers.get(iso.id)
                if layer is None:
                    continue
                if what in ("data", "smoothed", "sigma"):
                    layer.set_volume(node.active)
                elif what in ("visible", "show_outline"):
                    layer.set_visible(self._layer_visible(iso))
        if isinstance(node, IsosurfaceNode) and what in ("isovalue", "model", "k"):
            for other in self.scene.isosurfaces:
                if other.color_isosurface_id == node.id and other.id in self.views:
                    self.views[other.id].colour_by()
        # the curves follow their inputs: a new isovalue, model, plane position or data
        if what in ("isovalue", "model", "k", "origin", "normal", "data", "smoothed", "sigma"):
            for sec in self.scene.sections:
                volumes = [self.scene.volume_of(self.scene.get(i)).id for i in sec.inputs
                           if isinstance(self.scene.get(i), IsosurfaceNode)]
                if (node.id in sec.inputs or node.id in volumes) and sec.id in self.views:
                    self.views[sec.id].draw(recompute=True)

    def _layer_visible(self, node: IsosurfaceNode) -> bool:
        return (node.visible and self.scene.volume_of(node).visible
                and self.scene.shows(node, self.side))

    def _prop_visibility(self, node: Node) -> None:
        """Show or hide the prop of a point cloud, mesh or section (visible and on this
        view's side)."""
        name = self._props.get(node.id)
        if name is not None and name in self.spline_scene.props:
            self.spline_scene.set_prop_visible(
                name, node.visible and self.scene.shows(node, self.side))

    def _sides_changed(self) -> None:
        """The split was turned on or off: every object's visibility in this view again."""
        for view in self.views.values():
            view.sides_changed()

    # -- clip planes ---------------------------------------------------------------------

    def _volume_planes(self, volume_id: str) -> list:
        return [p.as_pair() for p in self.scene.clip_planes
                if p.enabled and p.volume_id == volume_id]

    def _update_planes(self) -> None:
        """Scene-wide planes go to the view, a volume's planes to its layers."""
        self.spline_scene.set_clip_planes([p.as_pair() for p in self.scene.clip_planes
                                           if p.enabled and p.volume_id is None])
        for iso in self.scene.isosurfaces:
            layer = self.layers.get(iso.id)  # None while the view replays the scene
            if layer is not None:
                layer.set_clip_planes(self._volume_planes(iso.volume_id))
        for vid, vlayer in self.volume_layers.items():
            vlayer.set_clip_planes(self._volume_planes(vid))

    # -- camera and view -----------------------------------------------------------------

    def _camera_changed(self, *_args) -> None:
        if not self._camera_lock:
            self.camera_to_vtk()

    def camera_to_vtk(self) -> None:
        """Place VTK's camera where the model's camera is."""
        cam = self.scene.camera
        vcam = self.plotter.renderer.GetActiveCamera()
        vcam.SetPosition(cam.position)
        vcam.SetFocalPoint(cam.focal_point)
        vcam.SetViewUp(cam.view_up)
        vcam.SetViewAngle(cam.view_angle)
        vcam.SetParallelScale(cam.parallel_scale)
        # the ray caster is perspective only (see render.scene.view_state_of)
        vcam.ParallelProjectionOff()
        self.plotter.camera_set = True  # else pyvista resets the camera on the first render

    def camera_from_vtk(self) -> None:
        """Copy VTK's camera (moved by the mouse) into the model, without echo."""
        vcam = self.plotter.renderer.GetActiveCamera()
        values = {"position": vcam.GetPosition(), "focal_point": vcam.GetFocalPoint(),
                  "view_up": vcam.GetViewUp(), "view_angle": vcam.GetViewAngle()}
        cam = self.scene.camera
        changed = {k: tuple(map(float, v)) if isinstance(v, tuple) else float(v)
                   for k, v in values.items()}
        changed = {k: v for k, v in changed.items() if getattr(cam, k) != v}
        if not changed:
            return
        self._camera_lock = True
        try:
            cam.update(changed)
        finally:
            self._camera_lock = False

    def _view_changed(self, info=None) -> None:
        if info is not None and info.signal.name == "split":
            self._sides_changed()
            return
        view = self.scene.view
        if view.background2 is None:
            self.plotter.set_background(view.background)
        else:  # a gradient, bottom to top, as ParaView's
            self.plotter.set_background(view.background, top=view.background2)
        self._update_grid()
        self._update_time_label()

    def enable_grid(self) -> None:
        """Show the axes grid from now on (see the ``grid`` parameter)."""
        self._grid_enabled = True
        self._update_grid()

    def rebuild_grid(self) -> None:
        """Make the axes grid anew: its labels are laid out as in a new view (a grid kept
        across camera moves places them from its earlier layouts)."""
        if self._grid is None:
            return
        self.plotter.remove_actor(self._grid, reset_camera=False, render=False)
        self._grid = None
        self._update_grid()

    def _update_grid(self) -> None:
        """An axes grid with world-unit labels around all data (the scale of the scene).

        The grid actor is made once, with the view, and then only moved or hidden: building
        one takes pyvista ~40 ms, too long for the GUI thread whenever data is opened."""
        if not self._grid_enabled:
            return
        if self._grid is None:
            self._grid = self.plotter.show_bounds(
                bounds=(0, 1, 0, 1, 0, 1), color=OUTLINE_COLOR, grid=False, location="outer",
                ticks="outside", font_size=10, minor_ticks=False, fmt="%.3g",
                use_3d_text=False, render=False)
            if self._resize_observer is None:
                # a view resized (split, four-up) relabels its axes for its new width
                self._resize_observer = self.plotter.renderer.AddObserver(
                    "StartEvent", self._grid_resized)
        bounds = self.scene.bounds()
        show = self.scene.view.show_scale and bounds is not None
        if show:
            self._grid_size = tuple(self.plotter.renderer.GetSize())
            label_grid(self._grid, bounds, self.scene.length_unit(),
                       grid_axis_px(*self._grid_size))
        self._grid.SetVisibility(int(show))

    def _grid_resized(self, *_args) -> None:
        """Before a render: the labels again when the view's size in pixels changed."""
        size = tuple(self.plotter.renderer.GetSize())
        if self._grid is not None and size != self._grid_size and self._grid.GetVisibility():
            self._update_grid()

    def _update_time_label(self, *_args) -> None:
        """"t = 0.75 s (step 4/6)" in the upper-left corner while the scene holds a
        time-varying volume and the view's ``show_time`` is on. The annotation is made the
        first time it shows (a scene without time-varying volumes draws as if it had none)
        and then only changed or hidden; its font follows the window's size, so a 4K
        screenshot's label is as legible as the view's."""
        steps = self.scene.time_steps()
        show = bool(steps) and self.scene.view.show_time
        if self._time_label is None:
            if not show:
                return
            self._time_label = self.plotter.add_text(
                "", position="upper_left", font_size=12, color=OUTLINE_COLOR,
                name="time label", render=False)
        if show:
            self._time_label.set_text("upper_left", time_label(self.scene))
        self._time_label.SetVisibility(int(show))

    # -- pictures ------------------------------------------------------------------------

    def render_exact(self) -> None:
        """One synchronous render with exact frames."""
        self.spline_scene.render_exact()

    def close(self) -> None:
        self.scene.inserted.disconnect(self._inserted)
        self.scene.removed.disconnect(self._removed)
        self.scene.camera.events.disconnect(self._camera_changed)
        self.scene.view.events.disconnect(self._view_changed)
        self.scene.time_changed.disconnect(self._update_time_label)
        if self._resize_observer is not None:
            self.plotter.renderer.RemoveObserver(self._resize_observer)
            self._resize_observer = None
        for node in self.scene:
            handler = self._handlers.pop(node.id, None)
            if handler is not None:
                node.events.disconnect(handler)
        for layer in self.layers.values():
            layer.close()
        self.spline_scene.close()


def time_label(scene: Scene) -> str:
    """The scene's current time step as the view draws it: ``"t = 0.75 s (step 4/6)"``
    (the time the step starts, in the unit of the first time-varying volume; no unit when
    the data name none). ``scene`` holds a time-varying volume."""
    from splineviz.io.time_series import format_time

    steps = scene.time_steps()
    unit = scene.time_varying[0].time_unit if scene.time_varying else ""
    k = scene.step_index()
    return f"t = {format_time(steps[k], unit)} (step {k + 1}/{len(steps)})"


def label_grid(grid, bounds, unit: str = "", axis_px: float = 400.0) -> None:
    """Place pyvista's cube axes ``grid`` around ``bounds`` ``((x0, x1), (y0, y1), (z0,
    z1))`` padded to round ticks, with the labels and titles of
    :func:`splineviz.core.ticks.axis_ticks` (engineering notation, no "-0" or float noise),
    all set anew for each data set; ``axis_px``: about how many pixels an axis spans on
    screen (labels are thinned to fit, :func:`splineviz.core.ticks.label_stride`)."""
    import vtk

    from splineviz.core.ticks import axis_ticks, label_stride

    axes = [axis_ticks(lo, hi, name, unit) for (lo, hi), name in zip(bounds, "XYZ", strict=True)]
    grid.x_title, grid.y_title, grid.z_title = (t.title for t in axes)
    grid.update_bounds([v for t in axes for v in (t.lo, t.hi)])
    # vtkCubeAxesActor makes its label texts anew only when an axis range changed: a range
    # one part in 1e9 off every other time (invisible: the labels are given) redraws
    # labels thinned for a new view size over the same data
    nudge = 1e-9 if getattr(grid, "_relabel_nudge", 0.0) == 0.0 else 0.0
    grid._relabel_nudge = nudge
    for i, t in enumerate(axes):
        lo, hi = t.shown_range
        getattr(grid, f"Set{'XYZ'[i]}AxisRange")((lo, hi + (hi - lo) * nudge))
        labels = vtk.vtkStringArray()
        stride = label_stride(t.labels, axis_px)
        k0 = round(t.lo / t.step)
        for k, text in enumerate(t.labels, start=k0):
            labels.InsertNextValue("" if k % stride else text)
        grid.SetAxisLabels(i, labels)


def grid_axis_px(width: int, height: int) -> float:
    """About how many pixels one axis of the grid spans in a view of ``width`` x ``height``
    pixels: the framed data box fills about the narrower side, and an axis of the
    isometric view is about 0.4 of that."""
    return 0.4 * max(min(width, height), 0)


class NodeView:
    """What a :class:`SceneView` shows of one node; one subclass per node type
    (:data:`VIEW_CLASSES`). It reads the node whenever the node changes and keeps nothing
    a session would need."""

    def __init__(self, owner: SceneView, node: Node):
        self.owner = owner
        self.node = node
        self.draw()

    def draw(self) -> None:
        """Show the node as it is now."""

    def changed(self, what: str) -> None:
        """The node's property ``what`` changed."""
        self.draw()

    def sides_changed(self) -> None:
        """The view was split or joined."""

    def remove(self) -> None:
        """The node left the scene: remove what shows it."""
        sv = self.owner
        name = sv._props.pop(self.node.id, None)
        if name is not None and name in sv.spline_scene.props:
            sv.spline_scene.remove_prop(name)


class OutlineView(NodeView):
    """A volume's box outline (its data are shown by its isosurfaces' layers)."""

    def draw(self) -> None:
        import pyvista as pv

        sv, node = self.owner, self.node
        name = f"outline:{node.id}"
        sv._props[node.id] = name
        if node.data is None:
            return
        outline = pv.Box(bounds=np.ravel(node.data.bounds)).outline()
        # the grid's own box, turned into world with an oblique scan's direction
        outline.points = to_world(node.data, np.asarray(outline.points))
        sv.spline_scene.add_mesh(name, outline, kind="outline", color=OUTLINE_COLOR,
                                 pickable=False)
        self._visibility()
        sv._update_grid()

        self.volume_rendering()

    def _visibility(self) -> None:
        sv, node = self.owner, self.node
        name = sv._props.get(node.id)
        if name in sv.spline_scene.props:
            sv.spline_scene.set_prop_visible(name, node.visible and node.show_outline)

    def volume_rendering(self) -> None:
        """Add, update or remove the volume's :class:`VolumeLayer` (live views only)."""
        sv, node = self.owner, self.node
        layer = sv.volume_layers.get(node.id)
        on = (sv.live_volume_rendering and node.volume_rendering and node.data is not None
              and isinstance(node.active, Volume))
        if not on:
            if layer is not None:
                self._remove_layer()
            return
        if layer is None:
            layer = VolumeLayer(node.active, node.name, node.transfer_function_spec,
                                node.rendering_model, node.rendering_shade, device=sv.device)
            sv.volume_layers[node.id] = layer
            sv.spline_scene.add_volume_layer(layer)
        elif layer.volume is not node.active:
            layer.set_volume(node.active)
        layer.configure(node.transfer_function_spec, node.rendering_model,
                        node.rendering_shade)
        layer.set_clip_planes(sv._volume_planes(node.id))
        layer.visible = bool(node.visible and sv.scene.shows(node, sv.side))

    def changed(self, what: str) -> None:
        if what == "data":
            self.draw()
        elif what in ("visible", "show_outline"):
            self._visibility()
        if what in ("visible", "smoothed", "sigma", "volume_rendering", "transfer_function",
                    "transfer_function_points", "rendering_model", "rendering_shade",
                    "shown_in"):
            self.volume_rendering()

    def sides_changed(self) -> None:
        self.volume_rendering()

    def _remove_layer(self) -> None:
        sv = self.owner
        layer = sv.volume_layers.pop(self.node.id, None)
        if layer is not None:
            sv.spline_scene.remove_volume_layer(layer)
            layer.close()

    def remove(self) -> None:
        self._remove_layer()
        super().remove()


class IsosurfaceView(NodeView):
    """A ray-cast isosurface: an :class:`IsosurfaceLayer` that reads the node."""

    def draw(self) -> None:
        sv, node = self.owner, self.node
        vol = sv.scene.volume_of(node)
        layer = IsosurfaceLayer(vol.active, device=sv.device, node=node)
        layer.set_visible(sv._layer_visible(node))
        layer.set_clip_planes(sv._volume_planes(vol.id))
        sv.layers[node.id] = layer
        sv.spline_scene.add_layer(layer)
        self.colour_by()

    def colour_by(self) -> None:
        """Give the layer the data its colour-by names by id (a volume, a surface)."""
        sv, node = self.owner, self.node
        other = None
        if node.color_volume_id is not None and node.color_volume_id in sv.scene:
            other = sv.scene.get(node.color_volume_id).active
        reference = None
        ref_id = node.color_isosurface_id
        if node.color_by == "distance" and ref_id is not None and ref_id in sv.scene:
            ref = sv.scene.get(ref_id)
            reference = (sv.scene.volume_of(ref).active, ref.model, ref.model_options(),
                         ref.isovalue)
        sv.layers[node.id].set_color_by(node.color_by, other, reference)

    def changed(self, what: str) -> None:
        if what in ("visible", "shown_in"):
            self.sides_changed()
        elif what in ("color_by", "color_volume_id", "color_isosurface_id"):
            self.colour_by()
        # every other property reaches the layer through the node's events

    def sides_changed(self) -> None:
        sv, node = self.owner, self.node
        sv.layers[node.id].set_visible(sv._layer_visible(node))
        # sections show where one of their isosurfaces does
        for sec in sv.scene.sections:
            if node.id in sec.inputs:
                sv._prop_visibility(sec)

    def remove(self) -> None:
        sv = self.owner
        layer = sv.layers.pop(self.node.id)
        sv.spline_scene.remove_layer(layer)
        layer.close()


class PropView(NodeView):
    """A point cloud or mesh as a VTK prop, re-made with the node's display options."""

    def draw(self) -> None:
        import pyvista as pv

        sv, node = self.owner, self.node
        name = f"{node.kind}:{node.id}"
        sv._props[node.id] = name
        if isinstance(node, PointsNode):
            if node.data is None:
                return
            data = pv.PolyData(np.asarray(node.data.points, dtype=np.float64))
            # shaded sprites: a cloud shows its shape, not a flat silhouette
            opts = dict(color=node.color, point_size=node.point_size, opacity=node.opacity,
                        render_points_as_spheres=True, style="points")
        else:
            if node.vertices is None:
                return
            data = node.to_polydata()
            opts = dict(color=node.color, opacity=node.opacity, show_edges=node.show_edges,
                        edge_color=(0.2, 0.25, 0.35), smooth_shading=node.has_normals)
        sv.spline_scene.add_mesh(name, data, kind=node.kind, **opts)
        sv._prop_visibility(node)
        sv._update_grid()

    def changed(self, what: str) -> None:
        if what in ("visible", "shown_in"):
            self.owner._prop_visibility(self.node)
        else:
            self.draw()

    def sides_changed(self) -> None:
        self.owner._prop_visibility(self.node)


class PlaneView(NodeView):
    """A clip plane: it cuts the layers of its volume, or the whole view's."""

    def draw(self) -> None:
        self.owner._update_planes()

    def remove(self) -> None:
        self.owner._update_planes()


class SectionView(NodeView):
    """A section's curves as lines (computed when the node has none yet)."""

    def __init__(self, owner: SceneView, node: SectionNode):
        self.owner = owner
        self.node = node
        self.draw(recompute=node.curves is None)

    def draw(self, recompute: bool = False) -> None:
        """(Re)draw the curves, computing them first if asked."""
        from splineviz.io.curves import curves_polydata
        from splineviz.model.analysis import section_curves

        sv, node = self.owner, self.node
        if recompute:
            section_curves(sv.scene, node)
        name = f"{node.kind}:{node.id}"
        if not node.curves:
            sv._props.pop(node.id, None)
            if name in sv.spline_scene.props:
                sv.spline_scene.remove_prop(name)
            return
        sv._props[node.id] = name
        sv.spline_scene.add_mesh(name, curves_polydata(node.curves), kind=node.kind,
                                 color=node.color, line_width=node.line_width,
                                 lighting=False)
        sv._prop_visibility(node)

    def changed(self, what: str) -> None:
        if what != "curves":
            self.draw()

    def sides_changed(self) -> None:
        self.owner._prop_visibility(self.node)


#: node type -> the class that shows such nodes (subclasses of a node type find theirs
#: through their bases)
VIEW_CLASSES: dict[type, type[NodeView]] = {
    VolumeNode: OutlineView,
    IsosurfaceNode: IsosurfaceView,
    PointsNode: PropView,
    MeshNode: PropView,
    ClipPlaneNode: PlaneView,
    SectionNode: SectionView,
}


def view_class(node: Node) -> type[NodeView]:
    """The :data:`VIEW_CLASSES` entry of ``node``'s type or of its nearest base."""
    for cls in type(node).__mro__:
        if cls in VIEW_CLASSES:
            return VIEW_CLASSES[cls]
    return NodeView


def smooth_pending(scene: Scene, device=None) -> None:
    """Make the smoothed data of every volume whose ``sigma`` asks for it (synchronously;
    the GUI does the same in a worker)."""
    from splineviz.compute.smoothing import gaussian_smooth

    for vol in scene.volumes:
        if vol.smoothing_pending:
            vol.set_smoothed(gaussian_smooth(vol.data, vol.sigma, device=device), vol.sigma)


class OffscreenRenderer:
    """Exact pictures of ``scene`` at ``size``, one per :meth:`render`, from off-screen
    plotters kept between calls (a movie renders its frames through one): each picture is
    the one :func:`render_scene` makes of the scene as it is at the call. A split scene
    (:attr:`splineviz.model.ViewNode.split`) is drawn as its two views side by side, each
    half as wide, as the window shows it. Use as a context manager, or :meth:`close`.

    Parameters
    ----------
    scene : splineviz.model.Scene
    size : (int, int)
        Width and height in pixels.
    transparent_background : bool
        RGBA pictures whose background is transparent.
    device : str or None
        OpenCL device preference of the ray casters.
    """

    def __init__(self, scene: Scene, size=(1024, 768), *,
                 transparent_background: bool = False, device=None):
        import pyvista as pv

        from splineviz.io._vtk import quiet_vtk_logger
        from splineviz.render.scene import SceneError

        w, h = int(size[0]), int(size[1])
        if w < 1 or h < 1 or w > 16384 or h > 16384:
            raise SceneError(f"a picture must be 1..16384 pixels per side, got {w}x{h}")
        self.scene = scene
        self.size = (w, h)
        self.device = device
        self.transparent_background = transparent_background
        self._quiet = quiet_vtk_logger
        self._split = bool(scene.view.split)
        smooth_pending(scene, device)
        if self._split:
            parts = (("left", w // 2), ("right", w - w // 2))
            if w < 2:
                raise SceneError("a picture of a split view needs 2 or more pixels across, "
                                 f"got {w}")
        else:
            parts = ((None, w),)
        self._views: list = []
        self._rendered = False
        with quiet_vtk_logger():
            try:
                for side, width in parts:
                    pl = pv.Plotter(off_screen=True, window_size=(width, h))
                    view = SceneView(scene, pl, progressive=False, device=device, side=side)
                    view.spline_scene.single_sample_for_cells()
                    self._views.append((pl, view))
            except BaseException:
                self.close()
                raise

    def render(self) -> np.ndarray:
        """The exact picture of the scene now: ``(H, W, 3)`` uint8, or ``(H, W, 4)`` with
        a transparent background."""
        from splineviz.render.scene import SceneError
        from splineviz.render.volume_rendering import composite_volume_rendering

        if bool(self.scene.view.split) != self._split:
            raise SceneError("the scene was split or joined since this renderer was made")
        smooth_pending(self.scene, self.device)
        images = []
        if self._rendered:
            for _pl, view in self._views:
                view.rebuild_grid()
        self._rendered = True
        with self._quiet():
            # twice for a split: the right half may widen a colour range both halves share
            # (the second pass casts nothing, the frames are current)
            for _ in range(len(self._views)):
                for _pl, view in self._views:
                    view.render_exact()
            for pl, view in self._views:
                shot = pl.screenshot(None, transparent_background=self.transparent_background,
                                     return_img=True)
                images.append(composite_volume_rendering(view, pl, shot, self.device))
        return images[0] if len(images) == 1 else np.concatenate(images, axis=1)

    def close(self) -> None:
        """Release the plotters and stop following the scene."""
        views, self._views = self._views, []
        for pl, view in views:
            view.close()
            pl.close()

    def __enter__(self) -> OffscreenRenderer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def render_scene(scene: Scene, size=(1024, 768), filename=None, *,
                 transparent_background: bool = False, device=None) -> np.ndarray:
    """Render ``scene`` off-screen at ``size`` with exact frames; optionally write a PNG.

    A split scene (:attr:`splineviz.model.ViewNode.split`) is drawn as its two views side by
    side, each half as wide, as the window shows it (see :class:`OffscreenRenderer`, which
    keeps its plotters for many pictures).

    Returns
    -------
    (H, W, 3) or (H, W, 4) uint8 image
    """
    with OffscreenRenderer(scene, size, transparent_background=transparent_background,
                           device=device) as renderer:
        img = renderer.render()
    if filename is not None:
        from splineviz.io.meshes import write_screenshot

        write_screenshot(filename, img)
    return img
