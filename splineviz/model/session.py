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

import os
from pathlib import Path

import numpy as np

from splineviz.io.errors import SessionError
from splineviz.io.session import (
    CameraState,
    Layout,
    Session,
    View,
    load_session,
    save_session,
)
from splineviz.model.nodes import (
    ClipPlaneNode,
    IsosurfaceNode,
    MeshNode,
    PointsNode,
    SectionNode,
    VolumeNode,
    mesh_arrays,
)
from splineviz.model.scene import Scene

SESSION_SUFFIX = ".svs"


def session_path(path) -> Path:
    """``path`` with the ``.svs`` suffix added when it has none (what users expect of a
    "Save as" that they typed without the suffix)."""
    p = Path(os.fspath(path)).expanduser()
    return p if p.suffix.lower() == SESSION_SUFFIX else p.with_name(p.name + SESSION_SUFFIX)


def _props(node, *names) -> dict:
    return {n: getattr(node, n) for n in names}


def to_session(scene: Scene, written: dict | None = None) -> Session:
    """The :class:`~splineviz.io.session.Session` of ``scene``.

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
        common = {"name": node.name, "id": node.id}
        path, read_options = getattr(node, "path", None), getattr(node, "read_options", {})
        if path is None and node.id in written:
            path, read_options = written[node.id]
        if isinstance(node, VolumeNode):
            extra = _props(node, "sigma", "show_outline", "visible")
            if node.source is not None:
                s.add("Source", {"source": node.source, "shape": list(node.data.shape),
                                 **extra}, **common)
            elif path is not None:
                s.add("VolumeFile", {"path": path, **read_options, **extra}, **common)
            else:
                raise SessionError(f"volume {node.name!r} has no file; save the session with "
                                   "save_scene, which writes it")
        elif isinstance(node, IsosurfaceNode):
            colour_by = _props(node, "color_by", "color_map", "color_range", "color_min",
                               "color_max")
            if node.color_volume_id is not None:
                colour_by["color_volume"] = node.color_volume_id
            if node.color_isosurface_id is not None:
                colour_by["color_isosurface"] = node.color_isosurface_id
            s.add("Isosurface", {**_props(node, "isovalue", "model", "k", "opacity", "visible",
                                          "material"), "color": list(node.color), **colour_by},
                  inputs=[node.volume_id], **common)
        elif isinstance(node, PointsNode):
            if path is None:
                raise SessionError(f"point cloud {node.name!r} has no file")
            s.add("PointsFile", {"path": path, "color": list(node.color),
                                 **_props(node, "point_size", "opacity", "visible")}, **common)
        elif isinstance(node, MeshNode):
            if path is None:
                raise SessionError(f"mesh {node.name!r} has no file")
            provenance = {k: v for k, v in _props(node, "edge_length", "rho").items()
                          if v is not None}
            inputs = [node.points_id] if node.points_id in scene else []
            s.add("MeshFile", {"path": path, "color": list(node.color),
                               **_props(node, "opacity", "show_edges", "visible"),
                               **provenance}, inputs=inputs, **common)
        elif isinstance(node, SectionNode):
            s.add("Section", {"color": list(node.color), **_props(node, "line_width", "visible")},
                  inputs=node.inputs, **common)
        elif isinstance(node, ClipPlaneNode):
            s.add("ClipPlane", {"origin": list(node.origin), "normal": list(node.normal),
                                **_props(node, "enabled", "show_widget")},
                  inputs=[] if node.volume_id is None else [node.volume_id], **common)
    view = s.views[0]
    cam = scene.camera
    view.camera = CameraState(position=cam.position, focal_point=cam.focal_point,
                              view_up=cam.view_up, view_angle=cam.view_angle,
                              parallel_projection=cam.parallel_projection,
                              parallel_scale=cam.parallel_scale)
    view.background = scene.view.background
    view.show_axes = scene.view.show_axes
    view.show_scale = scene.view.show_scale
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
        if obj.type in ("VolumeFile", "Source"):
            data[obj.id] = session.load_volume(obj.id, allow_outside=allow_outside)
        elif obj.type == "PointsFile":
            data[obj.id] = session.load_points(obj.id)
        elif obj.type == "MeshFile":
            mesh = read_mesh(obj.properties.path)
            v, f = mesh_arrays(mesh)
            normals = mesh.point_data.get("Normals") if hasattr(mesh, "point_data") else None
            data[obj.id] = (v, f, None if normals is None else np.asarray(normals))
    return data


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


def apply_session(scene: Scene, session: Session, data: dict | None = None) -> Scene:
    """Replace the contents of ``scene`` by ``session`` (``data`` from
    :func:`read_session_data`; read here when None). Ids and every property are kept."""
    from splineviz.core.registry import load_extensions

    data = read_session_data(session) if data is None else data
    load_extensions()  # plugin models named by isosurfaces
    scene.clear()
    for obj in session.objects:
        p = obj.properties
        common = {"id": obj.id, "name": obj.name or obj.id}
        if obj.type in ("VolumeFile", "Source"):
            is_file = obj.type == "VolumeFile"
            read = ({k: v for k, v in p.model_dump(exclude_defaults=True).items()
                     if k in ("format", "dims", "dtype", "byteorder", "offset", "spacing",
                              "origin")} if is_file else {})
            scene.add(VolumeNode(path=p.path if is_file else None,
                                 source=None if is_file else p.source, read_options=read,
                                 sigma=p.sigma, show_outline=p.show_outline, visible=p.visible,
                                 data=data[obj.id], **common))
        elif obj.type == "Isosurface":
            kinds = {o.id: o.type for o in session.objects}
            if p.color_volume is not None and \
                    kinds.get(p.color_volume) not in ("VolumeFile", "Source"):
                raise SessionError(f"isosurface {obj.id!r} is coloured by {p.color_volume!r}, "
                                   "which is not a volume")
            if p.color_isosurface is not None and \
                    kinds.get(p.color_isosurface) != "Isosurface":
                raise SessionError(f"isosurface {obj.id!r} measures the distance to "
                                   f"{p.color_isosurface!r}, which is not an isosurface")
            scene.add(IsosurfaceNode(volume_id=obj.inputs[0], model=p.model, k=p.k,
                                     isovalue=p.isovalue, color=p.color, opacity=p.opacity,
                                     visible=p.visible, material=p.material,
                                     color_by=p.color_by, color_map=p.color_map,
                                     color_range=p.color_range, color_min=p.color_min,
                                     color_max=p.color_max, color_volume_id=p.color_volume,
                                     color_isosurface_id=p.color_isosurface,
                                     **common))
        elif obj.type == "PointsFile":
            scene.add(PointsNode(path=p.path, color=p.color, point_size=p.point_size,
                                 opacity=p.opacity, visible=p.visible, data=data[obj.id],
                                 **common))
        elif obj.type == "MeshFile":
            v, f, n = data[obj.id]
            scene.add(MeshNode(path=p.path, points_id=obj.inputs[0] if obj.inputs else None,
                               edge_length=p.edge_length, rho=p.rho, color=p.color,
                               opacity=p.opacity, show_edges=p.show_edges, visible=p.visible,
                               vertices=v, faces=f, normals=n, **common))
        elif obj.type == "ClipPlane":
            scene.add(ClipPlaneNode(volume_id=_plane_volume(session, obj), origin=p.origin,
                                    normal=p.normal, enabled=p.enabled,
                                    show_widget=p.show_widget, **common))
        elif obj.type == "Section":
            first, second = obj.inputs
            is_plane = session.object(second).type == "ClipPlane"
            scene.add(SectionNode(isosurface_id=first, plane_id=second if is_plane else None,
                                  other_id=None if is_plane else second, color=p.color,
                                  line_width=p.line_width, visible=p.visible, **common))
    view = session.views[0]
    _apply_split(scene, session)
    c = view.camera
    scene.camera.update(position=c.position, focal_point=c.focal_point, view_up=c.view_up,
                        view_angle=c.view_angle, parallel_projection=c.parallel_projection,
                        parallel_scale=c.parallel_scale)
    scene.view.update(background=view.background, show_axes=view.show_axes,
                      show_scale=view.show_scale)
    scene.mark_saved()
    return scene


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
