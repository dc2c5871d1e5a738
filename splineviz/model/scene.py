"""The scene: every object the user has loaded or made, with ids, events and a camera.

:class:`Scene` is the one source of truth behind the GUI, the command line and session files
(napari's layer list, ParaView's pipeline). It owns nodes (:mod:`splineviz.model.nodes`),
gives each a unique id (objects are never matched by name), keeps dependent objects
consistent (removing a volume removes its isosurfaces and clip planes) and reports every
change through :class:`psygnal.Signal`\\ s:

* ``inserted(node)`` / ``removed(node)``: the list of objects changed;
* ``selection(node or None)``: the current object of the panels;
* ``changed()``: anything changed (unsaved-changes flag, autosave);
* ``time_changed(t)``: the scene's current time moved (:meth:`Scene.set_time`).

Time-varying volumes (a :class:`~splineviz.io.time_series.TimeSeries` on their node) follow
the scene's one current time (ParaView's animation time): each shows its last step at or
before it, and since the step is the node's ``data``, its isosurfaces, colourings, clip
planes and sections follow as after any change of data.

Nothing here imports Qt or VTK; views subscribe.
"""

from __future__ import annotations

from collections.abc import Iterator
from functools import partial

import numpy as np
from psygnal import Signal

from splineviz.core.raycast_reference import BACKGROUND
from splineviz.core.volume import Volume
from splineviz.io.time_series import TimeSeries
from splineviz.model.nodes import (
    PALETTE,
    CameraNode,
    ClipPlaneNode,
    IsosurfaceNode,
    MeshNode,
    ModelError,
    Node,
    PointsNode,
    SectionNode,
    ViewNode,
    VolumeNode,
)

#: standard views: name -> (direction from the focal point to the eye, view up). ParaView's
#: convention (its "Set view direction to +X" button): "+X" looks down +X, i.e. along +X,
#: from an eye on the -X side; the up vector is +Z for the X and Y views and +Y for Z views
STANDARD_VIEWS = {
    "+X": ((-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "-X": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "+Y": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "-Y": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    "+Z": ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    "-Z": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "isometric": ((1.0, -1.0, 0.8), (0.0, 0.0, 1.0)),
}


#: how new point clouds and meshes look. A property's default is what a session without it
#: means (schema 1-4 documents fixed those); a new object gets a look that tells it apart,
#: as new isosurfaces get the next :data:`~splineviz.model.nodes.PALETTE` colour and a new
#: scene the ray caster's background
NEW_POINTS = {"color": (0.85, 0.85, 0.9)}
NEW_MESH = {"color": (0.75, 0.85, 0.95), "show_edges": True}


def default_model() -> str:
    """The model new isosurfaces start with: cubic C1 (smooth, with an OpenCL kernel)."""
    from splineviz.core.splines import MODELS

    return "cubic-c1" if "cubic-c1" in MODELS else next(iter(MODELS))


def first_isovalue(volume) -> float:
    """The isovalue a volume's first isosurface starts with, from the histogram the volume
    already has (:func:`~splineviz.model.summaries.cached_histogram`: made once, by the
    reading process in the GUI)."""
    from splineviz.core.default_isovalue import isovalue_from_histogram
    from splineviz.model.summaries import cached_histogram

    log_counts, edges = cached_histogram(volume)
    lo, hi = volume.finite_range
    if not hi > lo:
        return lo
    return isovalue_from_histogram(np.rint(np.expm1(log_counts)), edges)


def _summarise(volume) -> None:
    """What the panels show of a volume (its range and histogram), computed where it is
    read: a time step's reading thread, not the GUI thread that shows it."""
    from splineviz.model.summaries import cached_histogram

    _ = volume.finite_range
    cached_histogram(volume)


def _prepare_steps(node: VolumeNode, *_args) -> None:
    # the steps of a time-varying volume come with their summaries
    if node.series is not None:
        node.series.prepare = _summarise


class Scene:
    """Objects of one scene, in insertion order (inputs before the objects that use them).

    Examples
    --------
    >>> import splineviz as sv
    >>> from splineviz.core import testfunctions as tf
    >>> scene = Scene()
    >>> vol = scene.add_volume(sv.Volume.from_function(tf.ml, (9, 9, 9), tf.ml.domain),
    ...                        name="ML", isosurface=False)
    >>> iso = scene.add_isosurface(vol, isovalue=0.5)
    >>> [n.id for n in scene], iso.volume_id
    (['volume1', 'isosurface1'], 'volume1')
    """

    inserted = Signal(object)
    removed = Signal(object)
    selection = Signal(object)
    changed = Signal()
    time_changed = Signal(float)

    def __init__(self):
        self._nodes: dict[str, Node] = {}
        self.camera = CameraNode(id="camera")
        self.view = ViewNode(id="view", background=BACKGROUND)
        self.selected: Node | None = None
        #: the scene's :class:`~splineviz.model.animation.Animation` (None: none); saved
        #: with the session
        self.animation = None
        #: True after any change since :meth:`mark_saved`
        self.modified = False
        self._aspect = 1.0
        #: what :meth:`frame` last framed and the camera pose it left (None: nothing yet)
        self._framed: tuple | None = None
        #: the model a volume's first isosurface starts with, when it names a registered
        #: one (the GUI's preferences set it); else :func:`default_model`
        self.preferred_model: str | None = None
        self._time = 0.0
        #: volume id -> its slot following time_index (to disconnect it on removal)
        self._step_slots: dict = {}
        self.view.events.connect(self._node_changed)
        # looking around is not an edit: the camera is saved, but moving it leaves
        # ``modified`` alone (no "unsaved changes" prompt after an orbit)
        self.camera.events.connect(self.changed.emit)

    # -- access --------------------------------------------------------------------------

    def __iter__(self) -> Iterator[Node]:
        return iter(list(self._nodes.values()))

    def __len__(self) -> int:
        return len(self._nodes)

    def __contains__(self, node) -> bool:
        key = node.id if isinstance(node, Node) else node
        return key in self._nodes

    def get(self, node_id: str) -> Node:
        try:
            return self._nodes[node_id]
        except KeyError:
            raise ModelError(f"the scene has no object {node_id!r}") from None

    def of_kind(self, cls) -> list:
        return [n for n in self._nodes.values() if isinstance(n, cls)]

    @property
    def volumes(self) -> list[VolumeNode]:
        return self.of_kind(VolumeNode)

    @property
    def isosurfaces(self) -> list[IsosurfaceNode]:
        return self.of_kind(IsosurfaceNode)

    @property
    def clip_planes(self) -> list[ClipPlaneNode]:
        return self.of_kind(ClipPlaneNode)

    def isosurfaces_of(self, volume: VolumeNode | str) -> list[IsosurfaceNode]:
        vid = volume.id if isinstance(volume, Node) else volume
        return [n for n in self.isosurfaces if n.volume_id == vid]

    def volume_of(self, iso: IsosurfaceNode) -> VolumeNode:
        return self.get(iso.volume_id)

    def planes_for(self, volume: VolumeNode | str) -> list[tuple[tuple, tuple]]:
        """``(origin, normal)`` of the enabled clip planes that cut ``volume``'s isosurfaces
        (its own and the scene-wide ones)."""
        vid = volume.id if isinstance(volume, Node) else volume
        return [p.as_pair() for p in self.clip_planes
                if p.enabled and p.volume_id in (None, vid)]

    def planes_cutting(self, node: Node) -> list[tuple[tuple, tuple]]:
        """The enabled planes that cut ``node`` in the view: an isosurface (or a volume's
        isosurfaces) by its volume's planes and the scene's, a mesh by the scene's."""
        if isinstance(node, IsosurfaceNode):
            return self.planes_for(node.volume_id)
        if isinstance(node, VolumeNode):
            return self.planes_for(node)
        if isinstance(node, MeshNode):
            return [p.as_pair() for p in self.clip_planes if p.enabled and p.volume_id is None]
        return []

    def shows(self, node: Node, side: str | None) -> bool:
        """Whether the view on ``side`` (``"left"``, ``"right"``; None: the single view)
        shows ``node`` by the split's rule: while :attr:`ViewNode.split` is on, an object
        whose ``shown_in`` names the other side is left out, and a section shows where one
        of its isosurfaces does. Visibility flags are not looked at here."""
        if side is None or not self.view.split:
            return True
        if isinstance(node, SectionNode):
            isos = [self._nodes.get(i) for i in node.inputs]
            isos = [n for n in isos if isinstance(n, IsosurfaceNode)]
            return not isos or any(self.shows(n, side) for n in isos)
        return getattr(node, "shown_in", "both") in ("both", side)

    def compare(self, isosurface: IsosurfaceNode, model: str | None = None,
                isovalue: float | None = None, *, distance: bool = False) -> IsosurfaceNode:
        """Split the view to compare ``isosurface`` with a copy of it in another spline model
        or at another isovalue: the original shows on the left, the copy on the right, the
        cameras are one. ``model`` defaults to trilinear (the baseline) for a smooth model
        and to :func:`default_model` for trilinear; ``distance`` also colours the original
        by its distance to the copy. Returns the copy."""
        if model is None:
            model = "trilinear" if isosurface.model != "trilinear" else default_model()
        props = isosurface.model_dump(exclude={"id", "name", "kind", "model", "isovalue",
                                               "shown_in", "volume_id", "visible"})
        copy = self.add(IsosurfaceNode(
            volume_id=isosurface.volume_id, model=model,
            isovalue=isosurface.isovalue if isovalue is None else float(isovalue),
            name=f"{isosurface.name} ({model})", shown_in="right", **props))
        isosurface.shown_in = "left"
        if distance:
            isosurface.update(color_by="distance", color_isosurface_id=copy.id)
        self.view.split = True
        return copy

    def bounds(self) -> tuple | None:
        """``((xmin, xmax), (ymin, ymax), (zmin, zmax))`` of all data, or None when empty."""
        boxes = []
        for n in self._nodes.values():
            if isinstance(n, VolumeNode) and n.data is not None:
                boxes.append(np.asarray(n.bounds, dtype=float))
            elif isinstance(n, PointsNode) and n.data is not None and len(n.data):
                boxes.append(np.asarray(n.data.bounds, dtype=float))
            elif isinstance(n, MeshNode) and n.vertices is not None and len(n.vertices):
                v = n.vertices
                boxes.append(np.stack([v.min(axis=0), v.max(axis=0)], axis=1))
        if not boxes:
            return None
        b = np.stack(boxes)
        return tuple((float(b[:, a, 0].min()), float(b[:, a, 1].max())) for a in range(3))

    def first_model(self) -> str:
        """The model of a volume's first isosurface: :attr:`preferred_model` if registered,
        else :func:`default_model`."""
        from splineviz.core.splines import MODELS

        return self.preferred_model if self.preferred_model in MODELS else default_model()

    def length_unit(self) -> str:
        """The unit of world coordinates the volumes' files state ("mm"), ``""`` when none
        does or they differ (see :mod:`splineviz.core.units`)."""
        from splineviz.core.units import common_unit

        return common_unit(n.data.unit for n in self._nodes.values()
                           if isinstance(n, VolumeNode) and n.data is not None)

    # -- editing -------------------------------------------------------------------------

    def new_id(self, prefix: str) -> str:
        n = 1
        while f"{prefix}{n}" in self._nodes:
            n += 1
        return f"{prefix}{n}"

    def add(self, node: Node, index: int | None = None) -> Node:
        """Insert ``node`` (an id is given when it has none) at the end of the scene's order,
        or at ``index`` (undo puts a removed object back in its place); returns it."""
        if not node.id:
            node.id = self.new_id(node.kind.replace("_", ""))
        if node.id in self._nodes or node.id in ("camera", "view"):
            raise ModelError(f"the scene already has an object {node.id!r}")
        for ref in ("volume_id",):
            target = getattr(node, ref, None)
            if target is not None and not isinstance(self._nodes.get(target), VolumeNode):
                raise ModelError(f"{node.kind} {node.id!r} refers to the volume {target!r}, "
                                 "which is not in the scene")
        if isinstance(node, SectionNode):
            self._check_section(node)
        if not node.name:
            node.name = node.id
        if index is None:
            self._nodes[node.id] = node
        else:
            items = list(self._nodes.items())
            items.insert(index, (node.id, node))
            self._nodes = dict(items)
        node.events.connect(self._node_changed)
        if isinstance(node, VolumeNode):
            slot = partial(self._follow_step, node)
            adopt = partial(_prepare_steps, node)
            self._step_slots[node.id] = (slot, adopt)
            node.events.time_index.connect(slot)
            node.events.series.connect(adopt)
            adopt()
            if node.series is not None:
                if node.data is None:
                    slot(node.time_index)
                self._time = node.time
        self.inserted.emit(node)
        self._node_changed()
        return node

    def remove(self, node: Node | str) -> None:
        """Remove an object and what depends on it (a volume's isosurfaces and planes)."""
        node = self.get(node) if isinstance(node, str) else node
        if node.id not in self._nodes:
            return
        if isinstance(node, VolumeNode):
            for dep in [n for n in self._nodes.values()
                        if getattr(n, "volume_id", None) == node.id]:
                self.remove(dep)
        for dep in [n for n in self.of_kind(SectionNode) if node.id in n.inputs]:
            self.remove(dep)
        # colourings that refer to it fall back to the flat colour
        for iso in self.of_kind(IsosurfaceNode):
            if node.id in (iso.color_volume_id, iso.color_isosurface_id):
                iso.update(color_by="none", color_volume_id=None, color_isosurface_id=None)
        if isinstance(node, PointsNode):
            for mesh in self.of_kind(MeshNode):
                if mesh.points_id == node.id:
                    mesh.points_id = None
        del self._nodes[node.id]
        if self.animation is not None:  # its tracks of the object go with it
            self.animation = self.animation.without(node.id)
        node.events.disconnect(self._node_changed)
        if isinstance(node, VolumeNode):
            slot, adopt = self._step_slots.pop(node.id)
            node.events.time_index.disconnect(slot)
            node.events.series.disconnect(adopt)
        if self.selected is node:
            self.select(None)
        self.removed.emit(node)
        self._node_changed()

    def clear(self) -> None:
        """Remove every object and the animation (camera and view settings stay)."""
        for node in reversed(list(self._nodes.values())):
            if node.id in self._nodes:
                self.remove(node)
        self.animation = None
        self.modified = False

    def select(self, node: Node | str | None) -> None:
        node = self.get(node) if isinstance(node, str) else node
        if node is self.selected:
            return
        self.selected = node
        self.selection.emit(node)

    def _node_changed(self, *_args) -> None:
        self.modified = True
        self.changed.emit()

    def mark_saved(self) -> None:
        self.modified = False

    # -- convenience constructors (what "open" and "add isosurface" do) -------------------

    def add_volume(self, volume: Volume, name: str = "", *, path=None, source=None,
                   read_options=None, isovalue=None, model=None, sigma: float = 0.0,
                   isosurface: bool = True) -> VolumeNode:
        """Add a volume and, unless ``isosurface=False``, its first isosurface."""
        node = self.add(VolumeNode(name=name, path=None if path is None else str(path),
                                   source=source, read_options=dict(read_options or {}),
                                   sigma=sigma, data=volume))
        if isosurface:
            self.add_isosurface(node, isovalue=isovalue, model=model)
        return node

    def add_isosurface(self, volume: VolumeNode, isovalue=None, model=None,
                       **props) -> IsosurfaceNode:
        """A new isosurface of ``volume``, in the next palette colour and the model of the
        volume's last isosurface. A given ``isovalue`` is kept as it is; by default the first
        isosurface separates background from object
        (:func:`~splineviz.core.default_isovalue.isovalue_from_histogram` of the volume's
        histogram: Otsu's threshold, or the level enclosing 1 % of noise-like samples) and
        the next ones spread over the range (golden ratio)."""
        others = self.isosurfaces_of(volume)
        n = len(others)
        if isovalue is None:
            isovalue = first_isovalue(volume.active) if n == 0 else None
        if isovalue is None:
            lo, hi = volume.active.finite_range
            isovalue = lo + (hi - lo) * (0.3 + 0.4 * ((n * 0.618) % 1.0))
        if model is None:
            model = others[-1].model if others else self.first_model()
        props.setdefault("color", PALETTE[n % len(PALETTE)])
        props.setdefault("name", f"isosurface {n + 1}" if n else "isosurface")
        return self.add(IsosurfaceNode(volume_id=volume.id, model=model,
                                       isovalue=float(isovalue), **props))

    def add_time_series(self, series: TimeSeries, name: str = "", *, step: int = 0, path=None,
                        read_options=None, **kwargs) -> VolumeNode:
        """Add a time-varying volume showing ``step`` of ``series`` (and, unless
        ``isosurface=False``, its first isosurface, from that step's samples); the scene's
        time moves to that step's. ``path``: the file, folder or pattern the series was
        opened from (:func:`~splineviz.io.time_series.open_time_series`), which sessions
        keep; ``kwargs`` as for :meth:`add_volume`."""
        step = series.check_index(step)
        node = self.add_volume(series.step(step), name or series.name, path=path,
                               read_options=read_options, **kwargs)
        # a session reopens the series from its file; one without (an array's) is saved as
        # the step shown
        node.update(series=series, time_series=path is not None, time_index=step)
        self._time = node.time
        return node

    # -- time ------------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """The scene's current time (in the unit of its time-varying volumes)."""
        return self._time

    @property
    def time_varying(self) -> list[VolumeNode]:
        """The volumes that follow the scene's time (those with a series of steps)."""
        return [n for n in self.volumes if n.series is not None]

    def time_steps(self) -> tuple[float, ...]:
        """Every time at which some time-varying volume starts a step, increasing (empty
        when none varies)."""
        return tuple(sorted({t for n in self.time_varying for t in n.times}))

    @property
    def play_rate(self) -> float:
        """Steps per second while the scene plays (kept by its time-varying volumes, so
        sessions keep it; 10 when none varies)."""
        return next((n.play_rate for n in self.time_varying), 10.0)

    @play_rate.setter
    def play_rate(self, rate: float) -> None:
        for node in self.time_varying:
            node.play_rate = float(rate)

    def set_time(self, time: float) -> None:
        """Move the scene to ``time``: each time-varying volume shows its last step at or
        before it (its first before it starts). Reads the steps not yet read (a player
        reads them ahead on a job thread first: :meth:`TimeSeries.read_ahead`)."""
        time = float(time)
        for node in self.time_varying:
            node.time_index = node.series.index_at_or_before(time - node.time_offset)
        self._time = time
        self.time_changed.emit(time)

    def set_step(self, index: int) -> None:
        """Move the scene to the ``index``-th of :meth:`time_steps` (negative counts from
        the end); a one-sentence error past either end."""
        steps = self.time_steps()
        if not steps:
            raise ModelError("the scene holds no time-varying volume")
        k = int(index) + len(steps) if int(index) < 0 else int(index)
        if not 0 <= k < len(steps):
            raise ModelError(f"the scene has {len(steps)} time step(s) (0 to "
                             f"{len(steps) - 1}); step {index} is not one")
        self.set_time(steps[k])

    def step_index(self) -> int:
        """The index in :meth:`time_steps` of the scene's current time (0 when none
        varies)."""
        steps = self.time_steps()
        return max(0, int(np.searchsorted(steps, self._time, side="right")) - 1) if steps else 0

    def _follow_step(self, node: VolumeNode, index: int) -> None:
        # a volume's data is the step its time_index names: read when they differ (the
        # step is the node's data, so everything that shows the volume redraws)
        if node.series is None:
            return
        volume = node.series.step(index)
        if volume is not node.data:
            # the old step's smoothing goes first: listeners of ``data`` see it pending
            node.update(smoothed=None, smoothed_sigma=0.0, data=volume)

    def _check_section(self, node: SectionNode) -> None:
        if not isinstance(self._nodes.get(node.isosurface_id), IsosurfaceNode):
            raise ModelError(f"section {node.id!r} needs an isosurface, not "
                             f"{node.isosurface_id!r}")
        if (node.plane_id is None) == (node.other_id is None):
            raise ModelError(f"section {node.id!r} needs either a clip plane or a second "
                             "isosurface")
        if node.plane_id is not None and \
                not isinstance(self._nodes.get(node.plane_id), ClipPlaneNode):
            raise ModelError(f"section {node.id!r}: {node.plane_id!r} is not a clip plane")
        if node.other_id is not None and (
                node.other_id == node.isosurface_id
                or not isinstance(self._nodes.get(node.other_id), IsosurfaceNode)):
            raise ModelError(f"section {node.id!r}: {node.other_id!r} is not another "
                             "isosurface")

    @property
    def sections(self) -> list[SectionNode]:
        return self.of_kind(SectionNode)

    def add_section(self, isosurface: IsosurfaceNode, plane: ClipPlaneNode | None = None,
                    other: IsosurfaceNode | None = None, **props) -> SectionNode:
        """The exact curves where ``isosurface`` meets ``plane`` or the isosurface
        ``other``."""
        props.setdefault("name", f"section of {isosurface.name}")
        return self.add(SectionNode(isosurface_id=isosurface.id,
                                    plane_id=None if plane is None else plane.id,
                                    other_id=None if other is None else other.id, **props))

    def add_points(self, cloud, name: str = "", *, path=None, **props) -> PointsNode:
        """A point cloud, in :data:`NEW_POINTS` unless ``props`` say otherwise."""
        return self.add(PointsNode(name=name, path=None if path is None else str(path),
                                   data=cloud, **{**NEW_POINTS, **props}))

    def add_mesh(self, vertices, faces, name: str = "", *, normals=None, **props) -> MeshNode:
        """A triangle mesh, in :data:`NEW_MESH` unless ``props`` say otherwise."""
        props = {**NEW_MESH, **props}
        return self.add(MeshNode(name=name, vertices=np.asarray(vertices, dtype=np.float64),
                                 faces=np.asarray(faces, dtype=np.int64), normals=normals,
                                 **props))

    def add_clip_plane(self, origin=None, normal=(1.0, 0.0, 0.0),
                       volume: VolumeNode | None = None, **props) -> ClipPlaneNode:
        """A clip plane through ``origin`` (default: the centre of the volume or scene)."""
        if origin is None:
            b = volume.bounds if volume is not None else (self.bounds() or ((0, 0),) * 3)
            origin = tuple(0.5 * (lo + hi) for lo, hi in b)
        return self.add(ClipPlaneNode(origin=tuple(map(float, origin)),
                                      normal=tuple(map(float, normal)),
                                      volume_id=None if volume is None else volume.id,
                                      **props))

    # -- pictures ------------------------------------------------------------------------

    def show(self, size=None, camera=None, *, interactive: bool = False, **options):
        """The scene's exact picture (a :class:`splineviz.notebook.Picture`, shown by a
        notebook), or with ``interactive=True`` its view in the browser; see
        :func:`splineviz.notebook.show`. The renderer is reached through the hook of
        :mod:`splineviz.core.pictures` (this layer imports no VTK)."""
        from splineviz.core.pictures import show

        return show(self, size=size, camera=camera, interactive=interactive, **options)

    def _repr_png_(self) -> bytes:
        """A notebook shows the scene as its exact picture (IPython's display protocol)."""
        return self.show()._repr_png_()

    def widget(self, size=None, **options):
        """An ipywidgets view of the scene in a notebook: its exact picture with an isovalue
        slider, model, clip plane and colour-by controls and orbit buttons
        (:class:`splineviz.widget.SceneWidget`, reached through the hook of
        :mod:`splineviz.core.pictures`)."""
        from splineviz.core.pictures import show

        return show(self, size=size, widget=True, **options)

    # -- camera --------------------------------------------------------------------------

    @property
    def aspect(self) -> float:
        """Width / height of the view that shows the scene (set by views; used to frame).

        A view whose shape changes while its camera is still where :meth:`frame` left it
        (the window laid out after a file opened from the command line, a dock shown or
        closed) is framed again for the new shape: framed for the default square, a
        portrait view cut the data at its sides."""
        return self._aspect

    @aspect.setter
    def aspect(self, value: float) -> None:
        value = float(value)
        if value == self._aspect:
            return
        self._aspect = value
        if self._framed is not None and self.camera.pose() == self._framed[1]:
            self.frame(self._framed[0])

    def frame(self, bounds=None, view: str | None = None) -> None:
        """Point the camera at ``bounds`` (default: all data) so that all of it is in view.

        ``view`` is a key of :data:`STANDARD_VIEWS`; None keeps the current direction.
        """
        bounds = self.bounds() if bounds is None else bounds
        if bounds is None:
            return
        b = np.asarray(bounds, dtype=float)
        centre = b.mean(axis=1)
        radius = 0.5 * float(np.linalg.norm(b[:, 1] - b[:, 0])) or 1.0
        cam = self.camera
        if view is not None:
            direction, up = (np.asarray(v, dtype=float) for v in STANDARD_VIEWS[view])
        else:
            direction = np.subtract(cam.position, cam.focal_point)
            up = np.asarray(cam.view_up, dtype=float)
        direction = direction / (np.linalg.norm(direction) or 1.0)
        # the bounding sphere fits the narrower of the two view angles (vertical, and
        # horizontal from the view's aspect ratio), with a 10 % margin
        half = np.radians(cam.view_angle) / 2.0
        half = min(half, float(np.arctan(np.tan(half) * max(self.aspect, 1e-3))))
        distance = 1.1 * radius / np.sin(half)
        up = up - np.dot(up, direction) * direction
        if np.linalg.norm(up) < 1e-9:
            up = np.array([0.0, 1.0, 0.0]) if abs(direction[1]) < 0.9 else np.array([1, 0, 0.0])
        cam.update(position=tuple(map(float, centre + distance * direction)),
                   focal_point=tuple(map(float, centre)),
                   view_up=tuple(map(float, up / np.linalg.norm(up))),
                   parallel_scale=radius)
        self._framed = (b, cam.pose())
