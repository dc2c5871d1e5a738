"""The objects of a scene as evented nodes (no Qt, no VTK).

Each node is a :class:`psygnal.EventedModel` (pydantic fields with one signal per field, the
napari habit): setting ``node.isovalue = 40.0`` validates the value and emits
``node.events.isovalue``; views (the VTK scene of :mod:`splineviz.render`, the Qt panels of
:mod:`splineviz.gui`) subscribe to those signals and never hold state of their own.

A node's fields are the one declaration of its properties: their types, defaults and
validation. Sessions (:mod:`splineviz.model.schema`, :mod:`splineviz.model.session`), the
render layer and the panels are derived from them, so a new property is one field here plus
the code that shows it. Heavy data (the samples of a volume, a point cloud, a mesh's arrays)
live in fields that are never written to sessions (``exclude=True``); fields made by
:func:`reference` hold the ids of other nodes (a session's ``inputs``); fields made by
:func:`origin` say where the data comes from (a session writes them in the object's own
form, e.g. a path and its read options); everything else is a plain property whose
non-default values :meth:`Node.state` returns, in field order (the order sessions write).

Conventions: colours are RGB in [0, 1]; points and vectors are world coordinates; meshes
are ``(V, 3)`` float vertex and ``(F, 3)`` int triangle arrays (docs/api.md: pyvista objects
only at the render/io boundary).
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from psygnal import EventedModel
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    model_validator,
)

from splineviz.core.chunked import ChunkedVolume
from splineviz.core.colour_by import COLORMAPS, FIELDS, RANGE_MODES
from splineviz.core.errors import SplinevizError
from splineviz.core.material import FRONT_COLOR, MATERIALS
from splineviz.core.points import PointCloud
from splineviz.core.renderers import AUTO, renderer_name
from splineviz.core.volume import Volume
from splineviz.io.session import ID_PATTERN, MAX_MAGNITUDE
from splineviz.io.time_series import TimeSeries
from splineviz.io.volume_data import MAX_FRAMES

Unit = Annotated[float, Field(ge=0.0, le=1.0, allow_inf_nan=False)]
RGB = tuple[Unit, Unit, Unit]
#: finite and within what float32 rendering and session files take
Finite = Annotated[float, Field(allow_inf_nan=False, ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]
Vec3 = tuple[Finite, Finite, Finite]
NodeId = Annotated[str, Field(pattern=ID_PATTERN)]
Positive = Annotated[float, Field(gt=0.0, le=MAX_MAGNITUDE, allow_inf_nan=False)]


def nonzero_normal(v):
    """A clip plane's normal, refused when it is the zero vector (pydantic validator)."""
    if sum(c * c for c in v) == 0.0:
        raise ValueError("a clip plane normal must not be zero")
    return v


def _model_name(name: str) -> str:
    # the spline model registry is the one place that knows the valid names; its lookup loads
    # plugin models on a miss (a session may name one before anything loaded them)
    from splineviz.core.splines.registry import model_spec

    model_spec(name)
    return name


#: a key of the spline model registry (:data:`splineviz.core.splines.MODELS`)
ModelName = Annotated[str, AfterValidator(_model_name)]
#: a key of :data:`splineviz.core.renderers.RENDERERS` (an alias is stored as its key)
RendererName = Annotated[str, AfterValidator(renderer_name)]
Normal = Annotated[Vec3, AfterValidator(nonzero_normal)]


def _transfer_function_name(spec: str) -> str:
    from splineviz.core.transfer_function import PRESETS, TransferFunctionError

    if spec not in PRESETS and not spec.lower().endswith(".json"):
        raise TransferFunctionError(f"{spec!r} is neither a transfer function preset "
                                    f"({', '.join(PRESETS)}) nor a ParaView .json file")
    return spec


#: a transfer function preset name or a ParaView JSON preset file
TransferFunctionName = Annotated[str, AfterValidator(_transfer_function_name)]


def _ordered(points: tuple) -> tuple:
    if any(b[0] < a[0] for a, b in zip(points[:-1], points[1:], strict=True)):
        raise ValueError("transfer function points must be in non-decreasing value order")
    return points


class TransferFunctionPoints(BaseModel):
    """A transfer function edited in the GUI: its colour and opacity points over data
    values (as :class:`~splineviz.core.transfer_function.TransferFunction`'s), kept in
    sessions as two lists of points.

    Attributes
    ----------
    rgb_points : tuple of (value, r, g, b)
        Colours in [0, 1], values non-decreasing.
    opacity_points : tuple of (value, opacity)
        Opacities in [0, 1] per unit step, values non-decreasing.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    rgb_points: Annotated[tuple[tuple[Finite, Unit, Unit, Unit], ...], Field(min_length=1),
                          AfterValidator(_ordered)]
    opacity_points: Annotated[tuple[tuple[Finite, Unit], ...], Field(min_length=1),
                              AfterValidator(_ordered)]

    @classmethod
    def of(cls, tf) -> TransferFunctionPoints:
        """The points of a :class:`~splineviz.core.transfer_function.TransferFunction`."""
        return cls(rgb_points=tuple(tuple(float(v) for v in p) for p in tf.rgb_points),
                   opacity_points=tuple(tuple(float(v) for v in p) for p in tf.opacity_points))

    def transfer_function(self, name: str = "edited"):
        """These points as a :class:`~splineviz.core.transfer_function.TransferFunction`."""
        from splineviz.core.transfer_function import TransferFunction

        return TransferFunction(np.array(self.rgb_points, np.float64),
                                np.array(self.opacity_points, np.float64), name)


def resolve_transfer_function(spec, value_range):
    """The :class:`~splineviz.core.transfer_function.TransferFunction` of a volume node's
    :attr:`VolumeNode.transfer_function_spec`: edited points as they are, a preset placed
    on ``value_range`` (lo, hi) of the data, a ParaView JSON file with its own values."""
    if isinstance(spec, TransferFunctionPoints):
        return spec.transfer_function()
    from splineviz.core.transfer_function import resolve

    return resolve(spec, value_range)


def reference(*types: str, alias: str | None = None) -> Any:
    """A field holding the id of another node (None: none). Without ``alias`` it is one of
    the object's session ``inputs``, filled from an input of one of the session object
    ``types``; with ``alias`` a property of that name."""
    return Field(default=None, alias=alias,
                 json_schema_extra=None if alias else {"inputs": list(types)})


def origin(default=None, default_factory=None) -> Any:
    """A field saying where a node's data comes from (a path, read options, a source)."""
    if default_factory is not None:
        return Field(default_factory=default_factory, json_schema_extra={"origin": True})
    return Field(default=default, json_schema_extra={"origin": True})


def per_view(default) -> Any:
    """A field that sessions write into their views (a split, the side an object shows
    in), not as a property of the object."""
    return Field(default=default, json_schema_extra={"view": True})


def is_required_in_documents(info) -> bool:
    """Whether a session must state the field's value (its default is the node's only)."""
    return _marked(info, "required")


def _marked(info, key: str) -> bool:
    return isinstance(info.json_schema_extra, dict) and key in info.json_schema_extra


def is_reference(info) -> bool:
    """Whether a field (pydantic ``FieldInfo``) is an input :func:`reference`."""
    return _marked(info, "inputs")


def is_origin(info) -> bool:
    """Whether a field is an :func:`origin` field."""
    return _marked(info, "origin")


#: default colours of successive isosurfaces of one volume (qualitative: tell them apart)
PALETTE = (FRONT_COLOR, (0.55, 0.80, 0.55), (0.90, 0.50, 0.45), (0.60, 0.65, 0.95))
#: the widest range of smoothing sigmas offered (voxels)
MAX_SIGMA = 8.0
#: where an object shows while the view is split in two (:attr:`ViewNode.split`): in both
#: views, or only in the left or the right one (3D Slicer's per-view visibility)
SIDES = ("both", "left", "right")
Side = Literal["both", "left", "right"]


class ModelError(SplinevizError, ValueError):
    """A scene property set to a value it cannot take (one sentence, no traceback)."""


def _describe(exc: ValidationError) -> str:
    e = exc.errors()[0]
    loc = ".".join(str(p) for p in e.get("loc", ()))
    return f"{loc}: {e.get('msg', 'invalid value').rstrip('.')}"


class Node(EventedModel):
    """Base of all scene nodes: an id and a display name.

    Assigning a bad value raises :class:`ModelError` and leaves the node unchanged. Fields of
    a subclass are declared in the order sessions write them (``visible`` among them, where
    a node can be hidden).
    """

    model_config = ConfigDict(arbitrary_types_allowed=True, validate_assignment=True,
                              extra="forbid", validate_by_name=True, validate_by_alias=True)

    id: str = ""
    name: str = ""

    #: short name of the node's kind (set by subclasses)
    kind: str = Field(default="", exclude=True, frozen=True)
    #: rules across properties that a saved document must keep; the node itself allows
    #: them broken for a moment (a panel moves one end of a range past the other)
    document_rules: ClassVar[tuple] = ()

    def __init__(self, **data: Any) -> None:
        try:
            super().__init__(**data)
        except ValidationError as exc:
            raise ModelError(f"{type(self).__name__} {data.get('name') or data.get('id', '')}: "
                             f"{_describe(exc)}") from None

    def __setattr__(self, name: str, value: Any) -> None:
        try:
            super().__setattr__(name, value)
        except ValidationError as exc:
            raise ModelError(f"{type(self).__name__} {self.name or self.id}: "
                             f"{_describe(exc)}") from None

    def update(self, values: dict | None = None, recurse: bool = True, **kwargs) -> None:
        """Set several properties; listeners of ``node.events`` hear of them only once all
        are set (a camera is never seen half moved)."""
        super().update({**(values or {}), **kwargs}, recurse=recurse)

    def state(self) -> dict:
        """The properties that differ from their defaults, in field order, as JSON values
        under their session names (napari's ``_get_state``); ``type(node)(**state)`` makes
        the node again, apart from its data."""
        return self.model_dump(mode="json", exclude_defaults=True, by_alias=True,
                               exclude={"id", "name", "kind"})

    @classmethod
    def properties(cls) -> dict:
        """``{field name: FieldInfo}`` of the plain properties (no data, :func:`origin`,
        input :func:`reference` or :func:`per_view` fields), in field order."""
        return {k: f for k, f in cls.model_fields.items()
                if k not in ("id", "name", "kind") and not f.exclude
                and not any(_marked(f, m) for m in ("origin", "inputs", "view"))}

    @classmethod
    def references(cls) -> dict:
        """``{field name: session object types it takes}`` of the input references."""
        return {k: tuple(f.json_schema_extra["inputs"]) for k, f in cls.model_fields.items()
                if is_reference(f)}


class VolumeNode(Node):
    """A volume: where it came from, its samples and the Gaussian smoothing applied to them.

    ``data`` is the original (never replaced by smoothing); ``smoothed`` is the data the
    isosurfaces use when ``sigma > 0``. ``path`` and the read options, or ``source`` (a
    synthetic source of a plugin) say how to load it again; a volume with neither is written
    beside the session when one is saved.
    """

    kind: str = Field(default="volume", exclude=True, frozen=True)
    path: str | None = origin()
    read_options: dict = origin(default_factory=dict)
    source: str | None = origin()
    sigma: Annotated[float, Field(ge=0.0, le=MAX_SIGMA, allow_inf_nan=False)] = 0.0
    show_outline: bool = True
    visible: bool = True
    #: direct volume rendering of the samples (splineviz.render.volume_rendering)
    volume_rendering: bool = False
    #: its transfer function: a preset of splineviz.core.transfer_function (placed on the
    #: data range) or a ParaView JSON colour-map preset file
    transfer_function: TransferFunctionName = "ct-bone"
    #: the transfer function edited in the GUI (it replaces ``transfer_function``, the one
    #: it was edited from; None: that one as it is)
    transfer_function_points: TransferFunctionPoints | None = None
    #: the spline model it samples, and whether it is shaded from the spline's gradient
    rendering_model: ModelName = "cubic-c1"
    rendering_shade: bool = True
    #: in-memory samples, or a lazily read chunked volume (rendered in bricks)
    data: Volume | ChunkedVolume | None = Field(default=None, exclude=True, repr=False)
    smoothed: Volume | None = Field(default=None, exclude=True, repr=False)
    #: the sigma ``smoothed`` was made with
    smoothed_sigma: float = Field(default=0.0, exclude=True)
    #: read as a series of time steps (a 4-D file's time axis, a folder or a file pattern:
    #: :func:`~splineviz.io.time_series.open_time_series`); ``data`` is step ``time_index``
    time_series: bool = False
    time_index: Annotated[int, Field(ge=0, le=MAX_FRAMES)] = 0
    #: added to the series' times on the scene's time line (volumes whose times differ)
    time_offset: Finite = 0.0
    #: steps per second while the scene plays
    play_rate: Annotated[float, Field(gt=0.0, le=1000.0, allow_inf_nan=False)] = 10.0
    #: the steps (:class:`~splineviz.io.time_series.TimeSeries`) of a time-varying volume
    series: TimeSeries | None = Field(default=None, exclude=True, repr=False)

    @model_validator(mode="after")
    def _step_in_series(self):
        if self.series is not None and self.time_index >= len(self.series):
            raise ValueError(f"time_index {self.time_index} is past the last of "
                             f"{len(self.series)} steps")
        return self

    def __setattr__(self, name: str, value: Any) -> None:
        # checked before the assignment, so that a refused step leaves the node unchanged
        if name == "time_index" and self.series is not None and \
                isinstance(value, int) and value >= len(self.series):
            raise ModelError(f"volume {self.name or self.id}: time_index {value} is past the "
                             f"last of {len(self.series)} steps")
        super().__setattr__(name, value)

    @property
    def times(self) -> tuple[float, ...]:
        """The time of each step on the scene's time line (the series' times plus
        ``time_offset``); one time for a volume that does not vary."""
        if self.series is None:
            return (self.time_offset,)
        return tuple(t + self.time_offset for t in self.series.times)

    @property
    def time(self) -> float:
        """The time of the step shown, on the scene's time line."""
        return self.times[self.time_index] if self.series is not None else self.time_offset

    @property
    def time_unit(self) -> str:
        """The unit of :attr:`times` (``""`` when the data do not say)."""
        return self.series.unit if self.series is not None else ""

    @property
    def transfer_function_spec(self):
        """What the renderers map values with (:func:`resolve_transfer_function`): the
        edited points, else the preset name or JSON file."""
        if self.transfer_function_points is not None:
            return self.transfer_function_points
        return self.transfer_function

    @property
    def active(self) -> Volume:
        """The samples the isosurfaces use: the smoothed data when ``sigma > 0`` (the last
        smoothing made, while a new one is computed), else the original."""
        if self.sigma > 0 and self.smoothed is not None:
            return self.smoothed
        return self.data

    @property
    def smoothing_pending(self) -> bool:
        """Whether ``sigma`` asks for smoothed data that has not been made yet."""
        return self.sigma > 0 and (self.smoothed is None or self.smoothed_sigma != self.sigma)

    def set_smoothed(self, volume: Volume, sigma: float) -> None:
        """Store the data smoothed with ``sigma`` (ignored if ``sigma`` is outdated)."""
        if sigma != self.sigma:
            return
        self.smoothed_sigma = float(sigma)
        self.smoothed = volume

    @property
    def bounds(self) -> tuple:
        """The world box of the data: its grid's box, turned by an oblique scan's direction
        (:func:`splineviz.core.frame.world_bounds`)."""
        from splineviz.core.frame import world_bounds

        return world_bounds(self.data)


class IsosurfaceNode(Node):
    """One spline isosurface of a volume (thesis ch. 6)."""

    kind: str = Field(default="isosurface", exclude=True, frozen=True)
    volume_id: str = reference("VolumeFile", "Source")
    #: (a session must state it: no default there)
    isovalue: Finite = Field(default=0.0, json_schema_extra={"required": True})
    model: ModelName = "to-quadratic"
    k: Annotated[int, Field(ge=1, le=16)] = 2
    #: what draws it: ray casting, cell projection, or ``"auto"`` (by the machine:
    #: :func:`splineviz.core.renderers.choose_renderer`)
    renderer: RendererName = AUTO
    color: RGB = (0.9, 0.9, 0.9)
    opacity: Annotated[float, Field(gt=0.0, le=1.0, allow_inf_nan=False)] = 1.0
    visible: bool = True
    material: Literal[tuple(MATERIALS)] = "default"
    #: colour by (:mod:`splineviz.core.colour_by`): field, map, range mode, manual range and
    #: the volume node whose values colour the surface when ``color_by == "volume"``
    color_by: Literal[FIELDS] = "none"
    color_map: Literal[COLORMAPS] = "viridis"
    color_range: Literal[RANGE_MODES] = "auto"
    color_min: Finite = 0.0
    color_max: Finite = 1.0
    color_volume_id: NodeId | None = reference(alias="color_volume")
    #: the isosurface node whose surface the distance is measured to (``"distance"``)
    color_isosurface_id: NodeId | None = reference(alias="color_isosurface")
    #: the view it shows in while the view is split (:data:`SIDES`)
    shown_in: Side = per_view("both")

    document_rules: ClassVar[tuple] = (
        (lambda p: p["color_min"] < p["color_max"], "color_min must be below color_max"),)

    def model_options(self) -> dict:
        """Keyword arguments of the spline model (``k`` for the models that take it)."""
        from splineviz.core.splines.registry import model_spec

        return {"k": self.k} if "k" in model_spec(self.model).options else {}


class PointsNode(Node):
    """A point cloud shown as points."""

    kind: str = Field(default="points", exclude=True, frozen=True)
    path: str | None = origin()
    #: the reader's format name when the file's suffix does not tell it
    format: str | None = origin()
    color: RGB = (0.8, 0.8, 0.8)
    point_size: Annotated[float, Field(gt=0.0, le=100.0, allow_inf_nan=False)] = 3.0
    opacity: Unit = 1.0
    visible: bool = True
    shown_in: Side = per_view("both")
    data: PointCloud | None = Field(default=None, exclude=True, repr=False)


class MeshNode(Node):
    """A triangle mesh: read from a file or made by remeshing a point cloud (thesis ch. 7).

    ``points_id``, ``edge_length``, ``rho`` and ``sharp_creases`` record how a remeshed mesh
    was made; ``stats`` is its :func:`splineviz.mesh_quality` report.
    """

    kind: str = Field(default="mesh", exclude=True, frozen=True)
    path: str | None = origin()
    points_id: str | None = reference("PointsFile")
    color: RGB = (0.8, 0.8, 0.8)
    opacity: Unit = 1.0
    show_edges: bool = False
    visible: bool = True
    edge_length: Positive | None = None
    rho: Annotated[float, Field(gt=0.0, le=10.0, allow_inf_nan=False)] | None = None
    sharp_creases: bool | None = None
    shown_in: Side = per_view("both")
    vertices: np.ndarray | None = Field(default=None, exclude=True, repr=False)
    faces: np.ndarray | None = Field(default=None, exclude=True, repr=False)
    normals: np.ndarray | None = Field(default=None, exclude=True, repr=False)
    stats: dict = Field(default_factory=dict, exclude=True, repr=False)

    @property
    def has_normals(self) -> bool:
        return self.normals is not None and len(self.normals) == len(self.vertices)

    def to_polydata(self):
        """The mesh as writers and renderers take it (``pyvista.PolyData`` made by
        :func:`splineviz.io.meshes.as_polydata`), its normals as the active float32 point
        normals (PLY ``nx ny nz``)."""
        from splineviz.io.meshes import as_polydata

        poly = as_polydata((self.vertices, self.faces))
        if self.has_normals:
            poly.point_data["Normals"] = np.asarray(self.normals, dtype=np.float32)
            poly.point_data.active_normals_name = "Normals"
        return poly


class ClipPlaneNode(Node):
    """A clip plane keeping the side its normal points to (docs/api.md ``clip_planes``).

    ``volume_id`` names the volume whose isosurfaces it cuts; None cuts every isosurface.
    """

    kind: str = Field(default="clip_plane", exclude=True, frozen=True)
    volume_id: str | None = reference("VolumeFile", "Source")
    origin: Vec3 = (0.0, 0.0, 0.0)
    normal: Normal = (1.0, 0.0, 0.0)
    enabled: bool = True
    show_widget: bool = True

    def as_pair(self) -> tuple[tuple, tuple]:
        """``(origin, normal)`` as :meth:`splineviz.RayCaster.render` takes it."""
        return tuple(self.origin), tuple(self.normal)


class SectionNode(Node):
    """Exact cross-section curves (:mod:`splineviz.core.sections`) of an isosurface with a
    clip plane (``plane_id``) or with another isosurface (``other_id``), shown as lines.

    ``curves`` holds the last computed :class:`~splineviz.core.sections.SectionCurve` list
    (derived data: never written to sessions, recomputed when an input changes).
    """

    kind: str = Field(default="section", exclude=True, frozen=True)
    isosurface_id: str = reference("Isosurface")
    plane_id: str | None = reference("ClipPlane")
    other_id: str | None = reference("Isosurface")
    color: RGB = (0.95, 0.25, 0.2)
    line_width: Annotated[float, Field(gt=0.0, le=20.0, allow_inf_nan=False)] = 3.0
    visible: bool = True
    curves: list | None = Field(default=None, exclude=True, repr=False)

    @property
    def inputs(self) -> list[str]:
        """The isosurface and the plane or second isosurface it intersects."""
        return [self.isosurface_id, self.plane_id if self.plane_id is not None
                else self.other_id]


class CameraNode(Node):
    """The view's camera, VTK conventions (like :class:`splineviz.core.camera.Camera`)."""

    kind: str = Field(default="camera", exclude=True, frozen=True)
    position: Vec3 = (0.0, 0.0, 1.0)
    focal_point: Vec3 = (0.0, 0.0, 0.0)
    view_up: Vec3 = (0.0, 1.0, 0.0)
    view_angle: Annotated[float, Field(gt=0.0, lt=180.0, allow_inf_nan=False)] = 30.0
    parallel_projection: bool = False
    parallel_scale: Positive = 1.0

    document_rules: ClassVar[tuple] = (
        (lambda p: tuple(p["position"]) != tuple(p["focal_point"]),
         "camera position and focal point must differ"),)

    def pose(self) -> dict:
        """The fields that place the camera (one dict, to compare or copy)."""
        return {k: getattr(self, k) for k in self.properties()}


#: the view layouts: the 3-D view alone, the 3-D view with the three slices (Slicer's
#: "four-up"), one slice alone (:mod:`splineviz.model.slices`)
LAYOUTS = ("3d", "four-up", "one-slice")
SliceName = Literal["axial", "coronal", "sagittal"]


class ViewNode(Node):
    """What the view shows around the objects: background (a gradient up to
    ``background2`` when set, as ParaView's), axes, scale bar, and whether it is split
    into two side-by-side views with one camera (ParaView's "Link Camera"), each showing
    the objects whose ``shown_in`` names its side or ``"both"``."""

    kind: str = Field(default="view", exclude=True, frozen=True)
    background: RGB = (0.1, 0.1, 0.15)
    #: the colour at the top of a gradient background (None: a plain background)
    background2: RGB | None = None
    show_axes: bool = True
    show_scale: bool = True
    #: the scene's current time drawn in a corner while a volume varies in time (sessions
    #: write it only when off)
    show_time: bool = True
    split: bool = per_view(False)
    #: the window's layout of the 3-D view and the slice views (see
    #: :class:`splineviz.model.slices.SliceViewNode`; sessions write it only when not "3d")
    slice_layout: Literal[LAYOUTS] = "3d"
    #: the slice the "one-slice" layout shows
    slice_single: SliceName = "axial"
    #: where the slice planes meet (world); None: the centre of the volume shown
    crosshair: Vec3 | None = None


#: node kind -> node class
NODE_TYPES = {cls.model_fields["kind"].default: cls
              for cls in (VolumeNode, IsosurfaceNode, PointsNode, MeshNode, ClipPlaneNode,
                          SectionNode)}


def mesh_arrays(mesh) -> tuple[np.ndarray, np.ndarray]:
    """``(V, 3)`` float64 vertices and ``(F, 3)`` int64 triangles of a triangle mesh given
    as a pair of arrays or anything with ``points`` and VTK-style ``faces`` (pyvista)."""
    if isinstance(mesh, tuple):
        v, f = mesh
        return np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64).reshape(-1, 3)
    faces = np.asarray(mesh.faces).reshape(-1, 4)
    if len(faces) and not np.all(faces[:, 0] == 3):
        raise ModelError("only triangle meshes can be shown")
    return np.asarray(mesh.points, dtype=np.float64), faces[:, 1:].astype(np.int64)
