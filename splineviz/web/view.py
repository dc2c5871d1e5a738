"""The scene's view as a stream of pictures: what the web page and the notebook widget show.

A :class:`RemoteView` holds an off-screen pyvista plotter with a progressive
:class:`~splineviz.render.scene_view.SceneView` of a scene model, as the window does: a change
(orbit, zoom, isovalue, model, clip plane, colour-by) gives a *preview* at once (the
reduced-resolution cast sized to :data:`splineviz.render.scene.PREVIEW_BUDGET_S`), and
:meth:`RemoteView.exact` the exact ray-cast frame, made by
:func:`~splineviz.render.scene_view.render_scene` of the same scene and camera.

VTK is not thread safe: every method is called from one thread (the server's render thread);
the scene's nodes are changed there too, so the view's handlers run in that thread.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from splineviz.core.colour_by import FIELDS
from splineviz.core.errors import SplinevizError
from splineviz.core.renderers import CELL_PROJECTION
from splineviz.model import ClipPlaneNode, IsosurfaceNode, Scene
from splineviz.render.scene import PREVIEW_LEVELS

#: degrees of orbit per pixel of drag across the view's height (VTK's trackball camera
#: turns 20 / height * MotionFactor 10 = 200 degrees a view height; this is its rate)
DEGREES_PER_VIEW_HEIGHT = 200.0
#: name of the clip plane the page turns on and off
CLIP_NAME = "web clip plane"
#: resolution factor of a preview the render thread casts itself (see RemoteView.preview):
#: the refining worker's preview level of the window
PREVIEW_SCALE = PREVIEW_LEVELS[4]


class WebViewError(SplinevizError, ValueError):
    """A request of the page that the scene cannot take (unknown control, bad value)."""


@dataclass(frozen=True)
class Shot:
    """One picture of the view and what it shows.

    Attributes
    ----------
    image : (H, W, 3) uint8
    exact : bool
        An exact frame (False: a preview of reduced resolution).
    state : dict
        :meth:`RemoteView.state` when it was taken (camera, isovalue, model...).
    """

    image: np.ndarray
    exact: bool
    state: dict


class RemoteView:
    """Pictures of ``scene`` at ``size`` (see module docstring).

    Parameters
    ----------
    scene : splineviz.model.Scene
    size : (width, height)
    device : str or None
        OpenCL device preference of the ray casters.
    """

    def __init__(self, scene: Scene, size=(640, 480), device=None):
        self.scene = scene
        self.size = (int(size[0]), int(size[1]))
        self.device = device
        self._plotter = None
        self._view = None

    def _ensure(self):
        if self._view is None:
            import pyvista as pv

            from splineviz.render.scene_view import SceneView, smooth_pending

            smooth_pending(self.scene, self.device)
            self._plotter = pv.Plotter(off_screen=True, window_size=self.size)
            self._view = SceneView(self.scene, self._plotter, progressive=True,
                                   device=self.device)
        return self._view

    # -- what the page controls ----------------------------------------------------------

    @property
    def isosurface(self) -> IsosurfaceNode | None:
        """The isosurface the page's controls act on: the scene's first."""
        isos = self.scene.isosurfaces
        return isos[0] if isos else None

    def controls(self) -> dict:
        """What the page offers: the isovalue range, the models, the colour-by fields."""
        from splineviz.core.splines import MODELS

        iso = self.isosurface
        out = {"size": list(self.size), "models": list(MODELS.names()),
               "color_by": [f for f in FIELDS if f not in ("volume", "distance")]}
        if iso is not None:
            lo, hi = self.scene.volume_of(iso).active.finite_range
            out["isovalue_range"] = [float(lo), float(hi)]
        return out

    def state(self) -> dict:
        """The camera (full precision) and the controls' values."""
        cam = self.scene.camera
        out = {"camera": {"position": list(cam.position), "focal_point": list(cam.focal_point),
                          "view_up": list(cam.view_up), "view_angle": cam.view_angle}}
        iso = self.isosurface
        if iso is not None:
            out.update(isovalue=iso.isovalue, model=iso.model, color_by=iso.color_by)
        plane = self._clip_plane()
        out["clip"] = bool(plane is not None and plane.enabled)
        return out

    def _clip_plane(self) -> ClipPlaneNode | None:
        for plane in self.scene.clip_planes:
            if plane.name == CLIP_NAME:
                return plane
        return None

    def set(self, name: str, value) -> None:
        """Set a control: ``isovalue``, ``model``, ``color_by`` (of the first isosurface) or
        ``clip`` (a plane through the volume's centre, normal +X, on or off)."""
        iso = self.isosurface
        if name == "clip":
            plane = self._clip_plane()
            if plane is None:
                if not value:
                    return
                volume = None if iso is None else self.scene.volume_of(iso)
                self.scene.add_clip_plane(volume=volume, name=CLIP_NAME)
            else:
                plane.enabled = bool(value)
            return
        if iso is None:
            raise WebViewError(f"the scene has no isosurface to set {name!r} of")
        if name == "isovalue":
            value = float(value)
            if not math.isfinite(value):
                raise WebViewError(f"isovalue must be a finite number, got {value!r}")
            iso.isovalue = value
        elif name == "model":
            from splineviz.core.splines import model_spec

            iso.model = model_spec(str(value)).name
        elif name == "color_by":
            if value not in self.controls()["color_by"]:
                raise WebViewError(f"cannot colour by {value!r}")
            iso.color_by = value
        else:
            raise WebViewError(f"unknown control {name!r}; choose isovalue, model, color_by "
                               "or clip")

    def orbit(self, dx: float, dy: float) -> None:
        """Turn the camera about its focal point by a mouse drag of ``(dx, dy)`` pixels
        (right, down), as VTK's trackball camera does."""
        view = self._ensure()
        rate = DEGREES_PER_VIEW_HEIGHT / self.size[1]
        vcam = self._plotter.renderer.GetActiveCamera()
        vcam.Azimuth(-float(dx) * rate)
        vcam.Elevation(float(dy) * rate)
        vcam.OrthogonalizeViewUp()
        view.camera_from_vtk()
        # and back: VTK's camera then holds exactly the model's numbers, as in render_scene
        view.camera_to_vtk()

    def zoom(self, factor: float) -> None:
        """Move the camera towards the focal point (``factor`` > 1) or away (< 1)."""
        view = self._ensure()
        factor = float(factor)
        if not (math.isfinite(factor) and 0.05 < factor < 20.0):
            raise WebViewError(f"zoom factor must be between 0.05 and 20, got {factor!r}")
        self._plotter.renderer.GetActiveCamera().Dolly(factor)
        view.camera_from_vtk()
        view.camera_to_vtk()

    # -- pictures ------------------------------------------------------------------------

    def preview(self) -> Shot:
        """The picture now: a preview where the view changed since the last exact frame."""
        view = self._ensure()
        scene = view.spline_scene
        scene.set_interacting(True)
        self._plotter.render_window.Render()
        # the window previews only with casters a worker has built, and at sizes they were
        # built for (never blocking the GUI thread): a new view, a new model or data gave no
        # frame above. This render thread may wait, so it casts those previews itself
        now = scene.view_state()
        # a surface drawn by cell projection previews by its tets (made here when missing)
        # or their stand-in, not by a ray-cast frame
        cells = [layer for layer in scene.layers
                 if layer.visible and scene.renderer_of(layer) == CELL_PROJECTION]
        missing = [layer for layer in scene.layers if layer.visible and layer not in cells
                   and not _shows(scene.shown_frame(layer), layer, now)]
        if missing or not all(layer.cells_current() for layer in cells):
            frames = [(layer, layer.compute(now, scale=PREVIEW_SCALE, preview=True))
                      for layer in missing]
            frames += [(layer, layer.cell_geometry()) for layer in cells]
            if scene.apply([(layer, rf) for layer, rf in frames if rf is not None]):
                self._plotter.render_window.Render()
        return Shot(self._screenshot(), not scene.needs_refine(), self.state())

    def exact(self) -> Shot:
        """The exact frame of the view now: :func:`~splineviz.render.scene_view.render_scene`
        of the scene, so the page shows the very picture a script or ``splineviz render``
        makes for this camera. (The preview window's axes grid keeps label placements from
        the cameras it was dragged through: its exact frame differed from a fresh window's
        in the grid's labels.)"""
        from splineviz.render.scene_view import render_scene

        self._ensure().spline_scene.set_interacting(False)
        return Shot(render_scene(self.scene, self.size, device=self.device), True,
                    self.state())

    def _screenshot(self) -> np.ndarray:
        return self._plotter.screenshot(None, return_img=True)

    def close(self) -> None:
        if self._view is not None:
            self._view.close()
            self._plotter.close()
            self._view = self._plotter = None


def _shows(rf, layer, view) -> bool:
    """Whether the frame ``rf`` (or None) is of ``layer``'s state and of ``view``."""
    return rf is not None and rf.state == layer.state and rf.view.key() == view.key()
