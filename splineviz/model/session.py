"""Sessions are the scene model written down: :func:`to_session` / :func:`apply_session`.

Every property of every node goes through here (nothing is read from widgets), objects keep
their ids, and references (an isosurface's volume, a plane's volume, a mesh's point cloud)
are ids, never names, so two ``ct.nrrd`` from different folders stay two volumes.

Data without a file (a volume made in Python, a remeshed mesh) cannot be described by a path
alone: :func:`save_scene` writes it into ``<session stem>_data/`` beside the session (VTI for
volumes, PLY for meshes and point clouds) and records those paths, so the session is
complete. Loading is two steps so that a GUI can read data in a worker:
:func:`read_session_data` (slow: files, sources) and :func:`apply_session` (fast: nodes).
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np

from splineviz.io.errors import SessionError
from splineviz.io.session import (
    READ_OPTIONS,
    Layout,
    Session,
    View,
    load_session,
    save_session,
)
from splineviz.io.time_series import TimeSeries
from splineviz.model.nodes import (
    CameraNode,
    ClipPlaneNode,
    MeshNode,
    PointsNode,
    ViewNode,
    VolumeNode,
    is_required_in_documents,
    mesh_arrays,
)
from splineviz.model.scene import Scene
from splineviz.model.schema import OBJECT_NODES, session_names

_log = logging.getLogger(__name__)

SESSION_SUFFIX = ".svs"


def session_path(path) -> Path:
    """``path`` with the ``.svs`` suffix added when it has none (what users expect of a
    "Save as" that they typed without the suffix)."""
    p = Path(os.fspath(path)).expanduser()
    return p if p.suffix.lower() == SESSION_SUFFIX else p.with_name(p.name + SESSION_SUFFIX)


def object_type(node) -> str | None:
    """The session object type of ``node`` (None: the node is not a pipeline object)."""
    if isinstance(node, VolumeNode):  # one node, two ways to say where its data is
        return "Source" if node.source is not None else "VolumeFile"
    return next((t for t, (cls, _) in OBJECT_NODES.items() if isinstance(node, cls)), None)


def _origin(node, type_name: str, path, read_options) -> dict:
    """The properties that say where ``node``'s data comes from (io's declaration)."""
    if type_name == "Source":
        return {"source": node.source, "shape": list(node.data.shape)}
    if path is None:
        if type_name == "VolumeFile":
            raise SessionError(f"volume {node.name!r} has no file; save the session with "
                               "save_scene, which writes it")
        what = "point cloud" if type_name == "PointsFile" else "mesh"
        raise SessionError(f"{what} {node.name!r} has no file")
    options = {"format": node.format} if isinstance(node, PointsNode) else read_options
    return {"path": path, **(options or {})}


def node_properties(node) -> dict:
    """The session properties of ``node``: its :meth:`~splineviz.model.nodes.Node.state`
    (non-default properties, under their session names) and the properties a document
    must state whatever their values."""
    names = session_names(type(node))
    state = node.state()
    props = {name: state[name] for name in names.values() if name in state}
    for field, info in type(node).properties().items():
        if is_required_in_documents(info) and names[field] not in props:
            props[names[field]] = getattr(node, field)
    return props


def to_session(scene: Scene, written: dict | None = None) -> Session:
    """The :class:`~splineviz.io.session.Session` of ``scene``.

    Each node is written as its properties (the document keeps the non-default ones: its
    ``Node.state()``), its input references as the object's ``inputs`` (those naming nodes
    of the scene) and, for data, where the data comes from.

    Parameters
    ----------
    scene : Scene
    written : dict, optional
        Object id -> ``(path, read options)`` of data without a file of its own that was
        written elsewhere (the GUI's autosave keeps such copies in its recovery folder and
        must not point the nodes at them); used for nodes whose ``path`` is None.

    Raises
    ------
    SessionError
        An object holds data without a file or source (use :func:`save_scene`, which
        writes such data first).
    """
    written = written or {}
    s = Session()
    for node in scene:
        type_name = object_type(node)
        if type_name is None:
            continue
        props = {}
        if OBJECT_NODES[type_name][1] is not None:
            path, read_options = getattr(node, "path", None), getattr(node, "read_options", {})
            if path is None and node.id in written:
                path, read_options = written[node.id]
            props = _origin(node, type_name, path, read_options)
        inputs = [getattr(node, k) for k in type(node).references()]
        s.add(type_name, {**props, **node_properties(node)},
              inputs=[i for i in inputs if i is not None and i in scene],
              name=node.name, id=node.id)
    if scene.animation is not None:
        s.animation = scene.animation
    view = s.views[0]
    view.camera = scene.camera.pose()
    for k in ViewNode.properties():
        setattr(view, k, getattr(scene.view, k))
    if scene.view.split:
        # the split as two views side by side with one camera; each hides the objects
        # shown only on the other side
        right = View(**view.model_dump(exclude={"id", "layout", "hidden"}), id="view2",
                     layout=Layout(col=1))
        view.hidden = [n.id for n in scene if getattr(n, "shown_in", None) == "right"]
        right.hidden = [n.id for n in scene if getattr(n, "shown_in", None) == "left"]
        s.views.append(right)
    return s


def needs_data_file(node) -> bool:
    """Whether ``node`` holds data that no file or source describes (a volume made in
    Python, a remeshed mesh): a session must write it somewhere first."""
    if isinstance(node, VolumeNode):
        return node.path is None and node.source is None
    return isinstance(node, MeshNode | PointsNode) and node.path is None


def write_node_data(node, folder, volume_suffix: str = ".vti") -> tuple[str, dict]:
    """Write the data of a node without a file (see :func:`needs_data_file`) into
    ``folder`` as ``<id><suffix>``; the node is not changed.

    Parameters
    ----------
    node : VolumeNode, MeshNode or PointsNode
    folder : path-like
        An existing folder.
    volume_suffix : str
        ``".vti"`` (keeps spacing and origin in the file) or ``".npy"`` (a plain array
        write, which releases the GIL: what a background writer wants; spacing and origin
        then go into the read options).

    Returns
    -------
    (str, dict)
        The file written and the read options a session records beside it.
    """
    from splineviz.io.meshes import write_mesh
    from splineviz.io.volumes import write_volume

    folder = Path(folder)
    if isinstance(node, VolumeNode):
        path = write_volume(folder / f"{node.id}{volume_suffix}", node.data)
        options = {}
        if volume_suffix == ".npy":
            vol = node.data
            options = {"spacing": [float(v) for v in np.broadcast_to(vol.spacing, 3)],
                       "origin": [float(v) for v in np.broadcast_to(vol.origin, 3)]}
        return str(path), options
    if isinstance(node, MeshNode):
        return str(write_mesh(folder / f"{node.id}.ply", node.to_polydata())), {}
    if isinstance(node, PointsNode):
        pts = np.asarray(node.data.points, dtype=np.float64)
        return str(write_mesh(folder / f"{node.id}.ply",
                              (pts, np.zeros((0, 3), dtype=np.int64)))), {}
    raise SessionError(f"{node.kind} {node.name!r} holds no data to write")


def save_scene(scene: Scene, path) -> Path:
    """Write ``scene`` as a session file (``.svs`` appended when missing), data without a
    file written into ``<stem>_data/`` beside it first; returns the session's path.

    Nodes whose data were written point at the new files afterwards, so saving again does
    not write them again.
    """
    p = session_path(path)
    folder = p.parent / f"{p.stem}_data"
    for node in scene:
        if needs_data_file(node):
            folder.mkdir(exist_ok=True)
            node.path, _ = write_node_data(node, folder)
    save_session(to_session(scene), p)
    scene.mark_saved()
    return p


def read_session_data(session: Session, *, allow_outside: bool = False) -> dict:
    """Read the data of every object of ``session`` that has some (slow; a worker may run
    it): object id -> Volume, PointCloud or ``(vertices, faces, normals or None)``.
    ``allow_outside`` lets the volume files' own headers name data outside their folders."""
    from splineviz.io.meshes import read_mesh

    data = {}
    for obj in session.objects:
        if obj.type == "VolumeFile" and obj.properties.time_series:
            data[obj.id] = _open_series(obj.properties, allow_outside)
        elif obj.type in ("VolumeFile", "Source"):
            data[obj.id] = session.load_volume(obj.id, allow_outside=allow_outside)
        elif obj.type == "PointsFile":
            data[obj.id] = session.load_points(obj.id)
        elif obj.type == "MeshFile":
            mesh = read_mesh(obj.properties.path)
            v, f = mesh_arrays(mesh)
            normals = mesh.point_data.get("Normals") if hasattr(mesh, "point_data") else None
            data[obj.id] = (v, f, None if normals is None else np.asarray(normals))
    return data


def _open_series(p, allow_outside: bool):
    """The :class:`~splineviz.io.time_series.TimeSeries` of a time-varying VolumeFile's
    properties ``p``, with the step the session shows read (the other steps are read when
    shown; a job process hands the series, that step included, to the GUI)."""
    from splineviz.io.time_series import open_time_series

    options = {k: getattr(p, k) for k in READ_OPTIONS if getattr(p, k) is not None}
    series = open_time_series(p.path, allow_outside=allow_outside, **options)
    if p.time_index < len(series):
        series.step(p.time_index)
    return series


def _plane_volume(session: Session, obj) -> str | None:
    """The volume a clip plane cuts: its volume input, the single volume of its isosurface
    inputs, or None (every isosurface) when it names several or none."""
    vols = set()
    for i in obj.inputs:
        src = session.object(i)
        if src.type in ("VolumeFile", "Source"):
            vols.add(src.id)
        elif src.type == "Isosurface":
            vols.add(src.inputs[0])
    return vols.pop() if len(vols) == 1 else None


def _references(session: Session, obj, node_cls) -> dict:
    """Reference fields of ``node_cls`` filled from ``obj``'s inputs: each input fills the
    first empty reference that takes an object of its type."""
    if node_cls is ClipPlaneNode:  # schema 2 planes also took isosurfaces and data
        return {"volume_id": _plane_volume(session, obj)}
    refs = dict.fromkeys(node_cls.references())
    for i in obj.inputs:
        typ = session.object(i).type
        key = next((k for k, types in node_cls.references().items()
                    if refs[k] is None and typ in types), None)
        if key is not None:
            refs[key] = i
    return refs


def _check_colour_by(session: Session, obj) -> None:
    """The ids an isosurface is coloured by name objects of the right kind."""
    p = obj.properties
    kinds = {o.id: o.type for o in session.objects}
    if p.color_volume is not None and kinds.get(p.color_volume) not in ("VolumeFile", "Source"):
        raise SessionError(f"isosurface {obj.id!r} is coloured by {p.color_volume!r}, "
                           "which is not a volume")
    if p.color_isosurface is not None and kinds.get(p.color_isosurface) != "Isosurface":
        raise SessionError(f"isosurface {obj.id!r} measures the distance to "
                           f"{p.color_isosurface!r}, which is not an isosurface")


def node_of(session: Session, obj, data=None):
    """The scene node of the session object ``obj``: ``Node(**properties, data=...)``."""
    node_cls, origin = OBJECT_NODES[obj.type]
    values = obj.properties.model_dump()
    kwargs = {k: values[name] for k, name in session_names(node_cls).items()}
    kwargs.update(_references(session, obj, node_cls))
    if obj.type == "VolumeFile":
        # a time-varying volume's data is its series: the scene reads the step it shows
        series, data = (data, None) if isinstance(data, TimeSeries) else (None, data)
        kwargs.update(path=values["path"], data=data, series=series, read_options={
            k: values[k] for k in READ_OPTIONS
            if values[k] != origin.model_fields[k].default})
    elif obj.type == "Source":
        kwargs.update(source=values["source"], data=data)
    elif obj.type == "PointsFile":
        kwargs.update(path=values["path"], format=values["format"], data=data)
    elif obj.type == "MeshFile":
        v, f, n = data
        kwargs.update(path=values["path"], vertices=v, faces=f, normals=n)
    return node_cls(id=obj.id, name=obj.name or obj.id, **kwargs)


def apply_session(scene: Scene, session: Session, data: dict | None = None) -> Scene:
    """Replace the contents of ``scene`` by ``session`` (``data`` from
    :func:`read_session_data`; read here when None). Ids and every property are kept."""
    from splineviz.core.registry import load_extensions

    data = read_session_data(session) if data is None else data
    load_extensions()  # plugin models named by isosurfaces
    _check_animation(session)
    scene.clear()
    for obj in session.objects:
        if obj.type == "Isosurface":
            _check_colour_by(session, obj)
        scene.add(node_of(session, obj, data.get(obj.id)))
    view = session.views[0]
    _apply_split(scene, session)
    scene.camera.update(view.camera.model_dump())
    scene.animation = session.animation
    scene.view.update({k: getattr(view, k) for k in ViewNode.properties()})
    if any(v.lights != View.model_fields["lights"].default for v in session.views):
        _log.warning("session: the view's lights are not rendered (the view has one "
                     "headlight); they are kept only in the session file")
    scene.mark_saved()
    return scene


def _check_animation(session: Session) -> None:
    """The objects the session's animation animates are in it, of a kind that has the
    property (checked before the scene changes)."""
    from splineviz.model.animation import ANIMATED, TIME_TARGET, SceneTime

    if session.animation is None:
        return
    kinds = {o.id: OBJECT_NODES[o.type][0] for o in session.objects}
    for track in session.animation.tracks:
        if track.target == "camera":
            node_cls = CameraNode
        elif track.target == TIME_TARGET:
            node_cls = SceneTime
        elif track.target in kinds:
            node_cls = kinds[track.target]
        else:
            raise SessionError(f"the animation animates {track.target!r}, which is not an "
                               "object of the session")
        if not issubclass(node_cls, ANIMATED[track.property].nodes):
            raise SessionError(f"the animation's {track.property} track cannot animate "
                               f"{track.target!r}")


def _apply_split(scene: Scene, session: Session) -> None:
    """Two or more views: the scene's split, the left one the view in the first column
    (the first view when none is), the right one the first other view; an object hidden
    in one of them and not in the other shows only in the other. Hiding lists of a single
    view are not read (the scene has no per-view hiding outside a split)."""
    views = session.views
    if len(views) < 2:
        scene.view.split = False
        return
    left = next((v for v in views if v.layout.col == 0), views[0])
    right = next(v for v in views if v is not left)
    hidden_left, hidden_right = set(left.hidden), set(right.hidden)
    for node in scene:
        if hasattr(node, "shown_in"):
            in_left, in_right = node.id not in hidden_left, node.id not in hidden_right
            node.shown_in = ("left" if in_left and not in_right else
                             "right" if in_right and not in_left else "both")
    scene.view.split = True


def load_scene(path, *, repoint=None, scene: Scene | None = None,
               allow_outside: bool = False) -> Scene:
    """Read a session file and its data into ``scene`` (a new one when None);
    ``allow_outside`` accepts data outside the session's folder (see
    :func:`~splineviz.io.session.load_session`)."""
    session = load_session(path, repoint=repoint, allow_outside=allow_outside)
    return apply_session(Scene() if scene is None else scene, session,
                         read_session_data(session, allow_outside=allow_outside))
