"""Session files (``*.svs``): a ParaView-like, versioned JSON description of a scene.

Document layout (schema :data:`SCHEMA_VERSION`)::

    {
      "format": "splineviz-session",
      "schema_version": 4,
      "app_version": "0.1.0",
      "objects": [                          # pipeline, inputs before outputs
        {"id": "vol1", "type": "VolumeFile", "name": "bonsai",
         "properties": {"path": "data/bonsai.vti"}},
        {"id": "iso1", "type": "Isosurface", "inputs": ["vol1"],
         "properties": {"isovalue": 40.0, "model": "cubic-c1", "color": [0.8, 0.6, 0.3]}},
        {"id": "clip1", "type": "ClipPlane", "inputs": ["vol1"],
         "properties": {"origin": [128, 128, 128], "normal": [1, 0, 0]}}
      ],
      "views": [{"id": "view1", "camera": {...}, "background": [...], "lights": [...],
                 "layout": {...}}],
      "animation": {"frames": 120, "tracks": [...]}   # only when the scene has one
    }

A clip plane cuts the isosurfaces of the volumes it takes as input, the isosurfaces it
takes as input, or, with no input, every isosurface of the scene.

Only properties that differ from their defaults are written (the napari ``_get_state`` habit).
Data paths are stored relative to the session file and resolved against its folder on load.
A path whose real location (``..`` and symbolic links followed) is outside that folder, such
as ``../data/ct.nrrd`` or a link to ``/etc/passwd``, is refused with a
:class:`~splineviz.io.errors.SessionOutsideFolderError` unless the caller opts in
(``allow_outside=True``; ``--allow-outside-data`` on the command line; the GUI asks the user):
a session received from someone else must not read files of the receiver's choosing. A
missing file can be re-pointed with the ``repoint`` callback of :func:`load_session`. Every
path must name a regular file or a folder: device files and pipes (``/dev/zero``, FIFOs)
that could hang a reader are refused.

Safety: a session is data only. It is parsed with :func:`json.loads` (NaN/Infinity and
duplicate keys refused), validated by pydantic models that forbid unknown keys, bounded in
size, depth and number magnitude, and never names code to import or run. A malformed session
raises a :class:`~splineviz.io.errors.SessionError` and changes nothing.

Migrations: :data:`MIGRATIONS` maps a schema version to the function that lifts a document
to the next version; :func:`migrate` applies them in order, then drops the entries that
schema 1-4 allowed but nothing read (``Remesh`` objects, a view's ``size``, layout spans).

Object types: where an object's data comes from (a file and its read options, a source) is
declared here; every other property is declared once, by the scene node the object becomes
(:mod:`splineviz.model.schema` derives the properties models from the nodes).
"""

from __future__ import annotations

import json
import logging
import os
import re
import stat
from collections.abc import Callable
from pathlib import Path, PurePosixPath
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
)

from splineviz.core.registry import load_extensions
from splineviz.io._util import atomic_write_bytes, confined, outside_allowed
from splineviz.io.errors import (
    SessionError,
    SessionOutsideFolderError,
    SessionPathError,
    SessionVersionError,
)

_log = logging.getLogger(__name__)

FORMAT = "splineviz-session"
SCHEMA_VERSION = 4
#: largest session file read, in bytes (a scene description, not data)
MAX_SESSION_BYTES = 16 * 2**20
#: largest coordinate or value magnitude accepted (beyond it float32 rendering breaks down)
MAX_MAGNITUDE = 1e15
#: most pipeline objects / views / lights in one session
MAX_OBJECTS = 10_000
MAX_VIEWS = 64
MAX_LIGHTS = 16
#: longest stored path or name
MAX_TEXT = 4096

#: pattern of object and view ids
ID_PATTERN = r"^[A-Za-z_][A-Za-z0-9_.\-]{0,63}$"

Finite = Annotated[float, Field(allow_inf_nan=False, ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]
Unit = Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=1.0)]
Vec3 = tuple[Finite, Finite, Finite]
RGB = tuple[Unit, Unit, Unit]
Text = Annotated[str, Field(max_length=MAX_TEXT)]
Size = Annotated[int, Field(ge=2, le=4096)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


def _check_path_text(v: str) -> str:
    if not v or "\x00" in v:
        raise ValueError("a data path must be a non-empty string without NUL characters")
    return v


# ---------------------------------------------------------------------------- objects
# Where an object's data comes from is io's to declare (a file and the options to read it,
# or a plugin's source); an object's other properties are declared once, by the scene node
# the object becomes (:mod:`splineviz.model.schema` derives each properties model from them
# and registers it with :func:`register_object_type`).
class VolumeFileOrigin(_Model):
    """A volume read with :func:`~splineviz.io.read_volume`; raw files need dims/dtype."""

    path: Text
    format: str | None = None
    dims: tuple[Size, Size, Size] | None = None
    dtype: Literal["uint8", "int8", "uint16", "int16", "uint32", "int32", "float32",
                   "float64"] | None = None
    byteorder: Literal["little", "big"] = "little"
    offset: Annotated[int, Field(ge=0, le=2**40)] = 0
    spacing: tuple[Annotated[float, Field(gt=0, le=MAX_MAGNITUDE, allow_inf_nan=False)],
                   ...] | None = None
    origin: Vec3 | None = None

    _v = field_validator("path")(classmethod(lambda cls, v: _check_path_text(v)))


#: the read options of a volume file (the fields of :class:`VolumeFileOrigin` but ``path``)
READ_OPTIONS = tuple(k for k in VolumeFileOrigin.model_fields if k != "path")


class SourceOrigin(_Model):
    """A synthetic source offered by a plugin (see :mod:`splineviz.plugins`)."""

    source: Annotated[str, Field(pattern=r"^[A-Za-z0-9_.\-]{1,64}$")]
    shape: tuple[Size, Size, Size] = (64, 64, 64)


class PointsFileOrigin(_Model):
    """A point cloud read with :func:`~splineviz.io.read_points`."""

    path: Text
    format: str | None = None

    _v = field_validator("path")(classmethod(lambda cls, v: _check_path_text(v)))


class MeshFileOrigin(_Model):
    """A triangle mesh file (with a PointsFile input: the remeshing that made it)."""

    path: Text

    _v = field_validator("path")(classmethod(lambda cls, v: _check_path_text(v)))


class CameraBase(_Model):
    """A view's camera, VTK conventions (as :class:`splineviz.core.camera.Camera`). Its
    entries are the properties of the scene's camera node: :func:`camera_model` is this
    class with them (derived and registered by :mod:`splineviz.model.schema`)."""

    def to_camera(self):
        """The :class:`splineviz.core.camera.Camera` of this state (perspective only)."""
        from splineviz.core.camera import Camera, CameraError

        try:
            return Camera(self.position, self.focal_point, view_up=self.view_up,
                          view_angle=self.view_angle)
        except CameraError as exc:
            raise SessionError(f"the session's camera is unusable: {exc}") from None


#: object type -> model of its properties (filled by :func:`register_object_type`)
PROPERTIES: dict[str, type[BaseModel]] = {}
#: the model of a view's camera (set by :func:`register_camera_model`) and of the
#: document's animation (set by :func:`register_animation_model`)
_CAMERA: dict[str, type[CameraBase]] = {}
_ANIMATION: dict[str, type[BaseModel]] = {}


def register_object_type(name: str, properties: type[BaseModel]) -> None:
    """Declare the pipeline object type ``name`` and the model of its properties."""
    PROPERTIES[name] = properties


def register_camera_model(model: type[CameraBase]) -> None:
    """Declare the model of a view's camera (a subclass of :class:`CameraBase`)."""
    _CAMERA["camera"] = model


def register_animation_model(model: type[BaseModel]) -> None:
    """Declare the model of a session's ``animation`` entry (the scene model's
    :class:`~splineviz.model.animation.Animation`)."""
    _ANIMATION["animation"] = model


def _declared() -> None:
    if not PROPERTIES or not _CAMERA or not _ANIMATION:
        # the scene nodes declare the properties (see the comment above the origins); a
        # document read before anything imported the scene model needs them all the same,
        # and the extension hook that ``splineviz`` installs declares them (io never
        # imports the model layer)
        load_extensions()


def object_types() -> dict[str, type[BaseModel]]:
    """Object type -> properties model of every declared pipeline object type."""
    _declared()
    return PROPERTIES


def camera_model() -> type[CameraBase]:
    """The model of a view's camera (:class:`CameraBase` with the camera node's fields)."""
    _declared()
    return _CAMERA["camera"]


def __getattr__(name: str):
    if name == "CameraState":  # the name of the camera model before it was derived
        return camera_model()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class PipelineObject(_Model):
    """One object of the pipeline: its id, type, name, inputs and properties (a model
    of :func:`object_types` for its type)."""

    id: Annotated[str, Field(pattern=ID_PATTERN)]
    type: str
    name: Annotated[str, Field(max_length=200)] = ""
    inputs: Annotated[list[Annotated[str, Field(pattern=ID_PATTERN)]], Field(max_length=64)] = []
    properties: Any = Field(default_factory=dict, validate_default=True)

    @field_validator("type")
    @classmethod
    def _known_type(cls, v: str) -> str:
        types = object_types()
        if v not in types:
            raise ValueError(f"unknown object type {v[:64]!r}; valid: {', '.join(types)}")
        return v

    @field_validator("properties", mode="before")
    @classmethod
    def _typed(cls, v, info: ValidationInfo):
        model = object_types().get(info.data.get("type"))
        if model is None:  # the type was refused already
            return v
        return v if isinstance(v, model) else model.model_validate(v)


#: object type -> (number of inputs allowed (min, max), input types allowed); ``Remesh``
#: is a type of schema 1-4 documents that :func:`migrate` removes (nothing ever read it)
INPUT_RULES: dict[str, tuple[tuple[int, int], tuple[str, ...]]] = {
    "VolumeFile": ((0, 0), ()),
    "Source": ((0, 0), ()),
    "PointsFile": ((0, 0), ()),
    "MeshFile": ((0, 1), ("PointsFile",)),
    "Isosurface": ((1, 1), ("VolumeFile", "Source")),
    "Remesh": ((1, 1), ("PointsFile",)),
    "ClipPlane": ((0, 64), ("VolumeFile", "Source", "Isosurface", "PointsFile", "MeshFile")),
    "Section": ((2, 2), ("Isosurface", "ClipPlane")),
}

#: object types whose ``properties.path`` names a data file
FILE_TYPES = ("VolumeFile", "PointsFile", "MeshFile")


# ---------------------------------------------------------------------------- views
class Light(_Model):
    type: Literal["headlight", "camera", "scene"] = "headlight"
    position: Vec3 = (0.0, 0.0, 1.0)
    focal_point: Vec3 = (0.0, 0.0, 0.0)
    color: RGB = (1.0, 1.0, 1.0)
    intensity: Annotated[float, Field(ge=0, le=100, allow_inf_nan=False)] = 1.0


class Layout(_Model):
    """Cell of the view in the window's grid of views (a split scene: the column)."""

    row: Annotated[int, Field(ge=0, le=15)] = 0
    col: Annotated[int, Field(ge=0, le=15)] = 0


class View(_Model):
    """A render view: camera, background (a gradient up to ``background2`` when set),
    lights, its cell in the layout, the objects it hides, its decorations and the window's
    slice views (layout and crosshair).

    ``lights`` round-trips in documents, but the renderer has one headlight (the shading of
    :mod:`splineviz.core.material`): a scene loaded from a session with other lights says
    so (see :func:`splineviz.model.session.apply_session`).
    """

    id: Annotated[str, Field(pattern=ID_PATTERN)] = "view1"
    type: Literal["RenderView"] = "RenderView"
    camera: Any = Field(default_factory=dict, validate_default=True)
    background: RGB = (0.1, 0.1, 0.15)
    background2: RGB | None = None
    lights: Annotated[list[Light], Field(max_length=MAX_LIGHTS)] = [Light()]
    layout: Layout = Field(default_factory=Layout)
    hidden: Annotated[list[Annotated[str, Field(pattern=ID_PATTERN)]],
                      Field(max_length=MAX_OBJECTS)] = []
    show_axes: bool = True
    show_scale: bool = True
    #: the time of time-varying volumes drawn in the view (written only when off)
    show_time: bool = True
    #: the window's layout of the 3-D view and slice views, the slice a "one-slice" layout
    #: shows and where the slice planes meet (None: the volume's centre). Written only when
    #: not the defaults, so documents of scenes that never used the slice views stay as
    #: they were (schema 4; a reader older than these fields refuses a document using them)
    slice_layout: Literal["3d", "four-up", "one-slice"] = "3d"
    slice_single: Literal["axial", "coronal", "sagittal"] = "axial"
    crosshair: Vec3 | None = None

    @field_validator("camera", mode="before")
    @classmethod
    def _camera(cls, v):
        model = camera_model()
        return v if isinstance(v, model) else model.model_validate(v)


class Session(_Model):
    """A scene: pipeline objects (inputs first) and views.

    Data paths in a loaded session are absolute (resolved against the session's folder);
    :func:`save_session` writes them relative to the new file's folder.
    """

    format: Literal["splineviz-session"] = FORMAT
    schema_version: Literal[4] = SCHEMA_VERSION
    app_version: Annotated[str, Field(max_length=64)] = ""
    objects: Annotated[list[PipelineObject], Field(max_length=MAX_OBJECTS)] = []
    views: Annotated[list[View], Field(max_length=MAX_VIEWS)] = Field(
        default_factory=lambda: [View()])
    #: the scene's animation (keyframed tracks, see :mod:`splineviz.model.animation`);
    #: written only when there is one, so documents without one are those of schema 4
    animation: Any = None

    @field_validator("animation", mode="before")
    @classmethod
    def _animation(cls, v):
        if v is None:
            return None
        _declared()
        model = _ANIMATION["animation"]
        return v if isinstance(v, model) else model.model_validate(v)

    def object(self, obj_id: str):
        """The pipeline object with id ``obj_id``."""
        for o in self.objects:
            if o.id == obj_id:
                return o
        raise KeyError(obj_id)

    def data_files(self) -> list[tuple[str, Path]]:
        """(object id, path) for every object that reads a data file."""
        return [(o.id, Path(o.properties.path)) for o in self.objects if o.type in FILE_TYPES]

    def missing_files(self) -> list[tuple[str, Path]]:
        """Data files that do not exist (to re-point)."""
        return [(i, p) for i, p in self.data_files() if not p.exists()]

    def repoint(self, obj_id: str, new_path) -> None:
        """Point object ``obj_id`` at another data file."""
        obj = self.object(obj_id)
        if obj.type not in FILE_TYPES:
            raise SessionError(f"object {obj_id!r} ({obj.type}) has no data file")
        obj.properties.path = str(Path(os.fspath(new_path)).expanduser().absolute())

    # -- editing (the GUI builds sessions through these, never through widget values)
    def new_id(self, prefix: str) -> str:
        """An unused object id ``<prefix><n>``."""
        used = {o.id for o in self.objects}
        n = 1
        while f"{prefix}{n}" in used:
            n += 1
        return f"{prefix}{n}"

    def add(self, type: str, properties: dict | None = None, *, inputs=(), name: str = "",
            id: str | None = None):
        """Append a pipeline object after validating it and its inputs; returns it.

        Examples
        --------
        >>> s = Session()
        >>> src = s.add("Source", {"source": "marschner-lobb"})
        >>> iso = s.add("Isosurface", {"isovalue": 0.5}, inputs=[src.id])
        >>> iso.id, s.clip_planes_for(iso.id)
        ('isosurface1', [])
        """
        types = object_types()
        if type not in types:
            raise SessionError(f"unknown object type {type!r}; valid: {', '.join(types)}")
        try:
            obj = PipelineObject.model_validate({
                "id": id or self.new_id(type.lower()), "type": type, "name": name,
                "inputs": list(inputs), "properties": properties or {}})
        except ValidationError as exc:
            raise SessionError(f"invalid {type}: {_describe(exc)}") from None
        if any(o.id == obj.id for o in self.objects):
            raise SessionError(f"an object with id {obj.id!r} already exists")
        (lo, hi), allowed = INPUT_RULES[type]
        types = {o.id: o.type for o in self.objects}
        if not lo <= len(obj.inputs) <= hi:
            raise SessionError(f"{type} needs {lo if lo == hi else f'{lo} to {hi}'} input(s), "
                               f"got {len(obj.inputs)}")
        for i in obj.inputs:
            if types.get(i) not in allowed:
                raise SessionError(f"{type} cannot take {i!r} ({types.get(i, 'missing')}) as "
                                   "input")
        self.objects.append(obj)
        return obj

    def remove(self, obj_id: str) -> None:
        """Remove an object that nothing else uses as input."""
        users = [o.id for o in self.objects if obj_id in o.inputs]
        if users:
            raise SessionError(f"{obj_id!r} is the input of {', '.join(users)}; remove those "
                               "first")
        self.object(obj_id)
        self.objects = [o for o in self.objects if o.id != obj_id]
        for v in self.views:
            if obj_id in v.hidden:
                v.hidden = [h for h in v.hidden if h != obj_id]

    # -- scene access for renderers and the GUI (no Qt, no VTK here)
    def clip_planes_for(self, obj_id: str) -> list[tuple[tuple, tuple]]:
        """``(origin, normal)`` of every enabled clip plane that cuts ``obj_id``: planes that
        take it, or (for an isosurface) its volume, as input, and planes with no input, in
        the form :meth:`splineviz.RayCaster.render` expects."""
        targets = {obj_id}
        obj = self.object(obj_id)
        if obj.type == "Isosurface":
            targets.update(obj.inputs)
        return [(o.properties.origin, o.properties.normal) for o in self.objects
                if o.type == "ClipPlane" and o.properties.enabled
                and (not o.inputs or targets.intersection(o.inputs))]

    def visible(self, view_id: str | None = None) -> list:
        """Displayable objects (isosurfaces, point clouds, meshes) shown in a view."""
        view = self.views[0] if view_id is None else next(
            (v for v in self.views if v.id == view_id), None)
        if view is None:
            raise KeyError(view_id)
        return [o for o in self.objects
                if o.type in ("Isosurface", "PointsFile", "MeshFile")
                and o.properties.visible and o.id not in view.hidden]

    def load_volume(self, obj_id: str, *, allow_outside: bool = False):
        """The :class:`~splineviz.Volume` behind ``obj_id`` (a VolumeFile, a Source, or an
        Isosurface, whose input is read); ``allow_outside`` as in
        :func:`~splineviz.io.volumes.read_volume` (for the file's own header)."""
        from splineviz.core.sources import source_volume
        from splineviz.io.volumes import read_volume

        obj = self.object(obj_id)
        if obj.type == "Isosurface":
            obj = self.object(obj.inputs[0])
        if obj.type == "Source":
            return source_volume(obj.properties.source, obj.properties.shape)
        if obj.type != "VolumeFile":
            raise SessionError(f"object {obj_id!r} ({obj.type}) holds no volume")
        p = obj.properties
        return read_volume(p.path, format=p.format, dims=p.dims, dtype=p.dtype,
                           byteorder=p.byteorder, offset=p.offset, spacing=p.spacing,
                           origin=p.origin, allow_outside=allow_outside)

    def load_points(self, obj_id: str):
        """The :class:`~splineviz.PointCloud` of a PointsFile."""
        from splineviz.io.points import read_points

        obj = self.object(obj_id)
        if obj.type != "PointsFile":
            raise SessionError(f"object {obj_id!r} ({obj.type}) holds no point cloud")
        return read_points(obj.properties.path, format=obj.properties.format)

    def to_document(self, base_dir=None) -> dict:
        """The JSON document (non-default properties only), paths relative to ``base_dir``."""
        objects = []
        for o in self.objects:
            d = o.model_dump(mode="json", exclude_defaults=True)
            entry = {"id": o.id, "type": o.type}  # the discriminator is always written
            for key in ("name", "inputs"):
                if key in d:
                    entry[key] = d[key]
            entry["properties"] = o.properties.model_dump(mode="json", exclude_defaults=True)
            if "path" in entry["properties"] and base_dir is not None:
                entry["properties"]["path"] = _relative(entry["properties"]["path"],
                                                        Path(base_dir))
            objects.append(entry)
        views = []
        for v in self.views:
            entry = {"id": v.id, "type": v.type}
            camera = v.camera.model_dump(mode="json", exclude_defaults=True)
            if camera:
                entry["camera"] = camera
            entry.update((k, val) for k, val in v.model_dump(
                mode="json", exclude_defaults=True, exclude={"camera"}).items()
                if k not in ("id", "type"))
            views.append(entry)
        doc = {"format": FORMAT, "schema_version": SCHEMA_VERSION,
               "app_version": _app_version(),  # the version that wrote this document
               "objects": objects, "views": views}
        if self.animation is not None:
            doc["animation"] = self.animation.model_dump(mode="json", exclude_defaults=True)
        return doc


def _app_version() -> str:
    from splineviz import __version__

    return __version__


def _relative(path: str, base: Path) -> str:
    """``path`` relative to ``base`` in POSIX form. Paths of a loaded session are absolute;
    a relative path set in memory (e.g. by :meth:`Session.add`) is relative to the current
    directory, like any path the user typed."""
    p = Path(path).expanduser().absolute()
    try:
        rel = os.path.relpath(p, base.absolute())
    except ValueError:  # another drive on Windows: no relative path exists
        raise SessionPathError(f"{p} cannot be written relative to {base}") from None
    return PurePosixPath(*Path(rel).parts).as_posix()


# ---------------------------------------------------------------------------- migrations
def _hex_to_rgb(value):
    if isinstance(value, str) and re.fullmatch(r"#[0-9a-fA-F]{6}", value):
        return [round(int(value[i:i + 2], 16) / 255, 6) for i in (1, 3, 5)]
    return value


def _v1_to_v2(doc: dict) -> dict:
    """Schema 1 (pre-release builds): one ``view`` instead of ``views``, a single ``input``
    string instead of an ``inputs`` list, ``iso`` for ``isovalue`` and ``#rrggbb`` colours
    under the key ``colour``."""
    out = {k: v for k, v in doc.items() if k not in ("view", "objects")}
    objects = []
    if not isinstance(doc.get("objects", []), list):
        raise SessionError(f"invalid session entry objects: a schema-1 session needs a list "
                           f"of objects, got {type(doc['objects']).__name__}")
    for o in doc.get("objects", []):
        if not isinstance(o, dict):
            objects.append(o)
            continue
        o = dict(o)
        if "input" in o:
            inp = o.pop("input")
            o["inputs"] = [inp] if inp is not None else []
        props = dict(o.get("properties", {})) if isinstance(o.get("properties"), dict) \
            else o.get("properties")
        if isinstance(props, dict):
            if "iso" in props:
                props["isovalue"] = props.pop("iso")
            if "colour" in props:
                props["color"] = _hex_to_rgb(props.pop("colour"))
            o["properties"] = props
        objects.append(o)
    out["objects"] = objects
    if "view" in doc:
        view = dict(doc["view"]) if isinstance(doc["view"], dict) else doc["view"]
        if isinstance(view, dict):
            view.setdefault("id", "view1")
            if "background" in view:
                view["background"] = _hex_to_rgb(view["background"])
        out["views"] = [view]
    out["schema_version"] = 2
    return out


def _v2_to_v3(doc: dict) -> dict:
    """Schema 3 only adds properties (smoothing, material, outline, widget and view flags,
    remeshing provenance on meshes) and lets clip planes take volumes or nothing as input;
    a schema-2 document means the same under schema 3."""
    return {**doc, "schema_version": 3}


def _v3_to_v4(doc: dict) -> dict:
    """Schema 4 adds the colour-by properties of isosurfaces (defaults: the flat colour of
    schema 3) and Section objects, so a schema-3 document means the same under schema 4."""
    return {**doc, "schema_version": 4}


#: schema version -> function lifting a document of that version to the next one
MIGRATIONS: dict[int, Callable[[dict], dict]] = {1: _v1_to_v2, 2: _v2_to_v3, 3: _v3_to_v4}

#: the entries of schema 1-4 views that nothing ever read, and why each is dropped
_UNREAD_VIEW_ENTRIES = {
    "size": "the picture size is the window's, or --size on the command line",
    "row_span": "views take one cell each", "col_span": "views take one cell each",
}


def _drop_unread(doc: dict) -> dict:
    """Drop what schema 1-4 documents could hold but no version of the program ever read:
    ``Remesh`` objects (with their ids in other objects' inputs and views' hidden lists),
    a view's ``size`` and its layout's ``row_span``/``col_span``. The app never wrote them,
    so no document it wrote changes; a value a user set by hand is named in one warning
    line of the ``splineviz.io.session`` logger."""
    objects = doc.get("objects")
    dropped = set()
    if isinstance(objects, list):
        dropped = {o.get("id") for o in objects
                   if isinstance(o, dict) and o.get("type") == "Remesh"}
        if dropped:
            _log.warning("session: %d Remesh object(s) dropped (%s); remesh the point cloud "
                         "and save again to keep the mesh", len(dropped),
                         ", ".join(map(str, sorted(dropped, key=str))))
            objects = [_without_inputs(o, dropped) for o in objects
                       if not (isinstance(o, dict) and o.get("type") == "Remesh")]
    views = doc.get("views")
    if isinstance(views, list):
        views = [_view_without_unread(v, dropped) for v in views]
    out = dict(doc)
    if objects is not None:
        out["objects"] = objects
    if views is not None:
        out["views"] = views
    return out


def _without_inputs(obj, dropped: set):
    if not dropped or not isinstance(obj, dict) or not isinstance(obj.get("inputs"), list):
        return obj
    return {**obj, "inputs": [i for i in obj["inputs"] if i not in dropped]}


def _view_without_unread(view, dropped: set):
    if not isinstance(view, dict):
        return view
    view = dict(view)
    if dropped and isinstance(view.get("hidden"), list):
        view["hidden"] = [h for h in view["hidden"] if h not in dropped]
    layout = view.get("layout")
    if isinstance(layout, dict):
        layout = view["layout"] = dict(layout)
    for key, why in _UNREAD_VIEW_ENTRIES.items():
        holder = view if key == "size" else layout
        if isinstance(holder, dict) and key in holder:
            value = holder.pop(key)
            if value not in (None, 1):
                _log.warning("session: view %s ignored (%s)", key, why)
    return view


def migrate(doc: dict) -> dict:
    """Lift a parsed session document to :data:`SCHEMA_VERSION` (a new dict; input unchanged).

    Raises
    ------
    SessionVersionError
        The version is missing, not an integer, newer than this program, or has no migration.
    """
    version = doc.get("schema_version")
    if isinstance(version, bool) or not isinstance(version, int):
        raise SessionVersionError(f"schema_version must be an integer, got {version!r}")
    if version > SCHEMA_VERSION:
        raise SessionVersionError(
            f"the session has schema version {version}, newer than the {SCHEMA_VERSION} this "
            "program understands; please update splineviz"
        )
    while version < SCHEMA_VERSION:
        step = MIGRATIONS.get(version)
        if step is None:
            raise SessionVersionError(f"schema version {version} is unknown and cannot be "
                                      "migrated")
        doc = step(doc)
        version = doc["schema_version"]
    return _drop_unread(doc)


# ---------------------------------------------------------------------------- load / save
def _reject_constant(name):
    raise SessionError(f"the session contains {name}, which is not a valid number")


def _no_duplicates(pairs):
    # one pass with a set: linear in the number of keys (a hostile object has 10^5 of them)
    seen = set()
    for k, _ in pairs:
        if k in seen:
            raise SessionError(f"the session repeats the key {k[:80]!r} in one object")
        seen.add(k)
    return dict(pairs)


def parse_document(text: str) -> dict:
    """Strict JSON parse of a session document (no NaN/Infinity, no duplicate keys)."""
    try:
        doc = json.loads(text, parse_constant=_reject_constant, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        raise SessionError(f"the session is not valid JSON: {exc.msg} at line {exc.lineno}, "
                           f"column {exc.colno}") from None
    except SessionError:
        raise
    except RecursionError:
        raise SessionError("the session is nested too deeply to be a session file") from None
    except ValueError as exc:
        if "integer string conversion" in str(exc):  # more digits than Python converts
            raise SessionError("the session holds a number with thousands of digits") from None
        raise SessionError(f"the session holds an unreadable value: {exc}") from None
    if not isinstance(doc, dict):
        raise SessionError("a session file must hold a JSON object at the top level")
    if doc.get("format") != FORMAT:
        raise SessionError(f"this is not a splineviz session (format is {doc.get('format')!r})")
    return doc


def _describe(err: ValidationError) -> str:
    e = err.errors()[0]
    loc = ".".join(str(p) for p in e.get("loc", ()))
    msg = e.get("msg", "invalid value").rstrip(".")
    return f"{loc or 'document'}: {msg}"


def validate_document(doc: dict) -> Session:
    """Migrate and validate a parsed document -> :class:`Session` (paths as stored)."""
    doc = migrate(doc)
    try:
        session = Session.model_validate(doc)
    except ValidationError as exc:
        raise SessionError(f"invalid session entry {_describe(exc)}") from None
    seen: dict[str, str] = {}
    for o in session.objects:
        if o.id in seen:
            raise SessionError(f"two pipeline objects share the id {o.id!r}")
        (lo, hi), allowed = INPUT_RULES[o.type]
        if not lo <= len(o.inputs) <= hi:
            raise SessionError(f"{o.type} {o.id!r} needs {lo if lo == hi else f'{lo} to {hi}'} "
                               f"input(s), got {len(o.inputs)}")
        for i in o.inputs:
            if i not in seen:
                raise SessionError(f"object {o.id!r} uses input {i!r}, which is not defined "
                                   "before it")
            if seen[i] not in allowed:
                raise SessionError(f"{o.type} {o.id!r} cannot take the {seen[i]} {i!r} as input")
        if o.type == "Section" and seen[o.inputs[0]] != "Isosurface":
            raise SessionError(f"section {o.id!r} must take an isosurface as its first input")
        seen[o.id] = o.type
    view_ids = [v.id for v in session.views]
    if len(view_ids) != len(set(view_ids)):
        raise SessionError("two views share the same id")
    for v in session.views:
        for h in v.hidden:
            if h not in seen:
                raise SessionError(f"view {v.id!r} hides {h!r}, which is not an object")
    return session


def _resolve(session: Session, session_file: Path) -> None:
    """Make every data path absolute (relative ones against the session's folder) and refuse
    those whose real path (``..`` and symbolic links followed) leaves that folder, unless
    :func:`~splineviz.io._util.outside_allowed` is in force."""
    for o in session.objects:
        if o.type not in FILE_TYPES:
            continue
        raw = o.properties.path
        p = Path(raw).expanduser() if raw.startswith("~") else Path(raw)
        if p.is_absolute() or PurePosixPath(raw).is_absolute() or re.match(r"^[A-Za-z]:[\\/]",
                                                                           raw):
            name = os.path.normpath(p)
        else:  # stored in POSIX form; confined() joins it with the session's folder
            name = os.path.normpath(Path(*PurePosixPath(raw.replace("\\", "/")).parts))
        resolved = confined(name, session_file, what=f"data file of object {o.id!r}",
                            error=SessionOutsideFolderError)
        o.properties.path = str(Path(os.path.normpath(resolved)))


def _check_data(session: Session, repoint) -> None:
    from splineviz.core.sources import sources

    for obj_id, p in session.data_files():
        while True:
            ok = _usable(p)
            if ok is True:
                break
            if repoint is None:
                raise SessionPathError(f"data file {p} of object {obj_id!r} {ok}")
            new = repoint(obj_id, p)
            if new is None:
                raise SessionPathError(f"data file {p} of object {obj_id!r} {ok} and was not "
                                       "re-pointed")
            session.repoint(obj_id, new)
            p = Path(session.object(obj_id).properties.path)
            if _usable(p) is not True:
                raise SessionPathError(f"the re-pointed data file {p} {_usable(p)}")
            break
    names = None
    for o in session.objects:
        if o.type == "Source":
            names = sources() if names is None else names
            if o.properties.source not in names:
                raise SessionError(
                    f"source {o.properties.source!r} of object {o.id!r} is not provided by "
                    f"any installed plugin (available: {', '.join(sorted(names)) or 'none'})"
                )


def _usable(p: Path):
    """True, or the reason why ``p`` cannot be a data file or DICOM folder."""
    try:
        st = p.stat()
    except FileNotFoundError:
        return "does not exist"
    except OSError as exc:
        return f"cannot be accessed ({exc.strerror})"
    if stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode):
        return True
    return "is not a regular file"


def load_session(path, *, repoint: Callable[[str, Path], Any] | None = None,
                 check_data: bool = True, allow_outside: bool = False) -> Session:
    """Read, migrate and validate a session file.

    Parameters
    ----------
    path : path-like
        The ``.svs`` file.
    repoint : callable, optional
        ``repoint(object_id, missing_path) -> new path or None`` is asked for every data
        file that is missing (the GUI shows a file dialog). ``None`` gives up.
    check_data : bool
        Check that data files exist and sources are provided by a plugin.
    allow_outside : bool
        Accept data paths that resolve (``..`` and symbolic links followed) outside the
        session's folder. Refused by default with a
        :class:`~splineviz.io.errors.SessionOutsideFolderError` whose ``path`` a GUI can show
        the user before retrying with ``allow_outside=True``. Files chosen through
        ``repoint`` are the user's own choice and are not checked.

    Returns
    -------
    Session
        With absolute data paths.

    Raises
    ------
    SessionError
        Malformed, hostile or unknown-version documents; missing data that was not re-pointed
        (:class:`SessionPathError`).
    """
    p = Path(os.fspath(path)).expanduser()
    try:
        st = p.stat()
    except FileNotFoundError:
        raise SessionPathError(f"session file not found: {p}") from None
    if not stat.S_ISREG(st.st_mode):
        raise SessionPathError(f"{p} is not a regular file")
    if st.st_size > MAX_SESSION_BYTES:
        raise SessionError(f"{p.name} is {st.st_size:,} bytes, too large for a session file")
    try:
        text = p.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise SessionError(f"{p.name} is not UTF-8 text, so not a session file") from None
    session = validate_document(parse_document(text))
    with outside_allowed(allow_outside):
        _resolve(session, p)
    if check_data:
        _check_data(session, repoint)
    return session


def save_session(session: Session, path) -> Path:
    """Write ``session`` as JSON (paths relative to ``path``'s folder), atomically.

    Saving a loaded session again gives the same document.
    """
    if not isinstance(session, Session):
        raise SessionError(f"save_session needs a Session, got {type(session).__name__}")
    p = Path(os.fspath(path)).expanduser()
    # re-validate: a session edited in memory must still be a valid document
    doc = session.to_document(base_dir=p.parent)
    validate_document(json.loads(json.dumps(doc)))
    text = json.dumps(doc, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    data = text.encode("utf-8")
    if len(data) > MAX_SESSION_BYTES:
        raise SessionError(f"the session would be {len(data):,} bytes, more than the "
                           f"{MAX_SESSION_BYTES:,} a session file may hold")
    atomic_write_bytes(p, data)
    return p
