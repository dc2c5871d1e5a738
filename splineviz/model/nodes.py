"""The objects of a scene as evented nodes (no Qt, no VTK).

Each node is a :class:`psygnal.EventedModel` (pydantic fields with one signal per field, the
napari habit): setting ``node.isovalue = 40.0`` validates the value and emits
``node.events.isovalue``; views (the VTK scene of :mod:`splineviz.render`, the Qt panels of
:mod:`splineviz.gui`) subscribe to those signals and never hold state of their own.

Heavy data (the samples of a volume, a point cloud, a mesh's arrays) live in fields that are
never written to sessions (``exclude=True``); everything else is a plain property whose
non-default values :meth:`Node.state` returns for session files.

Conventions: colours are RGB in [0, 1]; points and vectors are world coordinates; meshes
are ``(V, 3)`` float vertex and ``(F, 3)`` int triangle arrays (DESIGN.md: pyvista objects
only at the render/io boundary).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from psygnal import EventedModel
from pydantic import ConfigDict, Field, ValidationError, field_validator

from splineviz.core.chunked import ChunkedVolume
from splineviz.core.errors import SplinevizError
from splineviz.core.points import PointCloud
from splineviz.core.volume import Volume
from splineviz.io.session import nonzero_normal

Unit = Annotated[float, Field(ge=0.0, le=1.0, allow_inf_nan=False)]
RGB = tuple[Unit, Unit, Unit]
Finite = Annotated[float, Field(allow_inf_nan=False)]
Vec3 = tuple[Finite, Finite, Finite]

#: default colours of successive isosurfaces of one volume (qualitative: tell them apart)
PALETTE = ((0.93, 0.78, 0.55), (0.55, 0.80, 0.55), (0.90, 0.50, 0.45), (0.60, 0.65, 0.95))
#: named Phong materials: (ambient, diffuse, specular, shininess)
MATERIALS = {
    "default": (0.15, 0.75, 0.35, 24.0),
    "matte": (0.2, 0.8, 0.0, 1.0),
    "shiny": (0.1, 0.7, 0.7, 60.0),
    "metal": (0.25, 0.55, 0.9, 12.0),
}
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
    """Base of all scene nodes: an id, a display name and visibility.

    Assigning a bad value raises :class:`ModelError` and leaves the node unchanged.
    """

    model_config = ConfigDict(arbitrary_types_allowed=True, validate_assignment=True,
                              extra="forbid")

    id: str = ""
    name: str = ""
    visible: bool = True

    #: session object type written for this node (set by subclasses)
    kind: str = Field(default="", exclude=True, frozen=True)

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
        """The properties that differ from their defaults (for session files)."""
        return self.model_dump(mode="json", exclude_defaults=True,
                               exclude={"id", "name", "kind"})


class VolumeNode(Node):
    """A volume: where it came from, its samples and the Gaussian smoothing applied to them.

    ``data`` is the original (never replaced by smoothing); ``smoothed`` is the data the
    isosurfaces use when ``sigma > 0``. ``path`` and the read options, or ``source`` (a
    synthetic source of a plugin) say how to load it again; a volume with neither is written
    beside the session when one is saved.
    """

    kind: str = Field(default="volume", exclude=True, frozen=True)
    path: str | None = None
    read_options: dict = Field(default_factory=dict)
    source: str | None = None
    sigma: Annotated[float, Field(ge=0.0, le=MAX_SIGMA, allow_inf_nan=False)] = 0.0
    show_outline: bool = True
    #: in-memory samples, or a lazily read chunked volume (rendered in bricks)
    data: Volume | ChunkedVolume | None = Field(default=None, exclude=True, repr=False)
    smoothed: Volume | None = Field(default=None, exclude=True, repr=False)
    #: the sigma ``smoothed`` was made with
    smoothed_sigma: float = Field(default=0.0, exclude=True)

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
        return self.data.bounds


class IsosurfaceNode(Node):
    """One spline isosurface of a volume (thesis ch. 6)."""

    kind: str = Field(default="isosurface", exclude=True, frozen=True)
    volume_id: str = ""
    model: str = "cubic-c1"
    k: Annotated[int, Field(ge=1, le=16)] = 2
    isovalue: Finite = 0.0
    color: RGB = PALETTE[0]
    opacity: Annotated[float, Field(gt=0.0, le=1.0, allow_inf_nan=False)] = 1.0
    material: str = "default"
    #: colour by (:mod:`splineviz.core.colour_by`): field, map, range mode, manual range and
    #: the volume node whose values colour the surface when ``color_by == "volume"``
    color_by: str = "none"
    color_map: str = "viridis"
    color_range: str = "auto"
    color_min: Finite = 0.0
    color_max: Finite = 1.0
    color_volume_id: str | None = None
    #: the isosurface node whose surface the distance is measured to (``"distance"``)
    color_isosurface_id: str | None = None
    #: the view it shows in while the view is split (:data:`SIDES`)
    shown_in: Side = "both"

    @field_validator("color_by", "color_map", "color_range", "model")
    @classmethod
    def _known_choice(cls, v: str, info) -> str:
        from splineviz.core.colour_by import COLORMAPS, FIELDS, RANGE_MODES
        from splineviz.core.splines import MODELS

        what, choices = {"color_by": ("colour-by field", FIELDS),
                         "color_map": ("colour map", COLORMAPS),
                         "color_range": ("range mode", RANGE_MODES),
                         "model": ("spline model", MODELS)}[info.field_name]
        if v not in choices:
            raise ValueError(f"unknown {what} {v!r}; choose one of {', '.join(choices)}")
        return v

    def model_options(self) -> dict:
        """Keyword arguments of the spline model (``k`` for the models that take it)."""
        from splineviz.core.splines import MODELS

        return {"k": self.k} if "k" in MODELS[self.model].options else {}

    @field_validator("material")
    @classmethod
    def _known_material(cls, v: str) -> str:
        if v not in MATERIALS:
            raise ValueError(f"unknown material {v!r}; choose one of {', '.join(MATERIALS)}")
        return v


class PointsNode(Node):
    """A point cloud shown as points."""

    kind: str = Field(default="points", exclude=True, frozen=True)
    path: str | None = None
    color: RGB = (0.85, 0.85, 0.9)
    point_size: Annotated[float, Field(gt=0.0, le=100.0, allow_inf_nan=False)] = 3.0
    opacity: Unit = 1.0
    shown_in: Side = "both"
    data: PointCloud | None = Field(default=None, exclude=True, repr=False)


class MeshNode(Node):
    """A triangle mesh: read from a file or made by remeshing a point cloud (thesis ch. 7).

    ``points_id``, ``edge_length`` and ``rho`` record how a remeshed mesh was made; ``stats``
    is its :func:`splineviz.mesh_quality` report.
    """

    kind: str = Field(default="mesh", exclude=True, frozen=True)
    path: str | None = None
    points_id: str | None = None
    edge_length: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None
    rho: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None
    color: RGB = (0.75, 0.85, 0.95)
    opacity: Unit = 1.0
    show_edges: bool = True
    shown_in: Side = "both"
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
    """A clip plane keeping the side its normal points to (DESIGN.md ``clip_planes``).

    ``volume_id`` names the volume whose isosurfaces it cuts; None cuts every isosurface.
    """

    kind: str = Field(default="clip_plane", exclude=True, frozen=True)
    volume_id: str | None = None
    origin: Vec3 = (0.0, 0.0, 0.0)
    normal: Vec3 = (1.0, 0.0, 0.0)
    enabled: bool = True
    show_widget: bool = True

    _nonzero = field_validator("normal")(classmethod(lambda cls, v: nonzero_normal(v)))

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
    isosurface_id: str = ""
    plane_id: str | None = None
    other_id: str | None = None
    color: RGB = (0.95, 0.25, 0.2)
    line_width: Annotated[float, Field(gt=0.0, le=20.0, allow_inf_nan=False)] = 3.0
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
    parallel_scale: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] = 1.0

    def pose(self) -> dict:
        """The fields that place the camera (one dict, to compare or copy)."""
        return {k: getattr(self, k) for k in ("position", "focal_point", "view_up",
                                              "view_angle", "parallel_projection",
                                              "parallel_scale")}


class ViewNode(Node):
    """What the view shows around the objects: background, axes, scale bar, and whether it
    is split into two side-by-side views with one camera (ParaView's "Link Camera"), each
    showing the objects whose ``shown_in`` names its side or ``"both"``."""

    kind: str = Field(default="view", exclude=True, frozen=True)
    background: RGB = (0.10, 0.10, 0.14)
    show_axes: bool = True
    show_scale: bool = True
    split: bool = False


#: session object type -> node class (the one table the session conversion reads)
NODE_TYPES = {cls.model_fields["kind"].default: cls
              for cls in (VolumeNode, IsosurfaceNode, PointsNode, MeshNode, ClipPlaneNode)}


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
