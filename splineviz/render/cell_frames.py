"""Exact cell-projected frames made off the GUI thread (thesis §6.1, in a progressive view).

On software OpenGL the cell projection of the default data's 75k relevant tets takes
0.25-0.8 s to draw (the rasteriser's work per tet and per covered pixel, not the shader's
root finding: a fragment program that discards at once cost 0.25 s). Drawn in the window,
every render would hold the GUI thread that long. A progressive view (the GUI) therefore
shows such a surface as it shows a ray-cast one: the exact frame is drawn in a worker and
composited by the view's :class:`~splineviz.render.quad.FrameQuad` with its per-pixel depth;
the trilinear stand-in shows while the camera moves.

The frames are drawn by one thread that owns an off-screen window, for the life of the
process (an OpenGL context is current in one thread at a time; VTK releases the GIL while it
draws, so the GUI thread runs meanwhile). The window is an EGL one where VTK has EGL: it
shares no X connection with the GUI's window. The shaders write the unit normal in view
coordinates packed as the quad's texture bytes (:meth:`CellProjectionLayer.set_normal_output`),
so the normals reach the quad rounded once, as a ray-cast frame's are.
"""

from __future__ import annotations

from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import vtk
from vtk.util import numpy_support

from splineviz.core.camera import Camera
from splineviz.core.raycast_reference import Frame, phong_shade
from splineviz.render.cell_projection import CellGeometry, CellProjectionLayer

#: cell-projection layers the drawing thread keeps (one per geometry drawn lately: the
#: surfaces of a scene, each view's isovalue)
KEPT_LAYERS = 4

_THREAD = ThreadPoolExecutor(max_workers=1, thread_name_prefix="splineviz-cell-frames")


class _Drawer:
    """The drawing thread's off-screen window and the layers it draws (used in that
    thread only)."""

    def __init__(self):
        self.window = _offscreen_window()
        self.window.SetMultiSamples(0)
        self.renderer = vtk.vtkRenderer()
        self.window.AddRenderer(self.renderer)
        self.layers: OrderedDict = OrderedDict()  # id(geometry) -> (geometry, layer)

    def layer(self, geometry: CellGeometry) -> CellProjectionLayer:
        kept = self.layers.pop(id(geometry), None)
        if kept is None or kept[0] is not geometry:
            layer = CellProjectionLayer(geometry.spline, None)
            layer.set_geometry(geometry)
            layer.set_normal_output(True)
            kept = (geometry, layer)
        self.layers[id(geometry)] = kept
        while len(self.layers) > KEPT_LAYERS:
            self.layers.popitem(last=False)
        return kept[1]

    def draw(self, geometry: CellGeometry, camera: Camera, size, clip_planes):
        layer = self.layer(geometry)
        layer.set_clip_planes(clip_planes)
        self.renderer.RemoveAllViewProps()
        self.renderer.AddActor(layer.actor)
        w, h = size
        self.window.SetSize(w, h)
        cam = self.renderer.GetActiveCamera()
        cam.SetPosition(*camera.position)
        cam.SetFocalPoint(*camera.focal_point)
        cam.SetViewUp(*camera.view_up)
        cam.SetViewAngle(camera.view_angle)
        cam.SetClippingRange(*camera.fit_clipping_range(geometry.spline.bounds))
        self.window.Render()
        rgba = vtk.vtkUnsignedCharArray()
        self.window.GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, rgba, 0)
        packed = numpy_support.vtk_to_numpy(rgba).reshape(h, w, 4)[::-1].copy()
        zbuf = vtk.vtkFloatArray()
        self.window.GetZbufferData(0, 0, w - 1, h - 1, zbuf)
        depth = numpy_support.vtk_to_numpy(zbuf).reshape(h, w)[::-1].astype(np.float32)
        return packed, depth


def _offscreen_window():
    """An EGL off-screen window where VTK has EGL and it works here, else VTK's default."""
    egl = getattr(vtk, "vtkEGLRenderWindow", None)
    if egl is not None:
        window = egl()
        window.SetOffScreenRendering(True)
        if window.SupportsOpenGL():
            return window
        window.Finalize()
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(True)
    return window


_DRAWER: list = []  # the drawing thread's _Drawer, made there on first use


def _draw(geometry, camera, size, clip_planes):
    if not _DRAWER:
        _DRAWER.append(_Drawer())
    return _DRAWER[0].draw(geometry, camera, size, clip_planes)


def cell_frame(geometry: CellGeometry, camera: Camera, size, clip_planes=()):
    """Draw the surface of ``geometry`` by cell projection in the drawing thread (blocks
    the calling thread until it is drawn; thread safe).

    Parameters
    ----------
    geometry : CellGeometry
    camera : Camera
        With the clipping range of the view the frame is for (else the one fitted to the
        data box).
    size : (width, height)
    clip_planes : sequence of (origin, normal)

    Returns
    -------
    frame : Frame
        ``hit`` (H, W) bool, ``depth`` (H, W) float32 window depth (1 where no hit);
        ``normal`` and ``position`` (H, W, 3) and ``color`` (H, W, 4) made when first read
        (from the 8-bit normals and the 24-bit depth: picking precision).
    normals : (H, W, 4) uint8
        Unit normals in view coordinates as :func:`splineviz.render.quad.view_normals`
        packs them (alpha 255 at hits), row 0 at the top.
    """
    w, h = (int(v) for v in size)
    packed, depth = _THREAD.submit(_draw, geometry, camera, (w, h), tuple(clip_planes)).result()
    hit = depth < 1.0
    packed[..., 3] = np.where(hit, 255, 0)
    right, up, dop = camera.basis()

    def normal():
        nv = packed[..., :3] / 127.5 - 1.0
        n = nv[..., :1] * right + nv[..., 1:2] * up - nv[..., 2:] * dop
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        return np.where(hit[..., None], n, np.nan)

    def position():
        near, far = camera.fit_clipping_range(geometry.spline.bounds)
        eye, dirs = camera.rays((w, h))
        ndc = 2.0 * depth.astype(np.float64) - 1.0
        ze = 2.0 * far * near / ((far + near) - ndc * (far - near))
        pos = eye + dirs * (ze / (dirs @ dop))[..., None]
        return np.where(hit[..., None], pos, np.nan)

    def color():
        return phong_shade(hit, frame.normal, camera.rays((w, h))[1])

    frame = Frame(hit, position, normal, depth, color)
    return frame, packed
