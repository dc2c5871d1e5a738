"""Direct volume rendering of the volumes whose node asks for it, in exact frames
(:func:`splineviz.render.scene_view.render_scene`).

The scene without volume rendering is drawn first (isosurfaces, meshes, points, outlines);
its colour and window depth are read back; each volume-rendered volume then casts its rays
in the same camera, and they end at the scene's depth (opaque geometry, the isosurfaces
written into the depth buffer by their quads), so everything drawn is embedded at its depth
and hides what is behind it; the accumulated colour is composited over the scene's picture
(``C + (1 - A) scene``). Clip planes of the volume and the scene-wide ones cut it. The
transfer function is the node's preset (placed on the data's range) or ParaView JSON file.
Several volume-rendered volumes are composited one after the other in scene order (their
overlap is not interleaved).
"""

from __future__ import annotations

import logging

import numpy as np

from splineviz.core.camera import Camera
from splineviz.core.volume import Volume

log = logging.getLogger(__name__)


def transfer_function_of(node):
    """The node's :class:`~splineviz.core.transfer_function.TransferFunction`."""
    from splineviz.core.transfer_function import resolve

    data = node.active.data
    return resolve(node.transfer_function, (float(np.min(data)), float(np.max(data))))


def vtk_camera(plotter) -> Camera:
    """The plotter's camera, with VTK's clipping range (the depth buffer's)."""
    cam = plotter.renderer.GetActiveCamera()
    return Camera(cam.GetPosition(), cam.GetFocalPoint(), view_up=cam.GetViewUp(),
                  view_angle=cam.GetViewAngle(), clipping_range=cam.GetClippingRange())


def window_depth(plotter, w: int, h: int) -> np.ndarray:
    """(H, W) float32 window depth of the last render, row 0 at the top."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkFloatArray

    arr = vtkFloatArray()
    plotter.ren_win.GetZbufferData(0, 0, w - 1, h - 1, arr)
    return vtk_to_numpy(arr).reshape(h, w)[::-1].astype(np.float32)


def composite_volume_rendering(view, plotter, image: np.ndarray, device=None) -> np.ndarray:
    """``image`` (the plotter's last screenshot, (H, W, 3 or 4) uint8) with the volume
    rendering of every visible volume node of ``view.scene`` whose ``volume_rendering`` is
    on; the image itself when there is none."""
    from splineviz.compute.dvr import VolumeRenderer, depth_stop

    scene = view.scene
    nodes = [v for v in scene.volumes if v.volume_rendering and v.visible]
    if not nodes:
        return image
    h, w = image.shape[:2]
    camera = vtk_camera(plotter)
    depth = window_depth(plotter, w, h)
    out = image[..., :3].astype(np.float64) / 255.0
    alpha = image[..., 3].astype(np.float64) / 255.0 if image.shape[2] == 4 else None
    scene_planes = [p.as_pair() for p in scene.clip_planes if p.enabled and p.volume_id is None]
    for node in nodes:
        if not isinstance(node.active, Volume):
            log.warning("volume rendering of %s skipped: chunked volumes are not volume "
                        "rendered", node.name)
            continue
        vr = VolumeRenderer(node.active, node.rendering_model, transfer_function_of(node),
                            device=device, shaded=node.rendering_shade)
        stop = depth_stop(depth, np.zeros((h, w, 3), np.uint8), camera, camera.clipping_range)
        stop[1][..., 3] = 0.0  # the scene's colour is composited below, everywhere
        frame = vr.render(camera, (w, h), clip_planes=scene_planes
                          + view._volume_planes(node.id), stop=stop)
        a = frame.rgba[..., 3:].astype(np.float64)
        out = frame.rgba[..., :3] + (1.0 - a) * out
        if alpha is not None:
            alpha = a[..., 0] + (1.0 - a[..., 0]) * alpha
    result = image.copy()
    result[..., :3] = np.rint(np.clip(out, 0.0, 1.0) * 255.0).astype(np.uint8)
    if alpha is not None:
        result[..., 3] = np.rint(np.clip(alpha, 0.0, 1.0) * 255.0).astype(np.uint8)
    return result
