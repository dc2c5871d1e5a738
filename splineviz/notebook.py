"""A scene in a notebook: its exact picture, or an interactive view in the browser.

``scene.show()`` and the notebook display of a :class:`splineviz.model.Scene` (IPython's
``_repr_png_``) come here through :mod:`splineviz.core.pictures`. The picture is
:func:`splineviz.render.scene_view.render_scene` of the scene, off-screen (EGL/OSMesa: no X
server, no GPU needed), so a notebook shows what ``splineviz render`` writes for the same
scene. ``interactive=True`` serves the scene's view (:mod:`splineviz.web`) on 127.0.0.1 from
a thread of the kernel and returns an ``<iframe>`` of its page; ``widget=True`` returns an
ipywidgets view of it (:class:`splineviz.widget.SceneWidget`).

A volume, point cloud or mesh the API returns is shown as the picture of a new scene holding
just that object (:func:`as_scene`): a volume with its default isosurface, framed isometric.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from splineviz.core.camera import Camera
from splineviz.core.pictures import PictureError
from splineviz.core.points import PointCloud
from splineviz.core.volume import Volume
from splineviz.model.nodes import CameraNode
from splineviz.model.scene import Scene
from splineviz.web.png import png_bytes

#: width, height of a notebook picture when none is asked for
DEFAULT_SIZE = (640, 480)


@dataclass(frozen=True)
class Picture:
    """An image a notebook shows.

    Attributes
    ----------
    image : (H, W, 3) or (H, W, 4) uint8
        Rows top to bottom (as :func:`~splineviz.render.scene_view.render_scene` returns).
    scene : Scene or None
        The scene it is a picture of.
    camera : dict or None
        The camera it was taken from (:meth:`CameraNode.pose` fields).
    """

    image: np.ndarray
    scene: Scene | None = field(default=None, repr=False, compare=False)
    camera: dict | None = None

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return int(self.image.shape[1]), int(self.image.shape[0])

    def png(self) -> bytes:
        """The image as PNG bytes (lossless: decoding gives ``image`` back exactly)."""
        return png_bytes(self.image)

    def _repr_png_(self) -> bytes:
        return self.png()

    def save(self, path) -> None:
        """Write the image as a PNG file."""
        from splineviz.io.meshes import write_screenshot

        write_screenshot(path, self.image)

    def __array__(self, dtype=None, copy=None):
        return self.image if dtype is None else self.image.astype(dtype)


def place_camera(scene: Scene, camera) -> None:
    """Put ``scene``'s camera where ``camera`` is: a :class:`~splineviz.core.camera.Camera`,
    a :class:`~splineviz.model.CameraNode`, or a mapping of its fields (``position``,
    ``focal_point``, ``view_up``, ``view_angle``: what the web view reports)."""
    if isinstance(camera, Camera | CameraNode):
        camera = {k: getattr(camera, k) for k in ("position", "focal_point", "view_up",
                                                  "view_angle")}
    fields = {k: tuple(map(float, v)) if k != "view_angle" else float(v)
              for k, v in dict(camera).items()
              if k in ("position", "focal_point", "view_up", "view_angle")}
    scene.camera.update(fields)


def as_scene(obj) -> Scene:
    """``obj`` itself if it is a scene, else a new scene holding just ``obj``.

    Parameters
    ----------
    obj : Scene, Volume, PointCloud, pyvista.PolyData or (vertices (V, 3), faces (F, 3))
        A volume comes with its first isosurface (the default isovalue and model of
        :meth:`Scene.add_volume`); a mesh without triangles is shown as its points.

    Returns
    -------
    Scene
    """
    if isinstance(obj, Scene):
        return obj
    scene = Scene()
    if isinstance(obj, Volume):
        scene.add_volume(obj, "volume")
    elif isinstance(obj, PointCloud):
        scene.add_points(obj, "points")
    else:
        vertices, faces, normals = _triangles(obj)
        if len(faces):
            scene.add_mesh(vertices, faces, "mesh", normals=normals)
        else:
            scene.add_points(PointCloud(vertices), "points")
    return scene


def _triangles(mesh):
    """``vertices (V, 3)``, ``faces (F, 3)``, point normals ``(V, 3)`` or None of a mesh."""
    import pyvista as pv

    from splineviz.io.errors import InvalidDataError
    from splineviz.io.meshes import as_polydata

    if not isinstance(mesh, pv.PolyData) and not isinstance(mesh, tuple | list):
        raise PictureError(f"cannot show a {type(mesh).__name__}: show a Scene, Volume, "
                           "PointCloud or mesh")
    try:
        poly = as_polydata(mesh)
    except InvalidDataError as exc:
        raise PictureError(str(exc)) from None
    if poly.n_cells and not poly.is_all_triangles:
        poly = poly.triangulate()
    faces = poly.faces.reshape(-1, 4)[:, 1:] if poly.faces.size else np.zeros((0, 3), int)
    name = poly.point_data.active_normals_name
    normals = None if name is None else np.asarray(poly.point_data[name], dtype=np.float64)
    return np.asarray(poly.points, dtype=np.float64), faces, normals


def show(scene: Scene, size=None, camera=None, *, interactive: bool = False, device=None,
         port: int = 0, widget: bool = False):
    """Show ``scene``: its exact picture, or its interactive view in the browser.

    Parameters
    ----------
    scene : splineviz.model.Scene, or an object :func:`as_scene` takes
    size : (width, height) or None
        Pixels (default :data:`DEFAULT_SIZE`).
    camera : Camera, CameraNode, mapping or None
        Look from there for this picture only (the scene's camera is put back after). A
        scene whose camera was never placed is framed first (isometric view of all data),
        so a new scene never shows an empty picture of the origin.
    interactive : bool
        Serve the view on 127.0.0.1 (:class:`splineviz.web.server.ViewServer`) and return an
        :class:`~splineviz.web.server.InteractiveView` (an ``<iframe>`` in a notebook).
    device : str or None
        OpenCL device preference of the ray casters.
    port : int
        The interactive view's port (0: a free one).
    widget : bool
        Return an ipywidgets view of the scene (:class:`splineviz.widget.SceneWidget`).

    Returns
    -------
    Picture, splineviz.web.server.InteractiveView or splineviz.widget.SceneWidget
    """
    from splineviz.core.camera import parse_size

    scene = as_scene(scene)
    size = DEFAULT_SIZE if size is None else parse_size(size)
    if scene.camera.pose() == CameraNode(id="camera").pose() and scene.bounds() is not None:
        scene.aspect = size[0] / size[1]
        scene.frame(view="isometric")
    if interactive:
        from splineviz.web.server import serve_in_thread

        return serve_in_thread(scene, size=size, port=port, device=device)
    if not os.environ.get("DISPLAY"):
        # no X server (a notebook on a server): VTK's default window would try X first and
        # print a warning into the cell before falling back to EGL
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    if widget:
        try:
            from splineviz.widget import SceneWidget
        except ModuleNotFoundError as exc:
            if exc.name != "ipywidgets":
                raise
            raise PictureError("scene.widget() needs ipywidgets: pip install "
                               "'splineviz[notebook]'") from None
        return SceneWidget(scene, size=size, device=device)
    from splineviz.render.scene_view import render_scene

    saved = scene.camera.pose()
    if camera is not None:
        place_camera(scene, camera)
    try:
        return Picture(render_scene(scene, size, device=device), scene, scene.camera.pose())
    finally:
        scene.camera.update(saved)
