"""Direct volume rendering of the volumes whose node asks for it, in exact frames
(:func:`splineviz.render.scene_view.render_scene`).

The scene without volume rendering is drawn first (isosurfaces, meshes, points, outlines);
its colour and window depth are read back; each volume-rendered volume then casts its rays
in the same camera, and they end at the scene's depth (opaque geometry, the isosurfaces
written into the depth buffer by their quads), so everything drawn is embedded at its depth
and hides what is behind it; the accumulated colour is composited over the scene's picture
(``C + (1 - A) scene``). Clip planes of the volume and the scene-wide ones cut it. The
transfer function is the node's edited points, preset (placed on the data's range) or
ParaView JSON file.
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
    """The node's :class:`~splineviz.core.transfer_function.TransferFunction` (its edited
    points, or its preset placed on the data's range, or its JSON file)."""
    from splineviz.model.nodes import resolve_transfer_function

    spec = node.transfer_function_spec
    if not isinstance(spec, str):
        return resolve_transfer_function(spec, None)
    data = node.active.data
    return resolve_transfer_function(spec, (float(np.min(data)), float(np.max(data))))


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
    casts = volume_casts(view)
    if not casts:
        return image
    h, w = image.shape[:2]
    return composite_casts(image, vtk_camera(plotter), window_depth(plotter, w, h), casts,
                           device)


def volume_casts(view) -> list[tuple]:
    """What :func:`composite_casts` casts for ``view`` (a :class:`SceneView`), read from its
    scene now (in the thread that owns the scene): per visible volume node whose
    ``volume_rendering`` is on, ``(volume, model, transfer function spec, shaded, clip
    planes)``."""
    scene = view.scene
    scene_planes = [p.as_pair() for p in scene.clip_planes if p.enabled and p.volume_id is None]
    casts = []
    for node in scene.volumes:
        if not (node.volume_rendering and node.visible):
            continue
        if not isinstance(node.active, Volume):
            log.warning("volume rendering of %s skipped: chunked volumes are not volume "
                        "rendered", node.name)
            continue
        casts.append((node.active, node.rendering_model, node.transfer_function_spec,
                      node.rendering_shade, scene_planes + view._volume_planes(node.id)))
    return casts


def composite_casts(image: np.ndarray, camera: Camera, depth: np.ndarray, casts,
                    device=None) -> np.ndarray:
    """``image`` ((H, W, 3 or 4) uint8, a picture of the scene without volume rendering)
    with the :func:`volume_casts` ``casts`` cast in ``camera`` and composited over it, one
    after the other; their rays end at ``depth`` ((H, W) window depth of ``image``, row 0
    at the top). Any thread: the casts hold the device as the refine workers do."""
    from splineviz.compute.dvr import VolumeRenderer, depth_stop
    from splineviz.model.nodes import resolve_transfer_function
    from splineviz.render.isosurface import _WORKERS_ON_DEVICE

    h, w = image.shape[:2]
    out = image[..., :3].astype(np.float64) / 255.0
    alpha = image[..., 3].astype(np.float64) / 255.0 if image.shape[2] == 4 else None
    for volume, model, spec, shaded, planes in casts:
        data = volume.data
        tf = resolve_transfer_function(spec, (float(np.min(data)), float(np.max(data))))
        with _WORKERS_ON_DEVICE:
            vr = VolumeRenderer(volume, model, tf, device=device, shaded=shaded)
            stop = depth_stop(depth, np.zeros((h, w, 3), np.uint8), camera,
                              camera.clipping_range)
            stop[1][..., 3] = 0.0  # the scene's colour is composited below, everywhere
            frame = vr.render(camera, (w, h), clip_planes=planes, stop=stop)
        a = frame.rgba[..., 3:].astype(np.float64)
        out = frame.rgba[..., :3] + (1.0 - a) * out
        if alpha is not None:
            alpha = a[..., 0] + (1.0 - a[..., 0]) * alpha
    result = image.copy()
    result[..., :3] = np.rint(np.clip(out, 0.0, 1.0) * 255.0).astype(np.uint8)
    if alpha is not None:
        result[..., 3] = np.rint(np.clip(alpha, 0.0, 1.0) * 255.0).astype(np.uint8)
    return result
